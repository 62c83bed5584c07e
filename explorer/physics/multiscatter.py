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
   a Poisson process in ``-ln C1(h)`` of rate ``Lambda`` (Heitz et al. 2016). A ray gets past an occluder by
   crossing the heightfield twice: into the occluder, whose facet faces the ray (a normal visible from
   ``-w``, below the horizon: steep facets met at large angles), reflecting ``rho_b``
   (:func:`occluder_reflectance_below`), then back out through the microsurface behind it, whose facets are
   those the direction sees, reflecting ``rho_a = 1 - f_t cos theta / G1`` (Eq. 28 divided by Eq. 30's
   ``G1``): it passes with ``p = (1 - rho_a)(1 - rho_b)`` (:func:`occluder_stop`). For grey facets
   ``rho_b = rho_a``; a Bragg facet's reflectance moves with the angle, and taking ``rho_a`` for both
   darkened a Bragg layer's first order by 5-8 % in luminance at ``alpha = 1`` against the walk.
   A ray that keeps its direction moves through the heights as a Markov chain (the second crossing lands
   it higher than the occluder was), solved once on a grid of heights (:func:`exit_probability`,
   :func:`chain_tables`): the first order reflects ``R`` at the first hit and leaves with the chain's exit
   probability from that hit's height (Eq. 17's ``G1(i) G1(o)`` replaced; at ``p = 0`` it is Heitz 2014's
   height-correlated ``G2``), or crosses there, passes an occluder under the layer, and is reflected by a
   later, lower facet it meets from above (the same chain; 0.06 of the albedo at 70 deg, ``alpha = 1``,
   ``R = 0.3``). For grey facets this first order is within 0.003 of the walk's at ``alpha = 1``,
   ``theta <= 70 deg``; with Bragg facets (the presets) within 0.001 in luminance.
2. **Ballistic transmission** through every occluder: ``(1 - rho_a)`` at the first hit times the chain's
   exit below (:func:`ballistic_transmissivity`), instead of Eq. 28's ``(1 - rho_a) G1``. For grey facets
   both are within 0.003 of the random walk's (``alpha = 1``, ``theta <= 70 deg``); pure thinning
   (``u^(Lambda s)``, no landing higher) was up to 0.017 low at 40 deg.
3. **What is still missing**, ``m(theta) = 1 - E_r(theta) - t_b(theta)`` (``E_r`` the directional albedo
   of the reflection of (1), ``t_b`` of (2)), is light scattered among the facets: a part ``r`` leaves
   upward and ``1 - r`` downward (:class:`LayerTerms`). ``r`` comes from the random walk itself
   (:func:`upward_share`), through the layer's own facets, with hero wavelengths: the share follows the
   spectrum (light scattered twice is filtered twice), where a grey
   facets' share at the mean reflectance missed by up to 0.25 between two Bragg bands.

For the structure (:mod:`explorer.physics.multiscatter_stack`) these are a layer's albedos; the lobe the
explorer adds is built there. All of it is per wavelength, before the conversion to RGB.

References
----------
Heitz, Hanika, d'Eon, Dachsbacher (2016). Multiple-scattering microfacet BSDFs with the Smith model. ACM
TOG 35(4). Smith's occlusion as a process along the ray (the heights' ``C1``).
Fourneau, Pacanowski, Barla (2024). Computer Graphics Forum 43(2). Eqs. 17-19, 28-30, 34.
Wilkie, Nawaz, Droske, Weidlich, Hanika (2014). Hero wavelength spectral sampling. Computer Graphics Forum
33(4). The upward share's walk.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
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


@functools.lru_cache(maxsize=8)
def _below_quadrature(alpha: float) -> np.ndarray:
    """Per row of :func:`compensation_theta`: the 0.25-degree rows of ``theta_d`` of the normals visible from ``-w``
    (a ray going up at the row's angle), k x k midpoints of the visible-normal sampler's square."""
    k = QUADRATURE_SIDE
    u1, u2 = np.meshgrid((np.arange(k) + 0.5) / k, (np.arange(k) + 0.5) / k)
    theta = np.maximum(compensation_theta(), 1e-4)
    v = np.stack([np.sin(theta), 0.0 * theta, -np.cos(theta)], axis=-1)
    v = np.broadcast_to(v[:, None, :], (theta.size, k * k, 3))
    m = microfacet.sample_ggx_visible_normal(v, alpha, np.broadcast_to(u1.ravel(), (theta.size, k * k)),
                                             np.broadcast_to(u2.ravel(), (theta.size, k * k)))
    return theta_d_row(np.sum(v * m, axis=-1))


