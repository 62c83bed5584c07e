"""The generic BRDF views: ``lit``, ``slice`` and ``scatter``, GLSL against numpy.

Each view calls a material's ``BRDF(L, V, N, X, Y)``: ``shaders/bragg_mirror.brd`` (whose numpy twin is
``explorer.materials.models.BraggMirrorModel.brdf``) and BRDF Explorer-style files of tests/data/brdf, whose twins
live in tests/brdf_twins.py (registered into explorer.materials.models.MODELS by this module only).

Tolerance: tests/twins.py's BRDF_TOLERANCE, 2e-3 relative where a pixel's value (its largest |channel|)
exceeds 1e-3, absolute (2e-3 x 1e-3) below.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import brdf_twins
from conftest import BRAGG_MATERIAL, BRDF_DATA, REPO_ROOT, one_line_error, run_cli, run_cli_process
from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.views.render import render_numpy
from explorer.views.geometry import DEFAULT_LIGHT, SCATTER_CIRCLES, brdf_view_geometry, light_direction, scatter_circles
from twins import Twins, assert_black_outside, assert_twins_equal, render_both

#: Not square, so that a swapped width and height shows.
SIZE = (36, 28)

#: (file, overrides, views): --set values as the CLI passes them (strings), or Python values.
CASES = {
    "bragg basic": (BRAGG_MATERIAL, {"method": "1"}, ("lit", "slice", "scatter")),
    "bragg tabulated": (BRAGG_MATERIAL, {"method": 3, "Lambda": "300"}, ("lit", "slice", "scatter")),
    "bragg reference": (BRAGG_MATERIAL, {"method": 0, "N": "8"}, ("lit", "slice")),
    "lambert": (BRDF_DATA / "lambert.brdf", {}, ("lit", "slice", "scatter")),
    "blinn-phong / N.L": (BRDF_DATA / "blinn_phong.brdf", {}, ("lit", "slice", "scatter")),
    "blinn-phong": (BRDF_DATA / "blinn_phong.brdf", {"divide_by_NdotL": "false", "n": "40"}, ("lit", "slice", "scatter")),
    "colored lambert": (BRDF_DATA / "colored_lambert.brdf", {"albedo": "0.2,0.5,0.9"}, ("lit", "slice", "scatter")),
    "ashikhmin-shirley": (BRDF_DATA / "ashikhmin_shirley.brdf", {}, ("lit", "slice", "scatter")),
}
#: The reference method costs about 1 s per 32x32 on llvmpipe: a smaller image.
SMALL = (20, 16)


@pytest.fixture(scope="module", autouse=True)
def twins():
    """The test materials' numpy twins, registered for this module only."""
    with brdf_twins.registered():
        yield


def materials():
    cache = {}

    def load(path):
        if path not in cache:
            cache[path] = load_material(path)
        return cache[path]

    return load


MATERIAL = materials()


def view_cases():
    for name, (_, _, views) in CASES.items():
        for view in views:
            yield pytest.param(name, view, id=f"{name}-{view}")


@pytest.mark.gl
@pytest.mark.parametrize("case,view", list(view_cases()))
def test_gl_equals_numpy_twin(gl_renderer, case, view):
    path, overrides, _ = CASES[case]
    material = MATERIAL(path)
    twins = render_both(gl_renderer, material, material.resolve(overrides), view, SMALL if case == "bragg reference" else SIZE)
    assert_twins_equal(twins, f"{case}, {view}")
    assert np.abs(twins.reference).max() > 0.05, "an empty image"
    if view != "slice":
        assert_black_outside(twins)


# --------------------------------------------------------------------------------------------------
# The conventions, checked on the geometry itself


