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


@dataclass(frozen=True)
class CompensationTables:
    """
    A rough Bragg layer's multiple-scattering compensation, per wavelength (471, the last axis).

    Attributes
    ----------
    missing : ndarray, shape (COMPENSATION_ROWS, 471), float32
        ``m(theta)``: the light single scattering with transparent occluders misses, at ``theta = k * 2 deg``.
    up : ndarray, shape (471,), float32
        ``r``: the part of it that leaves upward.
    missing_average : ndarray, shape (471,), float32
        ``m_avg = 2 int m cos sin d theta`` (the lobe's normalisation).
    """

    missing: np.ndarray = field(repr=False)
    up: np.ndarray = field(repr=False)
    missing_average: np.ndarray = field(repr=False)


def compensation_tables(reflectance: ArrayLike, transmissivity: ArrayLike, theta: ArrayLike, alpha: float) -> CompensationTables:
    """
    Build a layer's :class:`CompensationTables` from its single-scattering tables.

    Parameters
    ----------
    reflectance, transmissivity : array_like, shape (rows, 471)
        Yeh's ``R_lambda(theta)`` and Eq. 28's ``f_t cos theta`` at the angles ``theta`` (the layer tables).
    theta : array_like, shape (rows,)
        Their angles (radians, uniform from 0).
    alpha : float
        The layer's roughness.
    """
    alpha = float(microfacet.check_alpha(alpha))
    R = np.asarray(reflectance, dtype=np.float64)
    t = np.asarray(transmissivity, dtype=np.float64)
    theta = np.asarray(theta, dtype=np.float64)
    step = theta[1] - theta[0]

    def at(table, angle):
        x = np.clip(angle, 0.0, theta[-1]) / step
        k = np.minimum(np.floor(x).astype(np.int64), table.shape[0] - 2)
        f = (x - k)[..., None]
        return table[k] * (1.0 - f) + table[k + 1] * f

    rows = compensation_theta()
    cos_rows = np.cos(rows)
    rho_rows = occluder_reflectance(at(t, rows), cos_rows, alpha)
    G_rows = effective_masking(cos_rows, alpha, rho_rows)
    o_z, cos_d, above = _quadrature(alpha)
    # E_r(theta) = E_m[R(theta_d) (1 + Lambda_i) G2] over the normals visible from i (Eq. 17 with
    # correlated_masking_over_cos for G1 G1 / (cos_i cos_o): f cos / pdf = R G2 / G1(i)); float32, all rows at once.
    # Nearest table rows (0.25 deg) for the quadrature's angles: a gather, not an interpolation (as fast as it gets).
    row_o = np.rint(np.arccos(np.clip(o_z, 0.0, 1.0)) / step).astype(np.int64).ravel()
    row_d = np.rint(np.arccos(cos_d) / step).astype(np.int64).ravel()
    t32, R32 = t.astype(np.float32), R.astype(np.float32)
    oz = np.clip(o_z, 1e-6, 1.0).ravel()
    G1_o = microfacet.smith_G1(oz, alpha).astype(np.float32)[:, None]
    lam_o = smith_lambda(oz, alpha).astype(np.float32).reshape(o_z.shape + (1,))
    rho_o = np.clip(1.0 - t32[row_o] / np.maximum(G1_o, np.float32(1e-12)), 0.0, 1.0)
    stop_o = (rho_o * (2.0 - rho_o)).reshape(o_z.shape + (R.shape[1],))
    lam_i = smith_lambda(np.maximum(cos_rows, np.cos(np.radians(89.5))), alpha).astype(np.float32)[:, None, None]
    stop_i = occluder_stop(rho_rows).astype(np.float32)[:, None, :]
    weight = above[..., None] * (1.0 + lam_i) / (1.0 + lam_i * stop_i + lam_o * stop_o)
    E_r = (R32[row_d].reshape(o_z.shape + (R.shape[1],)) * weight).mean(axis=1, dtype=np.float64)
    missing = np.clip(1.0 - E_r - ballistic_transmissivity(rho_rows, G_rows), 0.0, 1.0)
    up = np.clip(hemispherical_average(R, theta), 0.0, 1.0)
    average = hemispherical_average(missing, rows)
    return CompensationTables(missing.astype(np.float32), up.astype(np.float32), average.astype(np.float32))


def missing_energy(tables: CompensationTables, theta: ArrayLike) -> np.ndarray:
    """``m(theta)`` (radians, in the host) by linear interpolation of the table's rows: shape ``theta.shape + (471,)``."""
    x = np.clip(np.asarray(theta, dtype=np.float64), 0.0, 0.5 * np.pi) / np.radians(COMPENSATION_STEP_DEG)
    k = np.minimum(np.floor(x).astype(np.int64), COMPENSATION_ROWS - 2)
    f = (x - k)[..., None]
    m = tables.missing.astype(np.float64)
    return m[k] * (1.0 - f) + m[k + 1] * f


def compensation_lobe(missing_i: ArrayLike, missing_o: ArrayLike, tables: CompensationTables) -> np.ndarray:
    """The upward multiple-scattering lobe ``r m(i) m(o) / (pi m_avg)`` (1/sr), per wavelength (Kulla & Conty's form)."""
    average = np.maximum(tables.missing_average.astype(np.float64), 1e-12)
    return tables.up * np.asarray(missing_i) * np.asarray(missing_o) / (np.pi * average)


def compensated_transmissivity(ballistic: ArrayLike, missing: ArrayLike, tables: CompensationTables) -> np.ndarray:
    """A layer's transmission as the layers below see it: the ballistic part plus the downward share ``(1 - r) m``."""
    return np.asarray(ballistic) + (1.0 - tables.up) * np.asarray(missing)


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