def theta_d_row(cos_d: np.ndarray) -> np.ndarray:
    """The row of the facet tables' ``theta_d`` grid (:data:`explorer.physics.microfacet.THETA_STEP`) nearest each ``cos_d``."""
    return np.rint(np.arccos(np.clip(cos_d, 0.0, 1.0)) / microfacet.THETA_STEP).astype(np.int64)


def occluder_reflectance_below(transmittance: ArrayLike, alpha: float) -> np.ndarray:
    """
    ``rho_b``: the mean reflectance ``1 - T`` of the facets a ray going up at each row of
    :func:`compensation_theta` meets as occluders, the normals visible from ``-w`` (below the horizon; Heitz
    2018's sampler, as the walk draws them), whose ``theta_d`` is larger than the direction's own facets'.
    ``transmittance``: the facets' ``T_lambda`` at ``theta_d = k * 0.25 deg``, shape (361, 471). Shape
    (COMPENSATION_ROWS, 471). (A ray going straight up meets none: ``Lambda = 0`` there.)
    """
    rows = _below_quadrature(float(alpha))
    T = np.asarray(transmittance, dtype=np.float32)
    return np.clip(1.0 - T[rows].mean(axis=1, dtype=np.float64), 0.0, 1.0)


# --------------------------------------------------------------------------------------------------
# A ray that keeps its direction through the heightfield: the chain of its heights, solved

#: The chain's tables: nodes in ``G1 = 1 / (1 + Lambda)`` (the first a floor: grazing), in the pass
#: probability ``p`` per occluder, the heights ``u = C1(h)`` the exit probability is solved on, and the
#: Gauss-Legendre nodes of its two jumps.
CHAIN_G1 = np.r_[0.004, np.arange(1, 33) / 32.0]
CHAIN_PASS = np.linspace(0.0, 1.0, 21)
CHAIN_HEIGHTS = 65
CHAIN_NODES = 16


def exit_probability(lam: float, passing: np.ndarray) -> np.ndarray:
    """
    ``f(u)``: the chance that a ray going away from the microsurface at ``u = C1(h)`` (on the heights
    ``linspace(0, 1, CHAIN_HEIGHTS)``) leaves it, when each occluder lets it past with ``passing`` (one row per
    value). Smith's occluders along the ray (Heitz et al. 2016): it leaves with ``u^Lambda``, else meets one at
    ``u1 = u V^(-1/Lambda)`` (``V`` uniform in ``[u^Lambda, 1]``); it crosses it, is under the microsurface going
    toward it (heights flipped, ``1 - u``), meets it at ``1 - u2 = (1 - u1) W^(1/(1 + Lambda))``, crosses again
    and goes on away from ``u2 > u1``:
    ``f(u) = u^Lambda + p E[f(u2)]``, a linear system on the heights (linear interpolation between them).
    Pure thinning (``u^(Lambda (1 - p))``) leaves out the jump from ``u1`` to ``u2`` and loses up to 0.02 of the
    walk's ballistic transmission at 40 deg, ``alpha = 1``.
    """
    passing = np.atleast_1d(np.asarray(passing, dtype=np.float64))
    M, leave = _chain_kernel(lam)
    system = np.eye(leave.size)[None] - passing[:, None, None] * M[None]
    return np.linalg.solve(system, np.broadcast_to(leave[:, None], (passing.size, leave.size, 1)))[..., 0]


