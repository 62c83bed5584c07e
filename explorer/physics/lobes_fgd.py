"""
The tables of Belcour's (2018) FGD term for :mod:`explorer.physics.lobes`: the Fresnel terms per polarisation,
the nodes of the tables and their generators (``luts/lobes_fgd_correction.npy``,
``luts/lobes_ggx_moments.npy``, registered here with the table store :mod:`explorer.tables.luts`). A module
of its own so that the tables' generators do not import the model that loads the tables.

References
----------
Belcour, L. (2018). Efficient rendering of layered materials using an atomic decomposition with
statistical operators. ACM TOG 37(4).
Bati, M., Barla, P., Pacanowski, R. (2021). An inverse method for the exploration of layered material
appearance. ACM TOG 40(4). Section 4.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import microfacet
from explorer.tables import luts

#: The FGD tables: nodes t = k / (N_COS - 1) of the warped cosine (:func:`fgd_cos_coordinate`: the
#: critical angle of eta < 1 on the middle node, the nodes above it dense near it), alpha nodes k / (N_ALPHA - 1), eta nodes
#: ETA_TABLE_MAX ** (2 k / (N_ETA - 1) - 1) (log-spaced from 1 / 4 to 4), and the quadrature per entry.
FGD_COS_COUNT = 33
FGD_ALPHA_COUNT = 16
FGD_ETA_COUNT = 33
ETA_TABLE_MAX = 4.0
FGD_QUADRATURE = 48
#: The grazing node is evaluated at this cosine (the integrand's 1 / cos theta_i).
FGD_COS_FLOOR = 1e-3

# --------------------------------------------------------------------------------------------------
# Fresnel terms per polarisation


def fresnel_sp(cos_theta: ArrayLike, eta: ArrayLike, kappa: float = 0.0) -> np.ndarray:
    """
    Fresnel reflectances ``[R_s, R_p]`` of a smooth interface towards a medium of relative index
    ``eta + i kappa`` (relative to the medium of incidence), at incidence ``cos_theta``.

    Total internal reflection (``eta < 1``, beyond the critical angle) gives 1. Shapes broadcast;
    the result has a leading axis of length 2.
    """
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    n = np.asarray(eta, dtype=np.float64) + 1j * np.asarray(kappa, dtype=np.float64)
    n2 = n * n
    q = np.sqrt(n2 - (1.0 - c * c) + 0j)  # eta cos theta_t, principal branch (Re >= 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = (c - q) / (c + q)
        rp = (n2 * c - q) / (n2 * c + q)
    # c = 0 onto eta = 1 (q = 0): the grazing limit, |r| = 1.
    rs = np.where(np.abs(c + q) > 0.0, rs, 1.0)
    rp = np.where(np.abs(n2 * c + q) > 0.0, rp, 1.0)
    return np.stack([np.abs(rs) ** 2, np.abs(rp) ** 2])


def _fresnel_dielectric_mean(cos_theta, eta) -> np.ndarray:
    """``(R_s + R_p) / 2`` of a real relative index in real arithmetic (the tables' inner loop); 1 under TIR."""
    c = np.clip(cos_theta, 0.0, 1.0)
    q2 = eta * eta - 1.0 + c * c
    q = np.sqrt(np.maximum(q2, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = (c - q) / (c + q)
        rp = (eta * eta * c - q) / (eta * eta * c + q)
    value = 0.5 * (rs * rs + rp * rp)
    return np.where((q2 <= 0.0) | ~np.isfinite(value), 1.0, value)


def normal_reflectance(eta_0: ArrayLike, eta_1: ArrayLike, kappa_1: float = 0.0) -> np.ndarray:
    """Eq. 1: ``R_01 = ((eta_0 - eta_1)^2 + kappa_1^2) / ((eta_0 + eta_1)^2 + kappa_1^2)``."""
    eta_0, eta_1, kappa_1 = (np.asarray(v, dtype=np.float64) for v in (eta_0, eta_1, kappa_1))
    return ((eta_0 - eta_1) ** 2 + kappa_1**2) / ((eta_0 + eta_1) ** 2 + kappa_1**2)


# --------------------------------------------------------------------------------------------------
# FGD: directional albedo of a rough interface (host tables in luts/)


def fgd_cos_nodes() -> np.ndarray:
    """The table's nodes in the warped coordinate ``t`` (and in ``cos theta`` for ``eta >= 1``)."""
    return np.linspace(0.0, 1.0, FGD_COS_COUNT)


def _critical_cos(eta):
    eta = np.asarray(eta, dtype=np.float64)
    return np.sqrt(np.maximum(1.0 - eta * eta, 0.0))


def fgd_cos_coordinate(cos_theta: ArrayLike, eta: ArrayLike) -> np.ndarray:
    """
    The FGD table's coordinate ``t`` of ``cos theta``: ``cos theta`` itself for ``eta >= 1``; below 1, the
    critical angle (``cos theta_c = sqrt(1 - eta^2)``) at ``t = 1/2``, so that the Fresnel term's kink there
    falls on a node line of every row and interpolating between rows keeps it at the queried index's own
    critical angle (interpolated in ``cos theta``, the correction near the critical angle is off by up to
    0.35); linear in ``cos theta`` below it (TIR, ``F = 1``), and above it linear in
    ``sqrt(cos theta - cos theta_c)``, in which the Fresnel term (a function of
    ``eta cos theta_t = sqrt(cos^2 theta - cos^2 theta_c)``) is smooth: linear in ``cos theta`` there, the
    correction ``FGD - F`` inherited F's square-root edge and was off by up to 0.3 just past the critical
    angle (``alpha`` 0.05 to 0.2, ``eta = 0.8``).
    """
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    c_c = _critical_cos(eta)
    below = 0.5 * c / np.maximum(c_c, 1e-12)
    above = 0.5 + 0.5 * np.sqrt(np.maximum(c - c_c, 0.0) / np.maximum(1.0 - c_c, 1e-12))
    return np.where(c_c > 0.0, np.where(c <= c_c, below, above), c)


def fgd_cos_from_coordinate(t: ArrayLike, eta: ArrayLike) -> np.ndarray:
    """The inverse of :func:`fgd_cos_coordinate`."""
    t = np.asarray(t, dtype=np.float64)
    c_c = _critical_cos(eta)
    warped = np.where(t <= 0.5, 2.0 * t * c_c, c_c + (2.0 * t - 1.0) ** 2 * (1.0 - c_c))
    return np.where(c_c > 0.0, warped, t)


def fgd_alpha_nodes() -> np.ndarray:
    return np.linspace(0.0, 1.0, FGD_ALPHA_COUNT)


def fgd_eta_nodes() -> np.ndarray:
    return ETA_TABLE_MAX ** np.linspace(-1.0, 1.0, FGD_ETA_COUNT)


def _reflection_quadrature(cos_theta, alpha):
    """
    Deterministic quadrature of the GGX reflection lobe: for incidence ``cos_theta`` (shape ``(C,)``) and
    roughness ``alpha`` (``(A,)``), the weights ``w`` and half-angle cosines ``i.h`` (``(A, C, M*M)``) with
    ``int D G F (i.h) / cos_i d omega_h = sum w F(i.h)``: normals drawn from ``D cos theta_h`` on a
    midpoint grid, reflections below the horizon weighted 0.
    """
    M = FGD_QUADRATURE
    u1, u2 = np.meshgrid((np.arange(M) + 0.5) / M, (np.arange(M) + 0.5) / M, indexing="ij")
    u1, u2 = u1.ravel(), u2.ravel()
    a = np.asarray(alpha, dtype=np.float64)[:, None, None]
    tan2 = a * a * u1 / (1.0 - u1)
    cos_h = 1.0 / np.sqrt(1.0 + tan2)
    sin_h = np.sqrt(np.maximum(1.0 - cos_h**2, 0.0))
    phi = 2.0 * np.pi * u2
    c = np.maximum(np.asarray(cos_theta, dtype=np.float64), FGD_COS_FLOOR)[None, :, None]
    s = np.sqrt(1.0 - c * c)
    i_dot_h = s * sin_h * np.cos(phi) + c * cos_h
    cos_o = 2.0 * i_dot_h * cos_h - c  # o = 2 (i.h) h - i
    alpha_b = np.broadcast_to(a, cos_o.shape)
    G = microfacet.smith_G1(np.broadcast_to(c, cos_o.shape), alpha_b) * microfacet.smith_G1(cos_o, alpha_b)
    weight = np.where((cos_o > 0.0) & (i_dot_h > 0.0), G * i_dot_h / (c * cos_h), 0.0) / (M * M)
    return weight, np.clip(i_dot_h, 0.0, 1.0)


def generate_fgd_correction() -> np.ndarray:
    """
    ``FGD(cos theta, alpha, eta) - F(cos theta, eta)``, unpolarised, for a rough dielectric interface of
    relative index ``eta`` (both sides of 1: light from below included), shape
    ``(FGD_ETA_COUNT, FGD_ALPHA_COUNT, FGD_COS_COUNT)``. ``FGD`` is the directional albedo of the GGX
    reflection (separable Smith G, Eq. 19 of Fourneau et al.), Belcour's (2018) tabulated term.

    One correction for both polarisations: a microfacet's s and p are not the surface's, so the rough
    part is not split; at normal incidence FGD_s = FGD_p then, as the inverse method assumes.
    """
    alphas = fgd_alpha_nodes()
    table = np.empty((FGD_ETA_COUNT, FGD_ALPHA_COUNT, FGD_COS_COUNT))
    plain = _reflection_quadrature(fgd_cos_nodes(), alphas)  # the rows eta >= 1 share their nodes
    for j, eta in enumerate(fgd_eta_nodes()):
        cos_nodes = fgd_cos_from_coordinate(fgd_cos_nodes(), eta)
        weight, i_dot_h = plain if eta >= 1.0 else _reflection_quadrature(cos_nodes, alphas)
        smooth_c = np.maximum(cos_nodes, FGD_COS_FLOOR)
        F = _fresnel_dielectric_mean(i_dot_h, eta)  # (A, C, M*M)
        table[j] = (weight * F).sum(axis=-1) - fresnel_sp(smooth_c, eta).mean(axis=0)[None, :]
    table[:, fgd_alpha_nodes() == 0.0, :] = 0.0  # the smooth limit in closed form: FGD = F (see smooth_lobe_moments)
    return table


def generate_ggx_moments() -> np.ndarray:
    """
    ``[E, cbar_d]`` over (alpha, cos theta), shape ``(2, FGD_ALPHA_COUNT, FGD_COS_COUNT)``: the GGX
    reflection lobe's directional albedo with ``F = 1`` and its mean half-angle cosine ``E[i.h]``, for
    the conductors' ``FGD ~ E F(cbar_d)``.
    """
    weight, i_dot_h = _reflection_quadrature(fgd_cos_nodes(), fgd_alpha_nodes())
    E = weight.sum(axis=-1)
    cbar = (weight * i_dot_h).sum(axis=-1) / np.maximum(E, 1e-300)
    cbar = np.where(E > 0.0, cbar, np.maximum(fgd_cos_nodes(), FGD_COS_FLOOR)[None, :])
    smooth = fgd_alpha_nodes() == 0.0
    E[smooth], cbar[smooth] = smooth_lobe_moments(fgd_cos_nodes())
    return np.stack([E, cbar])


def smooth_lobe_moments(cos_theta: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """
    ``[E, cbar_d]`` of the GGX reflection lobe in its smooth limit ``alpha -> 0``, in closed form: the lobe
    is the mirror's Dirac, ``E = 1`` and ``i.h = cos theta`` (``FGD = F(cos theta)``, Fresnel's own term).

    The tables' ``alpha = 0`` rows are these, not the quadrature's: its grazing node is evaluated at
    :data:`FGD_COS_FLOOR` (the integrand's ``1 / cos theta``), so ``cbar_d`` there was ``1e-3`` instead of
    0 and, interpolated linearly in ``cos theta``, a bare smooth conductor was off Fresnel by up to 8e-3 at
    89.9 degrees (``eta = 4, kappa -> 0``; 1.2e-3 at 89 degrees on the validation's stacks). With these
    rows the interpolation reproduces ``cbar_d = cos theta`` exactly (a linear function) and the smooth
    limit is exact Fresnel at every angle, for conductors and dielectrics, TIR included.
    """
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    return np.ones_like(c), c


def _axis(value, count: int, lo: float, hi: float):
    """Node index and fraction of ``value`` on ``count`` uniform nodes over [lo, hi], clamped (texelFetch twin)."""
    x = (np.clip(np.asarray(value, dtype=np.float64), lo, hi) - lo) / (hi - lo) * (count - 1)
    i = np.minimum(np.floor(x).astype(np.int64), count - 2)
    return i, x - i


luts.register("lobes_fgd_correction", generate_fgd_correction, {
    "quantity": "FGD - Fresnel (unpolarised) of a rough GGX dielectric interface, eta x alpha x cos theta "
    "(explorer.physics.lobes; Belcour 2018's FGD term)",
    "eta": "4 ** linspace(-1, 1, 33)", "alpha": "linspace(0, 1, 16)",
    "cos_theta": "t = linspace(0, 1, 33) of explorer.physics.lobes.fgd_cos_coordinate (critical angle at t = 1/2 for eta < 1, sqrt(cos - cos_c) above it)",
    "quadrature": "48 x 48 midpoints of the GGX normal distribution",
    "smooth_limit": "alpha = 0 row in closed form: 0 (FGD = F)",
    "resolution_nm": None,  # no wavelength axis
    "shape": [33, 16, 33],
})
luts.register("lobes_ggx_moments", generate_ggx_moments, {
    "quantity": "GGX reflection lobe albedo (F = 1) and mean half-angle cosine, [E, cbar_d] x alpha x cos theta "
    "(explorer.physics.lobes: conductors' FGD ~ E F(cbar_d))",
    "alpha": "linspace(0, 1, 16)", "cos_theta": "linspace(0, 1, 33)",
    "quadrature": "48 x 48 midpoints of the GGX normal distribution",
    "smooth_limit": "alpha = 0 row in closed form: E = 1, cbar_d = cos theta (explorer.physics.lobes_fgd.smooth_lobe_moments)",
    "resolution_nm": None,  # no wavelength axis
    "shape": [2, 16, 33],
})
