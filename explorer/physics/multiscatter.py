"""
Multiple scattering among the microfacets of a rough Bragg layer, for the explorer's model: an energy
compensation after Kulla & Conty (2017), generalised to facets that reflect a spectrum ``R_lambda(theta_d)``
and let the rest through ballistically (Fourneau et al. 2024, Section 4.2.1). Numpy only; the GLSL twins of
the same names are in ``shaders/lib/layered.glsl``. Measured against the microsurface random walk
(:mod:`explorer.physics.microsurface`) in ``docs/layered_validation.md``.

Three changes to a layer's single-scattering terms (Eq. 17, Eq. 28), per wavelength, each exact for
facets that reflect everything (the furnace, where it is Kulla & Conty's) and for facets that let
everything through (where the layer is invisible):

1. **Transparent occluders.** A facet that masks or shadows another is itself a Bragg mirror: it lets
   ``1 - R`` of the light through. In Smith's model (uncorrelated heights) the occluders a ray meets form
   a Poisson process in ``-ln C1(h)`` of rate ``Lambda`` (Heitz et al. 2016); keeping only those that stop
   the ray thins it. Along the incoming ray and through the layer (2) an occluder stops the light with
   ``rho(theta) = 1 - f_t cos theta / G1``, the reflectance of the facets the direction sees (Eq. 28 divided
   by Eq. 30's ``G1``): ``G_eff = 1 / (1 + Lambda rho)`` (:func:`effective_masking`). A reflected ray that
   leaves the heightfield gets past an occluder only by crossing it twice (into the occluder, back out
   through the microsurface behind it), so there an occluder stops ``s = rho (2 - rho)``
   (:func:`occluder_stop`), and Eq. 17's ``G1(i) G1(o)`` becomes the height-correlated
   ``G2 = 1 / (1 + Lambda_i s_i + Lambda_o s_o)`` (:func:`correlated_masking_over_cos`; with white facets,
   the walk's own first order, Heitz et al. 2016).
   Against the walk's first order (``python3 -m explorer.dev.multiscatter_orders``) this is within ~0.01 up
   to alpha = 1 and 70 deg where the separable ``G_eff(i) G_eff(o)`` is up to 0.03 above it.
2. **Ballistic transmission** through every occluder: ``(1 - rho) G_eff^2`` instead of Eq. 28's
   ``(1 - rho) G1`` (:func:`ballistic_transmissivity`; within 1e-2 of the random walk for flat ``R`` at
   ``alpha <= 1``, ``theta <= 70 deg``).
3. **What is still missing**, ``m(theta) = 1 - E_r(theta) - t_b(theta)`` (``E_r`` the directional albedo
   of the reflection of (1), ``t_b`` of (2)), is light scattered among the facets: a part ``r`` leaves
   upward, as Kulla & Conty's lobe ``r m(i) m(o) / (pi m_avg)`` (whose albedo is ``r m(i)``, reciprocal),
   and ``1 - r`` downward, added to the layer's transmission seen by the layers below and the base
   (:func:`compensated_transmissivity`). ``r`` is the facets' hemispherical reflectance ``R_avg``:
   with ``R = 1`` all goes up (Kulla & Conty's ``E_avg`` normalisation), with small ``R`` light scattered
   among mostly transparent facets leaves mostly downward (the random walk gives ``r ~ R`` within ~0.1).

Kulla & Conty colour their lobe with ``F_avg^2 E_avg / (1 - F_avg (1 - E_avg))``; here the colour comes
from ``m`` itself (per wavelength: the light a Bragg facet does not reflect once is not lost, most of it
crosses) and ``r``. All of it is per wavelength, before the conversion to RGB.

References
----------
Kulla, Conty (2017). Revisiting physically based shading at Imageworks. SIGGRAPH 2017 course: Physically
Based Shading in Theory and Practice. The energy compensation lobe ``(1 - E(mu_i))(1 - E(mu_o)) / (pi (1 -
E_avg))`` and its Fresnel colour ``F_ms``.
Heitz, Hanika, d'Eon, Dachsbacher (2016). Multiple-scattering microfacet BSDFs with the Smith model. ACM
TOG 35(4). Smith's occlusion as a process along the ray (the heights' ``C1``).
Fourneau, Pacanowski, Barla (2024). Computer Graphics Forum 43(2). Eqs. 17-19, 28-30, 34.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import microfacet
from explorer.tables import luts

#: Rows of a layer's compensation table: theta = k * COMPENSATION_STEP_DEG, k = 0..45 (in the host).
COMPENSATION_STEP_DEG = 2.0
COMPENSATION_ROWS = int(round(90.0 / COMPENSATION_STEP_DEG)) + 1
#: The quadrature of a row's reflection albedo: k x k midpoints of the visible-normal sampler's square.
QUADRATURE_SIDE = 16


def smith_lambda(cos_theta: ArrayLike, alpha: ArrayLike) -> np.ndarray:
    """Smith's ``Lambda`` for GGX, ``(sqrt(c^2 + alpha^2 s^2) - c) / (2 c)`` (``G1 = 1 / (1 + Lambda)``, Eq. 19); large at grazing."""
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), 1e-6, 1.0)
    alpha = np.asarray(alpha, dtype=np.float64)
    return (np.sqrt(c * c + alpha * alpha * (1.0 - c * c)) - c) / (2.0 * c)


