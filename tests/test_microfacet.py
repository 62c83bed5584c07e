"""Rough Bragg layers (numpy): GGX D (Eq. 18), Smith G1 (Eq. 19), the microfacet Bragg BRDF (Eq. 17)
and the GGX transmission filter F_alpha (Eqs. 24-29, Appendix C).

References are independent of the implementation: Eqs. 18-19 in the paper's literal forms, Eq. 29's
psi_d integral summed by brute force (as the paper does with 1000 samples, here 20000), Eq. 23 as a
direct double integral over microfacet normals, and quadratures written here (sinh-mapped composite
Gauss-Legendre, which resolves narrow GGX peaks), never the module's own tables or closed forms.
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.physics import bragg, colorimetry, layered, microfacet
from explorer.physics.bragg import BraggMirror

SEED = 20240603
#: Appendix C: each row of the tabulated filter integrates to G1(theta_i) within this.
APPENDIX_C_ATOL = 1e-3
#: Appendix C, what the quadrature of microfacet.transmission_filter_table actually achieves.
APPENDIX_C_ACHIEVED = 2e-5
#: D normalisation and the closed forms against literal / brute-force evaluations (relative).
NORMALISATION_TOL = 1e-6
CLOSED_FORM_RTOL = 1e-6
#: Eq. 28 from the table against Eq. 23 integrated directly, for a smooth transmissivity (the table
#: samples T at its 0.25-degree nodes: O(h^2) = 2e-5 relative).
EQ23_RTOL = 2e-4
#: Reciprocity of Eq. 17 (relative; float64 rounding only).
RECIPROCITY_RTOL = 1e-12
#: White furnace of one rough Bragg layer with R = 1: the hemispherical quadrature's own error.
FURNACE_SLACK = 1e-4
ALPHAS = (0.001, 0.01, 0.1, 0.4, 1.0)


def gauss_legendre(a, b, panels, nodes=8):
    """Composite Gauss-Legendre nodes and weights on [a, b]."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    edges = np.linspace(a, b, panels + 1)
    half = 0.5 * np.diff(edges)
    centre = 0.5 * (edges[1:] + edges[:-1])
    return (centre[:, None] + half[:, None] * x).ravel(), (half[:, None] * w).ravel()


def theta_quadrature(alpha, panels=200, centre=0.0):
    """Nodes in [0, pi/2] with theta = centre + alpha sinh(t): fine near `centre`, coarse far away."""
    t0 = np.arcsinh((0.0 - centre) / alpha)
    t1 = np.arcsinh((0.5 * np.pi - centre) / alpha)
    t, w = gauss_legendre(t0, t1, panels)
    return centre + alpha * np.sinh(t), w * alpha * np.cosh(t)


def D_literal(cos_theta_m, alpha):
    """Eq. 18 as printed."""
    tan2 = (1.0 - cos_theta_m**2) / cos_theta_m**2
    return alpha**2 / (np.pi * cos_theta_m**4 * (alpha**2 + tan2) ** 2)


def G1_literal(theta, alpha):
    """Eq. 19 as printed (above the horizon, visible microfacet)."""
    return 2.0 / (1.0 + np.sqrt(1.0 + alpha**2 * np.tan(theta) ** 2))


def random_directions(rng, count, max_theta=np.pi / 2):
    theta = rng.uniform(0.0, max_theta, count)
    phi = rng.uniform(0.0, 2.0 * np.pi, count)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


# --------------------------------------------------------------------------------------------------
# Eqs. 18-19


@pytest.mark.parametrize("alpha", ALPHAS)
def test_ggx_D_is_normalised(alpha):
    theta, w = theta_quadrature(alpha)
    integral = 2.0 * np.pi * np.sum(microfacet.ggx_D(np.cos(theta), alpha) * np.cos(theta) * np.sin(theta) * w)
    assert abs(integral - 1.0) < NORMALISATION_TOL