def test_light_direction():
    np.testing.assert_allclose(light_direction((0.0, 0.0)), [0, 0, 1], atol=1e-7)
    np.testing.assert_allclose(light_direction((90.0, 90.0)), [0, 1, 0], atol=1e-7)
    np.testing.assert_allclose(light_direction((60.0, 180.0)), [-np.sqrt(3) / 2, 0, 0.5], atol=1e-7)
    np.testing.assert_array_equal(light_direction(None), light_direction(DEFAULT_LIGHT))
    assert light_direction(None).dtype == np.float32
    for bad in ((-1.0, 0.0), (181.0, 0.0), (float("nan"), 0.0), (45.0, float("inf"))):
        with pytest.raises(ValueError):
            light_direction(bad)


def test_slice_geometry_is_brdf_explorers():
    """Rusinkiewicz's (theta_h, theta_d, phi_d = 90 deg) as BRDF Explorer builds L and V from them."""
    width, height = SIZE
    *vectors, inside, factor = brdf_view_geometry("slice", width, height)
    L, V, N, X, Y = (np.asarray(a, np.float64) for a in vectors)
    assert inside.all() and (factor == 1.0).all()
    theta_h = np.radians(90.0 * (np.arange(width) + 0.5) / width)[None, :]
    theta_d = np.radians(90.0 * (np.arange(height) + 0.5) / height)[:, None]
    H = (L + V) / np.linalg.norm(L + V, axis=-1, keepdims=True)
    np.testing.assert_allclose(np.linalg.norm(L, axis=-1), 1.0, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(V, axis=-1), 1.0, atol=1e-6)
    np.testing.assert_allclose(H[..., 2], np.cos(theta_h) + 0 * theta_d, atol=1e-6)  # columns: theta_h
    np.testing.assert_allclose(H[..., 1], 0.0, atol=1e-6)  # phi_h = 0
    np.testing.assert_allclose(np.sum(H * L, axis=-1), np.cos(theta_d) + 0 * theta_h, atol=1e-6)  # rows: theta_d
    # phi_d = 90 deg: L = (sin th cos td, sin td, cos th cos td), V its mirror image about H.
    expected = np.stack(np.broadcast_arrays(np.sin(theta_h) * np.cos(theta_d), np.sin(theta_d),
                                            np.cos(theta_h) * np.cos(theta_d)), axis=-1)
    np.testing.assert_allclose(L, expected, atol=1e-6)
    assert (L[..., 2] > 0).all() and (V[..., 2] > 0).all()  # never below the horizon
    np.testing.assert_array_equal(N, np.broadcast_to([0, 0, 1], N.shape))
    np.testing.assert_array_equal(X, np.broadcast_to([1, 0, 0], X.shape))
    np.testing.assert_array_equal(Y, np.broadcast_to([0, 1, 0], Y.shape))


def test_lit_frame_is_brdf_explorers():
    """X = normalize(cross((0, 1, 0), N)), Y = normalize(cross(N, X)) (brdftemplatesphere.frag), V = +z."""
    width, height = SIZE
    *vectors, inside, factor = brdf_view_geometry("lit", width, height, (30.0, 0.0))
    L, V, N, X, Y = (np.asarray(a, np.float64) for a in vectors)
    N, X, Y = N[inside], X[inside], Y[inside]
    np.testing.assert_allclose(np.linalg.norm(N, axis=-1), 1.0, atol=1e-6)
    np.testing.assert_allclose(np.sum(X * N, axis=-1), 0.0, atol=1e-6)
    np.testing.assert_allclose(X[:, 1], 0.0, atol=1e-7)  # X is horizontal ...
    assert (X[:, 0] > 0).all()  # ... and points right on the visible hemisphere
    np.testing.assert_allclose(Y, np.cross(N, X), atol=1e-6)  # right-handed: X x Y = N
    np.testing.assert_allclose(V[inside], np.broadcast_to([0, 0, 1], N.shape))
    np.testing.assert_allclose(factor[inside], np.maximum(np.sum(N * L[inside], axis=-1), 0.0))
    # Pixel (i, j) is the sphere view's: x to the right, y up (row 0 at the top).
    x = 2.0 * (np.arange(width) + 0.5) / width - 1.0
    y = 1.0 - 2.0 * (np.arange(height) + 0.5) / height
    np.testing.assert_allclose(N[:, 0], np.broadcast_to(x[None, :], (height, width))[inside], atol=1e-6)
    np.testing.assert_allclose(N[:, 1], np.broadcast_to(y[:, None], (height, width))[inside], atol=1e-6)


