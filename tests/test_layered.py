"""Layered Bragg structures (numpy): the integrated transmissivity (Eq. 28), the absorption (Eq. 30),
the per-layer tables (Table 2's LUT version) and the single-reflection BRDF (Eq. 34).

References are independent of ``explorer.physics.layered``: Yeh's exact reflectance and the Airy slab of
``explorer.physics.bragg`` (themselves checked against ``tmm`` in the physics tests), Fresnel and Snell written
out, Eq. 17 through ``explorer.physics.layered.rough_bragg_brdf``, and hemispherical quadratures written
here. Spectral albedos are checked per wavelength.
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.physics import bragg, colorimetry, layered, microfacet
from explorer.physics.layered import LayeredBragg, RoughBraggLayer

SEED = 20240604
#: The tables' hat averages against a fixed 1/64-nm sampling, per wavelength: they converge on the colour
#: (2e-4 of its brightest channel), each wavelength less tightly (up to 1.03e-2 measured: a one-cell
#: slab's zero narrower than a nm at 89.75 degrees).
HAT_AVERAGE_ATOL = 2e-2
#: Their colour against the 1/64-nm one, relative to the brightest channel (floor 0.05).
HAT_COLOUR_RTOL = 2e-3
#: The tables' float32 fast path of Yeh's reflectance against the exact float64 one (absolute).
TABLE_ATOL = 2e-3
#: Table 2's Model-LUT against its Model (R at the exact half-vector angle), relative to the mean or peak.
LUT_RTOL = 5e-3
#: Reciprocity of Eq. 34 (relative; the formula is symmetric to the last bit).
RECIPROCITY_RTOL = 1e-12
#: White furnace: slack of the hemispherical quadratures on a directional albedo (sharp band edges
#: under a wide lobe converge slowly: 128 x 16 half vectors are within 1e-2 of 512 x 64).
FURNACE_SLACK = 1e-2
#: An invisible layer (n2 = n1) over a white base: albedo against its closed form (quadrature + tables).
INVISIBLE_ATOL = 2e-3

A = RoughBraggLayer(n2=1.5, Lambda=500.0, delta=0.5, N=10, alpha=0.1)  # Figure 7, configuration A
B = RoughBraggLayer(n2=1.5, Lambda=988.0, delta=0.5, N=10, alpha=0.05)  # Figure 7, configuration B
GAP = RoughBraggLayer(n2=2.5, Lambda=300.0, delta=0.5, N=30, alpha=0.4)  # band gaps in the visible
BEETLE = RoughBraggLayer(n2=1.67, Lambda=160.0, delta=0.51, N=8, alpha=0.05, n1=1.59)  # Table 3 (a)


def directions(theta, phi):
    theta, phi = np.broadcast_arrays(np.asarray(theta, dtype=float), np.asarray(phi, dtype=float))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


def random_directions(rng, count, max_theta=np.pi / 2):
    return directions(rng.uniform(0.0, max_theta, count), rng.uniform(0.0, 2.0 * np.pi, count))


def gauss_legendre(a, b, panels, nodes=8):
    x, w = np.polynomial.legendre.leggauss(nodes)
    edges = np.linspace(a, b, panels + 1)
    half = 0.5 * np.diff(edges)
    centre = 0.5 * (edges[1:] + edges[:-1])
    return (centre[:, None] + half[:, None] * x).ravel(), (half[:, None] * w).ravel()


# --------------------------------------------------------------------------------------------------
# Bad input


def test_bad_input_is_a_one_line_value_error():
    cases = [
        (lambda: RoughBraggLayer(alpha=-0.01), r"alpha must be in \[0, 1\]"),
        (lambda: RoughBraggLayer(alpha=1.01), r"alpha must be in \[0, 1\]"),
        (lambda: RoughBraggLayer(alpha=float("nan")), r"alpha must be in \[0, 1\]"),
        (lambda: LayeredBragg(layers=(A, A, B, B)), r"1 to 3 layers, got 4"),
        (lambda: LayeredBragg(layers=()), r"1 to 3 layers, got 0"),
        (lambda: LayeredBragg(layers=(A,), rho_d=(0.2, 1.3, 0.0)), r"rho_d must be in \[0, 1\]"),
        (lambda: LayeredBragg(layers=(A,), n1=0.9), r"n1 must be >= 1"),
        (lambda: LayeredBragg(layers=(A,), rho_d=(0.2, 0.3)), r"rho_d must be one number or three"),
        (lambda: RoughBraggLayer(N=0), r"N must be"),
        (lambda: layered.absorption(0.5, 2.0), r"alpha must be in \[0, 1\]"),
        (lambda: layered.layer_tables(A, 1.0, microfacet.transmission_filter_table(0.3)), r"filter is for alpha=0.3"),
    ]
    for make, message in cases:
        with pytest.raises(ValueError, match=message) as error:
            make()
        assert "\n" not in str(error.value)


def test_up_to_three_layers_and_grey_albedo_are_accepted():
    stack = LayeredBragg(layers=[A, B, GAP], n1=1.35, rho_d=0.5)
    assert stack.layers == (A, B, GAP) and stack.rho_d == (0.5, 0.5, 0.5)
    assert LayeredBragg(layers=A).layers == (A,)


# --------------------------------------------------------------------------------------------------
# Eqs. 28 and 30, the per-layer tables


def test_integrated_transmissivity_of_a_clear_layer_is_G1_and_absorption_is_eq30():
    """T = 1 in Eq. 28 leaves the filter's mass G1 (Appendix C): A = 1 - G1 (Eq. 30)."""
    for alpha in (0.01, 0.1, 0.4):
        F = microfacet.transmission_filter_table(alpha)
        clear = layered.integrated_transmissivity(F, np.ones((361, 4)))
        absorbed = layered.absorption(np.cos(F.theta), alpha)
        np.testing.assert_allclose(1.0 - clear, np.repeat(absorbed[:, None], 4, axis=1), atol=2e-5)
        # A layer without index contrast is clear: its table is the same.
        invisible = layered.layer_tables(RoughBraggLayer(n2=1.0, alpha=alpha), 1.0, F)
        np.testing.assert_allclose(invisible.reflectance, 0.0, atol=1e-7)
        np.testing.assert_allclose(invisible.transmissivity, 1.0 - np.repeat(absorbed[:, None], 471, axis=1), atol=2e-5)


