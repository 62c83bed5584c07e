"""Energy: no material reflects more light than it receives, in GL and in numpy.

A passive reflector keeps the luminance ``Y = 0.2126 R + 0.7152 G + 0.0722 B`` of its linear RGB at or
under 1, the white reflector's (``R(lambda) = 1`` gives (1, 1, 1) in this project's convention). A single
channel may exceed 1 without any violation (a red band-pass mirror has linear R ~ 1.25 with
``R(lambda) <= 1`` everywhere), so these tests bound the spectrum, or Y, never the channels one by one.

- the configurations that created light before the fix (a rough stack's smooth-limit colour seen
  through the rough layers' integrated transmissivity, up to Y = 1.15; a thin film's truncated Fourier
  series near total internal reflection, up to 1.06; a conductor base of index 1e10 that overflowed
  float32), as regression rows;
- property sweeps (hypothesis) over every shipped material's declared parameter box and every method:
  the specular colour views (``gradient``, over theta from 0 to 90 degrees) finite, Y <= 1 +
  :data:`Y_TOLERANCE`, GL equal to numpy with the colour views' tolerance (tests/twins.py);
- the spectra of the spectral methods: Yeh's Bragg reflectance and the Airy reflectance in [0, 1] at
  every wavelength, for any parameters of the box.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from conftest import REPO_ROOT
from explorer.materials import media
from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.materials.models import model_for
from explorer.physics import bragg, colorimetry, thinfilm
from explorer.views.render import render_numpy
from twins import assert_twins_equal, render_both

#: Y may exceed 1 by this much: float32 sums over 471 wavelengths and the tables' linear interpolation
#: (the largest seen over the sweeps: 2e-4, a flat white of 1 + 2e-7 per channel in float32).
Y_TOLERANCE = 1e-3
#: R(lambda) may exceed 1 by this much in float64 (Yeh's closed form: 1 - T with T ~ 1e-16).
SPECTRUM_TOLERANCE = 1e-9
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
#: The gradient view's size in the sweeps: 64 angles from 0 to 90 degrees.
SWEEP_SIZE = (64, 1)

#: Colour parameters declare no range in BRDF Explorer's format: their physical domain here.
COLOUR_BOXES = {
    "rho_d": (0.0, 1.0),
    "tau_1": (0.0, 4.0), "tau_2": (0.0, 4.0), "tau_3": (0.0, 4.0),
    "eta_base": (0.05, 5.0),
    "kappa_base": (0.0, 10.0),
}


def luminance(rgb) -> np.ndarray:
    return np.asarray(rgb, dtype=np.float64)[..., :3] @ LUMINANCE


def material(name: str):
    return load_material(REPO_ROOT / "shaders" / f"{name}.brd")


MATERIALS = sorted(p.stem for p in (REPO_ROOT / "shaders").glob("*.brd"))


def _value(p, draw):
    if p.type == "bool":
        return draw(st.booleans())
    if p.type == "color":
        lo, hi = (p.min, p.max) if p.min is not None and p.max is not None else COLOUR_BOXES[p.name]
        return tuple(draw(st.floats(lo, hi, allow_nan=False)) for _ in range(3))
    if p.type == "int":
        # The corners (1 cell, 1000 cells) are drawn as often as the rest.
        return float(draw(st.one_of(st.sampled_from([p.min, p.max]), st.integers(int(p.min), int(p.max)))))
    return draw(st.one_of(st.sampled_from([p.min, p.max]), st.floats(p.min, p.max, allow_nan=False)))


@st.composite
def parameter_sets(draw, name: str):
    """A point of the material's declared box: every parameter drawn, the corners among them."""
    mat = material(name)
    values = {p.name: _value(p, draw) for p in mat.parameters}
    # An absorbing host is refused at resolve (one line in the CLI), so it is no point of the box.
    assume("medium_nh" not in values or media.host_problem(values) is None)
    return mat, values