def test_ggx_D_is_eq18_and_vanishes_below_horizon():
    rng = np.random.default_rng(SEED)
    alpha = rng.uniform(0.01, 1.0, 200)
    cos_theta_m = rng.uniform(0.05, 1.0, 200)
    np.testing.assert_allclose(microfacet.ggx_D(cos_theta_m, alpha), D_literal(cos_theta_m, alpha), rtol=1e-12)
    assert np.all(microfacet.ggx_D(-cos_theta_m, alpha) == 0.0)


def test_smith_G1_is_eq19_and_tends_to_one_as_alpha_vanishes():
    rng = np.random.default_rng(SEED)
    theta = rng.uniform(0.0, np.deg2rad(89.0), 200)
    alpha = rng.uniform(0.0, 1.0, 200)
    np.testing.assert_allclose(microfacet.smith_G1(np.cos(theta), alpha), G1_literal(theta, alpha), rtol=1e-12)
    grid = np.deg2rad(np.linspace(0.0, 89.0, 90))
    previous = microfacet.smith_G1(np.cos(grid), 0.1)
    for alpha in (1e-2, 1e-3, 1e-4, 1e-6):
        G1 = microfacet.smith_G1(np.cos(grid), alpha)
        assert np.all(G1 >= previous)  # decreasing roughness only unmasks
        previous = G1
    assert np.max(np.abs(1.0 - previous)) < 1e-8
    assert np.max(np.abs(1.0 - microfacet.smith_G1(np.cos(grid), 0.0))) < 1e-8
    # Masked at grazing for any roughness; chi+ of Eq. 19 when i and m face apart.
    assert microfacet.smith_G1(0.0, 0.3) == 0.0
    assert microfacet.smith_G1(0.5, 0.3, i_dot_m=-0.1) == 0.0
    assert microfacet.smith_G1(0.5, 0.3, i_dot_m=0.1) > 0.0


@pytest.mark.parametrize("alpha", [0.05, 0.3, 1.0])
def test_smith_G1_is_the_projected_area_ratio(alpha):
    """Smith's definition (Heitz 2014): G1(i) = cos theta_i / int D(m) <i.m>+ d omega_m."""
    theta_m, w_theta = theta_quadrature(alpha, panels=200)
    phi, w_phi = gauss_legendre(0.0, np.pi, 16)
    for theta_i in np.deg2rad([0.0, 30.0, 60.0, 85.0]):
        i_dot_m = np.cos(theta_i) * np.cos(theta_m)[:, None] + np.sin(theta_i) * np.sin(theta_m)[:, None] * np.cos(phi)
        integrand = microfacet.ggx_D(np.cos(theta_m), alpha)[:, None] * np.sin(theta_m)[:, None] * np.maximum(i_dot_m, 0.0)
        projected = 2.0 * np.sum(integrand * w_theta[:, None] * w_phi)
        assert abs(np.cos(theta_i) / projected - microfacet.smith_G1(np.cos(theta_i), alpha)) < 1e-4


# --------------------------------------------------------------------------------------------------
# Eq. 17


@pytest.mark.parametrize("alpha", [0.02, 0.2, 0.7])
def test_rough_bragg_brdf_is_reciprocal(alpha):
    rng = np.random.default_rng(SEED)
    i, o = random_directions(rng, 64), random_directions(rng, 64)
    mirror = BraggMirror(n1=1.0, n2=1.5, Lambda=500.0, delta=0.5, N=10)
    forward = layered.rough_bragg_brdf(i, o, mirror, alpha)
    backward = layered.rough_bragg_brdf(o, i, mirror, alpha)
    assert np.all(np.isfinite(forward)) and np.max(forward) > 0.0
    np.testing.assert_allclose(forward, backward, rtol=RECIPROCITY_RTOL, atol=0.0)


