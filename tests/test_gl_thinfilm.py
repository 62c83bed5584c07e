"""The thin-film material (Belcour & Barla 2017): shaders/lib/thinfilm.glsl and shaders/thin_film.brd
against their numpy twins (explorer.physics.thinfilm, explorer.materials.thinfilm_model.ThinFilmModel).

- every method of thin_film.brd, in the ``gradient`` and ``sphere`` views, on dielectric and conducting
  bases and on a film that turns evanescent (eta1 > eta2): GL equals numpy to 2e-3 per linear channel
  (measured: a few 1e-6; the float32 parameters' rounding, amplified near the film's critical angle, makes
  the Fourier methods the least exact, a few 1e-4 at worst on random films);
- the GLSL functions one by one (Airy reflectance per polarisation and wavelength, C_m, the sensitivity
  transforms) through small materials written here;
- a cross-check: a Bragg mirror with N = 1 (nh = n1, method 0) is the thin film (n2, d2)
  between n1 and n1 (method 0), in GL;
- no NaN or Inf over random parameters and the parameter box's corners; the BRDF's numpy twin against
  explorer.physics.microfacet's Eq. 17; bad input through the CLI.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli, run_cli_process
from explorer.materials.methods import ThinFilmMethod
from explorer.tables import luts
from explorer.physics import microfacet, thinfilm
from explorer.materials.brd import load_material
from explorer.materials.models import MODELS, model_for
from explorer.views.render import render_numpy
from explorer.views.geometry import view_cos_theta
from explorer.materials.thinfilm_model import ThinFilmModel
from twins import COLOUR_TOLERANCE, LIGHTS, Twins, assert_black_outside, assert_twins_equal, render_both

THIN_FILM_MATERIAL = REPO_ROOT / "shaders" / "thin_film.brd"
THINFILM_GLSL = REPO_ROOT / "shaders" / "lib" / "thinfilm.glsl"

#: The GLSL functions tested one by one: spectral values, far from the views' 2e-3.
FUNCTION_ATOL = 1e-4
#: W = 180: the last column at theta = 89.75 deg. The reference costs ~0.3 s per 256x256 on llvmpipe.
VIEW_SIZES = {"gradient": (180, 1), "sphere": (32, 32)}
SWEEP_SIZES = {"gradient": (48, 1), "sphere": (12, 12)}
METHODS = [int(m) for m in ThinFilmMethod]

#: Films as the CLI passes values (strings) or a UI would (floats).
FILMS = {
    # Figure 7: eta2 = 1.5, d = 525 nm over eta3 = 1.09 (the material's defaults).
    "figure 7 (dielectric)": {},
    # Figure 17: an oxide layer on a metal.
    "figure 17 (conductor)": {"eta2": "1.33", "d": "600", "eta3": "1.5", "kappa3": "3"},
    # Figure 10's middle sphere: D_inc = 1600 nm, eta2 = 1.5, eta3 = 1.1, kappa3 = 1.5.
    "figure 10 (conductor)": {"eta2": 1.5, "d": 1600.0 / 3.0, "eta3": 1.1, "kappa3": 1.5},
    # A clear coat denser than the film: evanescent beyond 48.6 deg (frustrated total reflection).
    "eta1 > eta2": {"eta1": "1.6", "eta2": "1.2", "eta3": "2.2", "kappa3": "0.5", "d": "300"},
    # Total internal reflection at the base (eta3 < eta2): R23 = 1 beyond 41.8 deg.
    "base TIR": {"eta2": "2.4", "eta3": "1.6", "d": "250"},
    "thickest, densest film": {"d": "3000", "eta2": "3"},
    "no film (d = 0)": {"d": "0"},
}


@pytest.fixture(scope="module")
def thin_film_material():
    return load_material(THIN_FILM_MATERIAL)


# --------------------------------------------------------------------------------------------------
# The material and its numpy twin


def test_model_is_registered(thin_film_material):
    assert thin_film_material.model == ThinFilmModel.name
    assert MODELS[ThinFilmModel.name] is ThinFilmModel
    assert thin_film_material.specialised == ("method",) or list(thin_film_material.specialised) == ["method"]
    names = [p.name for p in thin_film_material.parameters]
    assert names == ["d", "eta1", "eta2", "eta3", "kappa3", "alpha", "method"]
    by_name = {p.name: p for p in thin_film_material.parameters}
    assert by_name["d"].min == 0.0 and by_name["kappa3"].min == 0.0 and by_name["eta3"].min > 0.0
    assert (by_name["method"].min, by_name["method"].max) == (0.0, 5.0)


@pytest.mark.parametrize("method", METHODS)
def test_model_reflectance_is_the_thinfilm_module(thin_film_material, method):
    """The twin dispatches each method to explorer.physics.thinfilm as the shader's reflectance() does."""
    film = {"eta2": 1.33, "d": 600.0, "eta3": 1.5, "kappa3": 3.0}
    model = model_for(thin_film_material, thin_film_material.resolve({**film, "method": method}))
    cos_theta = np.linspace(0.0, 1.0, 11)
    args = (1.0, 1.33, 1.5, 3.0, cos_theta, 600.0)
    expected = {
        0: lambda: thinfilm.reference_rgb(*args, step=1.0),  # the shader's 1-nm sum
        1: lambda: thinfilm.fourier_rgb(*args, m_max=1),
        2: lambda: thinfilm.fourier_rgb(*args, m_max=2),
        3: lambda: thinfilm.fourier_rgb(*args, m_max=3),
        4: lambda: thinfilm.fourier_rgb(*args, m_max=3, sensitivity="gaussian"),
        5: lambda: thinfilm.naive_rgb(*args),
    }[method]()
    np.testing.assert_array_equal(model.reflectance(cos_theta), expected)
    assert model.textures() == {}


