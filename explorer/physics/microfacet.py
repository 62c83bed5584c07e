"""
Rough Bragg layers: the GGX microfacet distribution, Smith's shadowing, the microfacet Bragg BRDF and
the GGX transmission filter of Fourneau et al. (2024), Section 4.

A *rough Bragg layer* is a distribution of identical Bragg mirrors, oriented by an isotropic GGX
distribution of roughness ``alpha`` in a host of index ``n1`` (Section 4.1). It reflects by Eq. 17 (a
microfacet BRDF whose Fresnel term is Yeh's reflectance at the half-vector angle) and transmits
*ballistically* (Section 4.2.1): the transmitted fraction is Yeh's transmissivity filtered over the
difference angle ``theta_d`` between ``i`` and the microfacet normal by ``F_alpha(theta_i, theta_d)``
(Eqs. 28-29), which depends on ``alpha`` only and is tabulated once per ``alpha``.

Conventions. Directions ``i`` and ``o`` are unit vectors (last axis of length 3) in the local frame of
the layer, with the geometric normal ``n = +z``, both pointing away from the surface (Walter et al.
2007). Angles are in radians. Spectra are sampled at :data:`explorer.physics.colorimetry.WAVELENGTHS` (last
axis). ``alpha`` lies in [0, 1] (:func:`check_alpha`); ``alpha = 0``, a smooth mirror whose ``D`` is a
Dirac, is evaluated as :data:`ALPHA_MIN`. Every function here is numpy only.

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. Computer Graphics Forum 43(2). Sections 4.1-4.2, Eqs. 17-19 and 24-30, Figures 5-7, Appendix C.
Walter, Marschner, Li, Torrance (2007). Microfacet Models for Refraction through Rough Surfaces. EGSR.
Heitz (2014). Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs. JCGT 3(2).
Heitz (2018). Sampling the GGX Distribution of Visible Normals. JCGT 7(4) (the env view's sampling).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike


#: ``alpha = 0`` is a smooth layer: ``D`` is then a Dirac, evaluated with this roughness instead.
ALPHA_MIN = 1e-6
#: Angular resolution of the transmission filter and of the per-layer tables (Figure 7: 0.25 degrees).
THETA_STEP_DEG = 0.25
#: Nodes ``theta_k = k * 0.25 deg``, ``k = 0 .. 360``, from normal incidence to grazing inclusive.
THETA_COUNT = int(round(90.0 / THETA_STEP_DEG)) + 1
THETA_STEP = np.deg2rad(THETA_STEP_DEG)
#: Directions closer than this to the horizon count as grazing (``cos theta`` is clamped to it).
COS_THETA_MIN = 1e-9

#: The filter table's quadrature (see :func:`transmission_filter_table`): cells whose length in the
#: sinh-mapped variable exceeds ``REFINE_LENGTH`` are refined into pieces of at most ``PIECE_LENGTH``
#: with ``PIECE_NODES`` Gauss-Legendre nodes each; the others take 2 nodes; rows go by blocks of
#: ``ROW_BLOCK`` (arrays that stay in cache are ~3x faster than one 361 x 722 pass).
REFINE_LENGTH = 0.1
PIECE_LENGTH = 0.5
PIECE_NODES = 4
ROW_BLOCK = 16


def theta_nodes() -> np.ndarray:
    """The angles ``theta_k = k * 0.25 deg`` (radians), ``k = 0 .. 360``, of every table here."""
    theta = np.arange(THETA_COUNT) * THETA_STEP
    theta[-1] = 0.5 * np.pi
    return theta


def theta_cell_edges() -> np.ndarray:
    """Edges of the ``theta_d`` cells around the nodes: ``[0, 0.125, 0.375, ..., 89.875, 90]`` degrees."""
    return np.concatenate([[0.0], (np.arange(THETA_COUNT - 1) + 0.5) * THETA_STEP, [0.5 * np.pi]])


def check_alpha(alpha: ArrayLike) -> np.ndarray:
    """
    Validate a GGX roughness (Eq. 18: ``alpha`` in [0, 1]).

    Returns
    -------
    ndarray
        ``alpha`` as float64, with 0 replaced by :data:`ALPHA_MIN`.

    Raises
    ------
    ValueError
        One line, when any ``alpha`` is outside [0, 1] or not a number.
    """
    value = np.asarray(alpha, dtype=np.float64)
    if not np.all((value >= 0.0) & (value <= 1.0)):
        shown = value if value.ndim == 0 else value[~((value >= 0.0) & (value <= 1.0))].ravel()[0]
        raise ValueError(f"alpha must be in [0, 1], got {float(shown):g}")
    return np.maximum(value, ALPHA_MIN)


# --------------------------------------------------------------------------------------------------
# GGX and Smith (Eqs. 18-19)


def ggx_D(cos_theta_m: ArrayLike, alpha: ArrayLike) -> np.ndarray:
    """
    The isotropic GGX (Trowbridge-Reitz) distribution of microfacet normals (Eq. 18).

    ``D(m) = alpha^2 chi+(m.n) / (pi cos^4 theta_m (alpha^2 + tan^2 theta_m)^2)``, evaluated as
    ``alpha^2 / (pi (alpha^2 cos^2 theta_m + sin^2 theta_m)^2)`` (the same expression multiplied out),
    finite at grazing angles and, with ``sin^2 = (1 - cos)(1 + cos)``, exact at ``m = n`` however small
    ``alpha`` is. Normalised so that ``int D(m) cos theta_m d omega_m = 1``.

    Parameters
    ----------
    cos_theta_m : array_like
        ``m . n``; 0 below the horizon (the Heaviside ``chi+``).
    alpha : float or array_like
        Roughness in [0, 1].

    Returns
    -------
    ndarray
        ``D`` in 1/sr.

    References
    ----------
    Fourneau et al. (2024), Eq. 18; Walter et al. (2007), Eq. 33.
    """
    alpha = check_alpha(alpha)
    cos_theta_m = np.asarray(cos_theta_m, dtype=np.float64)
    a2 = alpha * alpha
    c = np.clip(cos_theta_m, 0.0, 1.0)
    denominator = a2 * c * c + (1.0 - c) * (1.0 + c)
    return np.where(cos_theta_m > 0.0, a2 / (np.pi * denominator * denominator), 0.0)


def smith_G1(cos_theta_i: ArrayLike, alpha: ArrayLike, i_dot_m: ArrayLike | None = None) -> np.ndarray:
    """
    Smith's masking function for GGX (Eq. 19): ``chi+(i.m / i.n) 2 / (1 + sqrt(1 + alpha^2 tan^2 theta_i))``.

    Evaluated as ``2 cos / (cos + sqrt(cos^2 + alpha^2 sin^2))``, exact at grazing (0) and for
    ``alpha -> 0`` (1 above the horizon).

    Parameters
    ----------
    cos_theta_i : array_like
        ``i . n``; directions at or below the horizon are masked (0).
    alpha : float or array_like
        Roughness in [0, 1].
    i_dot_m : array_like, optional
        ``i . m`` for the ``chi+`` of Eq. 19; omitted, the microfacet is taken as visible.

    Returns
    -------
    ndarray
        ``G1`` in [0, 1].

    References
    ----------
    Fourneau et al. (2024), Eq. 19; Heitz (2014), Eq. 72.
    """
    alpha = check_alpha(alpha)
    c = np.clip(np.asarray(cos_theta_i, dtype=np.float64), 0.0, 1.0)
    s2 = 1.0 - c * c
    G1 = np.where(c > 0.0, 2.0 * c / np.maximum(c + np.sqrt(c * c + alpha * alpha * s2), 1e-300), 0.0)
    if i_dot_m is not None:
        G1 = np.where(np.asarray(i_dot_m) * np.asarray(cos_theta_i) > 0.0, G1, 0.0)
    return G1


def smith_G1_over_cos(cos_theta_i: ArrayLike, alpha: ArrayLike) -> np.ndarray:
    """
    ``G1(theta_i) / cos theta_i = 2 / (cos + sqrt(cos^2 + alpha^2 sin^2))`` (Eq. 19 over Eq. 17's
    cosine): finite at grazing incidence, where both vanish. 0 below the horizon.
    """
    alpha = check_alpha(alpha)
    c = np.clip(np.asarray(cos_theta_i, dtype=np.float64), 0.0, 1.0)
    s2 = 1.0 - c * c
    value = 2.0 / np.maximum(c + np.sqrt(c * c + alpha * alpha * s2), 1e-300)
    return np.where(np.asarray(cos_theta_i) > 0.0, value, 0.0)


# --------------------------------------------------------------------------------------------------
# The microfacet Bragg BRDF (Eq. 17)


def half_vector(i: ArrayLike, o: ArrayLike) -> np.ndarray:
    """``h = (i + o) / |i + o|`` (Eq. 17); ``+z`` where ``i = -o`` (both on the horizon, opposite)."""
    s = np.asarray(i, dtype=np.float64) + np.asarray(o, dtype=np.float64)
    norm = np.linalg.norm(s, axis=-1, keepdims=True)
    fallback = np.zeros_like(s)
    fallback[..., 2] = 1.0
    return np.where(norm > 1e-12, s / np.maximum(norm, 1e-300), fallback)


def half_vector_cosine(i: ArrayLike, o: ArrayLike) -> np.ndarray:
    """
    ``cos theta_d = i.h = o.h = |i + o| / 2`` for unit ``i, o``: symmetric in ``i`` and ``o`` to the last
    bit, so that Eq. 17 is exactly reciprocal even where Yeh's reflectance varies fast with angle.
    """
    s = np.asarray(i, dtype=np.float64) + np.asarray(o, dtype=np.float64)
    return np.clip(0.5 * np.linalg.norm(s, axis=-1), 0.0, 1.0)


def microfacet_lobe(i: ArrayLike, o: ArrayLike, n: ArrayLike, alpha: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Eq. 17 without its reflectance, about any normal ``n``: ``D(h) G1(i) G1(o) / (4 |i.n| |o.n|)``, the
    twin of ``microfacet_lobe`` in ``shaders/lib/microfacet.glsl``.

    Parameters
    ----------
    i, o, n : array_like, shape (..., 3)
        Unit vectors (broadcast together); ``i`` and ``o`` point away from the surface.
    alpha : float
        GGX roughness in [0, 1].

    Returns
    -------
    lobe, cos_theta_d, above : ndarray, shape (...)
        The lobe (0 unless both ``i`` and ``o`` are above the surface), ``cos theta_d = |i + o| / 2``
        (:func:`half_vector_cosine`) at which a material reads its reflectance, and the mask of pairs
        above the surface.
    """
    i, o, n = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (i, o, n)))
    cos_i, cos_o = np.sum(n * i, axis=-1), np.sum(n * o, axis=-1)
    above = (cos_i > 0.0) & (cos_o > 0.0)
    s = i + o
    norm = np.linalg.norm(s, axis=-1)
    cos_h = np.sum(n * s, axis=-1) / np.maximum(norm, 1e-300)
    lobe = 0.25 * ggx_D(cos_h, alpha) * smith_G1_over_cos(cos_i, alpha) * smith_G1_over_cos(cos_o, alpha)
    return np.where(above, lobe, 0.0), np.clip(0.5 * norm, 0.0, 1.0), above


