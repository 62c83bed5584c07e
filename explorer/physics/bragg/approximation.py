"""
The paper's approximation (Fourneau et al. 2024): the reflectance envelope and the spectral landmarks (Section 3.2.1,
Appendix A), and the piecewise-constant RGB approximation (Section 3.2.2). Numpy only; GLSL twins of the same names in
``shaders/lib/bragg.glsl``.
"""

from __future__ import annotations

from typing import Iterator

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.physics.bragg.mirror import (
    BISECTION_STEPS,
    POLARISATIONS,
    WAVELENGTH_HIGH,
    WAVELENGTH_LOW,
    BraggMirror,
    CellGeometry,
    cell_geometry,
)
from explorer.physics.bragg.reflectance import airy_slab_coefficients, cos_K_Lambda, reflectance_polarised

# --------------------------------------------------------------------------------------------------
# The envelope and the spectral landmarks (Section 3.2.1, Appendix A)


def host_reflectance(geometry: CellGeometry) -> np.ndarray:
    """``R_h1 = |r_h1|^2``, the host interface's reflectance (0 when the host is ``n1``), at most 1."""
    if geometry.host_is_n1:
        return np.zeros(np.shape(geometry.p1))
    return np.minimum(np.abs(geometry.r_h1) ** 2, 1.0)