def test_model_brdf_is_eq17_with_the_film(thin_film_material):
    """brdf(L, V, N, X, Y) against explorer.physics.microfacet.microfacet_brdf with the film's reflectance; reciprocal."""
    values = thin_film_material.resolve({"method": 3, "alpha": 0.3, "eta3": 1.5, "kappa3": 2.0})
    model = model_for(thin_film_material, values)
    rng = np.random.default_rng(5)
    L, V = rng.normal(size=(2, 200, 3))
    L /= np.linalg.norm(L, axis=-1, keepdims=True)
    V /= np.linalg.norm(V, axis=-1, keepdims=True)
    N = np.broadcast_to([0.0, 0.0, 1.0], L.shape)
    X = np.broadcast_to([1.0, 0.0, 0.0], L.shape)
    Y = np.broadcast_to([0.0, 1.0, 0.0], L.shape)
    ours = model.brdf(L, V, N, X, Y)
    expected = microfacet.microfacet_brdf(L, V, 0.3, lambda c: model.reflectance(c[..., 0]))
    assert ours.shape == (200, 3)
    np.testing.assert_allclose(ours, expected, rtol=1e-12, atol=0)
    np.testing.assert_allclose(model.brdf(V, L, N, X, Y), ours, rtol=1e-14, atol=0)
    below = (L[:, 2] <= 0) | (V[:, 2] <= 0)
    assert below.any() and (ours[below] == 0).all() and (ours[~below] > 0).all()


@pytest.mark.parametrize("bad", [{"d": -1.0}, {"kappa3": -1.0}, {"eta3": 0.0}, {"alpha": 2.0}, {"d": float("nan")}])
def test_model_rejects_bad_values(thin_film_material, bad):
    values = {**thin_film_material.resolve({}), **bad}
    with pytest.raises(ValueError):
        ThinFilmModel(values)


# --------------------------------------------------------------------------------------------------
# The GLSL library against explorer.physics.thinfilm: constants, names, functions