def test_scatter_geometry():
    """Radius proportional to theta_o (90 deg at the rim), azimuth phi_o; the pixel is f_r cos theta_o."""
    width, height = SIZE
    L, V, N, X, Y, inside, factor = brdf_view_geometry("scatter", width, height, (40.0, 30.0))
    x = 2.0 * (np.arange(width) + 0.5) / width - 1.0
    y = 1.0 - 2.0 * (np.arange(height) + 0.5) / height
    r = np.hypot(x[None, :], y[:, None])
    V = np.asarray(V, np.float64)
    np.testing.assert_allclose(np.degrees(np.arccos(np.clip(V[..., 2], -1, 1)))[inside], 90.0 * r[inside], atol=2e-3)
    phi = np.arctan2(V[..., 1], V[..., 0])
    np.testing.assert_allclose(np.cos(phi - np.arctan2(y[:, None], x[None, :]))[inside], 1.0, atol=1e-6)
    np.testing.assert_allclose(factor[inside], V[..., 2][inside])
    np.testing.assert_allclose(L[0, 0], light_direction((40.0, 30.0)))


@pytest.mark.gl
@pytest.mark.parametrize("light,where", [((30.0, 0.0), "right"), ((30.0, 90.0), "up"), ((60.0, 180.0), "left")])
def test_lit_lambert_is_brightest_facing_the_light(gl_renderer, light, where):
    """On the GPU: a Lambertian sphere is brightest where N = L, at (sin t cos p, sin t sin p)."""
    material = MATERIAL(BRDF_DATA / "lambert.brdf")
    size = 65
    image = gl_renderer.render(material, material.resolve(), "lit", size, size, light=light)
    j, i = np.unravel_index(image[..., 0].argmax(), image.shape[:2])
    x, y = 2.0 * (i + 0.5) / size - 1.0, 1.0 - 2.0 * (j + 0.5) / size
    theta, phi = np.radians(light)
    assert np.hypot(x - np.sin(theta) * np.cos(phi), y - np.sin(theta) * np.sin(phi)) < 0.05, where
    assert image.max() == pytest.approx(0.8 / np.pi, rel=2e-3)


@pytest.mark.gl
def test_bragg_slice_rows_are_the_reflectance_at_theta_d(gl_renderer, bragg_material):
    """The mirror's BRDF is its reflectance at H.L = cos theta_d: each slice row is one angle's colour."""
    values = bragg_material.resolve({"method": 3})
    width, height = SIZE
    image = gl_renderer.render(bragg_material, values, "slice", width, height)
    theta_d = np.radians(90.0 * (np.arange(height) + 0.5) / height)
    expected = model_for(bragg_material, values).reflectance(np.cos(theta_d))
    np.testing.assert_allclose(image, np.broadcast_to(expected[:, None, :], image.shape), atol=2e-4)


def test_numpy_twins_need_brdf():
    class NoBRDF:
        pass

    with pytest.raises(ValueError, match="brdf"):
        render_numpy(NoBRDF(), "lit", 4, 4)


# --------------------------------------------------------------------------------------------------
# The command line


def relative(path: Path) -> str:
    return str(path.relative_to(REPO_ROOT))


BAD_LIGHTS = {
    "not numbers": ("lit", "up,left"),
    "one number": ("lit", "45"),
    "three numbers": ("scatter", "45,0,0"),
    "theta above 180": ("lit", "181,0"),
    "negative theta": ("lit", "-5,0"),
    "nan": ("lit", "nan,0"),
    "scatter below the horizon": ("scatter", "100,0"),
    "a view without light": ("sphere", "45,0"),
}


@pytest.mark.parametrize("case", list(BAD_LIGHTS))
def test_malformed_light_is_one_line(tmp_path, case):
    view, light = BAD_LIGHTS[case]
    run = run_cli("render", relative(BRDF_DATA / "lambert.brdf"), "--view", view, "--light", light,
                  "--size", "8", "--out", tmp_path / "x.png")
    assert "--light" in one_line_error(run)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.gl