def _chain_kernel(lam: float) -> tuple[np.ndarray, np.ndarray]:
    """
    The chain of :func:`exit_probability` on its heights: ``M[j, k]``, the chance that a ray going away at height
    ``u_j`` meets an occluder and, past it, goes on away from ``u_k`` (linear interpolation's weights), and
    ``u^Lambda``, the chance it leaves.
    """
    u = np.linspace(0.0, 1.0, CHAIN_HEIGHTS)
    if lam <= 1e-9:
        return np.zeros((u.size, u.size)), np.ones(u.size)
    x, w = np.polynomial.legendre.leggauss(CHAIN_NODES)
    t, w = 0.5 * (x + 1.0), 0.5 * w
    leave = u**lam
    V = leave[:, None] + (1.0 - leave[:, None]) * t[None, :]
    u1 = np.clip(u[:, None] * V ** (-1.0 / lam), 0.0, 1.0)
    u2 = 1.0 - (1.0 - u1)[:, :, None] * t[None, None, :] ** (1.0 / (1.0 + lam))
    weight = (1.0 - leave)[:, None, None] * w[None, :, None] * w[None, None, :]
    position = u2 * (u.size - 1)
    k = np.clip(np.floor(position).astype(np.int64), 0, u.size - 2)
    frac = position - k
    M = np.zeros((u.size, u.size))
    rows = np.broadcast_to(np.arange(u.size)[:, None, None], k.shape)
    np.add.at(M, (rows, k), weight * (1.0 - frac))
    np.add.at(M, (rows, k + 1), weight * frac)
    return M, leave


@functools.lru_cache(maxsize=1)
def chain_tables() -> tuple[np.ndarray, np.ndarray]:
    """
    ``(first, through)`` over the nodes :data:`CHAIN_G1` and :data:`CHAIN_PASS`:

    - ``first[gi, pi, go, po]``: light coming in at ``Lambda_i`` reflected once, by a facet it meets coming in
      from above, and leaving along a direction of ``Lambda_o`` (per unit of that facet's ``R``). The facet is
      the first hit (height density ``(1 + Lambda_i) u^Lambda_i``) or, after crossing there and passing an
      occluder under the layer (``pi`` per loop), a later one, lower: the ballistic chain's hits from above,
      ``(I - pi M^T)^-1`` of the first's. From each, :func:`exit_probability` along ``o`` (``po`` per occluder).
      At ``pi = po = 0`` it is Heitz 2014's height-correlated ``(1 + Lambda_i) / (1 + Lambda_i + Lambda_o)``.
    - ``through[g, p]``: a ray that crossed at the first hit leaves below in its own direction (the ballistic
      transmission over the first crossing's ``1 - rho_a``): the chain from ``1 - u``.

    Solved once (a fraction of a second).
    """
    x, w = np.polynomial.legendre.leggauss(64)
    t, w = 0.5 * (x + 1.0), 0.5 * w
    lam = 1.0 / CHAIN_G1 - 1.0
    heights = np.linspace(0.0, 1.0, CHAIN_HEIGHTS)
    exits = np.stack([exit_probability(value, CHAIN_PASS) for value in lam])  # (go, po, heights)
    first = np.zeros((lam.size, CHAIN_PASS.size, lam.size, CHAIN_PASS.size))
    through = np.zeros((lam.size, CHAIN_PASS.size))
    for i, lam_i in enumerate(lam):
        start = 1.0 - t ** (1.0 / (1.0 + lam_i))  # the first hit's height (by inversion of its density), flipped
        through[i] = np.stack([np.interp(start, heights, row) for row in exits[i]]) @ w
        # The first hit's weights on the heights (the transpose of linear interpolation), as the ray below starts.
        position = start * (heights.size - 1)
        k = np.clip(np.floor(position).astype(np.int64), 0, heights.size - 2)
        q0 = np.bincount(k, w * (k + 1 - position), heights.size) + np.bincount(k + 1, w * (position - k), heights.size)
        M, _ = _chain_kernel(lam_i)
        system = np.eye(heights.size)[None] - CHAIN_PASS[:, None, None] * M.T[None]
        below = np.linalg.solve(system, np.broadcast_to(q0[:, None], (CHAIN_PASS.size, heights.size, 1)))[..., 0]
        first[i] = np.einsum("ph,oqh->poq", below[:, ::-1], exits)  # hits from above at u = 1 - (the ray's start below)
    return first, through


