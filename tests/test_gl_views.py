"""GLSL against its numpy twin: every method of shaders/bragg_mirror.brd, in both views.

``Renderer.render(material, values, view, W, H)`` (float32 GLSL on the GPU, or Mesa's llvmpipe) must
equal ``render_numpy(model_for(material, values), view, W, H)`` (float64 numpy) per linear channel,
except on the sphere's float32 rim. Images are small: llvmpipe runs the spectral reference at about
1 s per 256x256 sphere on two cores.
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.materials.methods import BraggMethod
from explorer.physics import bragg, colorimetry
from explorer.materials.models import model_for
from explorer.views.render import render_numpy
from explorer.views.geometry import view_cos_theta
from twins import COLOUR_TOLERANCE, Twins, assert_black_outside, assert_twins_equal, render_both

#: W = 180: the last column is at theta = 89.75 deg, so the gradient reaches beyond 89.5 deg.
VIEW_SIZES = {"gradient": (180, 1), "sphere": (32, 32)}
SWEEP_SIZES = {"gradient": (48, 1), "sphere": (12, 12)}
METHODS = [int(m) for m in BraggMethod]
#: Linear RGB of a reflectance in [0, 1] lies in the object-colour box below, up to this slack.
OBJECT_COLOUR_SLACK = 1e-3

#: Values as the CLI passes them (strings) or as a UI would (floats); resolve() coerces both.
MIRRORS = {
    "default": {},
    "N=1000": {"N": "1000"},
    "n2<n1": {"n1": "1.6", "n2": "1.2"},
    "jewel beetle (nh=1)": {"n1": 1.59, "n2": 1.67, "Lambda": 160.0, "delta": 0.51, "N": 8.0, "nh": 1.0},
    "nh>n1": {"nh": 1.6, "n1": 1.0, "n2": 1.5},
    "Lambda=988": {"Lambda": "988"},
    # Few cells: the improved method resolves the fringes (exact reflectance per sub-box).
    "N=3 (Figure 12)": {"Lambda": 470.0, "delta": 0.3, "N": 3.0},
    "N=5 weak contrast": {"n1": 1.35, "n2": 1.5, "Lambda": 440.0, "delta": 0.3, "N": 5.0},
}


def object_colour_bounds() -> tuple[np.ndarray, np.ndarray]:
    """Per channel, the least and greatest linear RGB of any reflectance spectrum in [0, 1]."""
    per_wavelength = colorimetry.xyz_to_rgb(colorimetry.colour_matching_functions())
    return np.minimum(per_wavelength, 0.0).sum(axis=0), np.maximum(per_wavelength, 0.0).sum(axis=0)


def test_gradient_reaches_grazing():
    cos_theta, inside = view_cos_theta("gradient", *VIEW_SIZES["gradient"])
    assert inside.all()
    assert np.degrees(np.arccos(cos_theta[0, -1])) == pytest.approx(89.75, abs=1e-4)
    assert np.degrees(np.arccos(cos_theta[0, 0])) == pytest.approx(0.25, abs=1e-3)


@pytest.mark.gl
@pytest.mark.parametrize("view", list(VIEW_SIZES))
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("mirror", list(MIRRORS))
def test_gl_equals_numpy_twin(gl_renderer, bragg_material, mirror, method, view):
    overrides = {**MIRRORS[mirror], "method": method if method % 2 else str(method)}
    twins = render_both(gl_renderer, bragg_material, bragg_material.resolve(overrides), view, VIEW_SIZES[view])
    compared = twins.compared
    assert compared.sum() >= 0.9 * compared.size if view == "gradient" else compared.sum() > 500
    assert_twins_equal(twins, f"method {method}, {mirror}, {view}")
    if view == "sphere":
        assert_black_outside(twins)


@pytest.mark.gl
def test_tabulated_gl_equals_spectral_reference_on_a_smooth_mirror(gl_renderer, bragg_material):
    """Method 3 on the GPU against the numpy spectral reference (method 0): the jewel beetle's
    colour is smooth in cos theta, so the 256-entry table interpolates it within tolerance."""
    beetle = MIRRORS["jewel beetle (nh=1)"]
    for view, size in VIEW_SIZES.items():
        tabulated = gl_renderer.render(bragg_material, bragg_material.resolve({**beetle, "method": 3}), view, *size)
        values = bragg_material.resolve({**beetle, "method": 0})
        reference = render_numpy(model_for(bragg_material, values), view, *size)
        assert_twins_equal(Twins.of(tabulated, reference, view), f"method 3 against the reference, {view}", COLOUR_TOLERANCE)


#: bragg_mirror's natural-structure parameters (explorer/physics/natural.py): any of them above 0 makes every
#: method show the host's exact table (shaders/bragg_mirror.brd, natural_structure()), so the paper's sweep
#: leaves them at 0 and the natural sweep below draws them.
NATURAL_PARAMETERS = ("k1", "k2", "sigma")


def random_parameters(material, rng, natural: bool = False) -> dict:
    """Uniform values inside each float or int parameter's declared range (ints: any float, rounded by resolve;
    method 0's wavelength step left at the paper's 1 nm: finer steps cost proportionally more, and
    tests/test_converged.py checks one; the media, which pick a dispersion by index, are swept in
    tests/test_natural_render.py; :data:`NATURAL_PARAMETERS` only when ``natural``)."""
    values = {}
    for parameter in material.parameters:
        if parameter.type in ("float", "int") and parameter.name not in ("method", "wavelength_step") \
                and not parameter.name.startswith("medium_") and (natural or parameter.name not in NATURAL_PARAMETERS):
            values[parameter.name] = float(rng.uniform(parameter.min, parameter.max))
    return values


def sweep_failures(renderer, material, draws: list[dict]) -> list[str]:
    """Every method of every draw in both sweep views: what is not finite or leaves the object-colour box."""
    low, high = object_colour_bounds()
    failures = []
    for parameters in draws:
        for method in METHODS:
            values = material.resolve({**parameters, "method": method})
            for view, size in SWEEP_SIZES.items():
                image = renderer.render(material, values, view, *size)
                if not np.isfinite(image).all():
                    failures.append(f"non-finite: method {method}, {view}, {parameters}")
                elif (image < low - OBJECT_COLOUR_SLACK).any() or (image > high + OBJECT_COLOUR_SLACK).any():
                    failures.append(f"outside the object-colour box: method {method}, {view}, {parameters}")
    return failures


@pytest.mark.gl
def test_gl_sweep_is_finite_and_bounded(gl_renderer, bragg_material):
    """The paper's mirror (lossless, ordered layers: each method's own GLSL) at random values."""
    rng = np.random.default_rng(4242)
    draws = [random_parameters(bragg_material, rng) for _ in range(10)]
    assert not any(bragg_material.resolve(d)[name] for d in draws for name in NATURAL_PARAMETERS)
    failures = sweep_failures(gl_renderer, bragg_material, draws)
    assert not failures, "\n".join(failures)


@pytest.mark.gl
def test_gl_natural_sweep_is_finite_and_bounded(gl_renderer, bragg_material):
    """
    Natural mirrors at random values, one absorbing (ordered), one also disordered: every method shows the host's
    exact table, whose GL path these reach. The disordered table's cost grows with N (realisations x layers: 30-60 s
    on two cores near N = 1000), its GL lookup does not: that draw keeps to N <= 100. The tables' energy is swept
    in numpy (tests/test_natural_render.py, tests/test_energy.py).
    """
    rng = np.random.default_rng(4242)
    absorbing, disordered = (random_parameters(bragg_material, rng, natural=True) for _ in range(2))
    draws = [{**absorbing, "sigma": 0.0}, {**disordered, "N": 1.0 + disordered["N"] % 100.0}]
    assert all(d["k1"] > 0 and d["k2"] > 0 for d in draws) and draws[1]["sigma"] > 0 and draws[1]["N"] <= 100
    failures = sweep_failures(gl_renderer, bragg_material, draws)
    assert not failures, "\n".join(failures)


#: Corners of the parameter box that sliders reach: zero-thickness layers (delta = 0 or 1), one or a
#: thousand cells, extreme contrasts either way, host n1 (nh = 0) or the densest host.
CORNERS = [
    {"n1": n1, "n2": n2, "Lambda": Lambda, "delta": delta, "N": N, "nh": nh}
    for n1, n2 in ((1.0, 2.5), (2.5, 1.0))
    for Lambda in (50.0, 1500.0)
    for delta in (0.0, 1.0)
    for N in (1.0, 1000.0)
    for nh in (0.0, 2.5)
]


@pytest.mark.gl
def test_gl_parameter_corners_are_finite(gl_renderer, bragg_material):
    width, height = SWEEP_SIZES["gradient"]
    failures = []
    for corner in CORNERS:
        for method in METHODS:
            values = bragg_material.resolve({**corner, "method": method})
            image = gl_renderer.render(bragg_material, values, "gradient", width, height)
            twin = render_numpy(model_for(bragg_material, values), "gradient", width, height)
            for name, result in (("GLSL", image), ("numpy", twin)):
                if not np.isfinite(result).all():
                    failures.append(f"{name} non-finite: method {method}, {corner}")
    assert not failures, "\n".join(failures)


def test_object_colour_bounds_contain_reference():
    """The bound used above, checked on numpy references of random mirrors (and it is not vacuous)."""
    low, high = object_colour_bounds()
    assert (low < 0).any() and (high > 1).any() and (high < 3).all() and (low > -2).all()
    rng = np.random.default_rng(7)
    cos_theta = np.linspace(0.0, 1.0, 33)
    for _ in range(10):
        mirror = bragg.BraggMirror(
            n1=rng.uniform(1, 2.5), n2=rng.uniform(1, 2.5), Lambda=rng.uniform(50, 1500),
            delta=rng.uniform(0, 1), N=int(rng.integers(1, 1001)),
        )
        rgb = bragg.reference_rgb(cos_theta, mirror)
        assert (rgb >= low - 1e-9).all() and (rgb <= high + 1e-9).all()
