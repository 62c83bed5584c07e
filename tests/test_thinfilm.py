"""
The thin-film model of Belcour & Barla (2017), numpy reference (explorer.physics.thinfilm).

References independent of the module: the transfer-matrix package ``tmm`` (``coh_tmm``), Yeh's Bragg
mirror with one cell (explorer.physics.bragg), Fresnel's single interface (explorer.physics.fresnel), and the 1 nm
spectral reference for the Fourier method.
"""

from __future__ import annotations

import numpy as np
import pytest
from tmm import coh_tmm

from explorer.physics import colorimetry, thinfilm
from explorer.tables import luts
from explorer.physics.bragg import BraggMirror, bragg_reflectance
from explorer.physics.fresnel import fresnel_reflectance

#: Airy reflectance against tmm, and against the N = 1 Bragg mirror (absolute).
EXACT_ATOL = 1e-9
#: Figure 7 (eta_1 = 1, eta_2 = 1.5, d = 525 nm, eta_3 = 1.09): theta in [0, 89.5 deg], as the Bragg accuracy grid.
FIGURE7 = dict(eta_1=1.0, eta_2=1.5, eta_3=1.09, kappa_3=0.0, thickness_d=525.0)
FIGURE7_THETA_DEG = np.linspace(0.0, 89.5, 180)


def random_stacks(seed: int, count: int, conductor: bool, eta_1_max: float = 1.0):
    """Random three-medium stacks and incidences: (eta_1, eta_2, eta_3, kappa_3, d, theta, wavelength)."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield (
            rng.uniform(1.0, eta_1_max),
            rng.uniform(1.0, 3.0),
            rng.uniform(1.0, 3.0),
            rng.uniform(0.0, 5.0) if conductor else 0.0,
            rng.uniform(0.0, 2000.0),
            np.radians(rng.uniform(0.0, 89.0)),
            rng.uniform(360.0, 830.0),
        )


def tmm_stack(pol, eta_1, eta_2, eta_3, kappa_3, d, theta, wavelength) -> dict:
    return coh_tmm(pol, [eta_1, eta_2, eta_3 + 1j * kappa_3], [np.inf, d, np.inf], theta, wavelength)


# --------------------------------------------------------------------------------------------------
# Airy reflectance and transmittance against tmm


@pytest.mark.parametrize("conductor", [False, True], ids=["dielectric base", "conductor base"])
@pytest.mark.parametrize("pol", ["s", "p"])
def test_airy_reflectance_matches_tmm(conductor, pol):
    stacks = list(random_stacks(5 + conductor, 120, conductor))
    ours, reference = [], []
    for eta_1, eta_2, eta_3, kappa_3, d, theta, wavelength in stacks:
        ours.append(thinfilm.airy_reflectance(eta_1, eta_2, eta_3, kappa_3, np.cos(theta), d, wavelength, pol))
        reference.append(tmm_stack(pol, eta_1, eta_2, eta_3, kappa_3, d, theta, wavelength)["R"])
    np.testing.assert_allclose(ours, reference, rtol=0, atol=EXACT_ATOL)


@pytest.mark.parametrize("conductor", [False, True], ids=["dielectric base", "conductor base"])
@pytest.mark.parametrize("pol", ["s", "p"])
def test_airy_reflection_coefficient_matches_tmm_amplitude(conductor, pol):
    """The complex r of Eq. 3, phase included: the convention of the phases phi_21, phi_23 is tmm's."""
    for eta_1, eta_2, eta_3, kappa_3, d, theta, wavelength in random_stacks(11 + conductor, 60, conductor):
        r = thinfilm.airy_reflection_coefficient(eta_1, eta_2, eta_3, kappa_3, np.cos(theta), d, wavelength, pol)
        assert abs(r - tmm_stack(pol, eta_1, eta_2, eta_3, kappa_3, d, theta, wavelength)["r"]) < EXACT_ATOL