def test_cli_lit_npy_equals_numpy_twin(gl_renderer, tmp_path):
    """A BRDF Explorer file with a bool, lit from --light 30,0 and the default environment fill, on the GPU through the CLI."""
    from explorer.views.fill import DEFAULT_FILL

    path = BRDF_DATA / "blinn_phong.brdf"
    out = tmp_path / "lit.npy"
    width, height = 40, 24
    run = run_cli_process("render", relative(path), "--view", "lit", "--light", "30,0", "--set", "divide_by_NdotL=0",
              "--size", f"{width}x{height}", "--out", out)
    assert run.returncode == 0, run.stderr
    assert "lit" in run.stdout
    image = np.load(out)
    material = MATERIAL(path)
    values = material.resolve({"divide_by_NdotL": "0"})
    # render's lit view fills with a uniform environment by default (explorer.views.fill)
    reference = render_numpy(model_for(material, values), "lit", width, height, light=(30.0, 0.0), fill=DEFAULT_FILL)
    assert_twins_equal(Twins.of(image, reference, "lit"), "CLI lit")


@pytest.mark.gl
def test_cli_scatter_circles_only_in_png(gl_renderer, tmp_path):
    from PIL import Image

    from explorer.physics.colorimetry import encode_srgb8

    path = BRDF_DATA / "colored_lambert.brdf"
    size = 96
    outputs = {suffix: tmp_path / f"scatter.{suffix}" for suffix in ("png", "npy")}
    for out in outputs.values():
        run = run_cli_process("render", relative(path), "--view", "scatter", "--set", "albedo=0.9,0.9,0.9", "--size", size, "--out", out)
        assert run.returncode == 0, run.stderr
    image = np.load(outputs["npy"])
    material = MATERIAL(path)
    values = material.resolve({"albedo": "0.9,0.9,0.9"})
    reference = render_numpy(model_for(material, values), "scatter", size, size)  # no circles in the twin either
    assert_twins_equal(Twins.of(image, reference, "scatter"), "CLI scatter")
    circles = scatter_circles(size, size)
    assert not (np.abs(image[circles] - reference[circles]) > 1e-3).any()  # the .npy has no circles
    with Image.open(outputs["png"]) as picture:
        pixels = np.asarray(picture)
    np.testing.assert_array_equal(pixels[circles], np.broadcast_to([255, 0, 0], pixels[circles].shape))
    np.testing.assert_array_equal(pixels[~circles], encode_srgb8(image)[~circles])
    # Four circles, at theta_o = 90 deg x radius = 5, 30, 60 and 90 deg, within half a pixel (90 / size deg).
    x = 2.0 * (np.arange(size) + 0.5) / size - 1.0
    angle = 90.0 * np.hypot(x[None, :], x[::-1, None])
    distance = np.abs(angle[..., None] - np.asarray(SCATTER_CIRCLES))
    assert (distance[circles].min(axis=-1) < 90.0 / size).all()
    for k, degrees in enumerate(SCATTER_CIRCLES):
        on_circle = circles & (distance[..., k] < 90.0 / size)
        assert on_circle.sum() >= 0.5 * np.pi * degrees / 90.0 * size, degrees  # half its circumference in pixels


def test_cli_numpy_engine_slice(tmp_path):
    """``--engine numpy`` renders the BRDF views of a material whose twin has brdf() (no GPU)."""
    out = tmp_path / "slice.npy"
    run = run_cli("render", relative(BRAGG_MATERIAL), "--view", "slice", "--engine", "numpy", "--set", "method=3",
              "--size", "16x12", "--out", out)
    assert run.returncode == 0, run.stderr
    values = load_material(BRAGG_MATERIAL).resolve({"method": "3"})
    np.testing.assert_array_equal(np.load(out), render_numpy(model_for(MATERIAL(BRAGG_MATERIAL), values), "slice", 16, 12))
