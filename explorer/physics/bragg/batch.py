"""
Yeh's reflectance of many mirrors at once (Section 3.1, Eqs. 2, 8-10, Appendix D): the batched forward model that
inverse design screens, scans and refines on (parameters as arrays, ``N`` continuous, complex indices allowed).
Numpy only; no GLSL twin (no view draws it).

It is :func:`explorer.physics.bragg.bragg_reflectance` (tested equal to 1e-9 at integer ``N``) with three
intended differences, each what a search over structures needs:

- ``N`` is real: ``U_{N-1}(cos t) = sin(N t) / sin t`` continues the Chebyshev polynomials to fractional cell
  counts (:func:`chebyshev_U_real_N`), so that the count is a continuous search variable;
- sampled ``step`` nm apart, fringes narrower than a few steps are blended into their average over a fringe
  (:func:`explorer.physics.bragg.fringe_average_under_host`), with the weight
  ``w = clip((lambda^2 / (2 N P) / s - 1) / 3, 0, 1)`` of the point value (``P`` the cell's optical thickness
  along z, ``lambda^2 / (2 N P)`` the fringes' spacing, ``s`` the step or the ``smooth`` width): the converged
  colour of such a mirror integrates that average, and point samples would alias;
- the slabs' phases ``k_z d`` have their decay capped (:func:`explorer.physics.bragg.clamp_decay`) before the
  exponentials, as in the dispersion relation, rather than only there.

With complex indices (a medium's ``n + i k``) the characteristic-matrix form holds at each wavelength with a
complex ``cos K Lambda`` (:func:`absorbing_reflectance_batch`). A mirror in ``n1`` whose waves all propagate (at an
angle) takes a real-arithmetic path (:func:`_lossless_reflectance`, tested equal to the complex one to 1e-9), which
also gives the analytic derivatives by ``Lambda``, ``delta`` and ``N`` that the paint's polish walks on
(:func:`bragg_reflectance_batch_gradient`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import multilayer
from explorer.physics.bragg.approximation import fringe_average_under_host
from explorer.physics.bragg.mirror import COS_THETA_MIN, POLARISATIONS, Omega
from explorer.physics.bragg.reflectance import (
    chebyshev_U,
    clamp_decay,
    reflection_coefficient_host,
    same_polarisations,
    slab_coefficients,
)
from explorer.physics.fresnel import cos_theta_transmitted, fresnel_r

#: Below this ``|sin K Lambda|`` (real indices) or ``|1 - z^2|`` (complex ones) the band edge's limits
#: ``U_{N-1} -> N``, ``U_{N-2} -> N - 1`` are taken: a continuous ``N`` lands there at any value.
BATCH_EDGE = 1e-9


def chebyshev_U_real_N(a: ArrayLike, N: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    :func:`explorer.physics.bragg.chebyshev_U` for a real (array) ``N``, with the band edges' limits ``N`` and
    ``N - 1`` where ``|sin t| <`` :data:`BATCH_EDGE`.
    """
    U_N1, U_N2, scale = chebyshev_U(a, N)
    in_band = np.abs(a) < 1.0
    edge = in_band & (np.abs(np.sin(np.arccos(np.clip(a, -1.0, 1.0)))) < BATCH_EDGE)
    if edge.any():
        N = np.broadcast_to(np.asarray(N, dtype=np.float64), U_N1.shape)
        U_N1, U_N2 = np.where(edge, N, U_N1), np.where(edge, N - 1.0, U_N2)
    return U_N1, U_N2, scale


@dataclass
class _CellPhases:
    """A cell's slab phases ``psi = k_1z d1``, ``phi = k_2z d2`` (decay capped) as exponentials, cosines and sines."""

    e_psi: np.ndarray
    e_phi: np.ndarray
    cos_psi: np.ndarray
    sin_psi: np.ndarray
    cos_phi: np.ndarray
    sin_phi: np.ndarray