def hat_averaged(spectra, K: int = 64) -> np.ndarray:
    """Spectra ``spectra(wavelengths)`` averaged over each nm's hat (half-width 1 nm): 1/K-nm samples, a triangular kernel."""
    fine = np.arange(359.0 * K, 831.0 * K + 1) / K
    kernel = (K - np.abs(np.arange(-K + 1, K))) / K**2
    averaged = np.array([np.convolve(row, kernel, mode="same") for row in spectra(fine)])
    return averaged[:, np.searchsorted(fine, colorimetry.WAVELENGTHS)]


@pytest.mark.parametrize("layer, n1", [(A, 1.0), (B, 1.35), (GAP, 1.0), (BEETLE, 1.0), (RoughBraggLayer(1.2, 400.0, 1.0, 5, 0.2), 1.6)])
def test_layer_tables_are_yeh_and_eq28(layer, n1):
    tables = layered.layer_tables(layer, n1)
    mirror = layer.mirror(n1)
    theta = microfacet.theta_nodes()
    assert tables.reflectance.shape == tables.transmissivity.shape == (361, 471)
    assert tables.reflectance.dtype == tables.transmissivity.dtype == np.float32
    # Each entry is Yeh's R averaged over its nm's hat function (half-width 1 nm): here from samples every
    # 1/64 nm and a triangular kernel, on every 24th angle.
    rows = np.arange(0, theta.size, 24)
    at_nodes = hat_averaged(lambda fine: bragg.bragg_reflectance(np.maximum(np.cos(theta[rows]), bragg.COS_THETA_MIN)[:, None], fine, mirror))
    assert np.max(np.abs(tables.reflectance[rows] - at_nodes)) < HAT_AVERAGE_ATOL
    exact = tables.reflectance.astype(np.float64)
    # Eq. 28 from the table's transmissivity 1 - R, summed here with the filter's cell weights.
    F = microfacet.transmission_filter_table(layer.alpha)
    eq28 = np.einsum("kj,jl->kl", F.weights, 1.0 - exact)
    assert np.max(np.abs(tables.transmissivity - eq28)) < TABLE_ATOL
    G1 = microfacet.smith_G1(np.cos(theta), layer.alpha)
    assert np.all(tables.transmissivity >= -1e-6) and np.all(tables.transmissivity <= G1[:, None] + 1e-5)
    assert tables.seconds > 0.0