@pytest.mark.parametrize("conductor", [False, True], ids=["dielectric base", "conductor base"])
def test_airy_reflectance_evanescent_film_matches_tmm(conductor):
    """eta_1 > eta_2 beyond the film's critical angle: frustrated total reflection (Eq. 3 path)."""
    rng = np.random.default_rng(21 + conductor)
    checked = 0
    for _ in range(80):
        eta_1, eta_2 = rng.uniform(1.6, 3.0), rng.uniform(1.0, 1.5)
        eta_3, kappa_3 = rng.uniform(1.0, 3.0), rng.uniform(0.0, 5.0) if conductor else 0.0
        critical = np.degrees(np.arcsin(eta_2 / eta_1))
        theta = np.radians(rng.uniform(critical + 1.0, 89.0))
        d, wavelength = rng.uniform(0.0, 400.0), rng.uniform(360.0, 830.0)
        for pol in ("s", "p"):
            R = thinfilm.airy_reflectance(eta_1, eta_2, eta_3, kappa_3, np.cos(theta), d, wavelength, pol)
            assert abs(R - tmm_stack(pol, eta_1, eta_2, eta_3, kappa_3, d, theta, wavelength)["R"]) < EXACT_ATOL
            checked += 1
    assert checked == 160


@pytest.mark.parametrize("pol", ["s", "p"])
def test_airy_transmittance_matches_tmm(pol):
    stacks = list(random_stacks(31, 60, False, eta_1_max=2.0)) + list(random_stacks(32, 60, True, eta_1_max=2.0))
    for eta_1, eta_2, eta_3, kappa_3, d, theta, wavelength in stacks:
        T = thinfilm.airy_transmittance(eta_1, eta_2, eta_3, kappa_3, np.cos(theta), d, wavelength, pol)
        assert abs(T - tmm_stack(pol, eta_1, eta_2, eta_3, kappa_3, d, theta, wavelength)["T"]) < EXACT_ATOL


def test_energy_conservation_on_dielectric_bases():
    """R + T = 1 for a lossless film on a dielectric base: total internal reflection at the base, an
    evanescent film (eta_1 > eta_2) and grazing incidence included."""
    rng = np.random.default_rng(41)
    shape = (400,)
    eta_1, eta_2, eta_3 = rng.uniform(1.0, 3.0, shape), rng.uniform(1.0, 3.0, shape), rng.uniform(1.0, 3.0, shape)
    cos_theta_1 = np.concatenate([rng.uniform(0.0, 1.0, 396), [0.0, 1e-7, 1e-3, 1.0]])
    d, wavelength = rng.uniform(0.0, 2000.0, shape), rng.uniform(360.0, 830.0, shape)
    for pol in ("s", "p", None):
        R = thinfilm.airy_reflectance(eta_1, eta_2, eta_3, 0.0, cos_theta_1, d, wavelength, pol)
        T = thinfilm.airy_transmittance(eta_1, eta_2, eta_3, 0.0, cos_theta_1, d, wavelength, pol)
        np.testing.assert_allclose(R + T, 1.0, rtol=0, atol=1e-12)
        assert np.all(T >= 0.0)
    # Total internal reflection at the base (eta_2 sin theta_2 = eta_1 sin theta_1 > eta_3): T = 0.
    T_tir = thinfilm.airy_transmittance(1.5, 2.0, 1.0, 0.0, np.cos(np.radians(60.0)), 300.0, 550.0)
    assert T_tir == pytest.approx(0.0, abs=1e-15)