def _cheap(name: str, values: dict) -> dict:
    """Keep a sweep example within a second: the tabulated method's converged table at N = 1000 costs
    3 s, and method 0 at 0.01 nm 100 times its 1-nm sum; both bounds hold at the other points."""
    values = dict(values)
    if name in ("bragg_mirror", "bragg_layer") and values.get("method") == 3:
        values["N"] = min(values["N"], 100.0)
    if values.get("sigma", 0.0) > 0.0:  # a disordered mirror's table: realisations x layers (explorer.physics.natural)
        # A rough layer's tables take its spectra at every angle (seconds per cell, as a stack's layer below):
        # two cells; the mirror's colour table, ten.
        values["N"] = min(values["N"], 2.0 if name == "bragg_layer" else 10.0)
    if "wavelength_step" in values:
        values["wavelength_step"] = max(values["wavelength_step"], 0.25)
    if name == "bragg_stack":
        for layer in (1, 2, 3):
            values[f"N_{layer}"] = min(values[f"N_{layer}"], 100.0)
            # A disordered layer's tables: realisations x cells x 46 angles, seconds per cell. The first layer
            # keeps its disorder (two cells at most); the others' is left to tests/test_natural_stack.py.
            if layer == 1 and values.get("sigma_1", 0.0) > 0.0:
                values["N_1"] = min(values["N_1"], 2.0)
            elif layer > 1:
                values[f"sigma_{layer}"] = 0.0
    return values


def assert_passive(image: np.ndarray, what: str, tolerance: float = Y_TOLERANCE) -> None:
    assert np.isfinite(image).all(), f"{what}: non-finite"
    Y = luminance(image)
    worst = np.unravel_index(np.argmax(Y), Y.shape)
    assert Y[worst] <= 1.0 + tolerance, f"{what}: Y = {Y[worst]:.5f} > 1 at {worst}, rgb {image[worst]}"


# --------------------------------------------------------------------------------------------------
# The rows that created light


#: (material, parameters, view, size): each reflected more than white before the fix.
ROWS = [
    ("bragg_stack", {"layers": 2, "nh": 1.5, "coating": False}, "gradient", (1024, 1)),
    ("bragg_stack", {"layers": 2, "nh": 1.2, "coating": False}, "gradient", (1024, 1)),
    ("bragg_stack", {"layers": 3, "nh": 2.0, "coating": False}, "gradient", (1024, 1)),
    ("bragg_stack", {"layers": 2, "nh": 1.5, "coating": False}, "sphere", (64, 64)),
    *[("thin_film", {"eta1": 2.0, "eta2": 1.3, "eta3": 2.0, "d": 2000.0, "method": m}, "gradient", (1024, 1)) for m in (1, 3, 4)],
    ("thin_film", {"eta1": 1.5, "eta2": 1.3, "eta3": 1.5, "d": 2000.0, "method": 1}, "gradient", (1024, 1)),
    ("layered_lobes", {"conductor": True, "eta_base": (1e10, 1e10, 1e10)}, "gradient", (1024, 1)),
]


@pytest.mark.gl
@pytest.mark.parametrize("name, overrides, view, size", ROWS, ids=[f"{r[0]}-{r[2]}-{i}" for i, r in enumerate(ROWS)])
def test_rows_that_created_light(gl_renderer, name, overrides, view, size):
    mat = material(name)
    twins = render_both(gl_renderer, mat, mat.resolve(overrides), view, size)
    assert_passive(twins.gl[twins.compared], f"{name} {overrides} GL")
    assert_passive(twins.reference[twins.compared], f"{name} {overrides} numpy")
    assert_twins_equal(twins, f"{name} {overrides}")


def test_thin_film_near_tir_is_close_to_the_reference():
    """The Fourier series' remainder (thinfilm.fourier_remainder) does more than bound the energy: near
    total internal reflection in the film it brings methods 1-3 to within 0.02 of the converged
    reference, where the plain truncation misses by up to 0.26."""
    cos_theta = np.cos(np.radians(np.linspace(0.0, 89.0, 90)))
    reference = thinfilm.reference_rgb(1.5, 1.3, 1.5, 0.0, cos_theta, 2000.0)
    for m in (2, 3):
        error = np.abs(thinfilm.fourier_rgb(1.5, 1.3, 1.5, 0.0, cos_theta, 2000.0, m) - reference).max()
        assert error < 0.02, (m, error)
    truncated = 0.0
    for pol in thinfilm.POLARISATIONS:
        terms = thinfilm.film_terms(1.5, 1.3, 1.5, 0.0, cos_theta, 2000.0, pol)
        with np.errstate(all="ignore"):
            truncated = truncated + 0.5 * thinfilm.spectral_integration_fourier(terms, 1, remainder=False)
    propagates = thinfilm.film_terms(1.5, 1.3, 1.5, 0.0, cos_theta, 2000.0, "s").film_propagates
    assert np.abs(truncated - reference)[propagates].max() > 0.1  # what the remainder fixes