def glsl_constant(name: str) -> np.ndarray:
    """The numbers of ``const float|vec3 NAME = ...;`` in the block lib/thinfilm.glsl includes (generated)."""
    from explorer.materials.shader_constants import GENERATED

    assert '#include "generated/thinfilm.glsl"' in THINFILM_GLSL.read_text()
    match = re.search(rf"const\s+(?:float|vec3)\s+{name}\s*=\s*([^;]+);", GENERATED["generated/thinfilm.glsl"]())
    assert match, f"{name} is not a constant of {THINFILM_GLSL.name}"
    return np.array([float(x) for x in re.findall(r"[-+]?\d*\.?\d+(?:[eE][-+]?\d+)?", match.group(1).replace("vec3", ""))])


@pytest.mark.parametrize(
    "name, value",
    [
        ("FILM_COS_THETA_MIN", thinfilm.COS_THETA_MIN),
        ("NAIVE_WAVELENGTHS", thinfilm.NAIVE_WAVELENGTHS),
        ("SENSITIVITY_FOURIER_STEP", thinfilm.SENSITIVITY_FOURIER_STEP),
        ("SENSITIVITY_FOURIER_CARRIER_NM", thinfilm.SENSITIVITY_FOURIER_CARRIER_NM),
        ("GAUSSIAN_FIT_VAL", thinfilm.GAUSSIAN_FIT_VAL),
        ("GAUSSIAN_FIT_POS", thinfilm.GAUSSIAN_FIT_POS),
        ("GAUSSIAN_FIT_VAR", thinfilm.GAUSSIAN_FIT_VAR),
        ("GAUSSIAN_FIT_X2", thinfilm.GAUSSIAN_FIT_X2),
        ("GAUSSIAN_FIT_NORM", thinfilm.GAUSSIAN_FIT_NORM),
        ("D_INC_BLEND", thinfilm.D_INC_BLEND),
    ],
)
def test_glsl_constants_are_the_python_ones(name, value):
    np.testing.assert_array_equal(glsl_constant(name), np.atleast_1d(np.asarray(value, dtype=np.float64)))


def test_table_node_zero_is_white():
    """lib/thinfilm.glsl takes S^(0) = 1 + 0i without fetching it: the table's first node, exactly."""
    table = luts.load("sensitivity_fourier")
    assert table.shape == (2, thinfilm.SENSITIVITY_FOURIER_COUNT, 3)
    np.testing.assert_array_equal(table[:, 0].astype(np.float32), [[1.0, 1.0, 1.0], [0.0, 0.0, 0.0]])


TWINS = [
    "cos_theta_transmitted_conductor", "fresnel_t", "film_terms", "optical_path_difference",
    "airy_reflection_coefficient_from_terms", "airy_reflectance_from_terms", "airy_reflectance", "C_0", "C_m",
    "sensitivity_fourier_transform_table", "sensitivity_fourier_transform_gaussian_xyz",
    "sensitivity_fourier_transform", "spectral_integration_fourier", "reference_rgb", "naive_rgb", "fourier_rgb",
    "D_inc", "film_from_D_inc",
]


@pytest.mark.parametrize("name", TWINS)
def test_glsl_twins_have_the_numpy_names(name):
    assert callable(getattr(thinfilm, name))
    assert re.search(rf"\b(?:void|float|vec2|vec3|bool|FilmTerms)\s+{name}\s*\(", THINFILM_GLSL.read_text()), name


def probe_material(tmp_path: Path, expression: str, name: str = "probe") -> object:
    """A material whose reflectance(cos_theta) returns ``expression`` (a vec3 of lib/thinfilm.glsl calls)."""
    path = tmp_path / f"{name}.brd"
    path.write_text(
        "analytic\n::begin parameters\n"
        "float d 0 3000 525\nfloat eta1 1 2.5 1\nfloat eta2 1 3 1.5\nfloat eta3 0.05 5 1.09\nfloat kappa3 0 10 0\n"
        "::end parameters\n::begin shader\n#include \"lib/thinfilm.glsl\"\n"
        f"vec3 reflectance(float cos_theta) {{ {expression} }}\n"
        "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return reflectance(dot(N, L)); }\n"
        "::end shader\n"
    )
    return load_material(path)


