"""
Spatially varying Bragg mirrors (supplemental Figure 7): Lambda(x) = Lambda (0.5 + 0.5 T(x)) and
delta(x) = delta^T(x) in the textured view, GL against the numpy twin on every method, the tabulated
method's (cos theta, T) table against the reference, the mappings' closed forms, the CLI.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli, run_cli_process
from twins import Twins, assert_twins_equal, render_both

MIRROR = REPO_ROOT / "shaders" / "bragg_mirror.brd"
#: Not square, so that a swapped width and height or flipped rows show.
SIZE = (36, 28)
#: Supplemental Figure 7's mirror: n1 = 1, n2 = 1.5, Lambda = 500 nm, delta = 0.15.
FIGURE7 = {"n1": 1.0, "n2": 1.5, "Lambda": 500.0, "delta": 0.15}


@pytest.fixture(scope="module")
def mirror():
    from explorer.materials.brd import load_material

    return load_material(MIRROR)


def stripes(size: int = 40) -> np.ndarray:
    """T rising left to right, 0 to 1: every mapping varies across the sphere."""
    return np.broadcast_to(np.linspace(0.0, 1.0, size, dtype=np.float32)[None, :], (size, size)).copy()


def test_mappings_are_the_papers():
    from explorer.physics.bragg import BraggMirror, textured_mirror

    base = BraggMirror(1.0, 1.5, 500.0, 0.15, 20)
    T = np.array([0.0, 0.25, 1.0])
    both = textured_mirror(base, T, "both")
    np.testing.assert_allclose(both.Lambda, 500.0 * (0.5 + 0.5 * T))
    np.testing.assert_allclose(both.delta, 0.15**T)
    assert np.all(textured_mirror(base, T, "lambda").delta == 0.15)
    assert np.all(textured_mirror(base, T, "delta").Lambda == 500.0)
    none = textured_mirror(base, T, "none")
    assert np.all(none.Lambda == 500.0) and np.all(none.delta == 0.15)


def test_textured_reflectance_at_constant_T_is_the_homogeneous_mirror(mirror):
    """T fixed everywhere: the textured colour is that of the mirror with Lambda(T), delta(T), every method."""
    from explorer.materials.models import model_for

    cos_theta = np.linspace(0.1, 1.0, 7)
    for method in (0, 1, 2, 4):
        model = model_for(mirror, mirror.resolve({**FIGURE7, "method": method}))
        textured = model.textured_reflectance(cos_theta, np.full(7, 0.4), "both")
        plain = model_for(mirror, mirror.resolve({**FIGURE7, "method": method, "Lambda": 500.0 * 0.7, "delta": 0.15**0.4}))
        np.testing.assert_allclose(textured, plain.reflectance(cos_theta), atol=1e-9, err_msg=f"method {method}")


def test_tabulated_table_matches_the_reference_between_its_nodes(mirror):
    """The (cos theta, T) table's bilinear lookup against the converged reference at off-node (cos theta, T)."""
    from explorer.materials.models import model_for
    from explorer.physics import bragg, colorimetry

    model = model_for(mirror, mirror.resolve({**FIGURE7, "method": 3}))
    rng = np.random.default_rng(3)
    cos_theta, T = rng.uniform(0.2, 1.0, 40), rng.uniform(0.0, 1.0, 40)
    table = model.textured_reflectance(cos_theta, T, "both")
    exact = np.array([bragg.reference_rgb(c, bragg.textured_mirror(model.mirror, t, "both").__class__(
        1.0, 1.5, 500.0 * (0.5 + 0.5 * t), 0.15**t, 20)) for c, t in zip(cos_theta, T)])
    delta_e = colorimetry.delta_E_2000(table, exact)
    assert np.median(delta_e) < 1.0 and delta_e.max() < 4.0, (np.median(delta_e), delta_e.max())