def _cell_phases(omega: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> _CellPhases:
    """
    :class:`_CellPhases` of optical thicknesses ``p1``, ``p2`` along z (real or complex): ``cos x = (e^{ix} + e^{-ix}) / 2``
    and ``sin x = (e^{ix} - e^{-ix}) / 2i`` from one exponential each.
    """
    e_psi, e_phi = np.exp(1j * clamp_decay(omega * p1)), np.exp(1j * clamp_decay(omega * p2))
    return _CellPhases(e_psi, e_phi, (e_psi + 1.0 / e_psi) / 2.0, (e_psi - 1.0 / e_psi) / 2j,
                       (e_phi + 1.0 / e_phi) / 2.0, (e_phi - 1.0 / e_phi) / 2j)


def _point_weight(p1, p2, wavelengths, N, step: float | None, smooth, shape) -> np.ndarray:
    """
    The point value's weight ``w`` (module docstring) of shape ``shape``: 1 without a ``step``. Fringes
    ``lambda^2 / (2 N P)`` apart (``P = Re p1 + Re p2``); a point sample per step resolves them from ~4 per
    fringe, and averages them out below 1 per fringe.
    """
    if step is None:
        return np.ones(shape)
    path = np.maximum(np.real(p1) + np.real(p2), 1e-9)
    fringe = wavelengths**2 / (2.0 * N * path)
    return np.broadcast_to(np.clip((fringe / (step if smooth is None else smooth) - 1.0) / 3.0, 0.0, 1.0), shape)


def _column(v, dtype=None) -> np.ndarray:
    """A parameter ``(B,)`` as ``(B, 1, 1)``; ``(B, 1, W)`` (a dispersive medium's index per wavelength) as it is."""
    a = np.asarray(v, dtype=dtype)
    return a.reshape(-1, 1, 1) if a.ndim <= 1 else a


def bragg_reflectance_batch(
    n1: ArrayLike, n2: ArrayLike, Lambda: ArrayLike, delta: ArrayLike, N: ArrayLike, nh: ArrayLike, cos_theta: ArrayLike,
    wavelengths: ArrayLike, step: float | None = None, smooth: float | None = None,
) -> np.ndarray:
    """
    Unpolarised ``R_lambda`` of many mirrors at once: parameters of shape ``(B,)`` (``nh < 1``: the host is
    ``n1``; ``N`` may be fractional; an index may also be ``(B, 1, W)``, per wavelength), ``cos_theta`` ``(A,)``
    in the host, ``wavelengths`` ``(W,)`` nm; returns ``(B, A, W)``. Appendix D's coefficient
    ``r_hN = (r_N + r_h1) / (1 + r_h1 r_N)`` with ``r_N = r1 U_{N-1} / (U_{N-1} - U_{N-2} t1 e^{i k_1z d1})`` and the
    slab's ``r1, t1`` (Eq. 10); ``|r_N|^2`` is Yeh's Eq. 2 when the host is ``n1`` (``r_h1 = 0``). Equals
    :func:`explorer.physics.bragg.bragg_reflectance` at integer ``N`` (tested) when ``step`` is None.

    ``step`` (nm): the spectrum is to be sampled that coarsely, so where the fringes are narrower than a
    few steps it is blended into its average over the fringes (the module docstring's ``w``).
    ``smooth`` (nm, default ``step``) averages out fringes narrower than a few times it: the screening's
    smoother landscape (the envelope's band gaps without the fringes' ripples). Complex indices:
    :func:`absorbing_reflectance_batch`.
    """
    if any(np.iscomplexobj(v) for v in (n1, n2, nh)):
        return absorbing_reflectance_batch(n1, n2, Lambda, delta, N, nh, cos_theta, wavelengths, step, smooth)
    columns = [_column(v, np.float64) for v in (n1, n2, Lambda, delta, N, nh)]
    rows = max(v.shape[0] for v in columns)
    n1, n2, Lambda, delta, N, nh = (np.broadcast_to(v, (rows,) + v.shape[1:]) for v in columns)
    cos_h = np.maximum(np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1), COS_THETA_MIN)
    wavelengths = np.asarray(wavelengths, dtype=np.float64).reshape(1, 1, -1)
    # The lossless fast path: no separate host (r_h1 = 0) and every wave propagating (real cosines).
    cos_2 = cos_theta_transmitted(cos_h, np.where(nh >= 1.0, nh, n1), n2)
    cos_1 = cos_theta_transmitted(cos_h, np.where(nh >= 1.0, nh, n1), n1)
    simple = ((nh < 1.0) | (nh == n1)) & (np.imag(cos_1) == 0.0) & (np.imag(cos_2) == 0.0)
    simple = np.all(np.broadcast_to(simple, np.broadcast_shapes(simple.shape, (rows, cos_h.shape[1], 1))), axis=2)  # (B, A)
    out = np.empty((rows, cos_h.shape[1], wavelengths.shape[2]))
    if simple.any():
        for at, part in _row_blocks(rows, cos_h, wavelengths, (n1, n2, Lambda, delta, N)):
            out[at] = _lossless_reflectance(*part, cos_h, wavelengths, step, smooth)[0]
    if simple.all():
        return out
    # Each other (mirror, angle) through the complex coefficients, one row per pair.
    row, angle = np.nonzero(~simple)
    pairs = _host_reflectance(*(v[row] for v in (n1, n2, Lambda, delta, N, nh)), cos_h[0, angle, 0].reshape(-1, 1, 1), wavelengths,
                              step, smooth)
    out[row, angle] = pairs[:, 0]
    return out