def test_closed_form_equals_airy_sum():
    """The Appendix's closed form (real Fresnel moduli and phases), literal and rearranged, equals |r|^2
    of Eq. 3 (complex amplitudes); C_m evaluated without cancellation equals Eq. 6 literally."""
    rng = np.random.default_rng(51)
    cos_theta = np.concatenate([rng.uniform(np.cos(np.radians(89.0)), 1.0, 500), [1e-3, 1e-6]])
    args = [np.ones(502), rng.uniform(1.0, 3.0, 502), rng.uniform(1.0, 3.0, 502),
            rng.uniform(0.0, 5.0, 502), cos_theta, rng.uniform(0.0, 2000.0, 502)]
    wavelength = rng.uniform(360.0, 830.0, 502)
    for pol in ("s", "p"):
        terms = thinfilm.film_terms(*args, pol)
        assert np.all(terms.film_propagates)
        closed = thinfilm.airy_reflectance_from_terms(terms, wavelength)
        airy_sum = np.abs(thinfilm.airy_reflection_coefficient_from_terms(terms, wavelength)) ** 2
        np.testing.assert_allclose(closed, airy_sum, rtol=0, atol=1e-12)
        appendix = thinfilm.airy_reflectance_appendix_from_terms(terms, wavelength)
        np.testing.assert_allclose(appendix[:500], closed[:500], rtol=0, atol=1e-12)
        for m in (1, 2, 3):
            eq6 = terms.R_l**m * (terms.R_star - terms.sqrt_T12T21)
            np.testing.assert_allclose(thinfilm.C_m(terms, m)[:500], eq6[:500], rtol=0, atol=1e-12)


def test_vanishing_film_is_the_single_interface():
    """d = 0 leaves the interface eta_1 | eta_3 (Fresnel), whatever eta_2."""
    cos_theta = np.linspace(0.0, 1.0, 101)
    for eta_1, eta_2, eta_3 in ((1.0, 1.5, 1.09), (1.0, 2.4, 1.5), (1.5, 1.2, 1.0), (1.33, 3.0, 2.0)):
        R = thinfilm.airy_reflectance(eta_1, eta_2, eta_3, 0.0, cos_theta, 0.0, 550.0)
        expected = fresnel_reflectance(np.maximum(cos_theta, thinfilm.COS_THETA_MIN), eta_1, eta_3)
        np.testing.assert_allclose(R, expected, rtol=0, atol=1e-12)


def test_broadcasts_over_angle_and_wavelength():
    cos_theta = np.linspace(0.1, 1.0, 7)
    wavelength = np.linspace(400.0, 700.0, 5)
    R = thinfilm.airy_reflectance(1.0, 1.5, 1.2, 0.3, cos_theta[:, None], 400.0, wavelength[None, :])
    assert R.shape == (7, 5)
    for i, c in enumerate(cos_theta):
        for j, w in enumerate(wavelength):
            assert R[i, j] == pytest.approx(float(thinfilm.airy_reflectance(1.0, 1.5, 1.2, 0.3, c, 400.0, w)), abs=1e-15)
    # Material parameters broadcast too.
    d = np.array([100.0, 200.0, 300.0])
    assert thinfilm.airy_reflectance(1.0, 1.5, 1.2, 0.0, 0.8, d[:, None], wavelength).shape == (3, 5)
    assert thinfilm.reference_rgb(1.0, 1.5, 1.2, 0.0, cos_theta[:, None], d).shape == (7, 3, 3)


# --------------------------------------------------------------------------------------------------
# The two models agree where they overlap: a Bragg mirror with N = 1 is a thin film


def test_bragg_mirror_with_one_cell_is_the_thin_film():
    rng = np.random.default_rng(61)
    for _ in range(40):
        n1, n2 = rng.uniform(1.0, 2.0), rng.uniform(1.0, 3.0)
        d2, delta = rng.uniform(1.0, 2000.0), rng.uniform(0.05, 0.95)
        mirror = BraggMirror(n1=n1, n2=n2, Lambda=d2 / (1.0 - delta), delta=delta, N=1)
        assert mirror.d2 == pytest.approx(d2, rel=1e-12) and mirror.eta_h == n1
        cos_theta = np.cos(np.radians(rng.uniform(0.0, 89.0, 16)))[:, None]
        wavelength = rng.uniform(360.0, 830.0, 12)[None, :]
        for pol in ("s", "p", None):
            bragg = bragg_reflectance(cos_theta, wavelength, mirror, pol)
            film = thinfilm.airy_reflectance(n1, n2, n1, 0.0, cos_theta, d2, wavelength, pol)
            np.testing.assert_allclose(film, bragg, rtol=0, atol=EXACT_ATOL)