def occluder_reflectance(transmissivity: ArrayLike, cos_theta: ArrayLike, alpha: ArrayLike) -> np.ndarray:
    """
    ``rho = 1 - f_t cos theta / G1``: the mean Yeh reflectance of the facets seen along a direction (Eq. 28's
    integrated transmissivity ``transmissivity`` over its total weight ``G1``, Eq. 30), clipped to [0, 1].
    ``transmissivity`` has the wavelengths on its last axis; ``cos_theta`` broadcasts with the others.
    """
    G1 = microfacet.smith_G1(cos_theta, alpha)[..., None]
    t = np.asarray(transmissivity, dtype=np.float64)
    return np.clip(1.0 - t / np.maximum(G1, 1e-12), 0.0, 1.0)


def effective_masking(cos_theta: ArrayLike, alpha: ArrayLike, rho: ArrayLike) -> np.ndarray:
    """Smith masking by occluders that reflect ``rho`` and let the rest through: ``1 / (1 + Lambda rho)`` (``G1`` at ``rho = 1``)."""
    return 1.0 / (1.0 + smith_lambda(cos_theta, alpha)[..., None] * np.asarray(rho, dtype=np.float64))


def ballistic_transmissivity(rho: ArrayLike, masking: ArrayLike) -> np.ndarray:
    """The light crossing the layer in its own direction through every facet it meets: ``(1 - rho) G_eff^2``."""
    return (1.0 - np.asarray(rho)) * np.asarray(masking) ** 2


def hemispherical_average(table: ArrayLike, theta: ArrayLike) -> np.ndarray:
    """``2 int_0^{pi/2} X(theta) cos theta sin theta d theta`` of a per-angle table (rows ``theta``, radians), trapezoidal."""
    theta = np.asarray(theta, dtype=np.float64)
    weight = np.cos(theta) * np.sin(theta)
    return 2.0 * np.trapezoid(np.asarray(table, dtype=np.float64) * weight[:, None], theta, axis=0)


def compensation_theta() -> np.ndarray:
    """The rows of a compensation table (radians)."""
    return np.radians(np.arange(COMPENSATION_ROWS) * COMPENSATION_STEP_DEG)