def bragg_reflectance_batch_gradient(
    n1: ArrayLike, n2: ArrayLike, Lambda: ArrayLike, delta: ArrayLike, N: ArrayLike, nh: ArrayLike, cos_theta: ArrayLike,
    wavelengths: ArrayLike, step: float | None = None, smooth: float | None = None,
) -> tuple[np.ndarray, dict[str, np.ndarray]] | None:
    """
    :func:`bragg_reflectance_batch` and its analytic derivatives ``{"Lambda", "delta", "N"}`` (each ``(B, A, W)``), for
    mirrors without a separate host whose waves all propagate (real indices); None for any other batch.
    """
    if any(np.iscomplexobj(v) for v in (n1, n2, nh)):
        return None
    columns = [_column(v, np.float64) for v in (n1, n2, Lambda, delta, N, nh)]
    rows = max(v.shape[0] for v in columns)
    n1, n2, Lambda, delta, N, nh = (np.broadcast_to(v, (rows,) + v.shape[1:]) for v in columns)
    cos_h = np.maximum(np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1), COS_THETA_MIN)
    cos_2 = cos_theta_transmitted(cos_h, n1, n2)
    if np.any(nh >= 1.0) or np.any(np.imag(cos_2) != 0.0):
        return None
    wavelengths = np.asarray(wavelengths, dtype=np.float64).reshape(1, 1, -1)
    R = np.empty((rows, cos_h.shape[1], wavelengths.shape[2]))
    grads = {name: np.empty_like(R) for name in ("Lambda", "delta", "N")}
    for at, part in _row_blocks(rows, cos_h, wavelengths, (n1, n2, Lambda, delta, N)):
        R[at], block = _lossless_reflectance(*part, cos_h, wavelengths, step, smooth, gradient=True)
        for name, value in block.items():
            grads[name][at] = value
    return R, grads


#: Samples (rows x angles x wavelengths) per block of the lossless path: its ~40 temporaries stay in cache.
BLOCK_SAMPLES = 1 << 13


