"""shaders/bragg_stack.brd: the single-reflection BRDF of layered Bragg structures (Eq. 34)
evaluated spectrally per pixel from the host's tables, GL against its numpy twin.

The numpy twin is :class:`explorer.materials.models.BraggStackModel` (over :func:`explorer.physics.layered.single_reflection_brdf`);
the tolerance is tests/twins.py's BRDF_TOLERANCE (2e-3 relative to a pixel's largest |channel| where it
exceeds 1e-3, absolute below), in every view. The physics of Eq. 34 itself (reciprocity, coating, white furnace, N = 1 slab) is tested in
test_layered.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli
from explorer.physics import bragg, colorimetry, layered
from explorer.materials.brd import load_material
from explorer.materials.models import BraggStackModel, model_for
from explorer.views.geometry import brdf_view_geometry
from test_bragg_layer import directions
from test_brdf_views import SIZE
from twins import BRDF_TOLERANCE, FLOOR, Tolerance, assert_twins_equal, render_both

STACK_MATERIAL = REPO_ROOT / "shaders" / "bragg_stack.brd"
#: The slice view's last row and column reach theta_h, theta_d = 89 deg, where float32 directions lose
#: ~5e-3 of Eq. 17's value (G1 / cos and D at grazing angles): those pixels get this tolerance.
GRAZING_RTOL = 1e-2
GRAZING_COS = 1e-2
GRAZING_TOLERANCE = Tolerance(f"{GRAZING_RTOL:g} x max(value, {FLOOR:g}) at grazing", atol=GRAZING_RTOL * FLOOR, rtol=GRAZING_RTOL)

#: One to three layers, a coating, Appendix D's host (the jewel beetle of Table 3), coloured bases.
CASES = {
    "one layer": {},
    "two layers over a base": {"layers": 2, "rho_d": "0.5,0.3,0.2"},
    "three layers, coated": {"layers": 3, "nh": 1.35, "n1_1": 1.35, "n1_2": 1.35, "n1_3": 1.35, "rho_d": 0.5, "N_3": 40},
    "coating off": {"layers": 2, "nh": 1.35, "coating": 0, "rho_d": 0.3},
    "jewel beetle (Appendix D)": {"n1_1": 1.59, "n2_1": 1.67, "Lambda_1": 160, "delta_1": 0.51, "N_1": 8, "alpha_1": 0.05},
    "large N, rough": {"layers": 2, "N_1": 300, "alpha_1": 0.6, "alpha_2": 0.01, "rho_d": 1},
    # A dispersive host: every wavelength refracts its own way through the coating.
    "chitin host, coated": {"layers": 2, "nh": "chitin", "rho_d": "0.5,0.3,0.2", "tau_h": 0.1},
}


@pytest.fixture(scope="module")
def stack_material():
    return load_material(STACK_MATERIAL)


@pytest.mark.gl
@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("view", ["lit", "slice", "scatter"])
def test_gl_equals_numpy_twin(gl_renderer, stack_material, case, view):
    twins = render_both(gl_renderer, stack_material, stack_material.resolve(CASES[case]), view, SIZE)
    what = f"bragg_stack {case}, {view}"
    width, height = SIZE
    if view == "slice":
        grazing = np.zeros((height, width), bool)
        grazing[-1, :] = grazing[:, -1] = True
    else:
        # Light or view within 0.6 deg of the horizon: the multiple-scattering lobe's m(theta) rises steeply
        # there and float32 directions lose ~1e-2 of it (a lit pixel at cos theta_i = 3e-4: 0.9 %).
        L, V, N = brdf_view_geometry(view, width, height, twins.light)[:3]
        grazing = np.minimum(np.sum(L * N, axis=-1), np.sum(V * N, axis=-1)) < GRAZING_COS
    assert_twins_equal(twins.where(twins.compared & grazing), what, GRAZING_TOLERANCE)
    twins = twins.where(twins.compared & ~grazing)
    assert_twins_equal(twins, what, BRDF_TOLERANCE)
    assert np.abs(twins.reference).max() > 0.05, "an empty image"


@pytest.mark.gl
@pytest.mark.parametrize("view", ["sphere", "gradient"])
def test_specular_colour_views(gl_renderer, stack_material, view):
    values = stack_material.resolve(CASES["three layers, coated"])
    twins = render_both(gl_renderer, stack_material, values, view, (24, 24) if view == "sphere" else (64, 2))
    assert_twins_equal(twins, f"bragg_stack {view}", BRDF_TOLERANCE)


def test_smooth_limit_colour_of_one_uncoated_layer_is_the_mirror_reference(stack_material):
    """One layer in air: the specular colour is Yeh's reference RGB (explorer.physics.bragg), up to the 0.25-degree table."""
    values = stack_material.resolve({"N_1": 6, "Lambda_1": 400})
    model = model_for(stack_material, values)
    cos_theta = np.cos(np.radians(np.arange(0.0, 89.0, 7.0)))
    expected = bragg.reference_rgb(cos_theta, model.stack.layers[0].mirror(1.0))
    np.testing.assert_allclose(model.reflectance(cos_theta), expected, atol=2e-3 * np.abs(expected).max())