# --------------------------------------------------------------------------------------------------
# Sweeps over the declared boxes


SWEEP = settings(max_examples=12, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])


@pytest.mark.gl
@pytest.mark.parametrize("name", MATERIALS)
@SWEEP
@given(data=st.data())
@pytest.mark.slow
def test_specular_colours_are_passive_in_gl_and_numpy(gl_renderer, name, data):
    mat, values = data.draw(parameter_sets(name))
    values = _cheap(name, values)
    twins = render_both(gl_renderer, mat, values, "gradient", SWEEP_SIZE)
    assert_passive(twins.reference, f"{name} numpy {values}")
    assert_passive(twins.gl, f"{name} GL {values}")
    assert_twins_equal(twins, f"{name} {values}")


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    n1=st.floats(1.0, 2.5), n2=st.floats(1.0, 2.5), Lambda=st.floats(50.0, 1500.0), delta=st.floats(0.0, 1.0),
    N=st.one_of(st.sampled_from([1, 1000]), st.integers(1, 1000)),
    nh=st.one_of(st.just(0.0), st.floats(1.0, 2.5)),
)
def test_bragg_spectrum_is_within_0_and_1(n1, n2, Lambda, delta, N, nh):
    """Yeh's reflectance (Eqs. 2, 9, 10; Appendix D under a host) at grazing angles too."""
    mirror = bragg.BraggMirror(n1=n1, n2=n2, Lambda=Lambda, delta=delta, N=N, nh=None if nh < 1.0 else nh)
    cos_theta = np.concatenate([np.linspace(0.0, 1.0, 33), [1e-9, 1e-6]])[:, None]
    R = bragg.bragg_reflectance(np.maximum(cos_theta, 1e-9), colorimetry.WAVELENGTHS[::5], mirror)
    assert np.isfinite(R).all()
    assert R.min() >= -SPECTRUM_TOLERANCE and R.max() <= 1.0 + SPECTRUM_TOLERANCE, (R.min(), R.max())


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    eta1=st.floats(1.0, 2.5), eta2=st.floats(1.0, 3.0), eta3=st.floats(0.05, 5.0),
    kappa3=st.one_of(st.just(0.0), st.floats(0.0, 10.0)), d=st.floats(0.0, 3000.0),
)
def test_airy_spectrum_is_within_0_and_1(eta1, eta2, eta3, kappa3, d):
    """The film's Airy reflectance, both polarisations, total internal reflection included."""
    cos_theta = np.linspace(0.0, 1.0, 33)[:, None]
    R = thinfilm.airy_reflectance(eta1, eta2, eta3, kappa3, cos_theta, d, colorimetry.WAVELENGTHS[::5])
    assert np.isfinite(R).all()
    assert R.min() >= -SPECTRUM_TOLERANCE and R.max() <= 1.0 + SPECTRUM_TOLERANCE, (R.min(), R.max())


@settings(max_examples=15, deadline=None, derandomize=True)
@given(data=st.data())
def test_fourier_methods_are_passive(data):
    """Eq. 10 with its remainder, every truncation and both sensitivities, over the film's box in float64."""
    _, values = data.draw(parameter_sets("thin_film"))
    cos_theta = np.cos(np.radians(np.linspace(0.0, 90.0, 181)))
    args = (values["eta1"], values["eta2"], values["eta3"], values["kappa3"], cos_theta, values["d"])
    for m, sensitivity in ((1, "table"), (2, "table"), (3, "table"), (3, "gaussian")):
        assert_passive(thinfilm.fourier_rgb(*args, m, sensitivity), f"m = {m} {sensitivity} {values}")


def test_numpy_gradient_of_every_material_at_its_defaults_is_passive():
    for name in MATERIALS:
        mat = material(name)
        assert_passive(render_numpy(model_for(mat, mat.resolve({})), "gradient", *SWEEP_SIZE), name)


# --------------------------------------------------------------------------------------------------
# Directional albedo (BRDF x cos over the outgoing hemisphere, Dirac reflections included)