PROBE_FILMS = {k: FILMS[k] for k in ("figure 7 (dielectric)", "figure 17 (conductor)", "eta1 > eta2", "base TIR")}


def probe_film(material, overrides):
    values = material.resolve({k: v for k, v in overrides.items() if k in ("d", "eta1", "eta2", "eta3", "kappa3")})
    return values, (values["eta1"], values["eta2"], values["eta3"], values["kappa3"])


@pytest.mark.gl
@pytest.mark.parametrize("film", list(PROBE_FILMS))
@pytest.mark.parametrize("pol", [0, 1], ids=["s", "p"])
def test_glsl_airy_reflectance_per_polarisation(gl_renderer, tmp_path, film, pol):
    """airy_reflectance_from_terms at 380, 550 and 780 nm, one polarisation, against numpy's."""
    wavelengths = (380.0, 550.0, 780.0)
    material = probe_material(
        tmp_path,
        f"FilmTerms t = film_terms(eta1, eta2, eta3, kappa3, cos_theta, d, {pol}); return vec3("
        + ", ".join(f"airy_reflectance_from_terms(t, {w:.1f})" for w in wavelengths) + ");",
    )
    values, (eta_1, eta_2, eta_3, kappa_3) = probe_film(material, PROBE_FILMS[film])
    gl = gl_renderer.render(material, values, "gradient", 180, 1)[0]
    cos_theta = view_cos_theta("gradient", 180, 1)[0][0]
    expected = thinfilm.airy_reflectance(
        eta_1, eta_2, eta_3, kappa_3, cos_theta[:, None], values["d"], np.array(wavelengths), "sp"[pol]
    )
    np.testing.assert_allclose(gl, expected, rtol=0, atol=FUNCTION_ATOL)


@pytest.mark.gl
@pytest.mark.parametrize("film", ["figure 7 (dielectric)", "figure 17 (conductor)", "base TIR"])
@pytest.mark.parametrize("pol", [0, 1], ids=["s", "p"])
def test_glsl_C_m(gl_renderer, tmp_path, film, pol):
    """C_0 and C_1..C_3 (Eq. 6) where the film propagates, against numpy's."""
    material = probe_material(
        tmp_path,
        f"FilmTerms t = film_terms(eta1, eta2, eta3, kappa3, cos_theta, d, {pol});"
        " return vec3(C_0(t), C_m(t, 1), C_m(t, 3));",
    )
    values, film_indices = probe_film(material, PROBE_FILMS[film])
    gl = gl_renderer.render(material, values, "gradient", 180, 1)[0]
    terms = thinfilm.film_terms(*film_indices, view_cos_theta("gradient", 180, 1)[0][0], values["d"], "sp"[pol])
    expected = np.stack([thinfilm.C_0(terms), thinfilm.C_m(terms, 1), thinfilm.C_m(terms, 3)], axis=-1)
    np.testing.assert_allclose(gl, expected, rtol=0, atol=FUNCTION_ATOL)


@pytest.mark.gl
@pytest.mark.parametrize("sensitivity", ["table", "gaussian"])
@pytest.mark.parametrize("pol", [0, 1], ids=["s", "p"])
def test_glsl_spectral_integration_fourier(gl_renderer, tmp_path, sensitivity, pol):
    """Eq. 10 for one polarisation at m_max = 2 (fourier_rgb shares the samples between polarisations)."""
    index = 0 if sensitivity == "table" else 1
    material = probe_material(
        tmp_path,
        f"return spectral_integration_fourier(film_terms(eta1, eta2, eta3, kappa3, cos_theta, d, {pol}), 2, {index});",
        name=f"probe_{sensitivity}_{pol}",
    )
    values, film_indices = probe_film(material, PROBE_FILMS["figure 17 (conductor)"])
    gl = gl_renderer.render(material, values, "gradient", 180, 1)[0]
    terms = thinfilm.film_terms(*film_indices, view_cos_theta("gradient", 180, 1)[0][0], values["d"], "sp"[pol])
    expected = thinfilm.spectral_integration_fourier(terms, 2, sensitivity)
    np.testing.assert_allclose(gl, expected, rtol=0, atol=FUNCTION_ATOL)