@pytest.mark.parametrize("alpha", [0.05, 0.4])
def test_rough_layer_with_one_cell_is_a_rough_dielectric_slab(alpha):
    """N = 1: Eq. 17 with the Airy slab reflectance |r1|^2 (Eq. 10), assembled here from Eqs. 18-19."""
    rng = np.random.default_rng(SEED)
    mirror = BraggMirror(n1=1.0, n2=1.7, Lambda=400.0, delta=0.4, N=1)
    i, o = random_directions(rng, 40, np.deg2rad(85.0)), random_directions(rng, 40, np.deg2rad(85.0))
    h = (i + o) / np.linalg.norm(i + o, axis=-1, keepdims=True)
    cos_d = np.sum(i * h, axis=-1)
    omega = 2.0 * np.pi / colorimetry.WAVELENGTHS
    slab = 0.0
    for pol in ("s", "p"):
        r1, _ = bragg.airy_slab_coefficients(omega, bragg.cell_geometry(cos_d[:, None], mirror, pol))
        slab = slab + 0.5 * np.abs(r1) ** 2
    lobe = (
        D_literal(h[:, 2], alpha)
        * G1_literal(np.arccos(i[:, 2]), alpha)
        * G1_literal(np.arccos(o[:, 2]), alpha)
        / (4.0 * i[:, 2] * o[:, 2])
    )
    expected = lobe[:, None] * slab
    np.testing.assert_allclose(layered.rough_bragg_brdf(i, o, mirror, alpha), expected, rtol=1e-9, atol=1e-12)


def half_vector_albedo(brdf, theta_i, alpha, panels=64, phis=48):
    """int f(i, o) cos theta_o d omega_o over half vectors h (d omega_o = 4 (o.h) d omega_h)."""
    i = np.array([np.sin(theta_i), 0.0, np.cos(theta_i)])
    theta_h, w_theta = theta_quadrature(alpha, panels)
    phi, w_phi = gauss_legendre(0.0, np.pi, phis // 8)  # symmetric in phi: twice [0, pi]
    th, ph = np.meshgrid(theta_h, phi, indexing="ij")
    h = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1)
    i_dot_h = h @ i
    o = 2.0 * i_dot_h[..., None] * h - i
    valid = (o[..., 2] > 0.0) & (i_dot_h > 0.0)
    weight = 2.0 * 4.0 * i_dot_h * np.sin(th) * w_theta[:, None] * w_phi[None, :] * np.maximum(o[..., 2], 0.0)
    values = brdf(np.broadcast_to(i, o.shape), o)
    return np.sum(np.where(valid, weight, 0.0)[..., None] * values, axis=(0, 1))


@pytest.mark.parametrize("alpha", [0.01, 0.1, 0.5, 1.0])
def test_microfacet_white_furnace(alpha):
    """With R = 1 the directional albedo of Eq. 17 is at most 1 (and near 1 when smooth and normal)."""
    unit = lambda cos_theta_d: np.ones_like(cos_theta_d)
    albedos = []
    for theta_i in np.deg2rad([0.0, 20.0, 45.0, 70.0, 85.0, 89.5]):
        albedo = half_vector_albedo(lambda i, o: microfacet.microfacet_brdf(i, o, alpha, unit), theta_i, alpha)[0]
        albedos.append(albedo)
        assert 0.0 < albedo <= 1.0 + FURNACE_SLACK
    if alpha <= 0.01:
        assert albedos[0] > 0.999


# --------------------------------------------------------------------------------------------------
# The transmission filter (Eqs. 24-29, Appendix C)