def test_layer_table_with_one_cell_is_the_airy_slab():
    layer = RoughBraggLayer(n2=1.7, Lambda=400.0, delta=0.4, N=1, alpha=0.2)
    tables = layered.layer_tables(layer, 1.0)
    # Every 10th angle, and the grazing ones, where the slab's reflectance has a zero narrower than a nm.
    rows = np.unique(np.concatenate([np.arange(0, 361, 10), np.arange(355, 361)]))
    cos_theta = np.maximum(np.cos(microfacet.theta_nodes()[rows]), bragg.COS_THETA_MIN)[:, None]

    def slab(wavelengths):
        total = 0.0
        for pol in ("s", "p"):
            r1, _ = bragg.airy_slab_coefficients(2.0 * np.pi / wavelengths, bragg.cell_geometry(cos_theta, layer.mirror(1.0), pol))
            total = total + 0.5 * np.abs(r1) ** 2
        return total

    expected = hat_averaged(slab)
    assert np.max(np.abs(tables.reflectance[rows] - expected)) < HAT_AVERAGE_ATOL
    # The colour, which the tables converge on, much closer.
    rgb, expected_rgb = colorimetry.spectrum_to_rgb(tables.reflectance[rows]), colorimetry.spectrum_to_rgb(expected)
    assert np.max(np.abs(rgb - expected_rgb).max(axis=-1) / np.maximum(np.abs(expected_rgb).max(axis=-1), 0.05)) < HAT_COLOUR_RTOL


# --------------------------------------------------------------------------------------------------
# Eq. 34


def fresnel_unpolarised(cos_theta, n):
    """Fresnel from air into n, written out."""
    cos_t = np.sqrt(1.0 - (1.0 - cos_theta**2) / n**2)
    rs = (cos_theta - n * cos_t) / (cos_theta + n * cos_t)
    rp = (n * cos_theta - cos_t) / (n * cos_theta + cos_t)
    return 0.5 * (rs**2 + rp**2)


def refract(d, n):
    t = d[..., :2] / n
    return np.concatenate([t, np.sqrt(1.0 - np.sum(t * t, axis=-1))[..., None]], axis=-1)


@pytest.mark.parametrize("exact", [False, True])
def test_eq34_is_reciprocal(exact):
    rng = np.random.default_rng(SEED)
    i, o = random_directions(rng, 48), random_directions(rng, 48)
    for stack in (LayeredBragg((A,), n1=1.0, rho_d=(0.8, 0.3, 0.1)), LayeredBragg((A, GAP, B), n1=1.35, rho_d=(0.2, 0.5, 0.9))):
        tables = layered.stack_tables(stack)
        forward = layered.single_reflection_brdf(stack, i, o, tables, exact)
        backward = layered.single_reflection_brdf(stack, o, i, tables, exact)
        assert np.all(np.isfinite(forward)) and np.max(np.abs(forward)) > 0.0
        np.testing.assert_allclose(forward, backward, rtol=RECIPROCITY_RTOL, atol=1e-15)


def test_coating_with_n1_equal_to_one_is_no_coating():
    rng = np.random.default_rng(SEED)
    i, o = random_directions(rng, 64), random_directions(rng, 64)
    coated = LayeredBragg((A, B), n1=1.0, rho_d=0.4, coating=True)
    bare = LayeredBragg((A, B), n1=1.0, rho_d=0.4, coating=False)
    tables = layered.stack_tables(bare)
    np.testing.assert_allclose(
        layered.single_reflection_brdf(coated, i, o, tables), layered.single_reflection_brdf(bare, i, o, tables), rtol=1e-12, atol=1e-15
    )
    # ... while a real coating changes the BRDF (the coating's path is the one just compared).
    thick = LayeredBragg((A, B), n1=1.35, rho_d=0.4)
    thick_bare = LayeredBragg((A, B), n1=1.35, rho_d=0.4, coating=False)
    thick_tables = layered.stack_tables(thick)
    difference = layered.single_reflection_brdf(thick, i, o, thick_tables) - layered.single_reflection_brdf(thick_bare, i, o, thick_tables)
    assert np.max(np.abs(difference)) > 1e-2