@pytest.mark.gl
@pytest.mark.parametrize("sensitivity", ["table", "gaussian"])
@pytest.mark.parametrize("part", ["re", "im"])
def test_glsl_sensitivity_fourier_transform(gl_renderer, tmp_path, sensitivity, part):
    """S^_j(mu) for mu from 0 to 45000 nm (past the table's last node, where it is 0)."""
    index = 0 if sensitivity == "table" else 1
    material = probe_material(
        tmp_path,
        f"vec3 re, im; sensitivity_fourier_transform(cos_theta * 45000.0, {index}, re, im); return {part};",
        name=f"probe_{sensitivity}_{part}",
    )
    gl = gl_renderer.render(material, material.resolve({}), "gradient", 600, 1)[0]
    mu = np.float32(view_cos_theta("gradient", 600, 1)[0][0]) * np.float32(45000.0)
    S = thinfilm.sensitivity_fourier_transform(mu.astype(np.float64), sensitivity)
    np.testing.assert_allclose(gl, S.real if part == "re" else S.imag, rtol=0, atol=FUNCTION_ATOL)


# --------------------------------------------------------------------------------------------------
# The views: GL against numpy, every method


@pytest.mark.gl
@pytest.mark.parametrize("view", list(VIEW_SIZES))
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("film", list(FILMS))
def test_gl_equals_numpy_twin(gl_renderer, thin_film_material, film, method, view):
    overrides = {**FILMS[film], "method": method if method % 2 else str(method)}
    twins = render_both(gl_renderer, thin_film_material, thin_film_material.resolve(overrides), view, VIEW_SIZES[view])
    assert_twins_equal(twins, f"method {method}, {film}, {view}")
    if view == "sphere":
        assert_black_outside(twins)


#: The BRDF views (twins.BRDF_TOLERANCE, twins.LIGHTS) in a small image: the reference method runs per pixel.
BRDF_SIZE = (20, 16)
BRDF_FILMS = {
    "figure 7, alpha 0.2": {},
    "figure 17, alpha 0.07": {**FILMS["figure 17 (conductor)"], "alpha": "0.07"},
}


@pytest.mark.gl
@pytest.mark.parametrize("view", list(LIGHTS))
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("film", list(BRDF_FILMS))
def test_brdf_views_gl_equals_numpy_twin(gl_renderer, thin_film_material, film, method, view):
    values = thin_film_material.resolve({**BRDF_FILMS[film], "method": method})
    twins = render_both(gl_renderer, thin_film_material, values, view, BRDF_SIZE)
    assert_twins_equal(twins, f"method {method}, {film}, {view}")
    assert np.abs(twins.reference).max() > 0.05, "an empty image"


#: The cross-check: (n1, n2, Lambda, delta) of a one-cell Bragg mirror under nh = n1.
BRAGG_CELLS = [
    (1.0, 1.5, 500.0, 0.5),
    (1.6, 1.2, 800.0, 0.3),  # n2 < n1: the layer turns evanescent beyond 48.6 deg
    (1.33, 2.5, 1500.0, 0.1),
    (1.0, 2.0, 120.0, 0.8),
]