def _chain_weights(g: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The node below ``g`` in :data:`CHAIN_G1` and the weight of the one above (clamped to the table)."""
    g = np.clip(np.asarray(g, dtype=np.float64), CHAIN_G1[0], 1.0)
    k = np.clip(np.searchsorted(CHAIN_G1, g, side="right") - 1, 0, CHAIN_G1.size - 2)
    return k, (g - CHAIN_G1[k]) / (CHAIN_G1[k + 1] - CHAIN_G1[k])


def _pass_lookup(table: np.ndarray, passing: np.ndarray) -> np.ndarray:
    """``table[..., p]`` (last axis over :data:`CHAIN_PASS`) at ``passing`` (broadcast on a new last axis), linearly."""
    x = np.clip(passing, 0.0, 1.0) * (CHAIN_PASS.size - 1)
    k = np.minimum(np.floor(x).astype(np.int64), CHAIN_PASS.size - 2)
    f = (x - k).astype(table.dtype)
    low = np.take_along_axis(table, k, axis=-1)
    return low * (1.0 - f) + np.take_along_axis(table, k + 1, axis=-1) * f


def ballistic_transmissivity(cos_theta: ArrayLike, alpha: float, rho_a: ArrayLike, rho_b: ArrayLike) -> np.ndarray:
    """
    The light crossing the layer in its own direction through every facet it meets: ``(1 - rho_a)`` at the
    first hit, then :func:`chain_tables`' ``through`` with ``p = (1 - rho_a)(1 - rho_b)`` per occluder below.
    Wavelengths on the last axis of ``rho_a``, ``rho_b``.
    """
    _, through = chain_tables()
    k, f = _chain_weights(microfacet.smith_G1(cos_theta, alpha))
    row = through[k] * (1.0 - f)[..., None] + through[k + 1] * f[..., None]
    rho_a = np.asarray(rho_a, dtype=np.float64)
    passing = 1.0 - occluder_stop(rho_a, rho_b)
    return (1.0 - rho_a) * _pass_lookup(row, passing)


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
                       exits: list, transmittance: ArrayLike | None = None) -> tuple[list, list]:
    """
    A layer's reflection albedos at the rows of :func:`compensation_theta` (host angles), each weighted by an
    exit factor ``W(theta_o)`` of the reflected direction (rows of ``theta``, shape (rows, 471), or ``None``
    for 1): ``E[R(theta_d) w W(theta_o)]`` over the normals visible from ``i`` (16 x 16 stratified), with
    ``w`` the height chain's exit probability plus the light reflected under the layer (transparent occluders,
    the module docstring's (1)) and with Eq. 17's ``w = G1(o)`` (opaque separable occluders: single scattering as published).
    ``transmittance``: the facets' ``T_lambda`` (``None``: ``1 - R``), for the occluders' :func:`occluder_reflectance_below`.

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
    T = 1.0 - R if transmittance is None else np.asarray(transmittance, dtype=np.float64)
    below_rows = occluder_reflectance_below(T, alpha)
    o_z, cos_d, above = _quadrature(alpha)
    # Nearest table rows (0.25 deg) for the quadrature's angles: a gather, not an interpolation (float32, all rows at once).
    row_o = np.rint(np.arccos(np.clip(o_z, 0.0, 1.0)) / step).astype(np.int64).ravel()
    row_d = np.rint(np.arccos(cos_d) / step).astype(np.int64).ravel()
    t32, R32 = t.astype(np.float32), R.astype(np.float32)
    shape = o_z.shape + (R.shape[1],)
    oz = np.clip(o_z, 1e-6, 1.0).ravel()
    G1_o = microfacet.smith_G1(oz, alpha).astype(np.float32)[:, None]
    rho_o = np.clip(1.0 - t32[row_o] / np.maximum(G1_o, np.float32(1e-12)), 0.0, 1.0)
    below_o = rows_at(below_rows, theta, np.radians(COMPENSATION_STEP_DEG)).astype(np.float32)[row_o]
    stop_o = occluder_stop(rho_o, below_o).astype(np.float32).reshape(shape)
    stop_i = occluder_stop(rho_rows, below_rows).astype(np.float32)[:, None, :]
    R_d = R32[row_d].reshape(shape)
    # Reflected once by a facet met coming in from above (the first hit, or a later one after crossing and passing
    # occluders under the layer), then out along o: f cos / pdf = R times chain_tables' first at G1(i), 1 - s_i,
    # G1(o), 1 - s_o (Eq. 17's G1(i) G1(o) replaced).
    table, _ = chain_tables()
    ki, fi = _chain_weights(microfacet.smith_G1(np.maximum(cos_rows, np.cos(np.radians(89.5))), alpha))
    at_i = (table[ki] * (1.0 - fi)[:, None, None, None] + table[ki + 1] * fi[:, None, None, None]).astype(np.float32).ravel()
    P, G = CHAIN_PASS.size, CHAIN_G1.size

    def nodes(passing):
        x = np.clip(passing, 0.0, 1.0) * (P - 1)
        k = np.minimum(np.floor(x).astype(np.int64), P - 2)
        return k, (x - k).astype(np.float32)

    kp, fp = nodes(1.0 - stop_i)  # (rows, 1, 471)
    ko, fo = _chain_weights(microfacet.smith_G1(oz, alpha))
    ko, fo = ko.reshape(o_z.shape)[..., None], fo.reshape(o_z.shape).astype(np.float32)[..., None]
    kq, fq = nodes(1.0 - stop_o)  # (rows, points, 471)
    # Multilinear in (p_i, G1(o), p_o), gathered from the flattened table (rows, p_i, G1(o), p_o).
    base = ((np.arange(o_z.shape[0])[:, None, None] * P + kp) * G + ko) * P + kq
    first = np.zeros(shape, dtype=np.float32)
    for dp, wp in ((0, 1.0 - fp), (1, fp)):
        for do, wo in ((0, 1.0 - fo), (1, fo)):
            for dq, wq in ((0, 1.0 - fq), (1, fq)):
                first += np.take(at_i, base + ((dp * G + do) * P + dq)) * (wp * wo * wq)
    weight = R_d * (above[..., None] * first)
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
    R = np.asarray(reflectance, dtype=np.float64)
    T = 1.0 - R if transmittance is None else np.asarray(transmittance, dtype=np.float64)
    rho = occluder_reflectance(rows_at(t, rows, step), cos_rows, alpha)
    ballistic = ballistic_transmissivity(cos_rows, alpha, rho, occluder_reflectance_below(T, alpha))
    (E_r,), _ = reflection_albedos(reflectance, t, theta, alpha, [None], transmittance)
    if lossless_transmissivity is None:
        missing = np.clip(1.0 - E_r - ballistic, 0.0, 1.0)
    else:
        t0 = np.asarray(lossless_transmissivity, dtype=np.float64)
        rho0 = occluder_reflectance(rows_at(t0, rows, step), cos_rows, alpha)
        (E_r0,), _ = reflection_albedos(reflectance, t0, theta, alpha, [None])
        ballistic0 = ballistic_transmissivity(cos_rows, alpha, rho0, occluder_reflectance_below(1.0 - R, alpha))
        lossless = np.clip(1.0 - E_r0 - ballistic0, 0.0, 1.0)
        G1 = microfacet.smith_G1(cos_rows, alpha)[:, None]
        absorbed = np.clip((rows_at(t0, rows, step) - rows_at(t, rows, step)) / np.maximum(G1, 1e-12), 0.0, 1.0)
        facet_albedo = np.clip(1.0 - hemispherical_average(absorbed, rows), 0.0, 1.0)
        missing = np.minimum(lossless * facet_albedo, np.clip(1.0 - E_r - ballistic, 0.0, 1.0))
    up = upward_share(reflectance, transmittance, alpha)
    return LayerTerms(E_r, ballistic, missing, up)


# --------------------------------------------------------------------------------------------------
# The upward share of the light scattered among the facets: the random walk itself, hero wavelengths

#: Incidence angles (host, degrees) of the walked paths; the share is interpolated linearly between them.
SHARE_THETA_DEG = (0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 88.0)
#: Paths per angle, the facet events kept per path (later ones count 1 on both sides of a path's weight), the seed.
SHARE_PATHS = 192000
SHARE_EVENTS = 32
SHARE_SEED = 2016
#: The share is computed at this many wavelengths, evenly spread (about every 3 nm), and interpolated between
#: (a ratio: smoother than ``R``); a multiple of SHARE_HEROES.
SHARE_COLUMNS = 160
#: Wavelengths per path, adjacent columns (:func:`share_groups`): the hero, which makes the path's choices, and the
#: others of its group (the same set whichever of them is the hero, as Wilkie et al. 2014's balance heuristic needs).
SHARE_HEROES = 8
#: The least share of the paths a group of columns gets, against the group that weighs most in a colour.
SHARE_GROUP_FLOOR = 0.1


def event_recorder(events: np.ndarray, count: np.ndarray) -> Callable[[np.ndarray, np.ndarray, np.ndarray], None]:
    """
    The walk's ``record`` hook (:func:`explorer.physics.microsurface.walk`): each path's facet events into the rows
    of ``events`` (its 0.25-degree ``theta_d`` row, plus 361 when reflected), as many as it has columns; ``count``
    counts every event of each path.
    """

    def record(rows: np.ndarray, cos_d: np.ndarray, reflect: np.ndarray) -> None:
        j = count[rows]
        kept = j < events.shape[1]
        row = theta_d_row(cos_d)
        events[rows[kept], j[kept]] = row[kept] + 361 * reflect[kept]
        count[rows] += 1

    return record


def share_columns(wavelengths: int) -> np.ndarray:
    """The wavelength columns (of ``wavelengths``) the share is computed at: :data:`SHARE_COLUMNS`, evenly spread."""
    return np.rint(np.linspace(0.0, wavelengths - 1.0, SHARE_COLUMNS)).astype(np.int64)


def upward_share(reflectance: ArrayLike, transmittance: ArrayLike | None, alpha: float) -> np.ndarray:
    """:func:`walked_share` at the rows of :func:`compensation_theta` and every wavelength (:func:`share_rows`)."""
    return share_rows(walked_share(reflectance, transmittance, alpha), np.shape(reflectance)[1])


def walked_share(reflectance: ArrayLike, transmittance: ArrayLike | None, alpha: float) -> np.ndarray:
    """
    ``r``: of the light scattered among the facets (left upward after two reflections or more, or downward after
    one or more), the part that leaves upward, at the angles :data:`SHARE_THETA_DEG` and the wavelengths
    :func:`share_columns`, shape (angles, columns): the random walk (:func:`explorer.physics.microsurface.walk`)
    through the layer, :data:`SHARE_PATHS` per angle, seeded.

    Each path carries a group of :data:`SHARE_HEROES` adjacent columns of :func:`share_columns`
    (:func:`share_groups`); one of them, the hero, taken in turn, makes its choices with its ``R(theta_d)``. Each
    wavelength of the group weighs the path by its own throughput (the product of each event's ``R``, reflected,
    or ``T``, crossed) over the mean over the group of the chance of its choices (the balance heuristic of
    hero-wavelength sampling, Wilkie et al. 2014: weights at most ``SHARE_HEROES``). An earlier walk with facets
    reflecting 0.5, reweighted to the layer's spectrum by ``R / 0.5`` and ``T / 0.5`` per event, kept 1-15 % of
    its paths as effective samples on the presets' Bragg layers and did not settle with more paths (0.004 of
    spread over seeds at 60000 and at 180000 paths per angle): its weights were heavy-tailed.

    ``reflectance``, ``transmittance``: the facets' ``R_lambda`` and ``T_lambda`` (``None``: ``1 - R``) at
    ``theta_d = k * 0.25 deg``, shape (361, 471).
    """
    from explorer.physics import microsurface

    alpha = float(microfacet.check_alpha(alpha))
    size = np.shape(reflectance)[1]
    columns = share_columns(size)
    R = np.asarray(reflectance, dtype=np.float64)[:, columns]
    T = 1.0 - R if transmittance is None else np.asarray(transmittance, dtype=np.float64)[:, columns]
    # Per event row (0.25-degree theta_d rows; + 361 reflected; 722 none): each wavelength's factor, and the
    # chance of the choice were that wavelength the hero.
    throughput = np.concatenate([T, R, np.ones((1, columns.size))])
    chance = np.concatenate([1.0 - R, R, np.ones((1, columns.size))])
    group = share_groups(size)  # each path's group of SHARE_HEROES adjacent columns
    member = np.arange(group.size) % SHARE_HEROES  # its hero, taken in turn
    hero = group * SHARE_HEROES + member
    path_columns = group[:, None] * SHARE_HEROES + np.arange(SHARE_HEROES)[None, :]  # (paths, heroes)
    share = np.full((len(SHARE_THETA_DEG), columns.size), 0.5)
    for k, stream in enumerate(np.random.SeedSequence(SHARE_SEED).spawn(len(SHARE_THETA_DEG))):
        rng = np.random.default_rng(stream)
        n = group.size
        count = np.zeros(n, dtype=np.int64)
        events = np.full((n, SHARE_EVENTS), 722, dtype=np.int16)

        def facet(cos_d, rows):
            return R[theta_d_row(cos_d), hero[rows]][:, None]

        record = event_recorder(events, count)

        theta = np.radians(SHARE_THETA_DEG[k])
        d = np.broadcast_to(np.array([-np.sin(theta), 0.0, -np.cos(theta)]), (n, 3))
        _, _, _, up, alive, _, reflections = microsurface.walk(d, np.ones((n, 1)), np.ones((n, 1)), alpha, facet, rng,
                                                                SHARE_EVENTS, record)
        scattered = np.flatnonzero(alive & (((reflections >= 2) & up) | ((reflections >= 1) & ~up)))
        cols = path_columns[scattered]
        weight = np.ones(cols.shape)
        pdf = np.ones(cols.shape)
        for j in range(SHARE_EVENTS):
            going = np.flatnonzero(events[scattered, j] != 722)  # only the paths with a j-th event (most have 2 or 3)
            if going.size == 0:
                break
            row = events[scattered[going], j].astype(np.int64)[:, None]
            weight[going] *= throughput[row, cols[going]]
            pdf[going] *= chance[row, cols[going]]
        weight /= np.maximum(pdf.mean(axis=1, keepdims=True), 1e-300)
        upward = np.bincount(cols.ravel(), (weight * up[scattered, None]).ravel(), columns.size)
        total = np.bincount(cols.ravel(), weight.ravel(), columns.size)
        share[k] = np.where(total > 0.0, upward / np.maximum(total, 1e-300), 0.5)
    return share


def share_groups(wavelengths: int) -> np.ndarray:
    """
    The group of each of an angle's :data:`SHARE_PATHS` paths: groups of :data:`SHARE_HEROES` adjacent columns of
    :func:`share_columns`, given paths in proportion to what they weigh in a colour (the colour matching
    functions' sum over the group, at least :data:`SHARE_GROUP_FLOOR` of the largest), a multiple of
    SHARE_HEROES each. A column's share is a ratio over its own group's paths, so the allocation leaves it
    unbiased and spends the paths where the colour is made.
    """
    from explorer.physics import colorimetry

    columns = share_columns(wavelengths)
    weight = colorimetry.colour_matching_functions()[columns].sum(axis=1).reshape(-1, SHARE_HEROES).sum(axis=1)
    weight = np.maximum(weight, SHARE_GROUP_FLOOR * weight.max())
    counts = SHARE_HEROES * np.floor(SHARE_PATHS / SHARE_HEROES * weight / weight.sum()).astype(np.int64)
    return np.repeat(np.arange(weight.size), counts)


def share_rows(share: np.ndarray, wavelengths: int) -> np.ndarray:
    """The share at the walked angles and :func:`share_columns` to the rows of :func:`compensation_theta` and every
    wavelength: linear in the wavelength, linear in the angle."""
    columns = share_columns(wavelengths)
    share = np.stack([np.interp(np.arange(wavelengths), columns, row) for row in share])
    rows = np.degrees(compensation_theta())
    return np.stack([np.interp(rows, SHARE_THETA_DEG, share[:, j]) for j in range(share.shape[1])], axis=-1)


def occluder_stop(rho_a: ArrayLike, rho_b: ArrayLike) -> np.ndarray:
    """
    The chance that an occluder stops a ray that leaves a heightfield: ``1 - (1 - rho_a)(1 - rho_b)``.
    Getting past an occluder of a heightfield crosses it twice: down through the occluder (a facet facing the
    ray, :func:`occluder_reflectance_below`'s ``rho_b``), back up through the microsurface behind it (the facets
    the direction sees, ``rho_a``) (measured against the random walk's first order by
    ``python3 -m explorer.dev.multiscatter_orders``).
    """
    return 1.0 - (1.0 - np.asarray(rho_a, dtype=np.float64)) * (1.0 - np.asarray(rho_b, dtype=np.float64))