# --------------------------------------------------------------------------------------------------
# Eq. 6 and Eq. 10


def test_C_m_terms_vanish_at_grazing_incidence():
    """Fig. 22: every C_m but C_0 vanishes at theta_1 = pi/2 (C_0 -> 1); C_m <= 0 and |C_m| decreases."""
    cos_theta = np.array([1.0, 0.5, 0.1, 1e-4, 0.0])
    for pol in ("s", "p"):
        terms = thinfilm.film_terms(1.0, 1.5, 1.2, 0.5, cos_theta, 300.0, pol)
        C = np.array([thinfilm.C_m(terms, m) for m in (1, 2, 3)])
        assert np.all(np.abs(C[:, -1]) < 1e-4)
        assert abs(C[0, 0]) > 1e-2 and np.all(np.abs(C[:, 0]) > 0.0)
        assert thinfilm.C_0(terms)[-1] == pytest.approx(1.0, abs=1e-4)
        assert np.all(C <= 0.0) and np.all(np.abs(C[1:]) <= np.abs(C[:-1]))


@pytest.mark.parametrize(
    "film",
    [
        dict(eta_1=1.0, eta_2=1.5, eta_3=1.09, kappa_3=0.0, thickness_d=525.0),  # Figure 7
        dict(eta_1=1.0, eta_2=1.33, eta_3=1.9, kappa_3=1.5, thickness_d=550.0),  # Figure 20: conductor
        dict(eta_1=1.5, eta_2=2.0, eta_3=1.0, kappa_3=0.0, thickness_d=300.0),  # TIR at the base
        dict(eta_1=1.2, eta_2=1.39, eta_3=1.2, kappa_3=0.5, thickness_d=505.0),  # Figure 18: clear coat
    ],
    ids=["figure 7", "conductor", "TIR at base", "clear coat"],
)
def test_fourier_series_converges_to_the_spectral_reference(film):
    """Eq. 10 with the exact transform of the 1 nm measure and many harmonics is the 1 nm reference:
    the C_m of Eq. 6, the phases phi_2 and the sign convention of Eq. 10 are all exact."""
    cos_theta = np.cos(np.radians(np.linspace(0.0, 80.0, 41)))
    reference = thinfilm.reference_rgb(cos_theta_1=cos_theta, step=1.0, **film)  # the 1 nm sum, not the converged integral
    series = thinfilm.fourier_rgb(cos_theta_1=cos_theta, m_max=160, sensitivity="exact", **film)
    np.testing.assert_allclose(series, reference, rtol=0, atol=1e-9)
    # And the truncation is what separates m = 3 from the reference.
    truncated = thinfilm.fourier_rgb(cos_theta_1=cos_theta, m_max=3, sensitivity="exact", **film)
    assert np.abs(truncated - reference).max() > 1e-9