def test_eq34_with_one_layer_is_eq17_under_the_coating():
    """One layer: (1 - F(i))(1 - F(o)) / n1^2 f_r,1(i', o') (Eq. 17 at the refracted directions)."""
    rng = np.random.default_rng(SEED)
    i, o = random_directions(rng, 32, np.deg2rad(88.0)), random_directions(rng, 32, np.deg2rad(88.0))
    for n1 in (1.0, 1.35, 1.6):
        stack = LayeredBragg((A,), n1=n1)
        spectra = layered.single_reflection_spectra(stack, i, o, exact_reflectance=True)
        eq17 = layered.rough_bragg_brdf(refract(i, n1), refract(o, n1), A.mirror(n1), A.alpha)
        factor = (1.0 - fresnel_unpolarised(i[:, 2], n1)) * (1.0 - fresnel_unpolarised(o[:, 2], n1)) / n1**2
        np.testing.assert_allclose(spectra.layers, factor[:, None] * eq17, rtol=1e-10, atol=1e-14)
        # The tabulated reflectance (Model-LUT) stays close to the exact one (Model): linear
        # interpolation between 0.25-degree nodes blurs fast fringes (up to 3% of the peak at a few
        # wavelengths), 0.2% on average and in colour.
        lut = layered.single_reflection_spectra(stack, i, o).layers
        assert np.mean(np.abs(lut - spectra.layers)) < LUT_RTOL * np.mean(spectra.layers)
        rgb_lut, rgb_exact = colorimetry.spectrum_to_rgb(lut), colorimetry.spectrum_to_rgb(spectra.layers)
        assert np.max(np.abs(rgb_lut - rgb_exact)) < LUT_RTOL * np.max(rgb_exact)


def test_eq34_base_term_through_an_invisible_layer():
    """n2 = n1: R = 0, f_t = G1, so the base term is (1-F)(1-F) G1(i') G1(o') / (pi n1^2)."""
    rng = np.random.default_rng(SEED)
    i, o = random_directions(rng, 32), random_directions(rng, 32)
    n1 = 1.5
    clear = RoughBraggLayer(n2=n1, alpha=0.3)
    spectra = layered.single_reflection_spectra(LayeredBragg((clear,), n1=n1, rho_d=1.0), i, o)
    i_host, o_host = refract(i, n1), refract(o, n1)
    expected = (
        (1.0 - fresnel_unpolarised(i[:, 2], n1))
        * (1.0 - fresnel_unpolarised(o[:, 2], n1))
        * microfacet.smith_G1(i_host[:, 2], 0.3)
        * microfacet.smith_G1(o_host[:, 2], 0.3)
        / (np.pi * n1**2)
    )
    np.testing.assert_allclose(spectra.base, np.repeat(expected[:, None], 471, axis=1), atol=1e-5)
    assert np.max(np.abs(spectra.layers)) < 1e-7
    rgb = layered.single_reflection_brdf(LayeredBragg((clear,), n1=n1, rho_d=(1.0, 0.5, 0.0)), i, o)
    np.testing.assert_allclose(rgb, expected[:, None] * np.array([1.0, 0.5, 0.0]), atol=2e-5)


def directional_albedo(stack, theta_i, tables):
    """
    Per-wavelength directional albedo of Eq. 34 with a white base, integrated over the hemisphere:
    the Bragg lobes over half vectors (d omega_o = 4 (o.h) d omega_h, theta_h = alpha_min sinh t), the
    base over outgoing directions, plus the coating's Dirac reflection.
    """
    i = np.array([np.sin(theta_i), 0.0, np.cos(theta_i)])
    alpha = min(layer.alpha for layer in stack.layers) / stack.n1
    t, w_t = gauss_legendre(0.0, np.arcsinh(0.5 * np.pi / alpha), 16)
    theta_h, w_h = alpha * np.sinh(t), w_t * alpha * np.cosh(t)
    phi, w_phi = gauss_legendre(0.0, np.pi, 2)  # the lobe is symmetric in phi: twice [0, pi]
    th, ph = np.meshgrid(theta_h, phi, indexing="ij")
    h = directions(th, ph)
    i_dot_h = h @ i
    o = 2.0 * i_dot_h[..., None] * h - i
    valid = (o[..., 2] > 0.0) & (i_dot_h > 0.0)
    weight = np.where(valid, 2.0 * 4.0 * i_dot_h * np.sin(th) * w_h[:, None] * w_phi * o[..., 2], 0.0)
    lobes = np.einsum("ab,abl->l", weight, layered.single_reflection_spectra(stack, np.broadcast_to(i, o.shape), o, tables).layers)
    theta_o, w_o = gauss_legendre(0.0, 0.5 * np.pi, 8)
    o_base = directions(theta_o, 0.0)
    base = layered.single_reflection_spectra(stack, np.broadcast_to(i, o_base.shape), o_base, tables).base
    base = 2.0 * np.pi * np.einsum("a,al->l", w_o * np.cos(theta_o) * np.sin(theta_o), base)
    specular = layered.coating_reflectance(np.cos(theta_i), stack.n1) if stack.coating else 0.0
    return specular + lobes + base