def filter_brute_force(theta_i, theta_d, alpha, samples=20000):
    """Eq. 29 literally: midpoint sum over psi_d in [0, psi_d_max] (Eq. 26) of D~(theta_m(psi_d)) (Eq. 24)."""
    if theta_i + theta_d >= np.pi / 2 and np.sin(theta_i) * np.sin(theta_d) > 0:
        psi_max = np.arccos(-1.0 / (np.tan(theta_i) * np.tan(theta_d)))
    else:
        psi_max = np.pi
    psi = (np.arange(samples) + 0.5) / samples * psi_max
    cos_m = np.cos(theta_i) * np.cos(theta_d) + np.sin(theta_i) * np.sin(theta_d) * np.cos(psi)
    D_tilde = alpha**2 / (np.pi * (alpha**2 * cos_m**2 + 1.0 - cos_m**2) ** 2)
    G1 = G1_literal(theta_i, alpha)
    return 2.0 * G1**2 * np.cos(theta_d) / np.cos(theta_i) * np.sum(D_tilde) * psi_max / samples * np.sin(theta_d)


@pytest.mark.parametrize("alpha", [0.01, 0.1, 0.4, 1.0])
def test_filter_closed_form_is_eq29(alpha):
    rng = np.random.default_rng(SEED)
    theta_i = rng.uniform(0.0, np.deg2rad(89.0), 60)
    theta_d = np.clip(np.where(rng.uniform(size=60) < 0.5, theta_i + 2.0 * alpha * rng.normal(size=60), rng.uniform(0.0, np.pi / 2, 60)), 0.0, np.deg2rad(89.9))
    expected = np.array([filter_brute_force(a, b, alpha) for a, b in zip(theta_i, theta_d)])
    np.testing.assert_allclose(microfacet.transmission_filter(theta_i, theta_d, alpha), expected, rtol=CLOSED_FORM_RTOL, atol=1e-12)


def test_psi_d_max_puts_the_normal_on_the_horizon():
    rng = np.random.default_rng(SEED)
    theta_i, theta_d = rng.uniform(0.0, np.pi / 2, (2, 500))
    psi = microfacet.psi_d_max(theta_i, theta_d)
    cut = theta_i + theta_d >= np.pi / 2
    assert np.all(psi[~cut] == np.pi)
    np.testing.assert_allclose(microfacet.cos_theta_m(theta_i[cut], theta_d[cut], psi[cut]), 0.0, atol=1e-12)
    # Just inside the bound the normal is above the horizon (Figure 5).
    assert np.all(microfacet.cos_theta_m(theta_i[cut], theta_d[cut], psi[cut] * (1.0 - 1e-6)) > 0.0)


@pytest.mark.parametrize("alpha", [0.01, 0.1, 0.4])
def test_filter_integrates_to_G1(alpha):
    """Appendix C: int_0^{pi/2} F_alpha(theta_i, theta_d) d theta_d = G1(theta_i), at every table row."""
    table = microfacet.transmission_filter_table(alpha)
    G1 = G1_literal(table.theta[:-1], alpha)
    error = np.abs(table.row_sums()[:-1] - G1)
    assert np.max(error) < APPENDIX_C_ATOL
    assert np.max(error) < APPENDIX_C_ACHIEVED
    assert abs(table.row_sums()[-1]) < 1e-12  # G1 = 0 at grazing incidence
    assert table.weights.shape == (361, 361) and np.all(table.weights >= 0.0)


def test_filter_table_is_the_cell_average_of_eq29():
    """Where F_alpha is smooth (alpha = 0.4), the cell averages equal the pointwise Eq. 29 to O(h^2)."""
    table = microfacet.transmission_filter_table(0.4)
    theta = table.theta
    k, j = np.meshgrid(np.arange(4, 357, 16), np.arange(1, 360), indexing="ij")
    # Away from the square-root kink at theta_d = pi/2 - theta_i (Eq. 26, Figure 6), within 1 degree.
    smooth = j < 356 - k
    k, j = k[smooth], j[smooth]
    pointwise = microfacet.transmission_filter(theta[k], theta[j], 0.4)
    np.testing.assert_allclose(table.values[k, j], pointwise, rtol=1e-4, atol=1e-8)