def test_sensitivity_table_is_current_and_samples_the_transform():
    assert luts.staleness("sensitivity_fourier") is None
    step, count = thinfilm.SENSITIVITY_FOURIER_STEP, thinfilm.SENSITIVITY_FOURIER_COUNT
    nodes = np.arange(0, count, 37) * step
    exact = thinfilm.sensitivity_fourier_transform(nodes, "exact")
    np.testing.assert_allclose(thinfilm.sensitivity_fourier_transform(nodes), exact, rtol=0, atol=1e-12)
    # White: S^_j(0) = 1 in every channel (flat 1 -> RGB (1, 1, 1)).
    np.testing.assert_allclose(thinfilm.sensitivity_fourier_transform(0.0), [1.0, 1.0, 1.0], atol=1e-12)
    # Between nodes the demodulated envelope interpolates linearly to 1e-4.
    cells = np.arange(0, count - 1, 7)
    between = (cells + np.random.default_rng(71).uniform(0.0, 1.0, cells.size)) * step
    error = np.abs(thinfilm.sensitivity_fourier_transform(between) - thinfilm.sensitivity_fourier_transform(between, "exact"))
    assert error.max() < 1e-4
    # Beyond the table: zero, where the transform is already negligible.
    last = (count - 1) * step
    assert np.all(thinfilm.sensitivity_fourier_transform(np.array([last + 1.0, 1e6])) == 0.0)
    assert np.abs(thinfilm.sensitivity_fourier_transform(np.linspace(last, last + 2e4, 50), "exact")).max() < 1e-4


def test_gaussian_fits_are_the_papers():
    """The Gaussian fits: white to 1e-3 (Y exactly normalised), near the exact transform of the XYZ
    CMFs (the fits' own target) at small OPDs, and decaying faster beyond."""
    xyz = thinfilm.sensitivity_fourier_transform_gaussian_xyz(np.array([0.0, 250.0, 500.0, 8000.0]))
    assert xyz[0, 1].real == pytest.approx(1.0, abs=1e-3)
    np.testing.assert_allclose(xyz[0].real, colorimetry.white_xyz(), atol=1e-3)
    nu = 1.0 / colorimetry.WAVELENGTHS
    cmf_transform = np.exp(-2j * np.pi * np.array([250.0, 500.0])[:, None] * nu) @ colorimetry.colour_matching_functions()
    assert np.abs(xyz[1:3] - cmf_transform).max() < 0.03
    assert np.abs(xyz[3]).max() < 1e-3


# --------------------------------------------------------------------------------------------------
# Figure 7: the methods against the spectral reference


@pytest.fixture(scope="module")
def figure7_delta_E():
    cos_theta = np.cos(np.radians(FIGURE7_THETA_DEG))
    reference = thinfilm.reference_rgb(cos_theta_1=cos_theta, **FIGURE7)
    methods = {f"Fourier m = {m}": thinfilm.fourier_rgb(cos_theta_1=cos_theta, m_max=m, **FIGURE7) for m in (1, 2, 3)}
    methods.update({
        f"Gaussian fits m = {m}": thinfilm.fourier_rgb(cos_theta_1=cos_theta, m_max=m, sensitivity="gaussian", **FIGURE7)
        for m in (1, 2, 3)
    })
    methods["naive RGB (606, 539, 445 nm)"] = thinfilm.naive_rgb(cos_theta_1=cos_theta, **FIGURE7)
    methods["naive XYZ (600, 560, 450 nm)"] = thinfilm.naive_rgb(
        cos_theta_1=cos_theta, wavelengths=thinfilm.PAPER_XYZ_WAVELENGTHS, space="xyz", **FIGURE7
    )
    delta_E = {name: colorimetry.delta_E_2000(rgb, reference) for name, rgb in methods.items()}
    print("\nFigure 7 (eta_2 = 1.5, d = 525 nm, eta_3 = 1.09): median / max Delta E 2000 over theta in [0, 89.5 deg]")
    for name, values in delta_E.items():
        print(f"  {name:30s} {np.median(values):7.4f} / {values.max():6.3f}")
    return delta_E


def test_figure7_fourier_m3_nearly_indistinguishable(figure7_delta_E):
    assert np.median(figure7_delta_E["Fourier m = 3"]) < 1.0


def test_figure7_every_method_finite(figure7_delta_E):
    for name, values in figure7_delta_E.items():
        assert values.shape == FIGURE7_THETA_DEG.shape and np.all(np.isfinite(values)), name


def test_naive_wavelengths_are_the_sensitivity_peaks():
    sensitivities = thinfilm.sensitivities_rgb()
    np.testing.assert_allclose(sensitivities.sum(axis=0), 1.0, atol=1e-12)
    assert tuple(colorimetry.WAVELENGTHS[np.argmax(sensitivities, axis=0)]) == thinfilm.NAIVE_WAVELENGTHS