@pytest.mark.parametrize(
    "stack",
    [
        LayeredBragg((A,), n1=1.0, rho_d=1.0),
        LayeredBragg((GAP,), n1=1.0, rho_d=1.0),
        LayeredBragg((B, A), n1=1.35, rho_d=1.0),
        LayeredBragg((RoughBraggLayer(2.0, 250.0, 0.3, 20, 0.02), GAP, RoughBraggLayer(1.5, 700.0, 0.7, 3, 1.0)), n1=1.6, rho_d=1.0),
    ],
    ids=["A", "band-gaps", "B-over-A-coated", "three-layers-coated"],
)
def test_white_furnace(stack):
    """Directional albedo <= 1 at every angle and wavelength (a single-reflection model loses energy)."""
    tables = layered.stack_tables(stack)
    for theta_i in np.deg2rad([0.0, 20.0, 40.0, 60.0, 80.0, 89.5]):
        albedo = directional_albedo(stack, theta_i, tables)
        assert np.all(np.isfinite(albedo)) and np.all(albedo >= 0.0)
        assert np.max(albedo) <= 1.0 + FURNACE_SLACK, f"theta_i={np.rad2deg(theta_i):.1f}: albedo {np.max(albedo):.4f}"


@pytest.mark.parametrize("n1", [1.0, 1.5])
def test_white_furnace_through_an_invisible_layer_matches_its_closed_form(n1):
    """n2 = n1 over a white base: albedo = F(i) + (1-F(i)) G1(i') / n1^2 int (1-F(o)) G1(o') cos_o / pi."""
    clear = RoughBraggLayer(n2=n1, alpha=0.2)
    stack = LayeredBragg((clear,), n1=n1, rho_d=1.0)
    tables = layered.stack_tables(stack)
    theta_o, w_o = gauss_legendre(0.0, 0.5 * np.pi, 16)
    cos_o = np.cos(theta_o)
    outgoing = np.sum(w_o * 2.0 * cos_o * np.sin(theta_o) * (1.0 - fresnel_unpolarised(cos_o, n1)) * microfacet.smith_G1(refract(directions(theta_o, 0.0), n1)[:, 2], 0.2))
    for theta_i in np.deg2rad([0.0, 40.0, 80.0]):
        albedo = directional_albedo(stack, theta_i, tables)
        cos_i = np.cos(theta_i)
        G1_i = microfacet.smith_G1(refract(directions(theta_i, 0.0), n1)[2], 0.2)
        expected = fresnel_unpolarised(cos_i, n1) + (1.0 - fresnel_unpolarised(cos_i, n1)) * G1_i * outgoing / n1**2
        np.testing.assert_allclose(albedo, expected, atol=INVISIBLE_ATOL)


# --------------------------------------------------------------------------------------------------
# Robustness


def test_no_nan_or_inf_over_a_sweep():
    rng = np.random.default_rng(SEED)
    horizon = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1e-12], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    i = np.concatenate([random_directions(rng, 6), horizon, horizon, -horizon])
    o = np.concatenate([random_directions(rng, 6), horizon, horizon[::-1], horizon])
    for alpha in (0.0, 1e-3, 0.03, 1.0):
        layers = (
            RoughBraggLayer(2.0, 700.0, 0.3, 40, alpha),
            RoughBraggLayer(1.2, 300.0, 1.0, 5, alpha),  # zero-thickness high layer, evanescent under n1 = 1.6
            RoughBraggLayer(1.67, 160.0, 0.51, 8, alpha, n1=1.59),  # Appendix D
        )
        for n1 in (1.0, 1.6):
            stack = LayeredBragg(layers, n1=n1, rho_d=(1.0, 0.5, 0.0))
            tables = layered.stack_tables(stack)
            for table in tables:
                assert np.all(np.isfinite(table.reflectance)) and np.all(np.isfinite(table.transmissivity))
            for exact in (False, True):
                rgb = layered.single_reflection_brdf(stack, i, o, tables, exact)
                assert np.all(np.isfinite(rgb))
                assert np.all(rgb[6 + 10 :] == 0.0)  # an incident direction below the horizon


def test_timings_are_measured():
    timings = layered.measure_timings(alphas=(0.1,), layers={"A": (A, 1.0)}, repeats=1)
    assert timings["transmission_filter_ms"]["alpha=0.1"] > 0.0 and timings["layer_tables_ms"]["A"] > 0.0