def _row_blocks(rows: int, cos_h, wavelengths, columns):
    """``(slice, columns[slice])`` over blocks of rows of about :data:`BLOCK_SAMPLES` samples each."""
    size = max(1, BLOCK_SAMPLES // max(1, cos_h.shape[1] * wavelengths.shape[2]))
    for start in range(0, rows, size):
        at = slice(start, start + size)
        yield at, tuple(v[at] for v in columns)


def _host_reflectance(n1, n2, Lambda, delta, N, nh, cos_h, wavelengths, step, smooth) -> np.ndarray:
    """:func:`bragg_reflectance_batch` through the complex coefficients: under a host, or with an evanescent layer."""
    host = nh >= 1.0
    eta_h = np.where(host, nh, n1)
    omega = 2.0 * np.pi / wavelengths
    cos_1 = cos_theta_transmitted(cos_h, eta_h, n1)
    cos_2 = cos_theta_transmitted(cos_h, eta_h, n2)
    p1 = n1 * cos_1 * delta * Lambda
    p2 = n2 * cos_2 * (1.0 - delta) * Lambda
    ph = _cell_phases(omega, p1, p2)
    w_point = _point_weight(p1, p2, wavelengths, N, step, smooth, np.broadcast_shapes(cos_1.shape, wavelengths.shape, n1.shape))
    # Each sample computes only the reflectances its weight needs: a scan's spectrum runs from point
    # samples (thin, short cells) to averages (thick stacks), blending both over a factor ~4 in between.
    point, averaged = w_point > 0.0, w_point < 1.0
    total = 0.0
    for pol in POLARISATIONS:
        r12 = fresnel_r(pol, n1, cos_1, n2, cos_2)
        a = np.real(ph.cos_psi * ph.cos_phi - 0.5 * Omega(pol, n1, cos_1, n2, cos_2) * ph.sin_psi * ph.sin_phi)  # Eq. 8
        r1, t1 = slab_coefficients(r12, ph.e_phi)
        r_h1 = np.where(host, fresnel_r(pol, eta_h, cos_h.astype(np.complex128), n1, cos_1), 0.0)
        R = _where_needed(point, _point_reflectance, a, N, r1, t1, ph.e_psi, r_h1)
        if averaged.any():
            average = _where_needed(averaged, _averaged_reflectance, r1, t1, omega, p1, r_h1, a)
            R = w_point * R + (1.0 - w_point) * average
        total = total + R
    return np.clip(total / 2.0, 0.0, 1.0)


#: A cell whose ``|r1|^2 / |t1|^2`` is below this reflects nothing (its phases at multiples of pi, to rounding).
ABSENTEE = 1e-24
#: Below this ``|sin K Lambda|`` or ``Im K Lambda`` the derivatives of ``U_{N-1}`` take their series at the band
#: edge (``dU/da = N (N^2 - 1) / 3``): the closed forms cancel there.
SERIES_EDGE = 1e-4


def _lossless_reflectance(n1, n2, Lambda, delta, N, cos_h, wavelengths, step, smooth, gradient: bool = False):
    """
    :func:`bragg_reflectance_batch` of mirrors in ``n1`` (no separate host) whose waves all propagate, in real
    arithmetic (:func:`explorer.physics.bragg.reflectance._reflectance_real`'s form): Eq. 2 as
    ``R = |r1|^2 U^2 / (|r1|^2 U^2 + |t1|^2)`` with ``U = U_{N-1}(cos K Lambda)`` (real ``N``), in band gaps
    ``|r1|^2 / (|r1|^2 + |t1|^2 S^2)`` with ``S = 1 / U = sinh x / sinh N x`` (Eq. 9, no overflow), and the fringe
    average ``1 - sqrt(|t1|^2 sin^2 K Lambda / (|r1|^2 + |t1|^2 sin^2 K Lambda))``; ``|r1|^2 : |t1|^2 = 4 r12^2
    sin^2 phi : (1 - r12^2)^2`` (their common denominator cancels). Returns ``(R, None)``, or with ``gradient``
    ``(R, {"Lambda": dR/dLambda, "delta": dR/ddelta, "N": dR/dN})``, each ``(B, A, W)``: analytic derivatives of the
    same expressions (the clip to [0, 1] aside, which a lossless mirror never reaches).
    """
    omega = 2.0 * np.pi / wavelengths
    c1 = cos_h  # the host is n1
    c2 = np.real(cos_theta_transmitted(cos_h, n1, n2))
    k1, k2 = n1 * c1, n2 * c2  # (B, A, 1) or per wavelength
    p1, p2 = k1 * delta * Lambda, k2 * (1.0 - delta) * Lambda
    psi, phi = omega * p1, omega * p2
    cos_psi, sin_psi, cos_phi, sin_phi = np.cos(psi), np.sin(psi), np.cos(phi), np.sin(phi)
    shape = np.broadcast_shapes(psi.shape, phi.shape, np.shape(N))
    N = np.asarray(N, dtype=np.float64)
    cell = _Cell(cos_psi * cos_phi, sin_psi * sin_phi, sin_phi * sin_phi, N, np.ones(shape), None)
    if step is not None:
        path = np.maximum(p1 + p2, 1e-9)
        fringe = wavelengths**2 / (2.0 * N * path)
        raw = (fringe / (step if smooth is None else smooth) - 1.0) / 3.0
        cell.w = np.broadcast_to(np.clip(raw, 0.0, 1.0), shape)
        cell.blended = bool(np.any(cell.w < 1.0))
    # Both polarisations' terms agree at normal incidence: there one pass counts twice.
    (r12_s, half_s), (r12_p, half_p) = ((fresnel_r(pol, n1, c1, n2, c2), 0.5 * Omega(pol, n1, c1, n2, c2)) for pol in POLARISATIONS)
    same = np.all(np.broadcast_to(same_polarisations(r12_s * r12_s, r12_p * r12_p, half_s, half_p),
                                  np.broadcast_shapes(r12_s.shape, half_s.shape, (1, shape[1], 1))), axis=(0, 2))
    twice = np.where(same, 2.0, 1.0).reshape(1, -1, 1)
    differ = np.flatnonzero(~same)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        terms = [(_polarisation(cell, r12_s, half_s, gradient), twice)]
        if differ.size:
            terms.append((_polarisation(cell.at(differ), r12_p[:, differ], half_p[:, differ], gradient), differ))
    total = terms[0][0][0] * twice
    if differ.size:
        total[:, differ] += terms[1][0][0]
    if not gradient:
        return np.clip(total / 2.0, 0.0, 1.0), None
    grads = {name: np.zeros(shape) for name in ("Lambda", "delta", "N")}
    for (_, jump, R_a, R_r, R_N), where in terms:
        at = slice(None) if where is twice else where
        factor = twice if where is twice else 1.0
        pick = lambda v: v[:, at] if np.ndim(v) == 3 and np.shape(v)[1] == shape[1] else v  # noqa: E731
        sp, cp, sf, cf, hf = pick(sin_psi), pick(cos_psi), pick(sin_phi), pick(cos_phi), pick(half_s if where is twice else half_p)
        r12 = pick(r12_s if where is twice else r12_p)
        R_psi = R_a * (-sp * cf - hf * cp * sf)
        R_phi = R_a * (-cp * sf - hf * sp * cf) + R_r * (8.0 * r12 * r12 * sf * cf)
        dL = (R_psi * pick(psi) + R_phi * pick(phi)) / Lambda
        dd = (R_psi * pick(k1) - R_phi * pick(k2)) * (omega * Lambda)
        dN = R_N
        if jump is not None:
            # The weight's own slope where it blends: w = (lambda^2 / (2 N P s) - 1) / 3, P = p1 + p2.
            r = pick(np.broadcast_to(raw, shape))
            dw = np.where((r > 0.0) & (r < 1.0), pick(np.broadcast_to(fringe, shape)) / (3.0 * (step if smooth is None else smooth)), 0.0)
            jump = jump * dw
            dN = dN - jump / N
            dL = dL - jump / Lambda
            dd = dd - jump * pick(k1 - k2) * Lambda / pick(path)
        for name, value in (("Lambda", dL), ("delta", dd), ("N", dN)):
            grads[name][:, at] += factor * value
    return np.clip(total / 2.0, 0.0, 1.0), {k: v / 2.0 for k, v in grads.items()}


@dataclass
class _Cell:
    """What both polarisations of :func:`_lossless_reflectance` share: the phases' products, ``N`` and the weight ``w``."""

    cos_cos: np.ndarray
    sin_sin: np.ndarray
    sin2_phi: np.ndarray
    N: np.ndarray
    w: np.ndarray
    blended: bool | None

    def at(self, angles: np.ndarray) -> "_Cell":
        A = self.w.shape[1]
        pick = lambda v: v[:, angles] if np.ndim(v) == 3 and v.shape[1] == A else v  # noqa: E731
        return _Cell(pick(self.cos_cos), pick(self.sin_sin), pick(self.sin2_phi), self.N, pick(self.w), self.blended)


def _polarisation(cell: _Cell, r12, half_omega, gradient: bool):
    """
    One polarisation of :func:`_lossless_reflectance`: ``(R, jump, dR/da, dR/d|r1|^2, dR/dN)`` (``jump``: the point
    value less the average, where the weight blends them; the derivatives None without ``gradient``).
    """
    N, w = cell.N, cell.w
    shape = w.shape
    a = cell.cos_cos - half_omega * cell.sin_sin  # Eq. 8
    r12_2 = r12 * r12
    r1_2 = (4.0 * r12_2) * cell.sin2_phi
    t1_2 = (1.0 - r12_2) ** 2  # (B, A, 1), broadcast
    band = np.abs(a) < 1.0
    gap = ~band
    any_gap = bool(gap.any())
    a_band = np.where(band, a, 0.0) if any_gap else a
    s2 = 1.0 - a_band * a_band  # sin^2 K Lambda in the band (1 in a gap, unused there)
    t = np.arccos(a_band)
    Nt = N * t
    sin_Nt = np.sin(Nt)
    edge = s2 < BATCH_EDGE * BATCH_EDGE
    # In the band R = |r1|^2 G / (|r1|^2 G + |t1|^2), G = U^2 = sin^2 N t / sin^2 t (N^2 at a band edge).
    G = sin_Nt * sin_Nt / np.where(edge, 1.0, s2)
    if edge.any():
        G = np.where(edge, N * N, G)
    D = r1_2 * G + t1_2
    R_point = np.divide(r1_2 * G, D, out=np.zeros(shape), where=D > 0.0)
    # In a gap (Eq. 9): x = Im K Lambda = acosh |a|, S = 1 / U = sinh x / sinh N x, R = |r1|^2 / (|r1|^2 + |t1|^2 S^2).
    x = np.ones(shape)
    S = np.zeros(shape)
    if any_gap:
        Nb, r1_2b, t1_2b = (np.broadcast_to(v, shape) for v in (N, r1_2, t1_2))
        xg = np.maximum(np.arccosh(np.abs(a[gap])), 1e-12)
        Ng = Nb[gap]
        Sg = np.exp(-(Ng - 1.0) * xg) * np.expm1(-2.0 * xg) / np.expm1(-2.0 * Ng * xg)
        x[gap], S[gap] = xg, Sg
        rg = r1_2b[gap]
        Dg = rg + t1_2b[gap] * Sg * Sg
        R_point[gap] = np.divide(rg, Dg, out=np.zeros(Dg.shape), where=Dg > 0.0)
    R, jump = R_point, None
    if cell.blended:
        s2_avg = np.where(band, s2, 0.0) if any_gap else s2  # sin^2 K Lambda: 0 in a gap, whose average is 1
        D_avg = r1_2 + t1_2 * s2_avg
        # A cell that reflects nothing (an absentee cell: |r1|^2 at rounding) has no gap and no fringes: R = 0, not 0/0.
        rho = np.divide(t1_2 * s2_avg, D_avg, out=np.ones(shape), where=(D_avg > 0.0) & (r1_2 > ABSENTEE * t1_2))
        root = np.sqrt(rho)
        R_avg = 1.0 - root
        jump = R_point - R_avg
        R = R_avg + w * jump
    if not gradient:
        return R, jump, None, None, None
    sin_t = np.sqrt(np.where(band, s2, 1.0))
    U = np.where(edge, N, sin_Nt / np.where(edge, 1.0, sin_t))
    D = np.where(band, D, r1_2 + t1_2 * S * S)
    cos_Nt = np.cos(Nt)
    small = sin_t < SERIES_EDGE
    safe = np.where(small, np.maximum(sin_t, BATCH_EDGE), sin_t)
    dU_da = np.where(small & (a_band > 0.0), N * (N * N - 1.0) / 3.0, -(N * cos_Nt * sin_t - sin_Nt * a_band) / safe**3)
    dU_da = np.where(edge & ~(a_band > 0.0), 0.0, dU_da)
    dU_dN = np.where(edge, 1.0, t * cos_Nt / np.where(edge, 1.0, sin_t))
    coth_Nx = 1.0 / np.tanh(N * x)
    series = x < SERIES_EDGE
    dlnS_dx = np.where(series, x * (1.0 - N * N) / 3.0, 1.0 / np.tanh(x) - N * coth_Nx)
    dS_da = np.where(series, S * (1.0 - N * N) / 3.0, S * dlnS_dx / np.sinh(np.where(series, 1.0, x))) * np.sign(a)
    dS_dN = -S * x * coth_Nx
    D2 = np.where(D > 0.0, D * D, np.inf)
    dR_dU = 2.0 * r1_2 * t1_2 * U / D2
    dR_dS = -2.0 * r1_2 * t1_2 * S / D2
    R_a = np.where(band, dR_dU * dU_da, dR_dS * dS_da)
    R_N = np.where(band, dR_dU * dU_dN, dR_dS * dS_dN)
    R_r = np.where(band, G, S * S) * t1_2 / D2
    if cell.blended:
        avg_D2 = np.where(D_avg > 0.0, D_avg * D_avg, np.inf)
        dAvg_drho = np.where(root > 1e-12, -0.5 / np.where(root > 1e-12, root, 1.0), 0.0)
        avg_a = np.where(band, dAvg_drho * (t1_2 * r1_2 / avg_D2) * (-2.0 * a_band), 0.0)
        avg_r = np.where(band, dAvg_drho * (-t1_2 * s2_avg / avg_D2), 0.0)
        R_a = w * R_a + (1.0 - w) * avg_a
        R_r = w * R_r + (1.0 - w) * avg_r
        R_N = w * R_N
    return R, jump, R_a, R_r, R_N


def _point_reflectance(a, N, r1, t1, e_psi, r_h1) -> np.ndarray:
    """``|r_hN|^2`` of :func:`bragg_reflectance_batch` at its samples (Appendix D, ``N`` real)."""
    U_N1, U_N2, _ = chebyshev_U_real_N(a, N)
    r_N = r1 * U_N1 / (U_N1 - U_N2 * t1 * e_psi)
    return np.abs(reflection_coefficient_host(r_N, r_h1)) ** 2


def _averaged_reflectance(r1, t1, omega, p1, r_h1, a) -> np.ndarray:
    """``|r_hN|^2`` of :func:`bragg_reflectance_batch` averaged over its fringes (Appendix D)."""
    return fringe_average_under_host(r1, t1, omega, _Geometry(p1, r_h1), a)


def _where_needed(mask: np.ndarray, function: Callable[..., np.ndarray], *arrays) -> np.ndarray:
    """``function(*arrays)`` where ``mask`` (the arrays broadcast to its shape), 0 elsewhere."""
    if mask.all():
        return np.broadcast_to(function(*arrays), mask.shape)
    out = np.zeros(mask.shape)
    if mask.any():
        out[mask] = function(*(np.broadcast_to(v, mask.shape)[mask] for v in arrays))
    return out


@dataclass
class _Geometry:
    """What :func:`explorer.physics.bragg.fringe_average_under_host` reads of a cell (``r_h1 = 0``: no host)."""

    p1: np.ndarray
    r_h1: np.ndarray


def absorbing_reflectance_batch(n1: ArrayLike, n2: ArrayLike, Lambda: ArrayLike, delta: ArrayLike, N: ArrayLike, nh: ArrayLike,
                                cos_theta: ArrayLike, wavelengths: ArrayLike,
                                step: float | None = None, smooth: float | None = None) -> np.ndarray:
    """
    :func:`bragg_reflectance_batch` with complex indices ``n1``, ``n2`` (``(B,)`` or ``(B, 1, W)``) under a lossless
    host ``nh`` (``nh < 1``: ``Re n1``, as :class:`explorer.physics.natural.NaturalMirror`).

    Yeh's ``[M]^N = U_{N-1} M - U_{N-2} I`` (Appendix D) holds at each wavelength with complex indices, where
    ``cos K Lambda`` is complex, and so is ``K Lambda = t``. With ``Im t >= 0`` and ``z = e^{i t}`` (``|z| <= 1``),
    ``z^{N-1} (1 - z^2) U_{N-1} = 1 - z^{2N}`` and ``z^{N-1} (1 - z^2) U_{N-2} = z (1 - z^{2N-2})``: ``r_N`` is a
    ratio of these, finite for any (real) ``N``. At point samples (``step`` None, or fringes wide against it) it
    is the exact unpolarised reflectance of :func:`explorer.physics.natural.mirror_spectrum` (tested to 1e-9).
    Fringes narrower than a few steps are blended into :func:`explorer.physics.bragg.fringe_average_under_host`
    taken at ``Re cos K Lambda`` (the screening's approximation), less so where absorption damps them
    (visibility ``exp(-2 N Im K Lambda)``).
    """
    n1, n2 = _column(n1).astype(np.complex128), _column(n2).astype(np.complex128)
    Lambda, delta, N = (_column(v, np.float64) for v in (Lambda, delta, N))
    nh = np.real(_column(nh)).astype(np.float64)
    eta_h = np.where(nh >= 1.0, nh, np.real(n1))
    cos_h = np.maximum(np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1), COS_THETA_MIN)
    wavelengths = np.asarray(wavelengths, dtype=np.float64).reshape(1, 1, -1)
    omega = 2.0 * np.pi / wavelengths
    n_sin = eta_h * np.sqrt(1.0 - cos_h * cos_h)
    kz_h = (eta_h * cos_h).astype(np.complex128)
    kz1, kz2 = multilayer.forward_kz(n1, n_sin), multilayer.forward_kz(n2, n_sin)
    p1, p2 = kz1 * delta * Lambda, kz2 * (1.0 - delta) * Lambda
    ph = _cell_phases(omega, p1, p2)
    shape = np.broadcast_shapes(kz1.shape, kz2.shape, wavelengths.shape, N.shape, Lambda.shape)
    w_point = _point_weight(p1, p2, wavelengths, N, step, smooth, shape)
    total = 0.0
    for pol in POLARISATIONS:
        r12, _ = multilayer.interface(pol, n1, kz1, n2, kz2)
        r_h1, _ = multilayer.interface(pol, eta_h.astype(np.complex128), kz_h, n1, kz1)
        x = kz2 / kz1 if pol == "s" else (n1 * n1 * kz2) / (n2 * n2 * kz1)
        x = np.where(np.abs(x) < 1e-10, 1e-10, x)
        a = ph.cos_psi * ph.cos_phi - 0.5 * (x + 1.0 / x) * ph.sin_psi * ph.sin_phi  # Eq. 8, complex
        r1, t1 = slab_coefficients(r12, ph.e_phi)
        # Below the gap at K Lambda ~ pi, U_n(-b) = (-1)^n U_n(b): the ratio U_{N-2} / U_{N-1} of -a, negated,
        # continues the count N as the real model does (chebyshev_U's gap: no phase e^{2 pi i N} between counts).
        flip = np.real(a) < -1.0
        t = np.arccos(np.where(flip, -a, a).astype(np.complex128))
        t = np.where(np.imag(t) < 0.0, -t, t)  # U_n(cos t) is even in t: the decaying branch
        z = np.exp(1j * t)
        one_z2 = 1.0 - z * z
        edge = np.abs(one_z2) < BATCH_EDGE
        safe = np.where(edge, 1.0, one_z2)
        W1 = np.where(edge, N, (1.0 - np.exp(2j * N * t)) / safe)
        W2 = np.where(edge, z * (N - 1.0), z * (1.0 - np.exp(2j * (N - 1.0) * t)) / safe)
        W2 = np.where(flip, -W2, W2)
        r_N = r1 * W1 / (W1 - W2 * t1 * ph.e_psi)
        R = np.abs(reflection_coefficient_host(r_N, r_h1)) ** 2
        if step is not None and np.any(w_point < 1.0):
            average = fringe_average_under_host(r1, t1, omega, _Geometry(p1, r_h1), np.real(a))
            w = 1.0 - (1.0 - w_point) * np.exp(-2.0 * N * np.imag(t))
            R = w * R + (1.0 - w) * average
        total = total + R
    return np.clip(total / 2.0, 0.0, 1.0)