def microfacet_brdf(i: ArrayLike, o: ArrayLike, alpha: float, reflectance: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """
    A GGX microfacet BRDF with a given microfacet reflectance (Eq. 17):
    ``f_r(i, o) = D(h) G1(i) G1(o) R(i.h) / (4 |i.n| |o.n|)``.

    Parameters
    ----------
    i, o : array_like, shape (..., 3)
        Unit directions, ``n = +z``, pointing away from the surface.
    alpha : float
        GGX roughness in [0, 1].
    reflectance : callable
        ``reflectance(cos_theta_d)`` for ``cos_theta_d = i.h`` of shape ``(..., 1)``; returns the
        microfacet's reflectance, e.g. spectra of shape ``(..., n_wavelengths)``.

    Returns
    -------
    ndarray, shape (..., n_wavelengths)
        0 where ``i`` or ``o`` is at or below the horizon.

    References
    ----------
    Fourneau et al. (2024), Eq. 17; Walter et al. (2007), Eq. 20.
    """
    lobe, cos_theta_d, _ = microfacet_lobe(i, o, (0.0, 0.0, 1.0), alpha)
    return lobe[..., None] * reflectance(cos_theta_d[..., None])


# --------------------------------------------------------------------------------------------------
# Sampling the visible normals (Heitz 2018), for the env view's Monte Carlo estimator


def sample_ggx_visible_normal(v: ArrayLike, alpha: float, u1: ArrayLike, u2: ArrayLike) -> np.ndarray:
    """
    Sample a microfacet normal from GGX's distribution of normals visible from ``v`` (Heitz 2018).

    The twin of ``sample_ggx_visible_normal`` in ``shaders/lib/sampling.glsl``: the view direction is
    stretched to the hemisphere configuration, a point is picked uniformly on the projected disc of
    the half-sphere (the half facing away from ``v`` scaled by ``(1 + v_h.z) / 2``), lifted onto the
    hemisphere and unstretched. The density of ``m`` is :func:`ggx_visible_normal_pdf`.

    Parameters
    ----------
    v : array_like, shape (..., 3)
        Unit view direction in the local frame (``n = +z``), ``v.z > 0``.
    alpha : float
        GGX roughness in [0, 1] (0 is :data:`ALPHA_MIN`).
    u1, u2 : array_like
        Uniform numbers in [0, 1) (broadcast with ``v[..., 0]``).

    Returns
    -------
    ndarray, shape (..., 3)
        Unit microfacet normals, ``m.z >= 0``.

    References
    ----------
    Heitz (2018). Sampling the GGX Distribution of Visible Normals. JCGT 7(4), Listing 1.
    """
    a = float(check_alpha(alpha))
    v = np.asarray(v, dtype=np.float64)
    u1, u2 = np.asarray(u1, dtype=np.float64), np.asarray(u2, dtype=np.float64)
    vh = np.stack([a * v[..., 0], a * v[..., 1], v[..., 2]], axis=-1)
    vh = vh / np.linalg.norm(vh, axis=-1, keepdims=True)
    lensq = vh[..., 0] ** 2 + vh[..., 1] ** 2
    safe = np.sqrt(np.where(lensq > 0.0, lensq, 1.0))
    t1_axis = np.where(
        (lensq > 0.0)[..., None],
        np.stack([-vh[..., 1], vh[..., 0], np.zeros_like(lensq)], axis=-1) / safe[..., None],
        np.array([1.0, 0.0, 0.0]),
    )
    t2_axis = np.cross(vh, t1_axis)
    r, phi = np.sqrt(u1), 2.0 * np.pi * u2
    t1, t2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1.0 + vh[..., 2])
    t2 = (1.0 - s) * np.sqrt(np.maximum(1.0 - t1 * t1, 0.0)) + s * t2
    lift = np.sqrt(np.maximum(0.0, 1.0 - t1 * t1 - t2 * t2))
    nh = t1[..., None] * t1_axis + t2[..., None] * t2_axis + lift[..., None] * vh
    m = np.stack([a * nh[..., 0], a * nh[..., 1], np.maximum(nh[..., 2], 0.0)], axis=-1)
    return m / np.linalg.norm(m, axis=-1, keepdims=True)


