"""Materials out of their domain: every view that evaluates a BRDF follows one rule, in GLSL and numpy.

The rule (``view_brdf`` in shaders/lib/views.glsl, :func:`explorer.views.geometry.view_brdf`): the BRDF is
evaluated only where N.L > 0 and N.V > 0 (0 elsewhere), and a NaN or infinite channel counts as 0; a
finite negative channel is kept. Five of BRDF Explorer's own 40 files (Minnaert's, Ward's, Edwards',
Kurt's and Ward's G) returned NaN in the lit view: the failure patterns of those files are reproduced by
our own files in tests/data/brdf (limb_darkening, anisotropic_ward, compact_lobe, azimuth_ratio,
lommel_seeliger, non_finite_channels; twins in tests/brdf_twins.py). Every material of tests/data/brdf
(but the bad_* files) and every shipped shaders/*.brd is rendered in lit, slice and scatter, lights
included that leave most of the sphere dark, below the horizon or straight above (the H = N pixel),
with no NaN or infinity, and equal to its numpy twin with the BRDF views' tolerance (tests/twins.py).
"""

from __future__ import annotations

import numpy as np
import pytest

import brdf_twins
from conftest import BRDF_DATA, REPO_ROOT
from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.views.geometry import brdf_view_geometry, finite_or_zero, view_brdf
from explorer.views.mirror import is_mirror_only
from twins import assert_twins_equal, compared_pixels, render_both

#: Odd sides: the disc views have a centre pixel (x = y = 0), where H = N under a light straight above.
SIZE = (35, 27)
#: The spectral layered stack costs ~0.2 s a pixel in numpy: a smaller image.
SMALL = (15, 11)
#: (view, light): the lit view under a light from the side (most of the sphere dark), behind (the lit
#: side a crescent) and straight above; the scatter view with the light above, oblique and below the
#: horizon (every direction pair then out of the domain: 0 everywhere).
VIEW_LIGHTS = (
    ("lit", (115.0, 30.0)), ("lit", (160.0, 250.0)), ("lit", (0.0, 0.0)),
    ("slice", None),
    ("scatter", (0.0, 0.0)), ("scatter", (50.0, 200.0)), ("scatter", (100.0, 0.0)),
)
#: The files that exist to break a view, and where they do (without the rule): the view, its light,
#: and what the raw BRDF returns there ("non-finite" or "negative").
PATTERNS = {
    "limb_darkening.brdf": ("lit", (115.0, 30.0), "non-finite"),  # pow(N.L N.V, k - 1), N.L < 0
    "anisotropic_ward.brdf": ("lit", (115.0, 30.0), "non-finite"),  # sqrt(N.L N.V), N.L < 0
    "compact_lobe.brdf": ("slice", None, "non-finite"),  # pow(1 - t^2, n) on the lit side
    "azimuth_ratio.brdf": ("lit", (0.0, 0.0), "non-finite"),  # 0 / 0 at H = N
    "lommel_seeliger.brdf": ("scatter", (100.0, 0.0), "negative"),  # 1 / (N.L + N.V) below the horizon
    "non_finite_channels.brdf": ("slice", None, "non-finite"),
}


def material_paths():
    files = sorted(p for p in BRDF_DATA.glob("*.brdf") if not p.name.startswith("bad_"))
    return files + sorted((REPO_ROOT / "shaders").glob("*.brd"))


PATHS = material_paths()


@pytest.fixture(scope="module", autouse=True)
def twins():
    with brdf_twins.registered():
        yield


_MATERIALS = {}


def material(path):
    if path not in _MATERIALS:
        _MATERIALS[path] = load_material(path)
    return _MATERIALS[path]


def test_every_material_has_a_twin():
    """So that every file below is compared with numpy, not only checked for NaN."""
    assert {p.name for p in PATHS} >= {name for name in PATTERNS} | {"bragg_stack.brd", "thin_film.brd"}
    with brdf_twins.registered():
        for path in PATHS:
            m = material(path)
            assert model_for(m, m.resolve()) is not None, path.name