@functools.lru_cache(maxsize=8)
def _quadrature(alpha: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per row: the mirrored directions' cosines, the half-vector angle cosines, and which stay above (k*k each)."""
    k = QUADRATURE_SIDE
    u1, u2 = np.meshgrid((np.arange(k) + 0.5) / k, (np.arange(k) + 0.5) / k)
    theta = np.maximum(compensation_theta(), 1e-4)
    theta[-1] = np.radians(89.5)  # grazing: the row's albedo is continued from just above the horizon
    i = np.stack([np.sin(theta), 0.0 * theta, np.cos(theta)], axis=-1)
    v = np.broadcast_to(i[:, None, :], (theta.size, k * k, 3))
    m = microfacet.sample_ggx_visible_normal(v, alpha, np.broadcast_to(u1.ravel(), (theta.size, k * k)),
                                             np.broadcast_to(u2.ravel(), (theta.size, k * k)))
    cos_d = np.clip(np.sum(v * m, axis=-1), 0.0, 1.0)
    o_z = 2.0 * cos_d * m[..., 2] - i[:, 2:3]
    return o_z, cos_d, o_z > 0.0


def reflection_albedos(reflectance: ArrayLike, transmissivity: ArrayLike, theta: ArrayLike, alpha: float,
                       exits: list) -> tuple[list, list]:
    """
    A layer's reflection albedos at the rows of :func:`compensation_theta` (host angles), each weighted by an
    exit factor ``W(theta_o)`` of the reflected direction (rows of ``theta``, shape (rows, 471), or ``None``
    for 1): ``E[R(theta_d) w W(theta_o)]`` over the normals visible from ``i`` (16 x 16 stratified), with
    ``w = (1 + Lambda_i) G2`` (transparent occluders, height-correlated: :func:`correlated_masking_over_cos`)
    and with Eq. 17's ``w = G1(o)`` (opaque separable occluders: single scattering as published).

    Returns
    -------
    correlated, separable : list of ndarray, shape (COMPENSATION_ROWS, 471), float64
        One per exit factor.
    """
    alpha = float(microfacet.check_alpha(alpha))
    R = np.asarray(reflectance, dtype=np.float64)
    t = np.asarray(transmissivity, dtype=np.float64)
    theta = np.asarray(theta, dtype=np.float64)
    step = theta[1] - theta[0]
    rows = compensation_theta()
    cos_rows = np.cos(rows)
    rho_rows = occluder_reflectance(_at(t, rows, step), cos_rows, alpha)
    o_z, cos_d, above = _quadrature(alpha)
    # Nearest table rows (0.25 deg) for the quadrature's angles: a gather, not an interpolation (float32, all rows at once).
    row_o = np.rint(np.arccos(np.clip(o_z, 0.0, 1.0)) / step).astype(np.int64).ravel()
    row_d = np.rint(np.arccos(cos_d) / step).astype(np.int64).ravel()
    t32, R32 = t.astype(np.float32), R.astype(np.float32)
    shape = o_z.shape + (R.shape[1],)
    oz = np.clip(o_z, 1e-6, 1.0).ravel()
    G1_o = microfacet.smith_G1(oz, alpha).astype(np.float32)[:, None]
    lam_o = smith_lambda(oz, alpha).astype(np.float32).reshape(o_z.shape + (1,))
    rho_o = np.clip(1.0 - t32[row_o] / np.maximum(G1_o, np.float32(1e-12)), 0.0, 1.0)
    stop_o = (rho_o * (2.0 - rho_o)).reshape(shape)
    lam_i = smith_lambda(np.maximum(cos_rows, np.cos(np.radians(89.5))), alpha).astype(np.float32)[:, None, None]
    stop_i = occluder_stop(rho_rows).astype(np.float32)[:, None, :]
    R_d = R32[row_d].reshape(shape)
    # Eq. 17 with correlated_masking_over_cos for G1 G1: f cos / pdf = R G2 / G1(i) = R (1 + Lambda_i) G2.
    weight = R_d * (above[..., None] * (1.0 + lam_i) / (1.0 + lam_i * stop_i + lam_o * stop_o))
    separable = R_d * (above[..., None] * G1_o.reshape(o_z.shape + (1,)))
    correlated_out, separable_out = [], []
    for W in exits:
        if W is None:
            correlated_out.append(weight.mean(axis=1, dtype=np.float64))
            separable_out.append(separable.mean(axis=1, dtype=np.float64))
            continue
        W_o = np.asarray(W, dtype=np.float32)[row_o].reshape(shape)
        correlated_out.append((weight * W_o).mean(axis=1, dtype=np.float64))
        separable_out.append((separable * W_o).mean(axis=1, dtype=np.float64))
    return correlated_out, separable_out


def _at(table: np.ndarray, angle: np.ndarray, step: float) -> np.ndarray:
    """Linear interpolation of a table with rows every ``step`` radians from 0 at ``angle``."""
    x = np.clip(angle, 0.0, step * (table.shape[0] - 1)) / step
    k = np.minimum(np.floor(x).astype(np.int64), table.shape[0] - 2)
    f = (x - k)[..., None]
    return table[k] * (1.0 - f) + table[k + 1] * f


@dataclass(frozen=True)
class LayerTerms:
    """
    A rough Bragg layer's albedos with multiple scattering, per wavelength (471, the last axis), at the rows of
    :func:`compensation_theta` (host angles); the layer is the same seen from either side (Smith's heights are
    symmetric), so each holds for light arriving from above or below.

    Attributes
    ----------
    reflection : ndarray, shape (COMPENSATION_ROWS, 471)
        ``E_r``: reflected once, occluders transparent (1).
    ballistic : ndarray, shape (COMPENSATION_ROWS, 471)
        ``t_b``: crossed without a reflection (2).
    missing : ndarray, shape (COMPENSATION_ROWS, 471)
        ``m``: scattered among the facets (3); the facets' absorption taken out for absorbing layers.
    up : ndarray, shape (COMPENSATION_ROWS, 471)
        ``r``: the part of ``m`` that leaves upward (:func:`upward_share`, from the random walk).
    """

    reflection: np.ndarray = field(repr=False)
    ballistic: np.ndarray = field(repr=False)
    missing: np.ndarray = field(repr=False)
    up: np.ndarray = field(repr=False)

    @property
    def reflected(self) -> np.ndarray:
        """All the light the layer sends back: ``E_r + r m``."""
        return self.reflection + self.up * self.missing

    @property
    def transmitted(self) -> np.ndarray:
        """All the light that crosses it: ``t_b + (1 - r) m``."""
        return self.ballistic + (1.0 - self.up) * self.missing


def layer_terms(reflectance: ArrayLike, transmissivity: ArrayLike, theta: ArrayLike, alpha: float,
                lossless_transmissivity: ArrayLike | None = None) -> LayerTerms:
    """
    A layer's :class:`LayerTerms` from its single-scattering tables.

    Parameters
    ----------
    reflectance, transmissivity : array_like, shape (rows, 471)
        Yeh's ``R_lambda(theta)`` and Eq. 28's ``f_t cos theta`` at the angles ``theta`` (the layer tables).
    theta : array_like, shape (rows,)
        Their angles (radians, uniform from 0).
    alpha : float
        The layer's roughness.
    lossless_transmissivity : array_like, optional
        For absorbing facets (``T < 1 - R``): Eq. 28 with ``1 - R``. Light scattered among the facets meets
        one more facet at least, so ``m`` is the lossless one times the facets' hemispherical albedo
        ``R + T`` (``(f_t^lossless - f_t) / G1`` is what one crossing absorbs): it never puts back what a facet absorbed.
    """
    alpha = float(microfacet.check_alpha(alpha))
    theta = np.asarray(theta, dtype=np.float64)
    step = theta[1] - theta[0]
    rows = compensation_theta()
    cos_rows = np.cos(rows)
    t = np.asarray(transmissivity, dtype=np.float64)
    rho = occluder_reflectance(_at(t, rows, step), cos_rows, alpha)
    ballistic = ballistic_transmissivity(rho, effective_masking(cos_rows, alpha, rho))
    (E_r,), _ = reflection_albedos(reflectance, t, theta, alpha, [None])
    if lossless_transmissivity is None:
        missing = np.clip(1.0 - E_r - ballistic, 0.0, 1.0)
        rho_share = rho
    else:
        t0 = np.asarray(lossless_transmissivity, dtype=np.float64)
        rho0 = occluder_reflectance(_at(t0, rows, step), cos_rows, alpha)
        (E_r0,), _ = reflection_albedos(reflectance, t0, theta, alpha, [None])
        lossless = np.clip(1.0 - E_r0 - ballistic_transmissivity(rho0, effective_masking(cos_rows, alpha, rho0)), 0.0, 1.0)
        G1 = microfacet.smith_G1(cos_rows, alpha)[:, None]
        absorbed = np.clip((_at(t0, rows, step) - _at(t, rows, step)) / np.maximum(G1, 1e-12), 0.0, 1.0)
        facet_albedo = np.clip(1.0 - hemispherical_average(absorbed, rows), 0.0, 1.0)
        missing = np.minimum(lossless * facet_albedo, np.clip(1.0 - E_r - ballistic, 0.0, 1.0))
        rho_share = rho0
    up = upward_share(alpha, rho_share, rows)
    return LayerTerms(E_r, ballistic, missing, up)


# --------------------------------------------------------------------------------------------------
# The upward share of the light scattered among the facets, from the random walk of grey facets

#: The share table's nodes: roughness, the facets' reflectance seen along the direction (``rho``), host angle.
SHARE_ALPHAS = tuple(round(0.1 * k, 1) for k in range(1, 11))
SHARE_RHOS = (0.1, 0.25, 0.4, 0.55, 0.7, 0.85, 1.0)
SHARE_THETA_DEG = (0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 88.0)
#: Paths per node of the share table's walk.
SHARE_PATHS = 16000
SHARE_SEED = 2017


def generate_upward_share() -> np.ndarray:
    """
    ``r(alpha, rho, theta)``: of the light a layer of grey facets (``R = rho`` at every angle, ``T = 1 - R``)
    scatters among its facets, ``m = 1 - E_r - t_b``, the part that leaves upward, ``(up_walk - E_r) / m``, with
    ``up_walk`` the random walk's reflected light (:func:`explorer.physics.microsurface.walk`, :data:`SHARE_PATHS`
    paths per node, seeded) and ``E_r``, ``t_b`` this module's first-order terms. Clipped to [0, 1]; 1 where
    ``m < 1e-3`` (nothing to share).
    """
    from explorer.physics import microsurface

    rng = np.random.default_rng(SHARE_SEED)
    share = np.ones((len(SHARE_ALPHAS), len(SHARE_RHOS), len(SHARE_THETA_DEG)))
    node_rows = np.rint(np.asarray(SHARE_THETA_DEG) / COMPENSATION_STEP_DEG).astype(np.int64)
    theta_nodes = np.radians(SHARE_THETA_DEG)
    for a, alpha in enumerate(SHARE_ALPHAS):
        filt = microfacet.transmission_filter_table(alpha)
        R = np.broadcast_to(np.asarray(SHARE_RHOS), (filt.weights.shape[0], len(SHARE_RHOS)))
        t = filt.weights @ (1.0 - R)
        theta = np.radians(np.arange(filt.weights.shape[0]) * 0.25)
        step = theta[1] - theta[0]
        rows = compensation_theta()
        rho = occluder_reflectance(_at(t, rows, step), np.cos(rows), alpha)
        ballistic = ballistic_transmissivity(rho, effective_masking(np.cos(rows), alpha, rho))
        (E_r,), _ = reflection_albedos(R, t, theta, alpha, [None])
        m = 1.0 - E_r - ballistic
        for r, value in enumerate(SHARE_RHOS):
            n = SHARE_PATHS * len(SHARE_THETA_DEG)
            which = np.repeat(np.arange(len(SHARE_THETA_DEG)), SHARE_PATHS)
            d = np.stack([-np.sin(theta_nodes[which]), 0.0 * which, -np.cos(theta_nodes[which])], axis=-1)
            _, _, _, up, alive, _, _ = microsurface.walk(d, np.ones((n, 1)), np.ones((n, 1)), alpha,
                                                        lambda c, rows_, v=value: np.full((rows_.size, 1), v), rng)
            up_walk = np.bincount(which, weights=(up & alive).astype(np.float64), minlength=len(SHARE_THETA_DEG)) / SHARE_PATHS
            m_nodes = m[node_rows, r]
            share[a, r] = np.where(m_nodes > 1e-3, np.clip((up_walk - E_r[node_rows, r]) / np.maximum(m_nodes, 1e-3), 0.0, 1.0), 1.0)
    return share


luts.register("multiscatter_upward_share", generate_upward_share, {
    "quantity": "the upward share of the light grey Bragg facets scatter among themselves, alpha x rho x theta "
    "(explorer.physics.multiscatter: the random walk of Heitz et al. 2016 against the first-order terms)",
    "alpha": list(SHARE_ALPHAS), "rho": list(SHARE_RHOS), "theta_deg": list(SHARE_THETA_DEG),
    "paths": SHARE_PATHS, "seed": SHARE_SEED, "quadrature": f"{QUADRATURE_SIDE} x {QUADRATURE_SIDE} visible normals",
    "resolution_nm": None,
    "shape": [len(SHARE_ALPHAS), len(SHARE_RHOS), len(SHARE_THETA_DEG)],
})


@functools.lru_cache(maxsize=1)
def _share_table() -> np.ndarray:
    return luts.load("multiscatter_upward_share")


def upward_share(alpha: float, rho: ArrayLike, theta: ArrayLike) -> np.ndarray:
    """
    ``r``: the share table (:func:`generate_upward_share`) interpolated linearly in ``alpha``, ``rho`` and
    ``theta`` (radians, broadcast with ``rho``'s leading axes; ``rho`` has the wavelengths last). Below the
    first roughness node the share is that node's (it barely matters: ``m`` vanishes with ``alpha``); ``rho``
    is clamped to the nodes' range.
    """
    table = _share_table()
    rho = np.asarray(rho, dtype=np.float64)
    xa = np.interp(float(alpha), SHARE_ALPHAS, np.arange(len(SHARE_ALPHAS)))
    a0 = min(int(np.floor(xa)), len(SHARE_ALPHAS) - 2)
    fa = xa - a0
    plane = table[a0] * (1.0 - fa) + table[a0 + 1] * fa  # (rho, theta)
    xt = np.interp(np.degrees(np.asarray(theta, dtype=np.float64)), SHARE_THETA_DEG, np.arange(len(SHARE_THETA_DEG)))
    t0 = np.minimum(np.floor(xt).astype(np.int64), len(SHARE_THETA_DEG) - 2)
    ft = (xt - t0)[..., None]
    xr = np.interp(rho, SHARE_RHOS, np.arange(len(SHARE_RHOS)))
    r0 = np.minimum(np.floor(xr).astype(np.int64), len(SHARE_RHOS) - 2)
    fr = xr - r0
    t0 = np.broadcast_to(t0[..., None], rho.shape)
    ft = np.broadcast_to(ft, rho.shape)
    low = plane[r0, t0] * (1.0 - ft) + plane[r0, t0 + 1] * ft
    high = plane[r0 + 1, t0] * (1.0 - ft) + plane[r0 + 1, t0 + 1] * ft
    return low * (1.0 - fr) + high * fr


def occluder_stop(rho: ArrayLike) -> np.ndarray:
    """
    The chance that an occluder stops a ray that leaves a heightfield: ``1 - (1 - rho)^2 = rho (2 - rho)``.
    Getting past an occluder of a heightfield crosses it twice (down through the occluder, back up through
    the microsurface behind it), each crossing letting ``1 - rho`` through (measured against the random walk's
    first order by ``python3 -m explorer.dev.multiscatter_orders``).
    """
    rho = np.asarray(rho, dtype=np.float64)
    return rho * (2.0 - rho)


def correlated_masking_over_cos(cos_i: ArrayLike, cos_o: ArrayLike, alpha: ArrayLike, stop_i: ArrayLike, stop_o: ArrayLike) -> np.ndarray:
    """
    Height-correlated masking-shadowing by occluders that stop ``stop`` of the light (:func:`occluder_stop`),
    over Eq. 17's cosines: ``G2 / (cos_i cos_o)`` with ``G2 = 1 / (1 + Lambda_i stop_i + Lambda_o stop_o)``
    (Heitz 2014's height-correlated form, Smith's occluders thinned to those that stop the ray), evaluated as
    ``2 / (2 c_i c_o + c_o stop_i (root_i - c_i) + c_i stop_o (root_o - c_o))`` with ``root = sqrt(c^2 + alpha^2 s^2)``:
    finite at grazing where ``stop > 0``. 0 below the horizon. Wavelengths on the last axis of ``stop``.
    """
    ci = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)[..., None]
    co = np.clip(np.asarray(cos_o, dtype=np.float64), 0.0, 1.0)[..., None]
    alpha = np.asarray(alpha, dtype=np.float64)
    root_i = np.sqrt(ci * ci + alpha * alpha * (1.0 - ci * ci)) - ci
    root_o = np.sqrt(co * co + alpha * alpha * (1.0 - co * co)) - co
    value = 2.0 / np.maximum(2.0 * ci * co + co * np.asarray(stop_i) * root_i + ci * np.asarray(stop_o) * root_o, 1e-12)
    return np.where((ci > 0.0) & (co > 0.0), value, 0.0)