def test_coated_smooth_limit_adds_the_coating_fresnel(stack_material):
    """Normal incidence under a coating of index nh: F0 + (1 - F0)^2 R(0) (all flat in RGB except R)."""
    values = stack_material.resolve({"nh": 1.5, "n1_1": 1.5, "n2_1": 1.5})  # an invisible layer: R = 0
    model = model_for(stack_material, values)
    F0 = ((1.5 - 1.0) / (1.5 + 1.0)) ** 2
    np.testing.assert_allclose(model.reflectance(np.array([1.0])), np.full((1, 3), F0), atol=1e-9)


@pytest.mark.parametrize("case", ["two layers over a base", "three layers, coated", "jewel beetle (Appendix D)"])
def test_numpy_twin_is_reciprocal(stack_material, case):
    model = model_for(stack_material, stack_material.resolve(CASES[case]))
    assert isinstance(model, BraggStackModel)
    L, V = directions(64, 1), directions(64, 2)
    N, X, Y = np.eye(3)[2], np.eye(3)[0], np.eye(3)[1]
    forward, backward = model.brdf(L, V, N, X, Y), model.brdf(V, L, N, X, Y)
    assert np.abs(forward).max() > 0.0
    np.testing.assert_allclose(forward, backward, rtol=1e-12, atol=1e-15)


def test_twin_is_eq34_of_the_layered_module(stack_material):
    """The model passes its parameters through: the same BRDF as a LayeredBragg built by hand."""
    values = stack_material.resolve(CASES["three layers, coated"])
    model = model_for(stack_material, values)
    by_hand = layered.LayeredBragg(
        layers=tuple(layered.RoughBraggLayer(1.5, L, 0.5, N, a) for L, N, a in ((500, 10, 0.1), (988, 10, 0.05), (700, 40, 0.1))),
        n1=1.35, rho_d=0.5,
    )
    L, V = directions(16, 3), directions(16, 4)
    frame = np.eye(3)[2], np.eye(3)[0], np.eye(3)[1]
    np.testing.assert_allclose(model.brdf(L, V, *frame), layered.single_reflection_brdf(by_hand, L, V), rtol=1e-9)
    compensated = model_for(stack_material, {**values, "multiple_scattering": True})
    compensated.full_compensation = True  # alpha <= 0.4 fades the lobe out: the whole of it, to check what it is built from
    from explorer.physics import multiscatter_stack

    lobe = multiscatter_stack.rgb_table(multiscatter_stack.stack_compensation(by_hand), by_hand.rho_d)
    np.testing.assert_allclose(
        compensated.brdf(L, V, *frame),
        layered.single_reflection_brdf(by_hand, L, V) + multiscatter_stack.lookup_rgb(lobe, *multiscatter_stack.air_angles(L, V)), rtol=1e-6,
    )


@pytest.mark.parametrize("case", list(CASES))
def test_layer_choice_probabilities_partition_the_transmitted_light(stack_material, case):
    """Eq. 35 telescopes: the layers' probabilities and the base's sum to 1 - F (the coating's transmission)."""
    model = model_for(stack_material, stack_material.resolve(CASES[case]))
    cos_theta = np.linspace(0.0, 1.0, 41)
    p_refl, p_base = layered.layer_choice_probabilities(model.stack, cos_theta, model.tables)
    assert p_refl.shape == (41, len(model.stack.layers))
    assert np.all(p_refl >= 0.0) and np.all(p_base >= 0.0)
    F = layered.coating_reflectance(cos_theta, model.stack.n1) if model.stack.coating else 0.0
    np.testing.assert_allclose(p_refl.sum(axis=-1) + p_base, 1.0 - F, atol=1e-12)
    assert np.all(p_refl[:, 0] > 0.0), "the top layer reflects at every angle"


def test_textures_pack_one_layer_per_channel(stack_material):
    model = model_for(stack_material, stack_material.resolve(CASES["two layers over a base"]))
    textures = model.textures()
    assert textures["stack_reflectance"].shape == (361, colorimetry.WAVELENGTHS.size, 3)
    np.testing.assert_array_equal(textures["stack_reflectance"][..., 1], model.tables[1].reflectance)
    np.testing.assert_array_equal(textures["stack_transmissivity"][..., 2], 0.0)  # the unused third layer
    assert textures["stack_sampling"].shape == (361, 3)


