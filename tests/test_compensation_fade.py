"""
The multiple-scattering compensation is on by default and faded in by roughness
(:mod:`explorer.physics.compensation`): exactly 0 at alpha <= 0.4 (Eqs. 17 and 34 as published, the paper's
figures kept, no table built), exactly 1 from alpha = 0.5, smoothstep between; numpy and GLSL alike.

And ``bragg_layer``'s white furnace through its documented test hook
``BraggLayerModel.facet_reflectance_override`` (the tables the twin, the shader and the walk read): over a black
base the compensated layer keeps its albedo at 0.99 or more at alpha = 0.6 and 1, theta <= 70 deg, in numpy and GL
(test_white_furnace.py, with the stack's layer), and the microsurface random walk of the same layer gives 1 within
its standard error.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT
from explorer.gpu.context import VERTEX_SHADER
from explorer.gpu.twin_check import check_material
from explorer.materials.brd import load_material
from explorer.materials.glsl import ShaderBuilder
from explorer.materials.models import BraggLayerModel, model_for
from explorer.materials.presets import presets_for
from explorer.physics import compensation, position_free
from explorer.resources import SHADER_DIR
from test_bragg_layer import directions
from test_white_furnace import FURNACE_ALPHAS, FURNACE_THETA, FURNACES

LAYER = REPO_ROOT / "shaders" / "bragg_layer.brd"
STACK = REPO_ROOT / "shaders" / "bragg_stack.brd"
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
#: The walk's furnace: paths per angle, and how many standard errors its luminance may stray from 1.
WALK_PATHS, SIGMAS = 2048, 3.0


@pytest.fixture(scope="module")
def layer_material():
    return load_material(LAYER)


@pytest.fixture(scope="module")
def stack_material():
    return load_material(STACK)


def test_weight_is_zero_up_to_04_and_one_from_05():
    w = compensation.compensation_weight
    assert np.all(w([0.0, 0.1, 0.3999999, 0.4]) == 0.0)
    assert np.all(w([0.5, 0.5000001, 0.7, 1.0]) == 1.0)
    alpha = np.linspace(0.4, 0.5, 101)
    assert np.all(np.diff(w(alpha)) > 0.0) and w(0.45) == pytest.approx(0.5)
    # smoothstep: no kink at either end (the slope is 0 there), so the slider shows no step
    assert (w(0.4001) - w(0.4)) / 1e-4 < 0.1 and (w(0.5) - w(0.4999)) / 1e-4 < 0.1 and (w(0.4501) - w(0.45)) / 1e-4 > 10.0


PROBE = """#include "lib/complex.glsl"  // PI, which lib/multiscatter.glsl takes from its includer
#include "lib/multiscatter.glsl"
uniform float alphas[COUNT];
out vec4 result;
void main() { result = vec4(compensation_weight(alphas[int(gl_FragCoord.x)])); }
"""


@pytest.mark.gl
def test_weight_glsl_equals_numpy(gl_renderer):
    alpha = np.array([0.0, 0.2, 0.4, 0.41, 0.43, 0.45, 0.47, 0.49, 0.5, 0.6, 1.0], np.float32)
    ctx = gl_renderer.ctx
    builder = ShaderBuilder(include_dirs=[SHADER_DIR])
    builder.define("COUNT", str(alpha.size))
    builder.add_source(PROBE, "probe")
    program = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=builder.build().code)
    framebuffer = ctx.framebuffer(color_attachments=[ctx.renderbuffer((alpha.size, 1), 4, dtype="f4")])
    try:
        gl_renderer.draw(program, framebuffer, uniforms={"alphas": alpha.tolist()})
        gl = np.frombuffer(framebuffer.read(components=4, dtype="f4"), dtype=np.float32).reshape(alpha.size, 4)[:, 0]
    finally:
        framebuffer.color_attachments[0].release()
        framebuffer.release()
    expected = compensation.compensation_weight(alpha.astype(np.float64))
    np.testing.assert_allclose(gl, expected, atol=1e-6)
    assert np.all(gl[alpha <= 0.4] == 0.0) and np.all(gl[alpha >= 0.5] == 1.0)  # exactly, in float32 too


def test_on_by_default(layer_material, stack_material):
    assert layer_material.resolve({})["multiple_scattering"] and stack_material.resolve({})["multiple_scattering"]


def test_no_shipped_preset_builds_a_lobe(layer_material, stack_material):
    """Every shipped preset of both materials has alpha <= 0.4: the default (compensation on) is Eq. 17 / Eq. 34
    as published there, without a table (weight exactly 0)."""
    count = 0
    for material, path in ((layer_material, LAYER), (stack_material, STACK)):
        for name, preset in presets_for(path).presets.items():
            model = model_for(material, material.resolve(preset.values))
            assert model.multiple_scattering and model.compensation_weight == 0.0, name
            assert model.compensation is None and model._compensation is None, name
            count += 1
    assert count > 20


@pytest.mark.parametrize("which, values", [
    ("layer", {"alpha": 0.4, "rho_d": "0.3,0.4,0.5"}),
    ("stack", {"layers": 2, "alpha_1": 0.4, "alpha_2": 0.3, "rho_d": 0.5}),
])
def test_at_04_the_model_is_single_scattering_exactly(layer_material, stack_material, which, values):
    material = layer_material if which == "layer" else stack_material
    on = model_for(material, material.resolve({**values, "multiple_scattering": 1}))
    off = model_for(material, material.resolve({**values, "multiple_scattering": 0}))
    L, V = directions(64, 3), directions(64, 4)
    frame = np.eye(3)[2], np.eye(3)[0], np.eye(3)[1]
    np.testing.assert_array_equal(on.brdf(L, V, *frame), off.brdf(L, V, *frame))
    assert on.compensation is None
    assert not on.textures()["layer_lobe" if which == "layer" else "stack_missing"].any()


@pytest.mark.gl
def test_at_04_gl_is_single_scattering_exactly(gl_renderer, stack_material):
    values = {"layers": 2, "alpha_1": 0.4, "alpha_2": 0.2, "rho_d": 0.5}
    on, off = (gl_renderer.render(stack_material, stack_material.resolve({**values, "multiple_scattering": m}), "lit", 48, 48)
               for m in (1, 0))
    np.testing.assert_array_equal(on, off)


@pytest.mark.parametrize("which, values", [
    ("layer", {"alpha": 0.45, "rho_d": "0.3,0.5,0.2", "N": 10}),
    ("stack", {"layers": 2, "alpha_1": 0.2, "alpha_2": 0.46, "rho_d": 0.4}),  # the roughest layer decides
])
def test_the_fade_in_numpy_and_gl(gl_renderer, layer_material, stack_material, which, values):
    """Between 0.4 and 0.5 the model adds the weight's share of the lobe, in numpy (exactly) and in GL (the twins'
    tolerances: the shader computes its weight from its own uniforms)."""
    material = layer_material if which == "layer" else stack_material
    resolved = material.resolve(values)
    on = model_for(material, resolved)
    off = model_for(material, {**resolved, "multiple_scattering": False})
    weight = on.compensation_weight
    assert 0.05 < weight < 0.95
    L, V = directions(64, 5), directions(64, 6)
    frame = np.eye(3)[2], np.eye(3)[0], np.eye(3)[1]
    added = on.brdf(L, V, *frame) - off.brdf(L, V, *frame)
    from explorer.physics import multiscatter_stack

    full = multiscatter_stack.lookup_rgb(on.compensation_rgb, *multiscatter_stack.air_angles(L, V))
    np.testing.assert_allclose(added, weight * full, rtol=1e-5, atol=1e-7)
    assert np.abs(added).max() > 0.01  # the lobe is there, scaled
    results = check_material(gl_renderer, material, resolved, views=("lit",))
    assert results and all(result.passed for result in results), [str(result) for result in results]


# --------------------------------------------------------------------------------------------------
# bragg_layer's white furnace (facets that reflect everything, a black base)

FURNACE = FURNACES[BraggLayerModel][0]


@pytest.fixture
def white_facets(monkeypatch):
    monkeypatch.setattr(BraggLayerModel, "facet_reflectance_override", 1.0)


@pytest.mark.parametrize("alpha", FURNACE_ALPHAS)
def test_layer_white_furnace_walk(layer_material, white_facets, alpha):
    """The reference walks the layer's own structure and tables (the hook's): 1 within its standard error, where
    its single-scattering walk loses light."""
    model = model_for(layer_material, layer_material.resolve({**FURNACE, "alpha": alpha}))
    structure, tables = model.layer_structure
    assert np.all(np.asarray(tables[0].reflectance) == 1.0)
    walk = position_free.PositionFree(structure, tables, "walk").albedo(FURNACE_THETA, samples=WALK_PATHS, seed=36)
    Y, Y_err = walk.value @ LUMINANCE, np.sqrt(walk.stderr**2 @ LUMINANCE**2)
    assert np.all(np.abs(Y - 1.0) <= SIGMAS * Y_err + 1e-12), (Y, Y_err)
    single = position_free.PositionFree(structure, tables, "single").albedo(FURNACE_THETA, samples=WALK_PATHS, seed=36)
    assert np.all(single.value @ LUMINANCE < 0.8)


def test_the_hook_needs_the_tables(layer_material, white_facets):
    with pytest.raises(ValueError, match="tabulated method"):
        model_for(layer_material, layer_material.resolve({**FURNACE, "method": 1, "alpha": 0.6}))


def test_blender_tables_carry_the_faded_lobe(layer_material):
    """Blender's converged table is the twin's albedo: the lobe (weighted) from alpha 0.5, none at 0.4."""
    from explorer.blender import converged_tables

    def table(alpha, on):
        return converged_tables(layer_material, layer_material.resolve({"alpha": alpha, "N": 10, "multiple_scattering": on}), size=8)[0]

    np.testing.assert_array_equal(table(0.4, 1), table(0.4, 0))
    assert np.all(table(0.8, 1)[1:] @ LUMINANCE > table(0.8, 0)[1:] @ LUMINANCE + 0.05)