@pytest.mark.gl
@pytest.mark.parametrize("method", [0, 1, 2, 3, 4])
def test_textured_bragg_gl_equals_numpy(gl_renderer, mirror, method):
    from explorer.views.surface_texture import BraggTexture

    texture = BraggTexture(stripes(), "both")
    values = mirror.resolve({**FIGURE7, "method": method})
    twins = render_both(gl_renderer, mirror, values, "textured", SIZE, light=(20.0, 30.0), thickness=texture)
    assert np.abs(twins.reference).max() > 0.01
    assert_twins_equal(twins, f"textured bragg method {method}")


@pytest.mark.gl
@pytest.mark.parametrize("mapping", ["none", "lambda", "delta"])
def test_textured_bragg_mappings_gl_equal_numpy(gl_renderer, mirror, mapping):
    from explorer.views.surface_texture import BraggTexture

    values = mirror.resolve({**FIGURE7, "method": 4})
    twins = render_both(gl_renderer, mirror, values, "textured", SIZE, light=(20.0, 30.0), thickness=BraggTexture(stripes(), mapping))
    assert_twins_equal(twins, f"textured bragg {mapping}")
    if mapping == "none":  # nothing varies: the homogeneous mirror's BRDF under the light (its half-vector reflectance;
        # the lit view shows a smooth mirror as a mirror ball instead: tests/test_lit_mirror.py)
        from explorer.materials.models import model_for
        from explorer.views.geometry import brdf_view_geometry, view_brdf

        L, V, N, X, Y, inside, factor = brdf_view_geometry("lit", *SIZE, (20.0, 30.0))
        homogeneous = np.zeros(inside.shape + (3,))
        homogeneous[inside] = view_brdf(model_for(mirror, values).brdf, *(a[inside] for a in (L, V, N, X, Y))) * factor[inside, None]
        assert_twins_equal(Twins.of(twins.gl, homogeneous, "lit"), "mapping none = the homogeneous mirror")


# -- the command line --------------------------------------------------------------------------------------


@pytest.mark.gl
def test_cli_figure7_four_spheres_equal_the_numpy_twin(mirror, tmp_path):
    """
    Supplemental Figure 7: the homogeneous mirror, Lambda mapped, delta mapped, both, by ``render --view
    textured`` (GL, the spectral reference: the approximations' discrete choices of boxes may flip between
    float32 and float64 on a noise texture), each equal to its numpy twin; the four differ from each other.
    """
    from explorer.resources import DEFAULT_TEXTURE
    from explorer.views.render import render_numpy
    from explorer.materials.models import model_for
    from explorer.views.surface_texture import BraggTexture

    sets = [arg for name, value in FIGURE7.items() for arg in ("--set", f"{name}={value}")]
    values = mirror.resolve({**FIGURE7, "method": 0})
    images = {}
    for mapping in ("none", "lambda", "delta", "both"):
        out = tmp_path / f"{mapping}.npy"
        run = run_cli_process("render", "bragg_mirror", "--view", "textured", "--mapping", mapping, "--set", "method=0", *sets,
                              "--size", "40x32", "--texture", DEFAULT_TEXTURE, "--out", out)
        assert run.returncode == 0, run.stderr
        images[mapping] = np.load(out)
        reference = render_numpy(model_for(mirror, values), "textured", 40, 32, thickness=BraggTexture.from_file(DEFAULT_TEXTURE, mapping))
        assert_twins_equal(Twins.of(images[mapping], reference, "textured"), f"figure 7 {mapping}")
    for a in images:
        for b in images:
            if a < b:
                assert np.abs(images[a] - images[b]).max() > 0.02, (a, b)