@pytest.mark.slow
def test_no_nan_or_inf_over_a_sweep(stack_material):
    rng = np.random.default_rng(7)
    L, V = directions(32, 5), directions(32, 6)
    L[0] = V[0] = [np.sin(np.radians(89.99)), 0.0, np.cos(np.radians(89.99))]
    for example in range(6):
        values = stack_material.resolve({
            "layers": int(rng.integers(1, 4)), "nh": float(rng.uniform(1.0, 2.5)), "rho_d": float(rng.uniform(0, 1)),
            **{f"alpha_{k}": float(rng.choice([0.0, 0.001, 0.5, 1.0])) for k in (1, 2, 3)},
            **{f"N_{k}": int(rng.choice([1, 20, 1000])) for k in (1, 2, 3)},
            **{f"n2_{k}": float(rng.uniform(1.0, 2.5)) for k in (1, 2, 3)},
            # Eq. 34 alone and with the compensation, in turn (the lobe's tables cost seconds at N = 1000).
            "multiple_scattering": example % 2,
        })
        model = model_for(stack_material, values)
        brdf = model.brdf(L, V, np.eye(3)[2], np.eye(3)[0], np.eye(3)[1])
        assert np.isfinite(brdf).all(), values
        assert np.isfinite(model.reflectance(np.linspace(0.0, 1.0, 9))).all(), values


@pytest.mark.parametrize("assignment, named", [("layers=4", "layers"), ("alpha_2=-0.1", "alpha_2"), ("alpha_1=1.5", "alpha_1")])
def test_bad_parameters_are_one_line(tmp_path, assignment, named):
    out = tmp_path / "x.png"
    run = run_cli("render", "shaders/bragg_stack.brd", "--view", "lit", "--set", assignment, "--size", "8", "--out", out)
    assert named in one_line_error(run)
    assert not out.exists()


PROBE_COLUMNS = 64
#: The material's sampling hook at V = (sin theta, 0, cos theta), N = +z, cos theta = (i + 0.5) / width.
HOOK_PROBE = """
layout(location = 0) out vec4 refl_out;
void main() {
    float c = gl_FragCoord.x / float(PROBE_COLUMNS);
    vec3 V = vec3(sqrt(1.0 - c * c), 0.0, c), N = vec3(0.0, 0.0, 1.0);
    vec4 alphas, weights;
    float base = sampling_lobes(V, N, alphas, weights);
    refl_out = vec4(weights.xyz, base);
}
"""


#: The layer choice's cases: and a host whose 550-nm index (2.65) lies beyond the nh slider's range (it shows 2.5).
SAMPLING_CASES = {**CASES, "TiO2 host, coated": {"layers": 2, "nh": "TiO2", "rho_d": 0.4}}


@pytest.mark.gl
@pytest.mark.parametrize("case", ["two layers over a base", "three layers, coated", "jewel beetle (Appendix D)", "TiO2 host, coated"])
def test_sampling_hook_is_eq35_of_the_numpy_twin(gl_renderer, stack_material, case):
    """The GLSL layer choice (sampling_lobes) equals explorer.physics.layered.layer_choice_probabilities (Eqs. 31, 35)."""
    from explorer.materials.glsl import ShaderBuilder
    from explorer.gpu.context import VERTEX_SHADER
    from explorer.resources import SHADER_DIR

    values = stack_material.resolve(SAMPLING_CASES[case])
    builder = ShaderBuilder(include_dirs=[SHADER_DIR])
    builder.define("PROBE_COLUMNS", PROBE_COLUMNS)
    builder.add_source(stack_material.uniform_declarations(), "parameters")
    builder.add_source(stack_material.shader, str(stack_material.path), stack_material.shader_line)
    builder.add_source(HOOK_PROBE, "probe")
    ctx = gl_renderer.ctx
    program = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=builder.build().code)
    target = ctx.renderbuffer((PROBE_COLUMNS, 1), 4, dtype="f4")
    framebuffer = ctx.framebuffer(color_attachments=[target])
    try:
        uniforms, textures = gl_renderer.bindings(program, stack_material, values)
        gl_renderer.draw(program, framebuffer, uniforms=uniforms, textures=textures)
        got = np.frombuffer(framebuffer.read(components=4, dtype="f4"), np.float32).reshape(PROBE_COLUMNS, 4)
    finally:
        framebuffer.release()
        target.release()
        program.release()
    model = model_for(stack_material, values)
    cos_theta = (np.arange(PROBE_COLUMNS) + 0.5) / PROBE_COLUMNS
    p_refl, p_base = layered.layer_choice_probabilities(model.stack, cos_theta, model.tables)
    expected = np.zeros((PROBE_COLUMNS, 3))
    expected[:, : p_refl.shape[1]] = p_refl
    np.testing.assert_allclose(got[:, :3], expected, atol=2e-5)
    np.testing.assert_allclose(got[:, 3], p_base * max(model.stack.rho_d), atol=2e-5)
    assert expected[:, 0].min() > 0.0