def ggx_visible_normal_pdf(v: ArrayLike, m: ArrayLike, alpha: float) -> np.ndarray:
    """
    The density (1/sr) of :func:`sample_ggx_visible_normal`: Heitz's distribution of visible normals
    ``D_v(m) = G1(v) max(0, v.m) D(m) / v.n`` (Eqs. 18-19 of Fourneau et al. 2024 for ``D`` and ``G1``),
    which integrates to 1 over the hemisphere of ``m`` because ``G1`` is Smith's (Heitz 2014, Eq. 14).

    Parameters
    ----------
    v, m : array_like, shape (..., 3)
        Unit view direction and microfacet normal in the local frame (``n = +z``).
    alpha : float
        GGX roughness in [0, 1].

    References
    ----------
    Heitz (2018), Eq. 1; Heitz (2014), Eq. 14.
    """
    v, m = np.asarray(v, dtype=np.float64), np.asarray(m, dtype=np.float64)
    cos_v = v[..., 2]
    v_dot_m = np.maximum(np.sum(v * m, axis=-1), 0.0)
    return smith_G1_over_cos(cos_v, alpha) * v_dot_m * ggx_D(m[..., 2], alpha)


def ggx_reflection_pdf(l: ArrayLike, v: ArrayLike, alpha: float) -> np.ndarray:
    """
    The density (1/sr) of ``l = reflect(-v, m)`` for ``m`` drawn by :func:`sample_ggx_visible_normal`:
    ``D_v(h) / (4 v.h) = G1(v) D(h) / (4 v.n)`` with ``h = (l + v) / |l + v|`` (the Jacobian of the
    reflection, Walter et al. 2007, Eq. 14). The twin of ``ggx_reflection_pdf`` in
    ``shaders/lib/sampling.glsl``; it integrates to 1 over the whole sphere of ``l`` (reflected
    directions may point below the surface).

    Parameters
    ----------
    l, v : array_like, shape (..., 3)
        Unit directions in the local frame (``n = +z``), ``v.z > 0``.
    alpha : float
        GGX roughness in [0, 1].
    """
    h = half_vector(l, v)
    v = np.asarray(v, dtype=np.float64)
    return np.where(v[..., 2] > 0.0, 0.25 * smith_G1_over_cos(v[..., 2], alpha) * ggx_D(h[..., 2], alpha), 0.0)