def test_fourier_falls_back_to_naive_where_the_film_is_evanescent():
    cos_theta = np.cos(np.radians([10.0, 30.0, 60.0, 85.0]))  # critical angle asin(1.2 / 1.8) = 41.8 deg
    film = dict(eta_1=1.8, eta_2=1.2, eta_3=1.5, kappa_3=0.0, thickness_d=200.0)
    fourier = thinfilm.fourier_rgb(cos_theta_1=cos_theta, **film)
    naive = thinfilm.naive_rgb(cos_theta_1=cos_theta, **film)
    np.testing.assert_array_equal(fourier[2:], naive[2:])
    assert np.abs(fourier[:2] - naive[:2]).max() > 1e-3


def test_flat_films_give_greys():
    """A film matched to its surroundings reflects nothing; a perfect conductor nearly everything, white."""
    cos_theta = np.linspace(0.05, 1.0, 9)
    for rgb in (thinfilm.reference_rgb(1.3, 1.3, 1.3, 0.0, cos_theta, 400.0),
                thinfilm.fourier_rgb(1.3, 1.3, 1.3, 0.0, cos_theta, 400.0),
                thinfilm.naive_rgb(1.3, 1.3, 1.3, 0.0, cos_theta, 400.0)):
        np.testing.assert_allclose(rgb, 0.0, atol=1e-15)
    for method in (thinfilm.reference_rgb, thinfilm.fourier_rgb, thinfilm.naive_rgb):
        rgb = method(1.0, 1.0, 1.0, 1e5, cos_theta, 400.0)
        np.testing.assert_allclose(rgb, 1.0, atol=1e-4)


# --------------------------------------------------------------------------------------------------
# D_inc parametrisation (Section 5)


def test_D_inc_parametrisation():
    assert thinfilm.D_inc(1.5, 525.0) == pytest.approx(1575.0)
    D_inc = np.array([0.0, 1e-3, 15.0, 30.0, 1575.0])
    eta_2, d = thinfilm.film_from_D_inc(D_inc, 1.0, 1.5)
    assert eta_2[0] == 1.0 and d[0] == 0.0
    assert 1.0 < eta_2[1] < eta_2[2] < 1.5 and eta_2[2] == pytest.approx(1.25)
    np.testing.assert_allclose(eta_2[3:], 1.5)
    np.testing.assert_allclose(thinfilm.D_inc(eta_2, d), D_inc, rtol=1e-15)
    # D_inc -> 0 ends on the single interface eta_1 | eta_3, continuously.
    R = []
    for D in (0.0, 1e-6, 1e-3):
        eta_2, d = thinfilm.film_from_D_inc(D, 1.0, 2.0)
        R.append(thinfilm.airy_reflectance(1.0, eta_2, 1.5, 0.0, 0.7, d, 550.0))
    single = fresnel_reflectance(0.7, 1.0, 1.5)
    assert R[0] == pytest.approx(single, abs=1e-15)
    assert abs(R[1] - single) < 1e-9 and abs(R[2] - single) < 1e-5


def test_D_max_is_finite_and_sane():
    """Section 5's bound: beyond D_max every |S^_j| <= epsilon (the paper quotes ~25 um for XYZ)."""
    D_max = thinfilm.D_max(0.05)
    assert 1000.0 < D_max < 40950.0
    mu = np.linspace(D_max, 40000.0, 500)
    assert np.abs(thinfilm.sensitivity_fourier_transform(mu, "exact")).max() <= 0.05 + 1e-4


# --------------------------------------------------------------------------------------------------
# No NaN or Inf anywhere in the parameter space