@pytest.mark.gl
@pytest.mark.parametrize("cell", BRAGG_CELLS, ids=[f"n1={c[0]},n2={c[1]},L={c[2]},delta={c[3]}" for c in BRAGG_CELLS])
def test_bragg_mirror_with_one_cell_is_a_thin_film_in_gl(gl_renderer, bragg_material, thin_film_material, cell):
    n1, n2, Lambda, delta = cell
    mirror = bragg_material.resolve({"n1": n1, "n2": n2, "Lambda": Lambda, "delta": delta, "N": 1, "nh": n1, "method": 0})
    film = thin_film_material.resolve(
        {"eta1": n1, "eta2": n2, "eta3": n1, "kappa3": 0, "d": (1.0 - delta) * Lambda, "method": 0}
    )
    for view, size in VIEW_SIZES.items():
        bragg_image = gl_renderer.render(bragg_material, mirror, view, *size)
        film_image = gl_renderer.render(thin_film_material, film, view, *size)
        assert_twins_equal(Twins.of(bragg_image, film_image, view), f"one cell against the film, {view}", COLOUR_TOLERANCE)
        # Not vacuous: the film is coloured, not a grey interface.
        inside = view_cos_theta(view, *size)[1]
        assert np.ptp(film_image[inside], axis=-1).max() > 0.01


# --------------------------------------------------------------------------------------------------
# Robustness: random parameters, the parameter box's corners


def random_parameters(material, rng) -> dict:
    return {p.name: float(rng.uniform(p.min, p.max)) for p in material.parameters if p.name != "method"}


#: Sliders' extremes: no film or the thickest, the exterior at both ends, the film's index at both ends,
#: the base from nearly empty (eta3 = 0.05) to dense, dielectric or the most absorbing.
CORNERS = [
    {"d": d, "eta1": eta1, "eta2": eta2, "eta3": eta3, "kappa3": kappa3}
    for d in (0.0, 3000.0)
    for eta1 in (1.0, 2.5)
    for eta2 in (1.0, 3.0)
    for eta3 in (0.05, 5.0)
    for kappa3 in (0.0, 10.0)
]


@pytest.mark.gl
def test_gl_sweep_and_corners_are_finite(gl_renderer, thin_film_material):
    rng = np.random.default_rng(2017)
    films = [random_parameters(thin_film_material, rng) for _ in range(12)] + CORNERS
    failures = []
    for parameters in films:
        for method in METHODS:
            values = thin_film_material.resolve({**parameters, "method": method})
            for view, size in SWEEP_SIZES.items():
                image = gl_renderer.render(thin_film_material, values, view, *size)
                if not np.isfinite(image).all():
                    failures.append(f"GLSL non-finite: method {method}, {view}, {parameters}")
            twin = render_numpy(model_for(thin_film_material, values), "gradient", *SWEEP_SIZES["gradient"])
            if not np.isfinite(twin).all():
                failures.append(f"numpy non-finite: method {method}, {parameters}")
    assert not failures, "\n".join(failures)


# --------------------------------------------------------------------------------------------------
# The command line


@pytest.mark.parametrize("assignment", ["d=-1", "kappa3=-1", "eta3=0"])
def test_cli_bad_value_is_one_line(tmp_path, assignment):
    """Bad thickness or kappa3: one line naming the parameter's declaration, a non-zero exit, no file."""
    material = str(THIN_FILM_MATERIAL.relative_to(REPO_ROOT))
    line = one_line_error(run_cli("render", material, "--set", assignment, "--out", tmp_path / "bad.png"))
    assert "thin_film.brd" in line and assignment.split("=")[0] in line and "range" in line, line
    assert list(tmp_path.iterdir()) == []


@pytest.mark.gl
def test_cli_npy_equals_numpy_twin(gl_renderer, tmp_path, thin_film_material):
    material = str(THIN_FILM_MATERIAL.relative_to(REPO_ROOT))
    good = run_cli_process("render", material, "--view", "sphere", "--size", "24", "--set", "method=3", "--set", "kappa3=2",
                           "--out", tmp_path / "good.npy")
    assert good.returncode == 0, good.stderr
    image = np.load(tmp_path / "good.npy")
    values = thin_film_material.resolve({"method": "3", "kappa3": "2"})
    reference = render_numpy(model_for(thin_film_material, values), "sphere", 24, 24)
    assert_twins_equal(Twins.of(image, reference, "sphere"), "CLI sphere .npy")