# --------------------------------------------------------------------------------------------------
# The GGX transmission filter (Section 4.2.2, Eqs. 24-29)


def cos_theta_m(theta_i: ArrayLike, theta_d: ArrayLike, psi_d: ArrayLike) -> np.ndarray:
    """
    ``cos theta_m = cos theta_i cos theta_d + sin theta_i sin theta_d cos psi_d`` (Eq. 24): the
    microfacet normal at angle ``theta_d`` from ``i`` and azimuth ``psi_d`` around it (Figure 5).
    """
    theta_i, theta_d = np.asarray(theta_i, dtype=np.float64), np.asarray(theta_d, dtype=np.float64)
    return np.cos(theta_i) * np.cos(theta_d) + np.sin(theta_i) * np.sin(theta_d) * np.cos(psi_d)


def psi_d_max(theta_i: ArrayLike, theta_d: ArrayLike) -> np.ndarray:
    """
    The bound of the ``psi_d`` integral where the microfacet normal reaches the horizon (Eq. 26):
    ``acos(-1 / (tan theta_i tan theta_d))`` if ``theta_i + theta_d >= pi/2``, else ``pi``.
    """
    theta_i, theta_d = np.asarray(theta_i, dtype=np.float64), np.asarray(theta_d, dtype=np.float64)
    a = np.cos(theta_i) * np.cos(theta_d)
    b = np.sin(theta_i) * np.sin(theta_d)
    cut = (theta_i + theta_d >= 0.5 * np.pi) & (b > 0.0)
    return np.where(cut, np.arccos(np.clip(-a / np.where(cut, b, 1.0), -1.0, 1.0)), np.pi)