@pytest.mark.gl
@pytest.mark.parametrize("path", PATHS, ids=[p.name for p in PATHS])
def test_views_are_finite_and_equal_their_twins(gl_renderer, path):
    m = material(path)
    values = m.resolve()
    width, height = SMALL if path.name == "bragg_stack.brd" else SIZE
    for view, light in VIEW_LIGHTS:
        what = f"{path.name}, {view}, light {light}"
        gl, reference, _ = twins = render_both(gl_renderer, m, values, view, (width, height), light=light)
        assert np.isfinite(gl).all(), f"{what}: GLSL non-finite at {np.argwhere(~np.isfinite(gl))[:3].tolist()}"
        assert np.isfinite(reference).all(), f"{what}: numpy non-finite"
        assert_twins_equal(twins, what)
        if light is not None and light[0] > 90.0 and view == "scatter":  # no pair in the domain
            assert (gl == 0.0).all() and (reference == 0.0).all(), what
        if view == "lit" and not is_mirror_only(m):  # nothing where the light is below the surface (a mirror reflects the sky)
            L, _, N, *_ = brdf_view_geometry("lit", width, height, light)
            dark = np.sum(N.astype(np.float64) * L, axis=-1) < -1e-6
            assert (gl[dark] == 0.0).all() and (reference[dark] == 0.0).all(), what


@pytest.mark.parametrize("name", list(PATTERNS))
def test_each_pattern_breaks_its_view_without_the_rule(name):
    """The raw twin (GLSL's arithmetic) is NaN, infinite or negative in its view: the rule is what removes it."""
    view, light, kind = PATTERNS[name]
    m = material(BRDF_DATA / name)
    model = model_for(m, m.resolve())
    L, V, N, X, Y, inside, _ = brdf_view_geometry(view, *SIZE, light)
    with np.errstate(all="ignore"):
        raw = model.brdf(*(a[inside].astype(np.float64) for a in (L, V, N, X, Y)))
    if kind == "non-finite":
        assert (~np.isfinite(raw)).any()
    else:
        assert (raw < 0.0).any() and np.isfinite(raw).all()
    ruled = view_brdf(model.brdf, *(a[inside] for a in (L, V, N, X, Y)))
    assert np.isfinite(ruled).all()


def test_view_brdf_rule():
    """Below the horizon (L or V) 0 and not evaluated; per channel NaN and +-inf are 0, negatives kept."""
    N = np.array([[0, 0, 1]] * 4, np.float32)
    L = np.array([[0, 0.6, 0.8], [0, 0.6, -0.8], [0, 0.6, 0.8], [0.6, 0, 0.8]], np.float32)
    V = np.array([[0, 0, 1], [0, 0, 1], [0.6, 0, -0.8], [0, 0, 1]], np.float32)
    seen = []

    def brdf(L, V, N, X, Y):
        seen.append(len(L))
        return np.tile([np.nan, -np.inf, -0.5], (len(L), 1))

    result = view_brdf(brdf, L, V, N, N, N)
    assert seen == [2]  # only the two pairs above the surface
    np.testing.assert_array_equal(result, [[0, 0, -0.5], [0, 0, 0], [0, 0, 0], [0, 0, -0.5]])
    np.testing.assert_array_equal(finite_or_zero([np.inf, -np.inf, np.nan, -2.0, 3.0]), [0, 0, 0, -2.0, 3.0])


@pytest.mark.gl
def test_non_finite_channels_keep_the_finite_one(gl_renderer):
    """Per channel in GL: red (NaN) and green (infinite) are 0, blue (negative) is the BRDF times the cosine."""
    m = material(BRDF_DATA / "non_finite_channels.brdf")
    width, height = SIZE
    for view, light in (("lit", (30.0, 0.0)), ("slice", None), ("scatter", (30.0, 0.0))):
        gl = gl_renderer.render(m, m.resolve(), view, width, height, light=light)
        *_, inside, factor = brdf_view_geometry(view, width, height, light)
        assert (gl[..., :2] == 0.0).all(), view
        shown = inside & compared_pixels(view, width, height) & (factor > 1e-3)
        np.testing.assert_allclose(gl[..., 2][shown], -0.25 * factor[shown], rtol=1e-5, err_msg=view)


