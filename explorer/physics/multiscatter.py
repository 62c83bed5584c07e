"""
Multiple scattering among the microfacets of a rough Bragg layer, for the explorer's model: the layer's
directional albedos (reflected, transmitted) with every bounce among facets that reflect a spectrum
``R_lambda(theta_d)`` and let the rest through ballistically (Fourneau et al. 2024, Section 4.2.1). Numpy
only. Measured against the microsurface random walk (:mod:`explorer.physics.microsurface`) in
``docs/layered_validation.md``.

Three changes to a layer's single-scattering terms (Eq. 17, Eq. 28), per wavelength, each exact for
facets that reflect everything (the furnace) and for facets that let everything through (where the layer
is invisible):

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
   upward and ``1 - r`` downward (:class:`LayerTerms`). ``r`` comes from the random walk itself
   (:func:`upward_share`): a few thousand paths walked once per roughness with facets that reflect half the
   light (:func:`walk_ensemble`), reweighted per wavelength by each event's ``R / 0.5`` or ``T / 0.5``. A
   path's geometry depends only on its choices, so this is the walk with the layer's own ``R_lambda(theta_d)``
   in expectation: the share follows the spectrum (light scattered twice is filtered twice), where a grey
   facets' share at the mean reflectance missed by up to 0.25 between two Bragg bands.

For the structure (:mod:`explorer.physics.multiscatter_stack`) these are a layer's albedos; the lobe the
explorer adds is built there. All of it is per wavelength, before the conversion to RGB.

References
----------
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
    rho_rows = occluder_reflectance(rows_at(t, rows, step), cos_rows, alpha)
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


def rows_at(table: np.ndarray, angle: np.ndarray, step: float) -> np.ndarray:
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
                lossless_transmissivity: ArrayLike | None = None, transmittance: ArrayLike | None = None) -> LayerTerms:
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
    transmittance : array_like, optional
        The facets' ``T_lambda`` (361, 471) when it is below ``1 - R`` (absorbing), for the upward share.
    """
    alpha = float(microfacet.check_alpha(alpha))
    theta = np.asarray(theta, dtype=np.float64)
    step = theta[1] - theta[0]
    rows = compensation_theta()
    cos_rows = np.cos(rows)
    t = np.asarray(transmissivity, dtype=np.float64)
    rho = occluder_reflectance(rows_at(t, rows, step), cos_rows, alpha)
    ballistic = ballistic_transmissivity(rho, effective_masking(cos_rows, alpha, rho))
    (E_r,), _ = reflection_albedos(reflectance, t, theta, alpha, [None])
    if lossless_transmissivity is None:
        missing = np.clip(1.0 - E_r - ballistic, 0.0, 1.0)
    else:
        t0 = np.asarray(lossless_transmissivity, dtype=np.float64)
        rho0 = occluder_reflectance(rows_at(t0, rows, step), cos_rows, alpha)
        (E_r0,), _ = reflection_albedos(reflectance, t0, theta, alpha, [None])
        lossless = np.clip(1.0 - E_r0 - ballistic_transmissivity(rho0, effective_masking(cos_rows, alpha, rho0)), 0.0, 1.0)
        G1 = microfacet.smith_G1(cos_rows, alpha)[:, None]
        absorbed = np.clip((rows_at(t0, rows, step) - rows_at(t, rows, step)) / np.maximum(G1, 1e-12), 0.0, 1.0)
        facet_albedo = np.clip(1.0 - hemispherical_average(absorbed, rows), 0.0, 1.0)
        missing = np.minimum(lossless * facet_albedo, np.clip(1.0 - E_r - ballistic, 0.0, 1.0))
    up = upward_share(reflectance, transmittance, alpha)
    return LayerTerms(E_r, ballistic, missing, up)


# --------------------------------------------------------------------------------------------------
# The upward share of the light scattered among the facets: the random walk's paths, reweighted per wavelength

#: Incidence angles (host, degrees) of the walked paths; the share is interpolated linearly between them.
SHARE_THETA_DEG = (0.0, 20.0, 40.0, 60.0, 75.0, 88.0)
#: Paths per angle, the facet events kept per path (later ones are taken as the reweighting's mean, 1), the seed.
SHARE_PATHS = 20000
SHARE_EVENTS = 10
SHARE_SEED = 2016
#: The walk's facets reflect with this probability; any other reflectance reweighs the same paths.
SHARE_SAMPLING_R = 0.5
#: The share is reweighted every this many nm and interpolated between (a ratio: smoother than ``R``).
SHARE_STEP_NM = 3