def _psi_integral_sum(a, b, sin_half_difference, sin_half_sum, one_minus_s, s):
    """
    ``4 pi / alpha^2`` times the ``psi_d`` integral of Eq. 29, ``int_0^psi_d_max D~(theta_m) d psi_d``,
    in closed form.

    With ``c = cos theta_m = a + b cos psi`` (Eq. 24; ``a = cos theta_i cos theta_d``,
    ``b = sin theta_i sin theta_d``) and ``s^2 = 1 - alpha^2``, Eq. 18 is
    ``D~ = alpha^2 / (pi (1 - s^2 c^2)^2)`` and, by partial fractions,
    ``1 / (1 - s^2 c^2)^2 = 1/4 sum_{sigma = +-1} [1 / (1 + sigma s c)^2 + 1 / (1 + sigma s c)]``.
    Each ``1 + sigma s c = p + q cos psi`` (``p = 1 + sigma s a``, ``q = sigma s b``) integrates as
    ``J1 = int_0^psi dpsi / (p + q cos psi) = 2 atan2(sqrt(p-q) sin(psi/2), sqrt(p+q) cos(psi/2)) / sqrt(p^2-q^2)``
    and ``J2 = int_0^psi dpsi / (p + q cos psi)^2 = (p J1 - q sin psi / (p + q cos psi)) / (p^2 - q^2)``,
    where ``p + q cos psi_d_max = 1`` when ``psi_d_max < pi`` (the normal is on the horizon there) and
    ``sin psi_d_max = 0`` otherwise. ``p +- q = 1 + sigma s cos(theta_i -+ theta_d)`` come from
    ``1 - s cos x = (1 - s) + 2 s sin^2(x/2)`` (and ``1 + s cos x = 2 - (1 - s cos x)``), without
    cancellation however small ``alpha`` is. The half angles of ``psi_d_max`` (Eq. 26) are
    ``cos^2(psi/2) = (b - a) / 2b`` and ``sin^2(psi/2) = (b + a) / 2b``.

    Returns ``sum_sigma (J1 + J2)``; every argument broadcasts.
    """
    cut = b > a  # theta_i + theta_d > pi / 2: psi_d_max < pi (Eq. 26)
    two_b = np.where(cut, 2.0 * b, 1.0)
    cos_half = np.sqrt(np.where(cut, np.maximum(b - a, 0.0) / two_b, 0.0))
    sin_half = np.sqrt(np.where(cut, np.minimum((b + a) / two_b, 1.0), 1.0))
    sin_psi = 2.0 * sin_half * cos_half
    # sigma = -1: p + q = 1 - s cos(theta_i - theta_d), p - q = 1 - s cos(theta_i + theta_d).
    plus_minus = sin_half_difference * sin_half_difference
    plus_minus *= 2.0 * s
    plus_minus += one_minus_s
    minus_minus = sin_half_sum * sin_half_sum
    minus_minus *= 2.0 * s
    minus_minus += one_minus_s
    total = np.zeros(np.broadcast_shapes(np.shape(a), np.shape(plus_minus)))
    # sigma = +1: p +- q = 2 - (the sigma = -1 values).
    for p_plus_q, p_minus_q in ((plus_minus, minus_minus), (2.0 - plus_minus, 2.0 - minus_minus)):
        root_plus, root_minus = np.sqrt(p_plus_q), np.sqrt(p_minus_q)
        root = root_plus * root_minus
        J1 = np.arctan2(root_minus * sin_half, root_plus * cos_half)
        J1 *= 2.0
        J1 /= root
        J2 = 0.5 * (p_plus_q + p_minus_q) * J1
        J2 -= 0.5 * (p_plus_q - p_minus_q) * sin_psi
        J2 /= root * root
        total += J1
        total += J2
    return total