@pytest.mark.gl
def test_textured_view_follows_the_rule(gl_renderer):
    """The thin film's textured view under a light that leaves most of the sphere dark: finite, equal to numpy."""
    from explorer.views.thickness import ThicknessTexture

    m = material(REPO_ROOT / "shaders" / "thin_film.brd")
    values = m.resolve({"method": 3})
    thickness = ThicknessTexture.from_file(dinc_range=(0.0, 1125.0))
    width, height = SIZE
    light = (115.0, 30.0)
    twins = render_both(gl_renderer, m, values, "textured", (width, height), light=light, thickness=thickness)
    assert np.isfinite(twins.gl).all() and np.abs(twins.reference).max() > 0.01
    assert_twins_equal(twins, "textured")


#: The env view: a few samples per pixel of every material, to find NaN rather than to converge.
ENV_SIZE, ENV_SPP = 12, 4


@pytest.mark.gl
@pytest.mark.parametrize("path", PATHS, ids=[p.name for p in PATHS])
def test_env_view_is_finite(gl_renderer, path):
    from explorer.views.env import EnvironmentMap
    from explorer.gpu.env import ProgressiveEnvRender

    m = material(path)
    render = ProgressiveEnvRender(gl_renderer, m, m.resolve(), EnvironmentMap.default(), ENV_SIZE, ENV_SIZE, seed=3)
    try:
        render.step(ENV_SPP)
        image = render.image()
        dropped = render.dropped_samples()
    finally:
        render.release()
    assert np.isfinite(image).all()
    inside = brdf_view_geometry("lit", ENV_SIZE, ENV_SIZE)[5]
    assert (image[~inside] == 0.0).all()
    if path.name in ("compact_lobe.brdf", "non_finite_channels.brdf"):  # non-finite on the lit side: counted
        assert dropped > 0
    elif path.name not in ("azimuth_ratio.brdf",):  # (its H = N direction is never sampled exactly)
        assert dropped == 0


@pytest.mark.gl
def test_env_converges_to_the_ruled_integral(gl_renderer):
    """
    compact_lobe (NaN wherever theta_h > atan(m), on the lit side) under the smooth test sky: the Monte
    Carlo mean converges to the numpy integral of the BRDF under the same rule (test_env's criteria).
    """
    from explorer.views.env import env_integral_numpy
    from explorer.gpu.env import ProgressiveEnvRender
    from test_env import CONVERGENCE_SIZE, CONVERGENCE_SPP, MAX_Z, QUADRATURE_RTOL, WITHIN_3SE, smooth_environment

    environment = smooth_environment()
    m = material(BRDF_DATA / "compact_lobe.brdf")
    values = m.resolve()
    size = CONVERGENCE_SIZE
    render = ProgressiveEnvRender(gl_renderer, m, values, environment, size, size, seed=5)
    try:
        render.step(CONVERGENCE_SPP)
        mean, se = render.image().astype(np.float64), render.standard_error().astype(np.float64)
        assert render.dropped_samples() > 0
    finally:
        render.release()
    exact = env_integral_numpy(model_for(m, values), environment, size, size).astype(np.float64)
    inside = brdf_view_geometry("lit", size, size)[5]
    within = (np.abs(mean - exact) <= 3.0 * se + QUADRATURE_RTOL * np.abs(exact))[inside]
    z = ((mean - exact) / np.maximum(se, 1e-30))[inside]
    assert np.isfinite(exact).all() and exact[inside].max() > 0.05
    assert within.mean() >= WITHIN_3SE and np.abs(z).max() <= MAX_Z, f"{within.mean():.4f}, max |z| {np.abs(z).max():.2f}"
