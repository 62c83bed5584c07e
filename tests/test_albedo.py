"""``bragg-explorer albedo`` and :mod:`explorer.views.albedo`: the directional albedo of every engine.

Independent references: closed forms (a Lambertian's albedo is its reflectance; Eq. 34 of an invisible
layer under a coating over a Lambertian base integrates to ``F + (1 - F) rho (1 - Fbar_int)``, with
Fresnel and ``Fbar`` written out in tests/test_position_free.py), and the position-free Monte Carlo
reference where single reflection is exact (one layer in air over a black base), within 3 standard
errors plus the quadrature's tolerance.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import BRDF_DATA, one_line_error, run_cli, run_cli_process
from test_position_free import fresnel_unpolarised, internal_diffuse_reflectance

from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.resources import material_path
from explorer.views import albedo

#: The numpy quadrature and the gl engine's scatter sum on smooth-ish lobes (alpha >= 0.025).
QUADRATURE_ATOL = 1e-3
THETA = [0.0, 30.0, 60.0, 85.0]


def _stack(values: dict):
    material = load_material(material_path("bragg_stack"))
    resolved = material.resolve(values)
    return material, resolved, model_for(material, resolved)


@pytest.mark.parametrize("alpha", [0.025, 0.4])
def test_numpy_quadrature_against_position_free(alpha):
    # One layer in air over a black base reflects exactly once: Eq. 34 (without multiple scattering among the
    # facets, as the reference's microsurface="single") is the whole answer.
    _, _, model = _stack({"layers": 1, "nh": 1, "rho_d": "0", "alpha_1": alpha, "N_1": 20, "Lambda_1": 500, "delta_1": 0.25,
                          "multiple_scattering": 0})
    theta = [0.0, 45.0, 85.0]
    quadrature = albedo.albedo_numpy(model, theta)
    reference = albedo.albedo_position_free(model, theta, samples=2048, seed=3)
    assert np.all(np.abs(quadrature - reference.value) <= 3.0 * reference.stderr + QUADRATURE_ATOL)


def test_single_reflection_under_coating_closed_form():
    nh, rho = 1.6, np.array([0.9, 0.5, 0.1])
    _, _, model = _stack({"layers": 1, "nh": nh, "n1_1": nh, "n2_1": nh, "alpha_1": 0.0, "rho_d": ",".join(map(str, rho))})
    theta = [0.0, 60.0, 85.0]
    result = albedo.albedo_numpy(model, theta)
    F = fresnel_unpolarised(np.cos(np.radians(theta)), 1.0, nh)[:, None]
    # Eq. 34's base term (1 - F_i)(1 - F_o) rho / (pi nh^2) integrates over o to (1 - F_i) rho (1 - Fbar_int),
    # since 1 - Fbar_ext = nh^2 (1 - Fbar_int); plus the coating's Dirac F.
    expected = F + (1.0 - F) * rho * (1.0 - internal_diffuse_reflectance(nh))
    np.testing.assert_allclose(result, expected, atol=QUADRATURE_ATOL)


def test_smooth_mirror_is_its_reflectance():
    material = load_material(material_path("bragg_mirror"))
    model = model_for(material, material.resolve({}))
    np.testing.assert_array_equal(albedo.albedo_numpy(model, THETA), model.reflectance(np.cos(np.radians(THETA))))


def test_quadrature_weights_integrate_the_hemisphere():
    # Integrands that vanish at the horizon (BRDF x cos) converge; a constant would see the cut-off cells.
    for theta in np.radians(THETA + [89.0]):
        o, w = albedo.half_vector_quadrature(theta)
        assert abs((w * o[:, 2]).sum() - np.pi) < 5e-4 and abs((w * o[:, 2] ** 2).sum() - 2.0 * np.pi / 3.0) < 5e-4
    x = 2.0 * (np.arange(512) + 0.5) / 512 - 1.0
    cos_o = np.cos(0.5 * np.pi * np.minimum(np.hypot(x[None, :], x[:, None]), 1.0))
    assert abs((albedo.scatter_solid_angles(512, 512) * cos_o).sum() - np.pi) < 5e-4


@pytest.mark.gl
@pytest.mark.parametrize("name, expected", [("lambert.brdf", (0.8, 0.8, 0.8)), ("colored_lambert.brdf", (0.82, 0.67, 0.16))])
def test_gl_lambertian_brdf_files(gl_renderer, name, expected):
    material = load_material(BRDF_DATA / name)
    result = albedo.albedo_gl(material, material.resolve({}), THETA, renderer=gl_renderer)
    np.testing.assert_allclose(result, np.broadcast_to(expected, result.shape), atol=QUADRATURE_ATOL)


@pytest.mark.gl
@pytest.mark.parametrize("name, values", [
    ("ggx_schlick", {"alpha": 0.05}),
    ("thin_film", {}),
    ("bragg_stack", {"layers": 2, "nh": 1.4, "rho_d": "0.3,0.5,0.2", "alpha_1": 0.1, "alpha_2": 0.2}),
])
def test_gl_matches_numpy(gl_renderer, name, values):
    material = load_material(material_path(name))
    resolved = material.resolve(values)
    model = model_for(material, resolved)
    theta = [70.0] if name == "bragg_stack" else [20.0, 70.0]
    gl = albedo.albedo_gl(material, resolved, theta, size=albedo.gl_size_for(model), renderer=gl_renderer, model=model)
    np.testing.assert_allclose(gl, albedo.albedo_numpy(model, theta), atol=QUADRATURE_ATOL)


def test_cli_json_and_errors():
    run = run_cli("albedo", "bragg_stack", "--preset", "figure7_A_on_base", "--theta", "0,45", "--json")
    assert run.returncode == 0, run.stderr
    document = json.loads(run.stdout)
    assert document["theta_deg"] == [0.0, 45.0] and np.shape(document["rgb"]) == (2, 3) and "stderr" not in document
    run = run_cli("albedo", "bragg_stack", "--set", "alpha_1=0.3", "--theta", "30", "--engine", "position-free",
                  "--samples", "64", "--json")
    assert run.returncode == 0, run.stderr
    document = json.loads(run.stdout)
    assert np.shape(document["rgb"]) == (1, 3) and np.shape(document["stderr"]) == (1, 3)
    for args in (("--theta", "90"), ("--theta", "x"), ("--samples", "10"), ("--engine", "position-free", "--samples", "0"),
                 ("--set", "alpha_1=2"), ("--preset", "nonexistent"),
                 ("--engine", "position-free", "--seed", "-1")):
        one_line_error(run_cli("albedo", "bragg_stack", *args))
    one_line_error(run_cli("albedo", "ggx_schlick", "--engine", "position-free"))
    one_line_error(run_cli("albedo", str(BRDF_DATA / "lambert.brdf"), "--engine", "numpy"))
    one_line_error(run_cli("render", "bragg_stack", "--engine", "position-free", "--view", "sphere", "--out", "x.png"))


def test_render_position_free_lit(tmp_path):
    out = tmp_path / "lit.npy"
    run = run_cli("render", "bragg_stack", "--engine", "position-free", "--view", "lit", "--size", "12", "--spp", "8", "--out", str(out))
    assert run.returncode == 0, run.stderr
    image = np.load(out)
    assert image.shape == (12, 12, 3) and np.isfinite(image).all() and image.max() > 0.0


# -- the albedo view against the albedo command ---------------------------------------------------------

#: The view and the command agree on each incidence angle's luminance within this (relative).
VIEW_COMMAND_RTOL = 0.01


def _luminance(rgb) -> np.ndarray:
    from explorer.physics.colorimetry import rgb_to_xyz

    return rgb_to_xyz(np.asarray(rgb, dtype=np.float64))[..., 1]


def _view_command_cases():
    """Every built-in material at its default, and at method 0 where it has methods."""
    from explorer.resources import builtin_materials

    cases = []
    for name, path in sorted(builtin_materials().items()):
        cases.append((name, ()))
        if any(p.name == "method" for p in load_material(path).parameters):
            cases.append((name, ("--set", "method=0")))
    return cases


@pytest.mark.gl
@pytest.mark.parametrize("name, args", _view_command_cases())
def test_albedo_view_equals_the_albedo_command(gl_renderer, name, args):
    """The albedo view (GL and its numpy twin) at one column (theta_i = 45 deg) equals ``albedo --theta 45``
    within 1 % luminance. A fragment that summed a whole hemisphere of a spectral BRDF outran llvmpipe's loop
    limit and showed ~1e-7."""
    from explorer.cli.materials import resolve_values
    from explorer.views.render import render_numpy

    run = run_cli("albedo", name, "--theta", "45", "--json", *args)
    assert run.returncode == 0, run.stderr
    command = np.asarray(json.loads(run.stdout)["rgb"][0])
    material = load_material(material_path(name))
    values = resolve_values(material, None, None, args[1:])  # as the command resolves them
    gl = gl_renderer.render(material, values, "albedo", 1, 1)[0, 0]
    twin = render_numpy(model_for(material, values), "albedo", 1, 1)[0, 0]
    assert _luminance(command) > 1e-3, command
    for engine, rgb in (("gl", gl), ("numpy", twin)):
        assert abs(_luminance(rgb) - _luminance(command)) <= VIEW_COMMAND_RTOL * _luminance(command), (engine, rgb, command)
        np.testing.assert_allclose(rgb, command, atol=2e-3, err_msg=engine)


@pytest.mark.gl
def test_render_albedo_view_of_a_spectral_layer_is_the_albedo(tmp_path):
    """``render bragg_layer --view albedo`` (GL) at a method with loops (the basic approximation's boxes, as the
    reference's wavelengths) equals the ``albedo`` command."""
    out = tmp_path / "albedo.npy"
    run = run_cli_process("render", "bragg_layer", "--view", "albedo", "--set", "method=1", "--size", "2", "--out", out)
    assert run.returncode == 0, run.stderr
    curve = np.load(out)
    np.testing.assert_allclose(curve[:, 0], [22.5, 67.5])
    command = run_cli("albedo", "bragg_layer", "--set", "method=1", "--theta", "22.5,67.5", "--json")
    rgb = np.asarray(json.loads(command.stdout)["rgb"])
    np.testing.assert_allclose(_luminance(curve[:, 1:]), _luminance(rgb), rtol=VIEW_COMMAND_RTOL)
    assert _luminance(rgb).min() > 0.05  # not the 1e-7 of a truncated sum