def _ggx_constants(alpha: float) -> tuple[float, float, float]:
    """``(alpha^2, s, 1 - s)`` with ``s = sqrt(1 - alpha^2)`` and ``1 - s = alpha^2 / (1 + s)``."""
    a2 = alpha * alpha
    s = np.sqrt(1.0 - a2)
    return a2, s, a2 / (1.0 + s)


def _G1_squared_over_cos(cos_theta_i, alpha) -> np.ndarray:
    """``G1^2(theta_i) / cos theta_i = 4 cos / (cos + sqrt(cos^2 + alpha^2 sin^2))^2``: 0 at grazing."""
    c = np.clip(cos_theta_i, 0.0, 1.0)
    root = c + np.sqrt(c * c + alpha * alpha * (1.0 - c * c))
    return 4.0 * c / (root * root)


def transmission_filter(theta_i: ArrayLike, theta_d: ArrayLike, alpha: float) -> np.ndarray:
    """
    The GGX transmission filter (Eq. 29), pointwise:
    ``F_alpha(theta_i, theta_d) = 2 G1^2(theta_i) (cos theta_d / cos theta_i) int_0^psi_d_max D~(theta_m) sin theta_d d psi_d``,
    with ``theta_m`` of Eq. 24 and ``psi_d_max`` of Eq. 26; the ``psi_d`` integral is in closed form
    (:func:`_psi_integral_sum`), exact for every ``alpha``, where the paper sums 1000 samples.

    Parameters
    ----------
    theta_i, theta_d : array_like
        Incidence angle and difference angle ``acos(i.m)``, in [0, pi/2] (radians; broadcast).
    alpha : float
        GGX roughness in [0, 1].

    Returns
    -------
    ndarray
        ``F_alpha`` in 1/rad: ``int_0^{pi/2} F_alpha d theta_d = G1(theta_i)`` (Appendix C).

    References
    ----------
    Fourneau et al. (2024), Eqs. 24-29, Figures 5-6, Appendix C.
    """
    alpha = float(check_alpha(alpha))
    theta_i = np.clip(np.asarray(theta_i, dtype=np.float64), 0.0, 0.5 * np.pi)
    theta_d = np.clip(np.asarray(theta_d, dtype=np.float64), 0.0, 0.5 * np.pi)
    a2, s, one_minus_s = _ggx_constants(alpha)
    cos_i, cos_d, sin_d = np.cos(theta_i), np.cos(theta_d), np.sin(theta_d)
    total = _psi_integral_sum(
        cos_i * cos_d, np.sin(theta_i) * sin_d, np.sin(0.5 * (theta_i - theta_d)), np.sin(0.5 * (theta_i + theta_d)), one_minus_s, s
    )
    # F = 2 G1^2/cos_i cos_d sin_d * (alpha^2 / 4 pi) * total
    return (a2 / (2.0 * np.pi)) * _G1_squared_over_cos(cos_i, alpha) * cos_d * sin_d * total