def test_filter_of_a_smooth_layer_is_the_identity():
    """alpha -> 0: the filter is a Dirac at theta_d = theta_i, its mass G1 -> 1 in the diagonal cell."""
    table = microfacet.transmission_filter_table(0.0)
    diagonal = np.diag(table.weights)
    np.testing.assert_allclose(diagonal[:-1], 1.0, atol=1e-5)
    assert np.max(np.abs(table.weights - np.diag(diagonal))) < 1e-5


@pytest.mark.parametrize("alpha", [0.05, 0.3])
def test_eq28_with_the_table_is_eq23(alpha):
    """sum_j T(theta_j) w[k, j] (Eq. 28) against Eq. 23 as a double integral over microfacet normals."""
    T = lambda theta_d: 0.3 + 0.7 * np.cos(theta_d) ** 2  # a smooth transmissivity
    table = microfacet.transmission_filter_table(alpha)
    theta_m, w_theta = theta_quadrature(alpha, panels=300)
    phi, w_phi = gauss_legendre(0.0, np.pi, 32)
    for k in (0, 60, 180, 300, 352):
        theta_i = table.theta[k]
        cos_d = np.cos(theta_i) * np.cos(theta_m)[:, None] + np.sin(theta_i) * np.sin(theta_m)[:, None] * np.cos(phi)
        visible = cos_d > 0.0
        theta_d = np.arccos(np.clip(cos_d, 0.0, 1.0))
        integrand = np.where(visible, cos_d / np.cos(theta_i) * T(theta_d), 0.0) * (
            G1_literal(theta_i, alpha) ** 2 * microfacet.ggx_D(np.cos(theta_m), alpha) * np.sin(theta_m)
        )[:, None]
        eq23 = 2.0 * np.sum(integrand * w_theta[:, None] * w_phi)
        eq28 = np.sum(T(table.theta) * table.weights[k])
        assert abs(eq28 - eq23) <= EQ23_RTOL * eq23


# --------------------------------------------------------------------------------------------------
# Robustness


def test_no_nan_or_inf_over_a_sweep():
    grazing = np.array([0.0, 1e-12, 1e-6, 1e-3, 0.5, 1.0])
    rng = np.random.default_rng(SEED)
    mirror = BraggMirror(n1=1.0, n2=2.0, Lambda=700.0, delta=0.3, N=40)
    horizon = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1e-12], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    i = np.concatenate([random_directions(rng, 8), horizon, horizon])
    o = np.concatenate([random_directions(rng, 8), horizon, horizon[::-1]])
    for alpha in np.concatenate([[0.0], np.logspace(-3, 0, 7)]):
        for value in (microfacet.ggx_D(grazing, alpha), microfacet.smith_G1(grazing, alpha), microfacet.smith_G1_over_cos(grazing, alpha)):
            assert np.all(np.isfinite(value))
        table = microfacet.transmission_filter_table(alpha)
        assert np.all(np.isfinite(table.weights))
        assert np.max(np.abs(table.row_sums() - microfacet.smith_G1(np.cos(table.theta), alpha))) < APPENDIX_C_ACHIEVED
        F = microfacet.transmission_filter(table.theta[:, None], table.theta[None, ::30], alpha)
        assert np.all(np.isfinite(F)) and np.all(F >= 0.0)
        f = layered.rough_bragg_brdf(i, o, mirror, alpha)
        assert np.all(np.isfinite(f)) and np.all(f >= 0.0)


@pytest.mark.parametrize("alpha", [-0.1, 1.5, float("nan")])
def test_alpha_outside_the_unit_interval_is_refused(alpha):
    for call in (
        lambda: microfacet.ggx_D(0.5, alpha),
        lambda: microfacet.smith_G1(0.5, alpha),
        lambda: microfacet.transmission_filter(0.1, 0.2, alpha),
        lambda: microfacet.transmission_filter_table(alpha),
    ):
        with pytest.raises(ValueError, match=r"^alpha must be in \[0, 1\], got [^\n]*$"):
            call()
