"""
A smooth mirror (``MIRROR_ONLY``: bragg_mirror.brd) in the lit view: the environment it reflects and the light
as a glint (shaders/views/lit.glsl, explorer/views/mirror.py), GL against numpy (tests/twins.py) on the sphere
and a mesh, the glint's unit irradiance, the white furnace against the sphere view, the CLI's --env and
--env-rotation, and rough materials unchanged.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli, run_cli_process
from twins import LIGHTS, Twins, assert_twins_equal, compared_pixels, render_both, tolerance_for

from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.views.env import ENVIRONMENTS, EnvironmentMap
from explorer.views.geometry import brdf_view_geometry, light_direction
from explorer.views.mirror import GLINT_RADIUS_DEGREES, is_mirror_only, light_glint
from explorer.views.render import render_numpy

MIRROR = REPO_ROOT / "shaders" / "bragg_mirror.brd"
GGX = REPO_ROOT / "shaders" / "ggx_schlick.brd"
SIZE = 48


def test_which_materials_are_mirrors():
    assert is_mirror_only(load_material(MIRROR))
    for name in ("bragg_layer", "bragg_stack", "ggx_schlick", "thin_film"):  # rough (the stack's coating Dirac comes with lobes)
        assert not is_mirror_only(load_material(REPO_ROOT / "shaders" / f"{name}.brd")), name


def test_glint_has_unit_irradiance_toward_the_light():
    """int glint(w) cos(w, l) dw = 1 (the lit view's unit irradiance), by a fine midpoint rule about the light."""
    rho = np.radians(GLINT_RADIUS_DEGREES)
    theta = (np.arange(20000) + 0.5) * (1.5 * rho / 20000)
    light = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    a = np.cross(light, [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    directions = np.cos(theta)[:, None] * light + np.sin(theta)[:, None] * a  # the profile is symmetric about the light
    irradiance = np.sum(light_glint(directions, light) * np.cos(theta) * 2.0 * np.pi * np.sin(theta)) * (1.5 * rho / 20000)
    assert irradiance == pytest.approx(1.0, rel=1e-4)
    assert light_glint(-light, light) == 0.0 and light_glint(directions[-1], light) == 0.0  # not behind, not beyond rho


@pytest.mark.gl
@pytest.mark.parametrize("method", [1, 3, 4])
@pytest.mark.parametrize("environment", ["sky", "studio turned"])
def test_lit_mirror_twins(gl_renderer, method, environment):
    material = load_material(MIRROR)
    values = material.resolve({"method": method})
    chosen = ENVIRONMENTS["sky"]() if environment == "sky" else ENVIRONMENTS["studio"]().rotated(70.0)
    light = LIGHTS["lit"]
    gl = gl_renderer.render(material, values, "lit", SIZE, SIZE, light=light, environment=chosen)
    reference = render_numpy(model_for(material, values), "lit", SIZE, SIZE, light=light, environment=chosen)
    twins = Twins.of(gl, reference, "lit", light)
    assert_twins_equal(twins, f"lit mirror, method {method}, {environment}")
    inside = brdf_view_geometry("lit", SIZE, SIZE)[5]
    assert np.abs(reference[inside]).max(axis=-1).min() > 0.0 and (gl[~inside] == 0.0).all()
    assert reference.max() > 20.0  # the glint (a reflectance of a few tenths of a peak of 465)


@pytest.mark.gl
def test_lit_mirror_default_environment_is_the_env_views(gl_renderer):
    """Without an environment the lit mirror reflects the env view's default (the shipped sky), in both twins."""
    material = load_material(MIRROR)
    values = material.resolve({"method": 1})
    twins = render_both(gl_renderer, material, values, "lit", (SIZE, SIZE))
    assert_twins_equal(twins, "lit mirror, default environment")
    sky = render_numpy(model_for(material, values), "lit", SIZE, SIZE, light=LIGHTS["lit"], environment=EnvironmentMap.default())
    np.testing.assert_array_equal(twins.reference, sky)
    turned = gl_renderer.render(material, values, "lit", SIZE, SIZE, light=LIGHTS["lit"], environment=EnvironmentMap.default().rotated(90.0))
    assert np.abs(turned - twins.gl).max() > 0.1  # the probe's turn reaches the shader


@pytest.mark.gl
def test_lit_mirror_on_a_mesh(gl_renderer):
    from test_mesh import MESH_DEPTH_GAP, MESH_EDGE_MARGIN

    from explorer.gpu.mesh import render_mesh
    from explorer.views.mesh import rasterise, teapot

    material = load_material(MIRROR)
    values = material.resolve({"method": 3})
    studio = ENVIRONMENTS["studio"]()
    gl = render_mesh(gl_renderer, material, values, "lit", teapot(), SIZE, SIZE, light=(30.0, 120.0), environment=studio)
    reference = render_numpy(model_for(material, values), "lit", SIZE, SIZE, light=(30.0, 120.0), mesh=teapot(), environment=studio)
    surface = rasterise(teapot(), SIZE, SIZE)
    safe = surface.covered & (surface.margin > MESH_EDGE_MARGIN) & (surface.depth_gap > MESH_DEPTH_GAP)  # as test_mesh's twins
    assert safe.sum() > 0.2 * SIZE * SIZE
    assert_twins_equal(Twins(gl, reference, safe, "lit"), "lit mirror teapot")


@pytest.mark.gl
def test_white_furnace_lit_mirror_is_the_sphere_view(gl_renderer):
    """Under radiance 1 the mirror shows R(V.N): the sphere view's reflectance at the same pixels, away from the glint."""
    material = load_material(MIRROR)
    values = material.resolve({"method": 1})
    light = (50.0, 200.0)
    lit = gl_renderer.render(material, values, "lit", SIZE, SIZE, light=light, environment=ENVIRONMENTS["white furnace"]())
    sphere = gl_renderer.render(material, values, "sphere", SIZE, SIZE)
    _, V, N, *_ = brdf_view_geometry("lit", SIZE, SIZE, light)
    reflected = 2.0 * np.sum(V * N, axis=-1, keepdims=True) * N - V
    dark = light_glint(reflected.astype(np.float64), light_direction(light)) == 0.0
    compared = compared_pixels("lit", SIZE, SIZE) & dark & brdf_view_geometry("lit", SIZE, SIZE)[5]
    assert compared.sum() > 0.6 * np.pi * SIZE * SIZE / 4
    np.testing.assert_allclose(lit[compared], sphere[compared], rtol=1e-5, atol=1e-6)
    assert lit[~dark].max() > 10.0 * sphere.max()  # the glint


@pytest.mark.gl
def test_rough_materials_are_unchanged(gl_renderer):
    """A rough material's lit program reads no environment, and its twin is the BRDF under the light, as before."""
    material = load_material(GGX)
    values = material.resolve({"alpha": 0.3})
    assert "mirror_environment" not in gl_renderer.program(material, "lit", values)
    twins = render_both(gl_renderer, material, values, "lit", (32, 32))
    assert_twins_equal(twins)
    L, V, N, X, Y, inside, factor = brdf_view_geometry("lit", 32, 32, LIGHTS["lit"])
    from explorer.views.geometry import view_brdf

    expected = view_brdf(model_for(material, values).brdf, L[inside], V[inside], N[inside], X[inside], Y[inside]) * factor[inside][:, None]
    np.testing.assert_allclose(twins.reference[inside], expected, rtol=1e-6, atol=1e-7)


@pytest.mark.gl
def test_cli_lit_mirror_environment(tmp_path, gl_renderer):
    out = tmp_path / "lit.npy"
    run = run_cli_process("render", "bragg_mirror", "--view", "lit", "--env", "studio", "--env-rotation", "30", "--light", "30,120",
                  "--size", "32", "--set", "method=1", "--out", out)
    assert run.returncode == 0, run.stderr
    material = load_material(MIRROR)
    values = material.resolve({"method": 1})
    reference = render_numpy(model_for(material, values), "lit", 32, 32, light=(30.0, 120.0),
                             environment=ENVIRONMENTS["studio"]().rotated(30.0))
    twins = Twins.of(np.load(out), reference, "lit", (30.0, 120.0))
    assert_twins_equal(twins, "CLI lit mirror", tolerance_for("lit"))
    for args in (["--spp", "4"], ["--background"]):  # the env view's own options
        line = one_line_error(run_cli("render", "bragg_mirror", "--view", "lit", "--env", "studio", *args, "--out", tmp_path / "x.png"))
        assert "--view" in line, line
    line = one_line_error(run_cli("render", GGX, "--view", "lit", "--env", "studio", "--out", tmp_path / "x.png"))
    assert "smooth mirror" in line, line  # a rough material reflects no environment in the lit view


def test_saved_view_holds_a_mirrors_environment(tmp_path):
    """The app saves the environment and its turn for a lit mirror (and the env mode), not for a rough lit material;
    render --params reproduces the lit mirror under them."""
    from explorer.app.parameter_files import load_view, save_values
    from explorer.app.state import AppState, CompareState

    mirror = load_material(MIRROR)
    values = mirror.resolve({"method": 1})
    state = AppState(MIRROR, mirror, values, CompareState({}), mode="lit", environment="studio", env_rotation=30.0)
    settings = state.view_settings()
    assert settings["view"] == "lit" and settings["environment"] == "studio" and settings["env_rotation"] == 30.0
    rough = load_material(GGX)
    settings_rough = AppState(GGX, rough, rough.resolve({}), CompareState({}), mode="lit", environment="studio", env_rotation=30.0).view_settings()
    assert settings_rough["environment"] is None and settings_rough["env_rotation"] is None
    for name in ("v.json", "v.bparam"):
        save_values(tmp_path / name, mirror, values, settings)
        assert load_view(tmp_path / name)["env_rotation"] == 30.0 and load_view(tmp_path / name)["environment"] == "studio"
        out = tmp_path / f"{name}.npy"
        run = run_cli("render", MIRROR, "--params", tmp_path / name, "--engine", "numpy", "--size", "16", "--out", out)
        assert run.returncode == 0, run.stderr
        light = tuple(float(c) for c in state.light)
        expected = render_numpy(model_for(mirror, values), "lit", 16, 16, light=light, environment=ENVIRONMENTS["studio"]().rotated(30.0))
        np.testing.assert_allclose(np.load(out), expected, rtol=1e-6, atol=1e-7)
    bad = (tmp_path / "v.bparam").read_text().replace("env_rotation 30.0", "env_rotation sideways")
    (tmp_path / "bad.bparam").write_text(bad)
    assert "env_rotation" in one_line_error(run_cli("render", MIRROR, "--params", tmp_path / "bad.bparam", "--out", tmp_path / "x.png"))