def test_sweep_is_finite_and_in_range():
    eta_1, eta_2, eta_3, kappa_3, cos_theta, d = np.meshgrid(
        [1.0, 1.7, 3.0],
        [1.0, 1.5, 2.2, 3.0],
        [1.0, 1.09, 2.0, 3.0],
        [0.0, 0.5, 5.0],
        [0.0, 1e-9, np.cos(np.radians(89.9)), np.cos(np.radians(89.5)), 0.5, 1.0],
        [0.0, 1.0, 525.0, 2000.0],
        indexing="ij",
    )
    args = tuple(a.ravel() for a in (eta_1, eta_2, eta_3, kappa_3, cos_theta, d))
    wavelength = colorimetry.WAVELENGTHS[::10]
    with np.errstate(divide="raise", invalid="raise", over="raise"):
        R = thinfilm.airy_reflectance(*(a[:, None] for a in args), wavelength)
        T = thinfilm.airy_transmittance(*(a[:, None] for a in args), wavelength)
        assert np.all(np.isfinite(R)) and np.all(np.isfinite(T))
        assert R.min() >= -1e-12 and R.max() <= 1.0 + 1e-12
        assert T.min() >= -1e-12 and (R + T).max() <= 1.0 + 1e-12
        colours = [thinfilm.reference_rgb(*args), thinfilm.naive_rgb(*args)]
        colours += [thinfilm.fourier_rgb(*args, m_max=m, sensitivity=s) for m in (1, 3) for s in ("table", "gaussian")]
    for rgb in colours:
        assert rgb.shape == (args[0].size, 3) and np.all(np.isfinite(rgb))


# --------------------------------------------------------------------------------------------------
# Bad input: one-line ValueErrors


PUBLIC = [
    lambda e1, e2, e3, k3, c, d: thinfilm.airy_reflectance(e1, e2, e3, k3, c, d, 550.0),
    lambda e1, e2, e3, k3, c, d: thinfilm.airy_transmittance(e1, e2, e3, k3, c, d, 550.0),
    lambda e1, e2, e3, k3, c, d: thinfilm.airy_reflection_coefficient(e1, e2, e3, k3, c, d, 550.0, "s"),
    lambda e1, e2, e3, k3, c, d: thinfilm.film_terms(e1, e2, e3, k3, c, d, "p"),
    thinfilm.reference_rgb,
    thinfilm.fourier_rgb,
    thinfilm.naive_rgb,
]


@pytest.mark.parametrize("function", PUBLIC)
@pytest.mark.parametrize(
    "args, word",
    [
        ((1.0, 1.5, 1.2, 0.0, 0.5, -1.0), "thickness_d"),
        ((1.0, 1.5, 1.2, 0.0, 0.5, np.array([100.0, -0.5])), "thickness_d"),
        ((1.0, 1.5, 1.2, -0.1, 0.5, 100.0), "kappa_3"),
        ((1.0, 0.0, 1.2, 0.0, 0.5, 100.0), "eta_2"),
        ((1.0, 1.5, 1.2, 0.0, np.nan, 100.0), "cos_theta_1"),
    ],
)
def test_bad_input_is_a_one_line_value_error(function, args, word):
    with pytest.raises(ValueError) as error:
        function(*args)
    message = str(error.value)
    assert word in message and "\n" not in message


def test_bad_D_inc_and_options():
    with pytest.raises(ValueError, match="D_inc"):
        thinfilm.film_from_D_inc(-5.0, 1.0, 1.5)
    with pytest.raises(ValueError, match="sensitivity"):
        thinfilm.fourier_rgb(1.0, 1.5, 1.2, 0.0, 0.5, 100.0, sensitivity="spline")
    with pytest.raises(ValueError, match="wavelength"):
        thinfilm.airy_reflectance(1.0, 1.5, 1.2, 0.0, 0.5, 100.0, 0.0)
    with pytest.raises(ValueError, match="polarisation"):
        thinfilm.airy_reflectance(1.0, 1.5, 1.2, 0.0, 0.5, 100.0, 500.0, "x")