@functools.lru_cache(maxsize=8)
def walk_ensemble(alpha: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    The random walk's paths through a layer of roughness ``alpha`` (:func:`explorer.physics.microsurface.walk`)
    whose facets reflect with probability :data:`SHARE_SAMPLING_R`, :data:`SHARE_PATHS` per angle of
    :data:`SHARE_THETA_DEG`, seeded: only those scattered among the facets (left upward after two reflections or
    more, or downward after one or more). A path's geometry depends on its choices only, so the same paths serve
    every reflectance (:func:`upward_share`).

    Returns
    -------
    events : ndarray of int, shape (n, SHARE_EVENTS)
        Per facet event, its row in a 0.25-degree table of ``theta_d`` plus 361 when it reflected; 722 (a row of
        ones) after the path's last event.
    up : ndarray of bool, shape (n,)
    node : ndarray of int, shape (n,)
        The path's angle, an index into :data:`SHARE_THETA_DEG`.
    """
    from explorer.physics import microsurface

    rng = np.random.default_rng(SHARE_SEED)
    nodes = len(SHARE_THETA_DEG)
    n = SHARE_PATHS * nodes
    node = np.repeat(np.arange(nodes), SHARE_PATHS)
    theta = np.radians(np.asarray(SHARE_THETA_DEG))[node]
    count = np.zeros(n, dtype=np.int64)
    events = np.full((n, SHARE_EVENTS), 722, dtype=np.int64)

    def record(rows, cos_d, reflect):
        k = count[rows]
        kept = k < SHARE_EVENTS
        row = np.rint(np.arccos(np.clip(cos_d, 0.0, 1.0)) / microfacet.THETA_STEP).astype(np.int64)
        events[rows[kept], k[kept]] = row[kept] + 361 * reflect[kept]
        count[rows] += 1

    d = np.stack([-np.sin(theta), 0.0 * theta, -np.cos(theta)], axis=-1)
    _, _, _, up, alive, _, reflections = microsurface.walk(
        d, np.ones((n, 1)), np.ones((n, 1)), float(alpha),
        lambda cos_d, rows: np.full((rows.size, 1), SHARE_SAMPLING_R), rng, record=record)
    scattered = alive & (((reflections >= 2) & up) | ((reflections >= 1) & ~up))
    return events[scattered], up[scattered], node[scattered]


def upward_share(reflectance: ArrayLike, transmittance: ArrayLike | None, alpha: float) -> np.ndarray:
    """
    ``r``: of the light scattered among the facets, the part that leaves upward, per wavelength, at the rows of
    :func:`compensation_theta`: the walk's scattered paths (:func:`walk_ensemble`) weighted by each event's
    ``R / R_s`` (reflected) or ``T / (1 - R_s)`` (crossed), ``R_s`` :data:`SHARE_SAMPLING_R` (importance
    reweighting: the walk with these facets, in expectation), the upward ones over all.

    ``reflectance``, ``transmittance``: the facets' ``R_lambda`` and ``T_lambda`` (``None``: ``1 - R``) at
    ``theta_d = k * 0.25 deg``, shape (361, 471).
    """
    columns = np.unique(np.r_[np.arange(0, np.shape(reflectance)[1], SHARE_STEP_NM), np.shape(reflectance)[1] - 1])
    R = np.asarray(reflectance, dtype=np.float32)[:, columns]
    T = np.float32(1.0) - R if transmittance is None else np.asarray(transmittance, dtype=np.float32)[:, columns]
    factors = np.concatenate([T / np.float32(1.0 - SHARE_SAMPLING_R), R / np.float32(SHARE_SAMPLING_R),
                              np.ones((1, R.shape[1]), np.float32)])
    events, up, node = walk_ensemble(float(alpha))
    share = np.full((len(SHARE_THETA_DEG), R.shape[1]), 0.5)
    for k in range(len(SHARE_THETA_DEG)):
        at = np.flatnonzero(node == k)
        if at.size == 0:
            continue
        weight = factors[events[at, 0]]
        for j in range(1, SHARE_EVENTS):
            going = np.flatnonzero(events[at, j] != 722)  # only the paths with a j-th event (most have 2 or 3)
            if going.size == 0:
                break
            weight[going] *= factors[events[at[going], j]]
        upward = weight[up[at]].sum(axis=0, dtype=np.float64)
        total = weight.sum(axis=0, dtype=np.float64)
        share[k] = np.where(total > 0.0, upward / np.maximum(total, 1e-300), 0.5)
    wavelengths = np.arange(np.shape(reflectance)[1])
    share = np.stack([np.interp(wavelengths, columns, row) for row in share])
    rows = np.degrees(compensation_theta())
    return np.stack([np.interp(rows, SHARE_THETA_DEG, share[:, j]) for j in range(share.shape[1])], axis=-1)


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