#: The albedo's quadrature error: the numpy engine's half-vector Gauss-Legendre rule resolves lobes down
#: to alpha ~ 1e-3 to ~1e-4 (tests/test_albedo.py); the gl engine's scatter sum at its size to ~1e-3.
ALBEDO_TOLERANCE = 3e-3
ALBEDO_THETA = (0.0, 60.0, 85.0)
#: The gl sweep's scatter image (256^2: a pixel spans 0.7 degree) resolves lobes of alpha >= 0.1; its
#: sweep draws roughnesses from there up, the numpy sweep covers the whole box.
GL_ALPHA_MIN = 0.1
GL_ALBEDO_SIZE = 256
ALPHAS = ("alpha", "alpha_1", "alpha_2", "alpha_3", "alpha_4")


def _albedo_values(name: str, values: dict, alpha_min: float = 0.0) -> dict:
    """A drawn point made cheap for an albedo: roughness floored for the gl engine, N at most 40, and the
    Bragg reference (its spectral sum per direction: minutes) replaced by the tabulated colours. The
    reference's own bound follows from its spectrum's (test_bragg_spectrum_is_within_0_and_1: positive
    CMF weights, white = 1) and from the lobe's, which every method shares."""
    values = _cheap(name, values)
    if name in ("bragg_mirror", "bragg_layer") and round(values.get("method", 0)) == int(BraggMethod.REFERENCE):
        values["method"] = float(BraggMethod.TABULATED)
    for key in ALPHAS:
        if key in values:
            values[key] = max(values[key], alpha_min)
    for key in ("N", "N_1", "N_2", "N_3"):
        if key in values:  # the reference's spectral sums per direction: N up to 40 keeps an example near a second
            values[key] = min(values[key], 40.0)
    return values


ALBEDO_SWEEP = settings(max_examples=4, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])


@pytest.mark.parametrize("name", MATERIALS)
@ALBEDO_SWEEP
@given(data=st.data())
@pytest.mark.slow
def test_albedo_is_passive_in_numpy(name, data):
    from explorer.views.albedo import albedo_numpy

    mat, values = data.draw(parameter_sets(name))
    values = _albedo_values(name, values)
    rgb = albedo_numpy(model_for(mat, mat.resolve(values)), ALBEDO_THETA)
    assert_passive(rgb, f"{name} numpy albedo at {ALBEDO_THETA} degrees, {values}", ALBEDO_TOLERANCE)


@pytest.mark.gl
@pytest.mark.parametrize("name", MATERIALS)
@ALBEDO_SWEEP
@given(data=st.data())
@pytest.mark.slow
def test_albedo_is_passive_in_gl(gl_renderer, name, data):
    from explorer.views.albedo import albedo_gl

    mat, values = data.draw(parameter_sets(name))
    values = mat.resolve(_albedo_values(name, values, GL_ALPHA_MIN))
    model = model_for(mat, values)
    rgb = albedo_gl(mat, values, ALBEDO_THETA[:2], gl_renderer, size=GL_ALBEDO_SIZE, model=model)
    assert_passive(rgb, f"{name} GL albedo at {ALBEDO_THETA[:2]} degrees, {values}", ALBEDO_TOLERANCE)


@pytest.mark.gl
@pytest.mark.parametrize("name", MATERIALS)
@settings(max_examples=2, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
@pytest.mark.slow
def test_albedo_view_equals_the_albedo_everywhere(gl_renderer, name, data):
    """The albedo view (GL, one fragment a quadrature node) equals the albedo's numpy quadrature at drawn
    points, within 1 % of the luminance: no method's loops cut the view's sum short."""
    from explorer.views.albedo import albedo_numpy

    mat, values = data.draw(parameter_sets(name))
    values = mat.resolve(_albedo_values(name, values, GL_ALPHA_MIN))
    view = gl_renderer.render(mat, values, "albedo", 1, 1)[0, 0]
    assert_passive(view[None], f"{name} albedo view at 45 degrees, {values}", ALBEDO_TOLERANCE)
    reference = albedo_numpy(model_for(mat, values), [45.0])[0]
    assert abs(luminance(view) - luminance(reference)) <= 0.01 * max(luminance(reference), 0.01), (name, values, view, reference)