def test_cli_textured_needs_a_declared_texture_and_its_own_options(tmp_path):
    out = tmp_path / "out.png"
    cases = {
        "no texture declared": (["ggx_schlick", "--view", "textured"], "# texture:"),
        "mapping on a film": (["thin_film", "--view", "textured", "--mapping", "both"], "--mapping"),
        "dinc-range on a mirror": (["bragg_mirror", "--view", "textured", "--dinc-range", "0,500"], "--dinc-range"),
        "prefilter on a mirror": (["bragg_mirror", "--view", "textured", "--prefilter", "on"], "--prefilter"),
        "mapping off the textured view": (["bragg_mirror", "--view", "lit", "--mapping", "both"], "--mapping"),
    }
    for name, (args, named) in cases.items():
        line = one_line_error(run_cli("render", *args, "--engine", "numpy", "--size", "8", "--out", out))
        assert named in line, f"{name}: {line}"
        assert not out.exists(), name


# -- under an environment (the env view) -------------------------------------------------------------------


@pytest.mark.gl
@pytest.mark.parametrize("method", [1, 3])
def test_textured_mirror_under_an_environment_gl_equals_numpy(gl_renderer, mirror, method):
    """A smooth mirror's env view is its Dirac alone (no sampling): GL equals the exact integral, texture and all."""
    from explorer.gpu.env import render_env
    from explorer.materials.models import model_for
    from explorer.views.env import EnvironmentMap, env_integral_numpy
    from explorer.views.surface_texture import BraggTexture

    values = mirror.resolve({**FIGURE7, "method": method})
    texture = BraggTexture(stripes(), "both")
    environment = EnvironmentMap.default()
    gl = render_env(mirror, values, *SIZE, environment=environment, spp=1, renderer=gl_renderer, surface=texture)
    reference = env_integral_numpy(model_for(mirror, values), environment, *SIZE, surface=texture)
    assert_twins_equal(Twins.of(gl, reference, "env"), f"textured env method {method}")
    plain = render_env(mirror, values, *SIZE, environment=environment, spp=1, renderer=gl_renderer)
    assert np.abs(plain - gl).max() > 0.02  # the texture shows


@pytest.mark.gl
def test_textured_film_under_an_environment_at_a_constant_texture_is_the_film(gl_renderer):
    """A constant D_inc = 2 eta2 d: the same film, the same random numbers, the same Monte Carlo image."""
    from explorer.gpu.env import render_env
    from explorer.materials.brd import load_material
    from explorer.materials.models import model_for
    from explorer.views.thickness import ThicknessTexture

    film = load_material(REPO_ROOT / "shaders" / "thin_film.brd")
    values = film.resolve({"method": 2, "alpha": 0.2})
    d_inc = 2.0 * values["eta2"] * values["d"]
    model = model_for(film, values)
    cos_theta = np.linspace(0.1, 1.0, 5)
    np.testing.assert_allclose(model.textured_reflectance(cos_theta, np.full(5, d_inc), 0.0, False), model.reflectance(cos_theta), atol=1e-9)
    texture = ThicknessTexture(np.full((4, 4), d_inc, np.float32))
    textured = render_env(film, values, *SIZE, spp=8, renderer=gl_renderer, surface=texture)
    plain = render_env(film, values, *SIZE, spp=8, renderer=gl_renderer)
    assert np.abs(plain).max() > 0.01
    np.testing.assert_allclose(textured, plain, rtol=1e-3, atol=1e-5)
    varied = render_env(film, values, *SIZE, spp=8, renderer=gl_renderer, surface=ThicknessTexture(np.asarray(stripes() * 1500.0, np.float32)))
    assert np.abs(varied - plain).max() > 0.01


def test_cli_env_texture_options(tmp_path):
    out = tmp_path / "out.png"
    cases = {
        "prefilter under env": (["thin_film", "--view", "env", "--texture", REPO_ROOT / "shaders" / "textures" / "thickness_noise.png",
                                 "--prefilter", "on"], "--prefilter"),
        "texture on a material without one": (["ggx_schlick", "--view", "env", "--mapping", "both"], "# texture:"),
    }
    for name, (args, named) in cases.items():
        line = one_line_error(run_cli("render", *args, "--engine", "numpy", "--size", "8", "--out", out))
        assert named in line, f"{name}: {line}"
        assert not out.exists(), name
