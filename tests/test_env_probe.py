"""
The env view's probe: its rotation about the vertical and the environment drawn behind the object, in
numpy (against texel shifts) and on the GPU (against the numpy twin).
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli

from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.views.env import EnvironmentMap, backdrop, env_integral_numpy, uv_to_direction

GGX = REPO_ROOT / "shaders" / "ggx_schlick.brd"
#: Background pixels: the GPU's float32 direction and bilinear lookup against float64 (relative).
BACKDROP_RTOL = 2e-3


def random_environment(width=32, height=16) -> EnvironmentMap:
    return EnvironmentMap(np.random.default_rng(3).uniform(0.1, 2.0, (height, width, 3)).astype(np.float32), "<random>")


def test_a_turn_of_one_texel_is_the_texels_shifted():
    environment = random_environment()
    shifted = EnvironmentMap(np.roll(environment.pixels, 1, axis=1), "<shifted>")
    rotated = environment.rotated(360.0 / environment.width)
    d = uv_to_direction(*np.random.default_rng(4).uniform(0.02, 0.98, (2, 500)))
    np.testing.assert_allclose(rotated.radiance(d), shifted.radiance(d), rtol=1e-12)
    np.testing.assert_allclose(environment.rotated(360.0).radiance(d), environment.radiance(d), rtol=1e-12)
    assert not np.allclose(environment.rotated(90.0).radiance(d), environment.radiance(d))


def test_quadrature_follows_the_turn():
    """The quadrature's cells carry the turned radiance: the rotated map's integral against a direction-dependent weight moves."""
    environment = random_environment()
    for degrees in (0.0, 33.0):
        rotated = environment.rotated(degrees)
        directions, solid_angle, radiance = rotated.quadrature(2)
        np.testing.assert_allclose(radiance, rotated.radiance(directions), rtol=1e-9)
        assert solid_angle.sum() == pytest.approx(4 * np.pi)


def test_backdrop_looks_along_minus_z():
    environment = random_environment()
    image = backdrop(environment, 9, 9)
    np.testing.assert_allclose(image[4, 4], environment.radiance(np.array([0.0, 0.0, -1.0])))
    assert image.shape == (9, 9, 3)


def test_cli_probe_options_are_for_the_env_view(tmp_path):
    out = tmp_path / "x.png"
    for option in (["--background"], ["--env-rotation", "30"]):
        assert "--view" in one_line_error(run_cli("render", GGX, "--view", "lit", *option, "--out", out))


@pytest.mark.gl
def test_gl_rotation_and_background_equal_numpy(gl_renderer):
    from test_env import HANDFUL, HANDFUL_MAX_Z, STACK_SIZE, progressive_mean, smooth_environment

    material = load_material(GGX)
    values = material.resolve({"alpha": 0.3, "F0": 0.8})
    environment = smooth_environment().rotated(57.0)
    size = STACK_SIZE
    mean, se = progressive_mean(gl_renderer, material, values, environment, size, 1024, background=True)
    exact = env_integral_numpy(model_for(material, values), environment, size, size, background=True).astype(np.float64)
    rows, columns = np.asarray(HANDFUL).T
    z = (mean[rows, columns] - exact[rows, columns]) / np.maximum(se[rows, columns], 1e-30)
    assert np.abs(z).max() <= HANDFUL_MAX_Z, f"z = {z.round(2).tolist()}"
    # Off the sphere: the backdrop, exactly (no variance), the turned environment's.
    from explorer.views.geometry import brdf_view_geometry

    outside = ~brdf_view_geometry("lit", size, size)[5]
    np.testing.assert_allclose(mean[outside], backdrop(environment, size, size)[outside], rtol=BACKDROP_RTOL)
    np.testing.assert_allclose(exact[outside], backdrop(environment, size, size)[outside], rtol=1e-6)
    assert not np.allclose(backdrop(environment, size, size), backdrop(smooth_environment(), size, size), rtol=1e-2)


def test_named_environments(tmp_path):
    from explorer.views.env import ENVIRONMENTS, EnvironmentFileError, environment_named

    assert set(ENVIRONMENTS) == {"sky", "studio", "white furnace"}
    furnace = environment_named("white furnace")
    np.testing.assert_array_equal(furnace.radiance(np.array([[0.0, 1.0, 0.0], [0.6, 0.0, -0.8]])), 1.0)
    studio = environment_named("studio")
    assert studio.pixels.max() == pytest.approx(6.0) and studio.pixels.min() == pytest.approx(0.05)
    with pytest.raises(EnvironmentFileError):
        environment_named("no such environment")
    out = tmp_path / "furnace.npy"
    run = run_cli("render", GGX, "--view", "env", "--env", "white furnace", "--engine", "numpy", "--size", "4", "--out", out)
    assert run.returncode == 0, run.stderr
    image = np.load(out)
    assert 0.0 < image.max() <= 1.0  # a passive material's directional albedo under radiance 1