def under_host(R_mirror: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    A mirror reflectance seen through the host interface ``nh -> n1``, added incoherently (our
    extension for the approximations when ``nh != n1``): ``R_h1 + (1 - R_h1)^2 R / (1 - R_h1 R)``,
    written as ``1 - (1 - R_h1)(1 - R) / (1 - R_h1 R)``, which stays 1 when both reflect totally.
    """
    if geometry.host_is_n1:
        return R_mirror
    R_h1 = np.minimum(np.abs(geometry.r_h1) ** 2, 1.0)
    return 1.0 - (1.0 - R_h1) * (1.0 - R_mirror) / np.maximum(1.0 - R_h1 * R_mirror, 1e-300)


def reflectance_envelope(omega: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    The envelope ``R^e = |C|^2 / (|C|^2 + sin^2 K Lambda)`` (Eq. 11); 1 inside band gaps.

    Under a host ``nh != n1`` the host interface is added incoherently, which keeps band gaps at 1
    (our extension; the paper's approximation assumes ``nh == n1``).
    """
    r1, t1 = airy_slab_coefficients(omega, geometry)
    a = cos_K_Lambda(omega, geometry)
    r1_2 = np.abs(r1) ** 2
    denominator = r1_2 + np.abs(t1) ** 2 * np.maximum(1.0 - a * a, 0.0)
    # A cell that reflects nothing (delta = 1) has no gap either: 0, not 0/0.
    return under_host(np.divide(r1_2, denominator, out=np.zeros_like(r1_2), where=denominator > 0.0), geometry)


def reflectance_fringe_average(omega: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    Yeh's reflectance averaged over its fringes: ``1 - |sin K Lambda| / sqrt(|C|^2 + sin^2 K Lambda)``.

    Outside band gaps ``R = |C|^2 / (|C|^2 + sin^2 K Lambda / sin^2 N K Lambda)`` oscillates ``N - 1``
    times between gaps; averaging over the fast phase ``N K Lambda`` at fixed ``K Lambda`` gives this
    closed form. It equals 1 at band edges and ``~ R^e / 2`` for weak contrast (what the paper's
    empirical ``w~0 ~ 0.53`` of Appendix B approximates). Our improvement, not in the paper.

    Under a host ``nh != n1`` (Appendix D): the coherent average of :func:`fringe_average_under_host`.
    """
    r1, t1 = airy_slab_coefficients(omega, geometry)
    a = cos_K_Lambda(omega, geometry)
    if not geometry.host_is_n1:
        return fringe_average_under_host(r1, t1, omega, geometry, a)
    t1_2_sin2 = np.abs(t1) ** 2 * np.maximum(1.0 - a * a, 0.0)
    denominator = np.abs(r1) ** 2 + t1_2_sin2
    ratio = np.divide(t1_2_sin2, denominator, out=np.ones_like(denominator), where=denominator > 0.0)
    return 1.0 - np.sqrt(ratio)


#: Below this |B|^2 the fringes' weight vanishes and the average is its limit |P / S|^2.
FRINGE_B_MIN = 1e-12
#: A pole of r_hN on the real x axis (never for real indices) is moved off it by this much.
FRINGE_Q_MIN = 1e-6


def fringe_average_under_host(r1: ArrayLike, t1: ArrayLike, omega: ArrayLike, geometry: CellGeometry, a: ArrayLike) -> np.ndarray:
    """
    ``|r_hN|^2`` (Appendix D) averaged over the fringes, coherently: the host's interface reflects in
    phase with the mirror, and the incoherent :func:`under_host` misses a slow modulation of up to
    ~0.07 in R (n1 = 1.33, n2 = 1.8, nh = 1).

    With ``u = N K Lambda``, ``U_{N-1} = sin u / sin t`` and ``U_{N-2} = (sin u cos t - cos u sin t) / sin t``
    (``t = K Lambda`` held fixed over a fringe), Appendix D's ``r_N = r1 / (A + B x)`` where ``x = cot u``,
    ``A = 1 - cos t t_cell`` and ``B = sin t t_cell``; then ``r_hN = (P + Q x) / (S + T x)`` with
    ``P = r1 + r_h1 A``, ``Q = r_h1 B``, ``S = A + r_h1 r1``, ``T = B``, i.e. ``alpha + beta / (x - z)``
    with ``alpha = Q / T``, ``beta = (P T - Q S) / T^2``, ``z = -S / T = p + i q``. As ``u`` sweeps a fringe,
    ``x`` sweeps the real line with the Cauchy density ``1 / (pi (1 + x^2))``, whose averages are
    ``<1 / (x - z)> = 1 / (-i sign(q) - z)`` and ``<1 / |x - z|^2> = (1 + |q|) / (|q| ((1 + |q|)^2 + p^2))``
    (two Cauchy densities convolved): so ``<|r_hN|^2> = |alpha|^2 + 2 Re(alpha* beta <1 / (x - z)>) +
    |beta|^2 <1 / |x - z|^2>``. For a lossless cell ``z`` lies on the imaginary axis, ``|z| >= 1``: no
    term is singular, also where the cell barely reflects.
    """
    t_cell = t1 * np.exp(1j * omega * geometry.p1)
    sin_t = np.sqrt(np.maximum(1.0 - a * a, 0.0))
    A = 1.0 - a * t_cell
    B = sin_t * t_cell
    r_h1 = geometry.r_h1
    P, Q, S, T = r1 + r_h1 * A, r_h1 * B, A + r_h1 * r1, B
    fringes = np.abs(B) ** 2 > FRINGE_B_MIN
    T = np.where(fringes, T, 1.0)
    alpha, beta, z = Q / T, (P * T - Q * S) / T**2, -S / T
    p, q = np.real(z), np.abs(np.imag(z))
    q = np.maximum(q, FRINGE_Q_MIN)
    mean_pole = 1.0 / (1j * np.where(np.imag(z) > 0.0, -1.0, 1.0) - z)
    mean_pole_2 = (1.0 + q) / (q * ((1.0 + q) ** 2 + p * p))
    average = np.abs(alpha) ** 2 + 2.0 * np.real(np.conj(alpha) * beta * mean_pole) + np.abs(beta) ** 2 * mean_pole_2
    # At a band edge (sin t -> 0) the fringes' weight vanishes: the limit |P / S|^2.
    limit = np.abs(P) ** 2 / np.maximum(np.abs(S) ** 2, 1e-300)
    return np.clip(np.where(fringes, average, limit), 0.0, 1.0)


def paper_weight(omega: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    The paper's box weight ``w = w~(theta) R^e`` (Section 3.2.2, Appendix B). Under a host ``nh != n1`` the
    host interface's own reflection is no fringe: the correction ``w~`` (a fringe average) applies to the
    mirror's envelope only, and the host interface is added after it, ``under_host(w~ R^e)`` (Appendix D;
    applying ``w~`` to the host's Fresnel reflection halved it).
    """
    if geometry.host_is_n1:
        return geometry.correction * reflectance_envelope(omega, geometry)
    r1, t1 = airy_slab_coefficients(omega, geometry)
    a = cos_K_Lambda(omega, geometry)
    r1_2 = np.abs(r1) ** 2
    denominator = r1_2 + np.abs(t1) ** 2 * np.maximum(1.0 - a * a, 0.0)
    envelope = np.divide(r1_2, denominator, out=np.zeros_like(r1_2), where=denominator > 0.0)
    return under_host(geometry.correction * envelope, geometry)


def optical_thickness(geometry: CellGeometry) -> np.ndarray:
    """``n_+ = n1 cos(theta_1) d1 + n2 cos(theta_2) d2`` (Appendix A), the real parts under TIR."""
    return np.maximum(np.real(geometry.p1) + np.real(geometry.p2), 1e-9)


def mode_frequency(m: ArrayLike, n_plus: ArrayLike) -> np.ndarray:
    """Spectral modes ``omega_m = m pi / n_+`` (Eq. 13): inside a band gap for every ``m >= 1``."""
    return m * np.pi / n_plus


def _bisect(f, lo, hi, positive_at_lo):
    """Fixed-step bisection, as the shader does, for the sign change of ``f`` on ``[lo, hi]``."""
    positive_at_lo = np.broadcast_to(positive_at_lo, np.shape(lo))
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        same_side = (f(mid) >= 0.0) == positive_at_lo
        lo = np.where(same_side, mid, lo)
        hi = np.where(same_side, hi, mid)
    return 0.5 * (lo + hi)


def airy_point(geometry: CellGeometry, omega_m: ArrayLike, omega_next: ArrayLike, m: ArrayLike) -> np.ndarray:
    """The zero of ``cos K Lambda`` between modes ``m`` and ``m + 1``, where ``R^e = |r1|^2``.

    ``cos K Lambda`` has the sign ``(-1)^m`` at ``omega_m`` (Appendix A)."""
    return _bisect(lambda w: cos_K_Lambda(w, geometry), omega_m, omega_next, (m % 2) == 0)


def band_edge(geometry: CellGeometry, lo: ArrayLike, hi: ArrayLike, gap_at_lo: bool) -> np.ndarray:
    """The band-gap edge ``|cos K Lambda| = 1`` between a mode and an Airy point, in either order."""
    return _bisect(lambda w: np.abs(cos_K_Lambda(w, geometry)) - 1.0, lo, hi, gap_at_lo)


def zero_point_after(geometry: CellGeometry, omega: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """
    The first zero point ``omega_z = z pi / (n2 cos theta_2 d2)`` (Eq. 12) above ``omega``.

    Returns the frequency and whether it exists (no zero points while ``n2`` is evanescent).
    """
    p2 = np.real(geometry.p2)
    exists = (np.abs(np.imag(geometry.p2)) == 0.0) & (p2 > 0.0)
    p2 = np.where(exists, p2, 1.0)
    z = np.floor(omega * p2 / np.pi) + 1.0
    return z * np.pi / p2, exists


# --------------------------------------------------------------------------------------------------
# The piecewise-constant approximation (Section 3.2.2)

def wavelength_of(omega: ArrayLike) -> np.ndarray:
    """``lambda = 2 pi / omega`` in nm; ``omega = 0`` (mode 0) maps past the visible range."""
    return 2.0 * np.pi / np.maximum(omega, 1e-9)


OMEGA_LOW = 2.0 * np.pi / WAVELENGTH_HIGH
OMEGA_HIGH = 2.0 * np.pi / WAVELENGTH_LOW


def mode_range(n_plus: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """First and last intervals ``[omega_m, omega_{m+1}]`` that overlap the visible range."""
    m_first = np.floor(OMEGA_LOW * n_plus / np.pi)
    m_last = np.floor(OMEGA_HIGH * n_plus / np.pi)
    return m_first, m_last


def subdivisions(m: ArrayLike, m_first: ArrayLike, s: int, mode_numbering: str = "relative") -> np.ndarray:
    """
    Sub-boxes per box outside band gaps: ``max(1, s - m)`` (Section 3.2.2); ``s = 0`` is the basic
    approximation (one box). The paper leaves open how ``m`` is counted: ``'relative'`` counts from
    the first interval between modes that overlaps the visible range (the reading of its Table 1,
    where ``s = 3`` costs more than the basic method at Lambda = 988 nm), ``'absolute'`` from mode 0.
    """
    if s <= 0:
        return np.ones_like(m)
    index = m if mode_numbering == "absolute" else m - m_first
    return np.maximum(1.0, s - index)


def subdivisions_by_mass(omega_low: ArrayLike, omega_high: ArrayLike, s: int) -> np.ndarray:
    """
    Sub-boxes of the improved variant (ours): ``ceil(4 s mu)``, with ``mu`` the box's share of the
    visible CMF mass (X + Y + Z), i.e. ``s`` sub-boxes per quarter of it. Boxes where the eye is most
    sensitive get the subdivisions, wherever their mode number. On the grid of Figure 4 this spends
    as many boxes as the paper's ``max(1, s - m)``; the mass comes from the box ends' lookups, which
    the method makes anyway (Eq. 15).
    """
    if s <= 0:
        return np.ones_like(omega_low)
    mass = (colorimetry.cmf_cumulative_at(wavelength_of(omega_low)) - colorimetry.cmf_cumulative_at(wavelength_of(omega_high))).sum(axis=-1)
    total = colorimetry.cmf_cumulative_at(WAVELENGTH_HIGH).sum()
    return np.maximum(1.0, np.ceil(4.0 * s * mass / total))


#: The improved variant resolves a pass band's fringes where, in its visible part, a fringe feature is
#: wider than ``FRINGE_RESOLVE_NM / s`` nm (8 nm at s = 3), times ``(N / N_RESOLVE)^GROW_EXPONENT`` beyond
#: ``N_RESOLVE`` cells (:func:`fringes_resolved`): its sub-boxes then sample the exact reflectance;
#: elsewhere the fringes are averaged in closed form (docs/accuracy.md).
FRINGE_RESOLVE_NM = 24.0
#: Sub-boxes per resolved fringe (each rises from a zero of R to a peak and back; 2 alias).
SAMPLES_PER_FRINGE = 3.0
#: Fringes are resolved only while ``SAMPLES_PER_FRINGE N`` is at most this (N <= 21).
RESOLVE_BUDGET = 64.0
#: Beyond this many cells the width a fringe must have to be resolved grows like ``N^GROW_EXPONENT``:
#: Figure 4's N = 20 mirrors (fringes of 10-25 nm) keep their fringe average and their cost, while the
#: weak-contrast mirrors of up to ~20 cells (a fringe of ~40 nm) are resolved.
N_RESOLVE = 10.0
GROW_EXPONENT = 2.0
#: At most this many sub-boxes per box (sharp dips at grazing angles ask for more).
MAX_RESOLVED_PIECES = 48.0


def bloch_phase(omega: ArrayLike, geometry: CellGeometry, at_edge: ArrayLike = False) -> np.ndarray:
    """
    The Bloch phase ``K Lambda`` in ``[0, pi]`` (Eq. 8) at ``omega``; where ``at_edge`` (a band edge, ``|cos K Lambda| = 1``)
    exactly 0 or pi by the sign of ``cos K Lambda``. ``arccos`` is ill-conditioned there (``arccos(1 - e) ~ sqrt(2 e)``):
    float32's rounding of a bisected edge would move the phase by ~1e-3 and with it the fringe count that sets the
    sub-boxes (:func:`subdivisions_resolving_fringes`), a step of the colour.
    """
    a = cos_K_Lambda(omega, geometry)
    return np.where(at_edge, np.where(a >= 0.0, 0.0, np.pi), np.arccos(np.clip(a, -1.0, 1.0)))


def fringe_count(omega_low: ArrayLike, omega_high: ArrayLike, geometry: CellGeometry, low_at_edge: ArrayLike = False,
                 high_at_edge: ArrayLike = False) -> np.ndarray:
    """
    How many fringes of Eq. 2 lie in a pass-band box: ``N |Delta K Lambda| / pi``. Between zeros of
    ``sin N K Lambda`` the Bloch phase ``K Lambda`` advances by ``pi / N``, and it is monotone across a
    pass band (Eq. 8 with ``|cos K Lambda| <= 1``). ``low_at_edge``, ``high_at_edge``: the box ends at a band edge
    (:func:`bloch_phase`).
    """
    t_low = bloch_phase(omega_low, geometry, low_at_edge)
    t_high = bloch_phase(omega_high, geometry, high_at_edge)
    return geometry.N * np.abs(t_high - t_low) / np.pi


def fringes_resolved(edge_low: ArrayLike, edge_high: ArrayLike, s: int, geometry: CellGeometry) -> np.ndarray:
    """
    Whether the improved variant (ours) resolves the fringes of the pass band ``[edge_low, edge_high]``.

    Eq. 2 has ``N`` fringes per pass band; the fringe average (:func:`reflectance_fringe_average`)
    replaces them by their mean, right when they are narrower than the CMFs vary: large ``N``. For a few
    cells (the jewel beetles of Table 3, ``N = 6-8``; Figure 12, ``N = 3``) a fringe spans tens of nm and
    where it lies is the colour. They are resolved where, in the pass band's visible part, a fringe's
    feature (:func:`fringe_sharpness`) is wider than ``FRINGE_RESOLVE_NM / s`` nm, a width that grows like
    ``(N / N_RESOLVE)^GROW_EXPONENT`` beyond :data:`N_RESOLVE` cells, and ``SAMPLES_PER_FRINGE N <= RESOLVE_BUDGET``.
    """
    if s <= 0:
        return np.zeros(np.shape(edge_low), dtype=bool)
    # The pass band's visible part: its fringes there, and their mean width in nm.
    low, high = np.maximum(edge_low, OMEGA_LOW), np.minimum(edge_high, OMEGA_HIGH)
    visible = high > low
    high = np.where(visible, high, low)
    fringes = np.maximum(fringe_count(low, high, geometry, edge_low >= OMEGA_LOW, edge_high <= OMEGA_HIGH), 1e-9)
    width_nm = wavelength_of(low) - wavelength_of(high)
    # The width (nm) to resolve grows beyond N_RESOLVE cells, as the cost of resolving them does.
    grow = max(1.0, geometry.N / N_RESOLVE) ** GROW_EXPONENT
    wide = width_nm * fringe_sharpness(geometry) * s > FRINGE_RESOLVE_NM * grow * fringes
    return visible & wide & (SAMPLES_PER_FRINGE * geometry.N <= RESOLVE_BUDGET)


def subdivisions_resolving_fringes(
    omega_low: ArrayLike, omega_high: ArrayLike, s: int, geometry: CellGeometry, resolved: ArrayLike, edge: int = 0,
) -> np.ndarray:
    """
    Sub-boxes of the improved variant (ours) in a pass-band box: :func:`subdivisions_by_mass`, and where
    the fringes are resolved (:func:`fringes_resolved`) at least :data:`SAMPLES_PER_FRINGE` per fringe
    feature (:func:`fringe_count`, :func:`fringe_sharpness`), at most :data:`MAX_RESOLVED_PIECES`. ``edge``: the box's
    band edge (-1 at ``omega_low``, +1 at ``omega_high``, 0 none; as :func:`_sub_box`).
    """
    by_mass = subdivisions_by_mass(omega_low, omega_high, s)
    if not np.any(resolved):
        return by_mass
    fringes = fringe_count(omega_low, omega_high, geometry, edge < 0, edge > 0)
    pieces = np.ceil(SAMPLES_PER_FRINGE * fringes / fringe_sharpness(geometry))
    pieces = np.minimum(pieces, MAX_RESOLVED_PIECES)
    return np.where(resolved, np.maximum(pieces, by_mass), by_mass)


def fringe_sharpness(geometry: CellGeometry) -> np.ndarray:
    """
    The share of a fringe its feature (a dip of Eq. 2) fills at most: ``min(1, 2 / (pi sqrt(k)))``, Eq. 2
    written ``R = k sin^2 u / (1 + k sin^2 u)`` with ``u = N K Lambda`` and ``k = |r1|^2 / (|t1|^2 sin^2 K Lambda)
    >= 4 r12^2 / (1 - r12^2)^2`` (Eq. 10 at ``sin phi = 1``). Where ``k >> 1`` (strong contrast, grazing
    angles) ``R ~ 1`` but for dips of width ``~ 2 / sqrt(k)`` in ``u``, which samples must resolve. Under a
    host ``nh != n1`` its interface sharpens them alike: ``k >= R_h1 / (1 - R_h1)``.
    """
    r12_2 = np.minimum(np.abs(geometry.r12) ** 2, 1.0 - 1e-12)
    k = 4.0 * r12_2 / (1.0 - r12_2) ** 2
    R_h1 = np.minimum(host_reflectance(geometry), 1.0 - 1e-12)
    k = np.maximum(k, R_h1 / (1.0 - R_h1))
    return np.minimum(1.0, 2.0 / (np.pi * np.sqrt(np.maximum(k, 1e-300))))


def pass_band_weight(omega: ArrayLike, geometry: CellGeometry, resolved: ArrayLike) -> np.ndarray:
    """The improved variant's weight in a pass band: the exact reflectance (Eqs. 2, 9, 10; Appendix D)
    where the fringes are resolved, their closed-form average otherwise."""
    average = reflectance_fringe_average(omega, geometry)
    if not np.any(resolved):
        return average
    return np.where(resolved, np.clip(reflectance_polarised(omega, geometry), 0.0, 1.0), average)


def gap_weight(omega_low: ArrayLike, omega_high: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    The improved variant's weight of a half band gap: the exact reflectance at its middle. The paper
    gives gaps ``w = 1``, the limit of Eq. 9 for large ``N``: ``R = 1 - O(e^{-2 N Im[K] Lambda})``. A mirror
    of a few cells or weak contrast (Table 3: ``n2 - n1 = 0.08``, ``N = 8``) reflects far less in its gaps,
    and under a host (Appendix D) the host interface adds to it in phase; without fringes in a gap, one
    sample suffices.
    """
    return np.clip(reflectance_polarised(0.5 * (omega_low + omega_high), geometry), 0.0, 1.0)


def _sub_box(lo, hi, j, pieces, edge):
    """
    Sub-box ``j`` of ``pieces`` in ``[lo, hi]`` and the point where its weight is sampled.

    ``edge = 0``: equal sub-boxes sampled at their centres (the paper). ``edge = -1`` (band edge at
    ``lo``) or ``+1`` (at ``hi``): sub-boxes graded quadratically toward the band edge, ``x = u^2``
    with ``u`` uniform, because the fringe average varies like ``sqrt(x)`` there; each is sampled at
    its centroid ``u = 2 (u0^2 + u0 u1 + u1^2) / (3 (u0 + u1))``, where ``1 - c u`` equals its mean.
    """
    u0, u1 = j / pieces, (j + 1.0) / pieces
    width = hi - lo
    if edge == 0:
        return lo + width * u0, lo + width * 0.5 * (u0 + u1), lo + width * u1
    uc = 2.0 * (u0 * u0 + u0 * u1 + u1 * u1) / (3.0 * (u0 + u1))
    if edge < 0:
        return lo + width * u0 * u0, lo + width * uc * uc, lo + width * u1 * u1
    return hi - width * u1 * u1, hi - width * uc * uc, hi - width * u0 * u0


def piecewise_constant_boxes(
    geometry: CellGeometry, s: int = 0, mode_numbering: str = "relative", variant: str = "paper"
) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """
    The boxes ``B_j`` of the approximation (Eq. 14) and their weights ``w_j`` (Section 3.2.2).

    Walks the intervals between consecutive modes that overlap the visible range; in each, finds the
    Airy point and both band-gap edges by bisection (Section 3.2.1), inserts a zero point where one
    falls outside the gaps, gives the gap halves ``w = 1`` and the boxes outside the gaps
    :func:`subdivisions` sub-boxes each.

    ``variant='paper'``: equal sub-boxes, ``w = w~(theta) R^e(centre)`` (Section 3.2.2, Appendix B).
    ``variant='improved'`` (ours): ``w =`` :func:`reflectance_fringe_average` at the sub-box's
    centroid, sub-boxes graded toward band edges (:func:`_sub_box`), their number set by the box's
    share of the CMF mass (:func:`subdivisions_by_mass`; ``mode_numbering`` is then unused). Same
    landmarks, same lookups per box. Where a pass band's fringes are wide (:func:`fringes_resolved`) they
    are resolved instead: sub-boxes per fringe weighted by the exact reflectance
    (:func:`pass_band_weight`), and the pass band's half-gaps by theirs (:func:`gap_weight`); the
    paper's weights under a host are :func:`paper_weight`.

    Yields
    ------
    omega_low, omega_high, weight, active : ndarray
        One box per element of the angle arrays (``active`` is False where that element has no box
        left). Intervals are cut at the top of the visible range: landmarks beyond it add nothing,
        and far beyond it evanescent layers overflow.
    """
    improved = variant == "improved"
    n_plus = optical_thickness(geometry)
    m_first, m_last = mode_range(n_plus)
    count = int(np.max(m_last - m_first)) + 1 if n_plus.size else 0
    ones = np.ones_like(n_plus)
    for k in range(count):
        active = m_first + k <= m_last
        m = np.minimum(m_first + k, m_last)  # finished elements redo their last interval, masked out
        omega_m = mode_frequency(m, n_plus)
        omega_next = np.minimum(mode_frequency(m + 1.0, n_plus), OMEGA_HIGH)
        omega_a = airy_point(geometry, omega_m, omega_next, m)
        edge_low = band_edge(geometry, omega_m, omega_a, True)
        edge_high = band_edge(geometry, omega_a, omega_next, False)
        omega_z, has_zero = zero_point_after(geometry, edge_low)
        has_zero = has_zero & (omega_z < edge_high)
        # Pass-band boundaries edge_low <= x1 <= x2 <= edge_high: the zero point, if any, on either
        # side of the Airy point; without one, x1 == x2 leaves an empty box.
        z = np.where(has_zero, omega_z, omega_a)
        x1 = np.minimum(z, omega_a)
        x2 = np.maximum(z, omega_a)
        boxes = ((edge_low, x1, -1), (x1, x2, 0), (x2, edge_high, 1))
        if improved:
            resolved = fringes_resolved(edge_low, edge_high, s, geometry)
            # Resolved fringes: the gaps take their finite-N reflectance too (the fringe average and
            # w = 1 are both the large-N limit, consistent only together).
            gap_low = np.where(resolved, gap_weight(omega_m, edge_low, geometry), 1.0)
            gap_high = np.where(resolved, gap_weight(edge_high, omega_next, geometry), 1.0)
        yield omega_m, edge_low, gap_low if improved else ones, active
        for lo, hi, edge in boxes:
            if improved:
                pieces = subdivisions_resolving_fringes(lo, hi, s, geometry, resolved, edge)
            else:
                pieces = subdivisions(m, m_first, s, mode_numbering)
            for j in range(int(np.max(np.where(active, pieces, 1.0)))):
                sub_lo, centre, sub_hi = _sub_box(lo, hi, j, pieces, edge if improved else 0)
                if improved:
                    weight = pass_band_weight(centre, geometry, resolved)
                else:
                    weight = paper_weight(centre, geometry)
                yield sub_lo, sub_hi, weight, active & (j < pieces)
        yield edge_high, omega_next, gap_high if improved else ones, active


def approximate_xyz_polarised(
    geometry: CellGeometry, s: int = 0, mode_numbering: str = "relative", variant: str = "paper"
) -> np.ndarray:
    """
    XYZ of the piecewise-constant spectrum for one polarisation (Eq. 15): each box adds
    ``w_j (C(omega_{j+1}) - C(omega_j))`` from the cumulative CMF table (Eq. 16).
    """
    xyz = np.zeros(np.shape(geometry.p1) + (3,))
    # Finished elements' extra boxes (masked by active) may lie at negative omega, where the exact
    # reflectance of the improved variant overflows: their warnings are noise.
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        for omega_low, omega_high, weight, active in piecewise_constant_boxes(geometry, s, mode_numbering, variant):
            # omega -> lambda reverses the order: the box covers [2 pi / omega_high, 2 pi / omega_low].
            span = colorimetry.cmf_cumulative_at(wavelength_of(omega_low)) - colorimetry.cmf_cumulative_at(wavelength_of(omega_high))
            xyz += np.where(active, weight, 0.0)[..., None] * span
    return xyz


def approximate_rgb(
    cos_theta: ArrayLike, mirror: BraggMirror, s: int = 0, mode_numbering: str = "relative", variant: str = "paper"
) -> np.ndarray:
    """
    The RGB approximation of Section 3.2: ``s = 0`` the basic one, ``s >= 1`` the subdivided one
    (``variant='improved'`` for ours); one XYZ per polarisation, averaged, then linear sRGB.

    Returns
    -------
    ndarray, shape ``cos_theta.shape + (3,)``
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    xyz = sum(
        approximate_xyz_polarised(cell_geometry(cos_theta, mirror, pol), s, mode_numbering, variant)
        for pol in POLARISATIONS
    )
    return colorimetry.xyz_to_rgb(0.5 * xyz)