@dataclass(frozen=True)
class TransmissionFilter:
    """
    The transmission filter ``F_alpha`` tabulated at 0.25 degrees in both angles (Figure 7).

    Attributes
    ----------
    alpha : float
        The roughness it was built for (after :func:`check_alpha`).
    theta : ndarray, shape (361,)
        The nodes ``theta_k = k * 0.25 deg`` (radians) of both ``theta_i`` (rows) and ``theta_d``
        (columns).
    weights : ndarray, shape (361, 361)
        ``weights[k, j] = int F_alpha(theta_k, theta_d) d theta_d`` over the cell of ``theta_d`` around
        node ``j`` (:func:`theta_cell_edges`): the quadrature weights of Eq. 28, so that
        ``sum_j T(theta_j) weights[k, j]`` approximates ``f_t(theta_k) cos theta_k`` and each row sums
        to ``G1(theta_k)`` (Appendix C). A filter narrower than a cell (small ``alpha``) keeps its
        mass: ``alpha -> 0`` gives ``G1`` on the diagonal.
    seconds : float
        Wall-clock time the table took to build.
    """

    alpha: float
    theta: np.ndarray
    weights: np.ndarray
    seconds: float

    @property
    def values(self) -> np.ndarray:
        """``F_alpha`` averaged over each ``theta_d`` cell (1/rad), shape (361, 361): what Figure 6 plots."""
        return self.weights / np.diff(theta_cell_edges())[None, :]

    def row_sums(self) -> np.ndarray:
        """``int_0^{pi/2} F_alpha(theta_k, theta_d) d theta_d`` per row: ``G1(theta_k)`` (Appendix C, Eq. 30)."""
        return self.weights.sum(axis=1)


#: Gauss-Legendre nodes on [-1, 1] for the regular cells and for the refined pieces.
_GL2 = np.polynomial.legendre.leggauss(2)
_GL_PIECE = np.polynomial.legendre.leggauss(PIECE_NODES)


def transmission_filter_table(alpha: float) -> TransmissionFilter:
    """
    Tabulate ``F_alpha`` (Eq. 29) for one roughness at 0.25 degrees in ``theta_i`` and ``theta_d``
    (Figure 7), as the integral of ``F_alpha`` over each ``theta_d`` cell.

    The ``psi_d`` integral of Eq. 29 is in closed form (:func:`transmission_filter`). Over ``theta_d``,
    every cell takes a 2-node Gauss-Legendre rule (exact for cubics), the nodes shared by all rows, so
    that their sines and cosines are computed once. ``F_alpha`` is analytic in ``theta_d`` except for
    poles at ``theta_d = +-theta_i +- i acosh(1 / sqrt(1 - alpha^2))`` (about ``alpha`` off the real
    axis) and a
    square-root kink where ``psi_d_max`` leaves ``pi`` (Figure 6); cells near the poles (long in
    ``t = asinh((theta_d - theta_i) / alpha)``, the sinh map of nearly singular integrals, in which the
    poles stay ``pi/2`` away whatever ``alpha``) are integrated in ``t`` by composite 4-node
    Gauss-Legendre pieces instead. Rows sum to ``G1(theta_i)`` within ~2e-5 for every ``alpha`` in
    [1e-6, 1] (Appendix C), without renormalisation.

    Parameters
    ----------
    alpha : float
        GGX roughness in [0, 1].

    Returns
    -------
    TransmissionFilter

    References
    ----------
    Fourneau et al. (2024), Eqs. 24-29, Figure 7 (0.25 degree tables; 1000 ``psi_d`` samples there),
    Appendix C. Johnston & Elliott (2005), Error estimation of quadrature rules for evaluating
    singular integrals in BEM (the sinh transformation).
    """
    start = time.perf_counter()
    alpha = float(check_alpha(alpha))
    a2, s, one_minus_s = _ggx_constants(alpha)
    theta = theta_nodes()
    edges = theta_cell_edges()
    cos_i, sin_i = np.cos(theta), np.sin(theta)
    half_sin_i, half_cos_i = np.sin(0.5 * theta), np.cos(0.5 * theta)
    row_factor = (a2 / (2.0 * np.pi)) * _G1_squared_over_cos(cos_i, alpha)

    # Regular cells: 2 Gauss-Legendre nodes per theta_d cell, shared by every row.
    width = np.diff(edges)
    centre = 0.5 * (edges[1:] + edges[:-1])
    x2, w2 = _GL2
    nodes = (centre[:, None] + 0.5 * width[:, None] * x2).ravel()
    node_weight = (0.5 * width[:, None] * w2).ravel()
    cos_d, sin_d = np.cos(nodes), np.sin(nodes)
    half_sin_d, half_cos_d = np.sin(0.5 * nodes), np.cos(0.5 * nodes)
    column_factor = cos_d * sin_d * node_weight
    weights = np.empty((THETA_COUNT, THETA_COUNT))
    for r0 in range(0, THETA_COUNT, ROW_BLOCK):
        r = slice(r0, min(THETA_COUNT, r0 + ROW_BLOCK))
        # sin((theta_i -+ theta_d)/2) by the angle-sum formulas (exact enough away from the poles,
        # where these cells are).
        sin_half_difference = half_sin_i[r, None] * half_cos_d - half_cos_i[r, None] * half_sin_d
        sin_half_sum = half_sin_i[r, None] * half_cos_d + half_cos_i[r, None] * half_sin_d
        total = _psi_integral_sum(
            cos_i[r, None] * cos_d, sin_i[r, None] * sin_d, sin_half_difference, sin_half_sum, one_minus_s, s
        )
        total *= row_factor[r, None] * column_factor
        weights[r] = total.reshape(-1, THETA_COUNT, 2).sum(axis=-1)

    # Cells near the poles: composite Gauss-Legendre in t = asinh((theta_d - theta_i) / alpha).
    t_low = np.arcsinh((edges[None, :-1] - theta[:, None]) / alpha)
    t_high = np.arcsinh((edges[None, 1:] - theta[:, None]) / alpha)
    length = t_high - t_low
    rows, columns = np.nonzero(length > REFINE_LENGTH)
    if rows.size:
        pieces = np.ceil(length[rows, columns] / PIECE_LENGTH).astype(np.int64)
        cell = np.repeat(np.arange(rows.size), pieces)
        piece = np.arange(cell.size) - (np.cumsum(pieces) - pieces)[cell]
        step = (length[rows, columns] / pieces)[cell]
        xp, wp = _GL_PIECE
        t = (t_low[rows, columns][cell] + piece * step)[:, None] + 0.5 * step[:, None] * (xp + 1.0)
        k = rows[cell][:, None]
        offset = alpha * np.sinh(t)  # theta_d - theta_i, exactly
        theta_d = np.clip(theta[k] + offset, 0.0, 0.5 * np.pi)
        cos_d_r, sin_d_r = np.cos(theta_d), np.sin(theta_d)
        total = _psi_integral_sum(
            cos_i[k] * cos_d_r,
            sin_i[k] * sin_d_r,
            np.sin(-0.5 * offset),
            np.sin(0.5 * (theta[k] + theta_d)),
            one_minus_s,
            s,
        )
        jacobian = alpha * np.cosh(t) * 0.5 * step[:, None] * wp
        values = (row_factor[k] * cos_d_r * sin_d_r * jacobian * total).sum(axis=1)
        weights[rows, columns] = np.bincount(cell, weights=values, minlength=rows.size)

    weights.setflags(write=False)
    theta.setflags(write=False)
    return TransmissionFilter(alpha=alpha, theta=theta, weights=weights, seconds=time.perf_counter() - start)
