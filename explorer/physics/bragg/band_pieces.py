"""
The converged colour by Gauss quadrature over band pieces (ours): the integral of Yeh's R against the CMFs with a few
hundred reflectances per angle whatever ``N`` (:func:`band_pieces_rgb`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.physics.bragg.mirror import POLARISATIONS, BraggMirror, cell_geometry
from explorer.physics.bragg.reflectance import chebyshev_U, one_minus_exp_minus_2x

# --------------------------------------------------------------------------------------------------
# The converged colour by Gauss quadrature over band pieces (ours)
#
# The integral of Yeh's R against the CMFs interpolated linearly (what the converged reference computes,
# :func:`explorer.physics.colorimetry.converged_spectra`), with a few hundred reflectances per angle
# whatever N. With x = omega n_+ and Delta = p1 - p2, Eq. 8 is a trigonometric polynomial,
#
#     cos K Lambda = a(omega) = (1/2 + Omega/4) cos(omega n_+) + (1/2 - Omega/4) cos(omega Delta),
#
# whose gaps hold the modes omega_m = m pi / n_+ (Eq. 13) and whose Airy points (a = 0) lie between
# them (Appendix A). Each interval [omega_m, omega_{m+1}] is cut at its band edges e+_m, e-_{m+1}
# (|a| = 1) and its Airy point into four pieces, each anchored at its band edge with the map
# omega = e + S t^2 (t in [0, 1]): Yeh's R is analytic in omega, the fringe average's square root
# 1 - a^2 ~ (omega - e) becomes linear in t, and fringes near the edge (u = K Lambda ~ t) are evenly
# spaced in t. On each piece:
#
# - a pass band's first BAND_EDGE_FRINGES fringes from its edge (u < M pi / N): Yeh's exact R. The cut lies
#   on a transmission dip (sin N u = 0), where the fringes' integration-by-parts boundary terms vanish (see
#   the windowed section above). Panels end at every half fringe (u = h pi / 2N, found by Newton's method);
#   around each dip 1 - R = 1 / (1 + F sin^2 N u), F = |C|^2 / sin^2 u, is integrated on nodes squeezed by
#   psi = arctan(tan(chi) / k), k = sqrt(1 + F), under which (1 - R) d psi = d chi / k: a dip of any
#   sharpness (F ~ (N |C|)^2 near edges) costs FRINGE_NODES nodes a side;
# - the rest of the pass band: the fringe average Rbar (its harmonics integrate to O((N u')^-2)),
#   smooth in t, on panels graded geometrically from the cut. Where fringes are wider than FRINGE_MEAN_NM
#   anywhere in a piece, or N < PIECES_EXACT_N, Yeh's R throughout instead;
# - a gap: Yeh's R while N Im[K] Lambda < GAP_DECAY (its deficit 1 - R decays like exp(-2 N Im[K] Lambda)),
#   then R = 1, integrated against the CMFs in closed form.
#
# Every panel is also cut to at most PANEL_NM nm for the CMFs. The pieces tile the visible range exactly
# (tests/test_fast_tables.py).
#
# Under a host nh != n1 (Appendix D) the same pieces hold |r_hN|^2: its transmission peaks are the mirror's dips moved
# by psi0 in N K Lambda and sharpened to k (_host_dip), so the fringe boundaries move there, and the fringe average is
# the coherent one (fringe_average_under_host, in closed form). References: Section 3.1 (Eqs. 2, 8-10), Appendices A
# and D; Yeh (1988), Chapter 6.

#: Fringes from a band edge integrated exactly (Yeh's R); beyond them, the fringe average. 8, not 4: with
#: fringes up to FRINGE_MEAN_NM wide the average's error at N = 64-100 halved (2e-4 -> 1e-4 of a 1e-5 reference).
BAND_EDGE_FRINGES = 8
#: Gauss-Legendre nodes per panel (one panel per fringe near band edges).
GAUSS_NODES = 8
#: Nodes per fringe near band edges (clustered at the fringe's ends, where its transmission dip is).
FRINGE_NODES = 6
#: A pass piece whose fringes are wider than this (nm) at its Airy point is Yeh's R throughout. 3 nm, not 1:
#: N = 64-300 pieces then take the fringe average beyond their edge fringes (half the nodes), within 1e-4.
FRINGE_MEAN_NM = 3.0
#: ... times N / PIECES_EXACT_N, up to this factor: the average's error at a given fringe width falls with N (measured:
#: 6-nm fringes 2.8e-4 at N = 64, 1.1e-4 at N = 100, against a 1e-5 reference).
FRINGE_MEAN_GROWTH = 2.0
#: ... under a host: a strongly reflecting host interface (grazing) and the mirror form a cavity whose fringes are
#: not the mirror's shape (nh = 1 over n1 = 1.5, N = 20, cos 0.02: 2.9e-4 with 6 nodes, 1.3e-4 with 8).
HOST_FRINGE_NODES = 8
#: ... under a host: its interface and the mirror interfere to first order in the mirror's r1 (the mirror alone: second),
#: so wide fringes' harmonics weigh more against R: no growth (weak contrast 1.05/1.10 under nh = 1, N = 300: 4.4e-4 with
#: 6-nm fringes averaged, 1e-7 with 3 nm).
HOST_FRINGE_MEAN_GROWTH = 1.0
#: Dips with k = sqrt(1 + F) above this are integrated as 1 - (1 - R), the dip on squeezed nodes.
DIP_SHARP = 2.0
#: Panels of a gap's exact part.
GAP_PANELS = 4
#: Widest panel in wavelength (nm), for the CMFs' own structure.
PANEL_NM = 16.0
#: N Im[K] Lambda beyond which a gap reflects 1 (to exp(-2 GAP_DECAY)).
GAP_DECAY = 12.0
#: Newton steps (bisection-safeguarded) for the Airy points, band edges and the cuts.
ROOT_STEPS = 8
#: Fringe boundaries: u on this many points of t per piece for first guesses, then Newton steps.
ROOT_GRID = 17
ROOT_POLISH = 2
#: Under a host: Newton steps moving the fringe boundaries to the host's peaks (_host_dip).
HOST_SHIFT_STEPS = 1


@functools.lru_cache(maxsize=None)
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


@functools.lru_cache(maxsize=None)
def _cmf_nodes() -> tuple[np.ndarray, np.ndarray]:
    """The CMFs at the 473 nodes 359..831 nm (zero at both ends) and their exact cumulative integral there."""
    c = np.vstack([np.zeros(3), colorimetry.colour_matching_functions(), np.zeros(3)])
    cumulative = np.vstack([np.zeros(3), np.cumsum(0.5 * (c[:-1] + c[1:]), axis=0)])
    return c, cumulative


def _cmf_linear(wavelength: np.ndarray) -> np.ndarray:
    """The CMFs interpolated linearly between their 1-nm nodes (zero outside 359-831 nm), ``(n, 3)``."""
    c, _ = _cmf_nodes()
    nodes = colorimetry.HAT_LOW + np.arange(c.shape[0], dtype=np.float64)
    return np.stack([np.interp(wavelength, nodes, c[:, channel], left=0.0, right=0.0) for channel in range(3)], axis=-1)


def _cmf_integral_to(wavelength: np.ndarray) -> np.ndarray:
    """``int_359^lambda`` of :func:`_cmf_linear` in closed form (piecewise quadratic), ``(n, 3)``."""
    c, cumulative = _cmf_nodes()
    x = np.clip(wavelength - colorimetry.HAT_LOW, 0.0, c.shape[0] - 1.0)
    i = np.minimum(x.astype(np.int64), c.shape[0] - 2)
    f = (x - i)[:, None]
    return cumulative[i] + c[i] * f + (c[i + 1] - c[i]) * (0.5 * f * f)


#: Below this many values :func:`_cos_sin` calls numpy's ``cos`` and ``sin``: per-call overhead dominates there.
COS_SIN_MIN_SIZE = 2048


def _cos_sin(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    ``(cos x, sin x)`` from ``tau = tan(r / 2)``, ``r`` = ``x`` reduced to [-pi, pi]: ``((1 - tau^2), 2 tau) / (1 + tau^2)``.
    numpy's float64 ``tan`` is vectorised where its ``cos`` and ``sin`` are not (1.5 against ~20 ns a value on this
    machine): 2.5x faster for both, to ~1e-14 for ``|x| <= 100`` (the band pieces' phases stay below ~70).
    """
    if np.size(x) < COS_SIN_MIN_SIZE:  # small arrays (root finding): two calls cost less than the ten below
        return np.cos(x), np.sin(x)
    tau = np.tan(0.5 * (x - (2.0 * np.pi) * np.rint(x * (0.5 / np.pi))))
    tau2 = tau * tau
    inverse = 1.0 / (1.0 + tau2)
    return (1.0 - tau2) * inverse, 2.0 * tau * inverse


@dataclass
class _Lines:
    """Per (angle, polarisation) line: Eq. 8's trigonometric form and Eq. 10's slab terms (real angles)."""

    n_plus: np.ndarray
    delta_p: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray
    p2: np.ndarray
    r12_2: np.ndarray
    N: int
    #: Under a host nh != n1 (Appendix D): the signed r12 and the host interface's real r_h1 per line; None otherwise.
    r12: np.ndarray | None = None
    r_h1: np.ndarray | None = None

    def a(self, omega, line):
        """``cos K Lambda`` (Eq. 8) and its derivative in omega."""
        n_plus, delta_p = self.n_plus[line], self.delta_p[line]
        (cos_x, sin_x), (cos_y, sin_y) = _cos_sin(omega * n_plus), _cos_sin(omega * delta_p)
        alpha, beta = self.alpha[line], self.beta[line]
        return alpha * cos_x + beta * cos_y, -(alpha * n_plus * sin_x + beta * delta_p * sin_y)


def _safeguarded_newton(g, lo, hi, guess, positive_at_lo, steps=ROOT_STEPS):
    """The root of ``g`` (returning value and slope) in ``[lo, hi]``, where it changes sign once."""
    x = np.clip(guess, np.minimum(lo, hi), np.maximum(lo, hi))
    for _ in range(steps):
        value, slope = g(x)
        same = (value >= 0.0) == positive_at_lo
        lo, hi = np.where(same, x, lo), np.where(same, hi, x)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = x - value / slope
        # A converged x sits on its bracket's end: its Newton step (x itself) is kept, not bisected away.
        inside = np.isfinite(step) & ((step - lo) * (step - hi) <= 0.0)
        x = np.where(inside, step, 0.5 * (lo + hi))
    return x


def _panels(piece, lo, hi, count):
    """``count`` equal panels of ``[lo, hi]`` per entry (flattened): their piece, lower end and width."""
    count = np.asarray(count, dtype=np.int64)
    panel_piece = np.repeat(piece, count)
    j = np.arange(panel_piece.size) - np.repeat(np.cumsum(count) - count, count)
    width = np.repeat((hi - lo) / np.maximum(count, 1), count)
    return panel_piece, np.repeat(lo, count) + j * width, width


def _pieces_xyz(lines: _Lines, exact_everywhere: bool, scale: int = 1) -> np.ndarray:
    """XYZ (the CMFs' integral of R) of every line, ``(n_lines, 3)``; ``scale`` multiplies every node count."""
    N = lines.N
    n_lines = lines.n_plus.size
    omega_lo, omega_hi = 2.0 * np.pi / colorimetry.HAT_HIGH, 2.0 * np.pi / colorimetry.HAT_LOW
    m_first = np.floor(omega_lo * lines.n_plus / np.pi)
    m_last = np.floor(omega_hi * lines.n_plus / np.pi)
    count = int((m_last - m_first).max()) + 1
    line, k = np.divmod(np.arange(n_lines * count), count)
    m = m_first[line] + k
    valid = m <= m_last[line]
    line, m = line[valid], m[valid]
    n_plus = lines.n_plus[line]
    omega_m, omega_next = m * np.pi / n_plus, (m + 1.0) * np.pi / n_plus
    sign_m = np.where(m % 2 == 0, 1.0, -1.0)  # the sign of a at omega_m (Appendix A)

    def shifted_a(sign, shift):
        def g(w):
            value, slope = lines.a(w, line)
            return sign * value - shift, sign * slope
        return g

    airy = _safeguarded_newton(shifted_a(sign_m, 0.0), omega_m, omega_next, 0.5 * (omega_m + omega_next), True)
    # Both band edges in one solve (a is +-1 there): elementwise the same as two, half the numpy calls.
    both_line, both_sign = np.concatenate([line, line]), np.concatenate([sign_m, -sign_m])

    def edge_g(w):
        value, slope = lines.a(w, both_line)
        return both_sign * value - 1.0, both_sign * slope

    edges = _safeguarded_newton(edge_g, np.concatenate([omega_m, airy]), np.concatenate([airy, omega_next]),
                                np.concatenate([0.5 * (omega_m + airy), 0.5 * (airy + omega_next)]),
                                np.repeat([True, False], line.size))
    edge_up, edge_down = np.where(m == 0, 0.0, edges[: line.size]), edges[line.size :]
    # Four pieces per interval, each anchored at a band edge e with omega = e + S t^2: two halves of the pass band
    # (towards the Airy point), two halves of gaps (towards the modes).
    anchor = np.concatenate([edge_up, edge_down, edge_up, edge_down])
    span = np.concatenate([airy - edge_up, airy - edge_down, omega_m - edge_up, omega_next - edge_down])
    piece_line = np.tile(line, 4)
    is_gap = np.repeat([False, False, True, True], line.size)
    with np.errstate(divide="ignore", invalid="ignore"):
        q_lo, q_hi = (omega_lo - anchor) / span, (omega_hi - anchor) / span
    t0 = np.sqrt(np.clip(np.nan_to_num(np.minimum(q_lo, q_hi), nan=1.0), 0.0, 1.0))
    t1 = np.sqrt(np.clip(np.nan_to_num(np.maximum(q_lo, q_hi), nan=0.0), 0.0, 1.0))
    keep = t1 > t0
    anchor, span, piece_line, is_gap, t0, t1 = (v[keep] for v in (anchor, span, piece_line, is_gap, t0, t1))

    def omega_at(t, pieces):
        return anchor[pieces] + span[pieces] * t * t

    def a_at_t(t, pieces):
        value, slope = lines.a(omega_at(t, pieces), piece_line[pieces])
        return value, slope * 2.0 * span[pieces] * t

    def nm_between(t_a, t_b, pieces):
        return np.abs(2.0 * np.pi / omega_at(t_a, pieces) - 2.0 * np.pi / omega_at(t_b, pieces))

    # u (or Im[K] Lambda in a gap) ~ sqrt(2 |a'(e)| |S|) t near the edge: the roots' first guesses.
    _, slope_e = lines.a(anchor, piece_line)
    u_slope = np.sqrt(np.maximum(2.0 * np.abs(slope_e * span), 1e-300))
    # Panels: (piece, t_a, t_span, k, kind): t = t_a + t_span (2 / pi) arctan(tan(chi) / k), chi in [0, pi / 2].
    panels = []

    def add(piece, t_a, t_span, k, kind, nodes):
        chi_hi = np.full(piece.size, 0.5 * np.pi)
        panels.append((piece, t_a, t_span, k, kind, nodes, chi_hi))

    band = np.flatnonzero(~is_gap)
    # Each pass piece is exact up to u_cut: M fringes from its edge, or the whole piece where fringes
    # (lambda^2 / (2 N du/domega) wide) are wider than FRINGE_MEAN_NM at its Airy point or at either end of its
    # visible part, as the fringe average's far harmonics then do not cancel against the CMFs.
    def fringe_nm_at(t):
        value, slope = lines.a(omega_at(t, band), piece_line[band])
        du_domega = np.abs(slope) / np.maximum(np.sqrt(np.maximum(1.0 - value * value, 0.0)), 1e-300)
        lam = 2.0 * np.pi / omega_at(t, band)
        return lam * lam / (2.0 * N * np.maximum(du_domega, 1e-300))

    fringe_nm = np.maximum(np.maximum(fringe_nm_at(t0[band]), fringe_nm_at(t1[band])), fringe_nm_at(np.ones(band.size)))
    growth = FRINGE_MEAN_GROWTH if lines.r_h1 is None else HOST_FRINGE_MEAN_GROWTH
    mean_nm = FRINGE_MEAN_NM * min(max(N / PIECES_EXACT_N, 1.0), growth)
    whole = exact_everywhere | (fringe_nm > mean_nm) | (BAND_EDGE_FRINGES * np.pi / N >= 0.5 * np.pi)
    u_cut = np.where(whole, 0.5 * np.pi, BAND_EDGE_FRINGES * np.pi / N)
    def fringe_panels(band, u_cut):
        """The exact part of the pass pieces ``band`` (up to ``u_cut``), as panels; returns the cut in t."""
        # Fringe boundaries: u = h pi / (2 N), h = 1..H (clamped to each piece's cut); the transmission dips at even h.
        H = int(np.ceil(2.0 * u_cut.max() * N / np.pi - 1e-9))
        halves = np.arange(1, H + 1)
        targets = np.minimum(halves[None, :] * 0.5 * np.pi / N, u_cut[:, None])  # (band, H)
        bp = np.repeat(band, H)
        target = targets.ravel()

        def g(t):
            value, slope = a_at_t(t, bp)
            u = np.arccos(np.clip(np.abs(value), 0.0, 1.0))
            return u - target, -np.sign(value) * slope / np.maximum(np.sin(u), 1e-300)

        # First guesses: u on a grid of t per piece, inverted linearly; then Newton within the grid's bracket.
        grid = np.linspace(0.0, 1.0, ROOT_GRID)
        u_grid = np.arccos(np.clip(np.abs(a_at_t(np.tile(grid, band.size), np.repeat(band, ROOT_GRID))[0]), 0.0, 1.0))
        u_grid = np.maximum.accumulate(u_grid.reshape(band.size, ROOT_GRID), axis=1)
        j = np.clip((u_grid[:, :, None] < targets[:, None, :]).sum(axis=1), 1, ROOT_GRID - 1)  # (band, H)
        u_a = np.take_along_axis(u_grid, j - 1, axis=1)
        u_b = np.take_along_axis(u_grid, j, axis=1)
        f = np.clip((targets - u_a) / np.maximum(u_b - u_a, 1e-300), 0.0, 1.0)
        guess = (grid[j - 1] + f * (grid[1] - grid[0])).ravel()
        bounds = _safeguarded_newton(g, grid[j - 1].ravel(), grid[j].ravel(), guess, False, steps=ROOT_POLISH)
        if lines.r_h1 is not None:
            # Under a host the transmission peaks sit at N K Lambda = j pi + psi0 (_host_dip), not at the mirror's
            # dips: the boundaries move there (Newton steps on N u - psi0 = h pi / 2: psi0 varies slowly), so that the
            # squeezed nodes are centred on the peaks and the cut to the fringe average lies where the fringes' boundary
            # terms vanish (cut at the mirror's dip instead: 1.3e-3 at nh = 2.4, N = 100; 3e-5 once moved).
            shifted = bounds
            for _ in range(HOST_SHIFT_STEPS):
                value, slope = a_at_t(shifted, bp)
                u = np.arccos(np.clip(np.abs(value), 0.0, 1.0))
                du_dt = np.abs(slope) / np.maximum(np.sin(u), 1e-300)
                psi0, _ = _host_dip(lines, omega_at(shifted, bp), piece_line[bp])
                # psi0 is defined mod pi: made continuous along each piece from its edge (where psi0 -> 0), so that every
                # even boundary stays on a peak, also where a host that reflects strongly (grazing) and a weak mirror
                # form a cavity whose sharp peaks sit near the mirror's half fringes (psi0 ~ pi / 2).
                psi0 = np.unwrap(psi0.reshape(band.size, H), period=np.pi, axis=1)
                # u is K Lambda from the piece's edge: N K Lambda = N u where a > 0, N pi - N u where a < 0.
                shift = np.sign(value).reshape(band.size, H) * psi0
                # A peak left between the edge and the first boundary (psi0 not -> 0 at the edge: nearly closed gaps,
                # delta ~ 0, where the edge's fringes are not sharp) would get plain nodes: the boundaries go a fringe back.
                shift = (shift - np.pi * (shift[:, :1] > 0.25 * np.pi)).ravel()
                goal = target + shift / N
                shifted = np.clip(shifted + (goal - u) / np.maximum(du_dt, 1e-300), 0.0, 1.0)
            bounds = np.maximum.accumulate(np.where(target < 0.5 * np.pi - 1e-12, shifted, bounds)
                                           .reshape(band.size, H), axis=1).ravel()
        bounds = np.where(target >= 0.5 * np.pi - 1e-12, 1.0, bounds).reshape(band.size, H)
        cut_t = bounds[:, -1]
        bounds = np.concatenate([np.zeros((band.size, 1)), bounds], axis=1)  # columns: h = 0..H
        # From the edge to the first half fringe: no dip (R -> kappa^2 / (1 + kappa^2) at the edge), Yeh's R.
        add(band, bounds[:, 0], bounds[:, 1] - bounds[:, 0], np.ones(band.size), 0, GAUSS_NODES)
        # Beyond it, two half panels around each dip u = j pi / N. Sharp dips (k = sqrt(1 + F) > DIP_SHARP): R = 1 - (1 - R),
        # the 1 on plain nodes, the dip 1 - R = 1 / (1 + F sin^2 N u) on nodes squeezed by psi = arctan(tan(chi) / k),
        # under which (1 - R) d psi = d chi / k for a fixed F: the dip, however narrow, is spread over the panel.
        dips = np.arange(2, H + 1, 2)
        if dips.size:
            t_dip = bounds[:, dips]
            dip_piece = np.repeat(band, dips.size)
            omega_dip = omega_at(t_dip.ravel(), dip_piece)
            line_dip = piece_line[dip_piece]
            sin_phi = np.sin(omega_dip * lines.p2[line_dip])
            r12_2 = lines.r12_2[line_dip]
            C2 = 4.0 * r12_2 * sin_phi * sin_phi / (1.0 - r12_2) ** 2  # |C|^2 (Eq. 2) = |r1|^2 / |t1|^2
            F = C2 / np.maximum(np.sin(np.tile(dips * 0.5 * np.pi / N, band.size)) ** 2, 1e-300)
            k_dip = np.sqrt(1.0 + F) if lines.r_h1 is None else _host_dip(lines, omega_dip, line_dip)[1]
            k = k_dip
            left = bounds[:, dips - 1].ravel() - t_dip.ravel()
            right = bounds[:, np.minimum(dips + 1, H)].ravel() - t_dip.ravel()
            sharp = k > DIP_SHARP
            # The map takes psi linear in t over the half panel; the dip's width in t is set by dpsi/dt at the dip.
            value, slope = a_at_t(t_dip.ravel(), dip_piece)
            dpsi_dt = N * np.abs(slope) / np.maximum(np.sqrt(np.maximum(1.0 - value * value, 0.0)), 1e-300)
            fringe_nodes = FRINGE_NODES if lines.r_h1 is None else HOST_FRINGE_NODES
            for side in (left, right):
                k = k_dip * np.clip(dpsi_dt * np.abs(side) / (0.5 * np.pi), 0.25, 4.0)
                # Soft dips: Yeh's R on plain nodes (1 and R - 1 would cancel to R's small values).
                add(dip_piece[~sharp], t_dip.ravel()[~sharp], side[~sharp], np.ones(int((~sharp).sum())), 0, fringe_nodes)
                add(dip_piece[sharp], t_dip.ravel()[sharp], side[sharp], np.ones(int(sharp.sum())), 2, fringe_nodes)
                add(dip_piece[sharp], t_dip.ravel()[sharp], side[sharp], k[sharp], 3, fringe_nodes)
        return cut_t

    cut_band = np.ones(band.size)
    for group in (whole, ~whole):
        if group.any():
            cut_band[group] = fringe_panels(band[group], u_cut[group])
    # The rest of the pass band: the fringe average, panels graded geometrically from the cut.
    s0 = cut_band
    rest = s0 < 1.0
    smooth, s0 = band[rest], s0[rest]
    doublings = np.ceil(np.log2(1.0 / np.maximum(s0, 1e-12))).clip(1, 40).astype(np.int64)
    geo_piece = np.repeat(smooth, doublings)
    jj = np.arange(geo_piece.size) - np.repeat(np.cumsum(doublings) - doublings, doublings)
    ratio = (1.0 / np.repeat(np.maximum(s0, 1e-12), doublings)) ** (1.0 / np.repeat(doublings, doublings))
    geo_lo = np.where(jj == 0, np.repeat(s0, doublings), np.repeat(np.maximum(s0, 1e-12), doublings) * ratio**jj)
    geo_hi = np.minimum(np.repeat(np.maximum(s0, 1e-12), doublings) * ratio ** (jj + 1), 1.0)
    add(geo_piece, geo_lo, geo_hi - geo_lo, np.ones(geo_piece.size), 1, GAUSS_NODES)
    # Gaps: Yeh's R up to N Im[K] Lambda = GAP_DECAY, then 1.
    gap = np.flatnonzero(is_gap)
    cut = np.ones(gap.size)
    if not exact_everywhere:
        x_cut = GAP_DECAY / N

        def h(t):
            value, slope = a_at_t(t, gap)
            abs_a = np.maximum(np.abs(value), 1.0)
            return np.arccosh(abs_a) - x_cut, np.sign(value) * slope / np.maximum(np.sqrt(abs_a * abs_a - 1.0), 1e-300)

        end_value, _ = a_at_t(np.ones(gap.size), gap)
        deep = np.arccosh(np.maximum(np.abs(end_value), 1.0)) > x_cut
        solved = _safeguarded_newton(h, np.zeros(gap.size), np.ones(gap.size), np.clip(x_cut / u_slope[gap], 0.0, 1.0), False)
        cut = np.where(deep, solved, 1.0)
    gap_piece, gap_lo, gap_width = _panels(gap, np.zeros(gap.size), cut, np.full(gap.size, GAP_PANELS))
    add(gap_piece, gap_lo, gap_width, np.ones(gap_piece.size), 0, GAUSS_NODES)
    # Nodes: each panel clipped to its piece's visible part (in chi), split for the CMFs (PANEL_NM), Gauss-Legendre.
    # Panels where R = 1 (kind 2, and the gaps beyond their exact part) integrate the CMFs in closed form instead.
    nodes_t, nodes_w, nodes_piece, nodes_kind = [], [], [], []
    ones_piece, ones_lo, ones_hi = [], [], []
    for piece, t_a, t_span, k, kind, n, _ in panels:
        with np.errstate(divide="ignore", invalid="ignore"):
            rel_lo = np.clip((t0[piece] - t_a) / t_span, 0.0, 1.0)
            rel_hi = np.clip((t1[piece] - t_a) / t_span, 0.0, 1.0)
        rel_lo, rel_hi = np.nan_to_num(np.minimum(rel_lo, rel_hi)), np.nan_to_num(np.maximum(rel_lo, rel_hi))
        if kind == 2:
            inside = (rel_hi > rel_lo) & (t_span != 0.0)
            ones_piece.append(piece[inside])
            ones_lo.append((t_a + t_span * rel_lo)[inside])
            ones_hi.append((t_a + t_span * rel_hi)[inside])
            continue
        chi_lo, chi_hi = np.arctan(k * np.tan(0.5 * np.pi * rel_lo)), np.arctan(k * np.tan(0.5 * np.pi * np.minimum(rel_hi, 1.0 - 1e-16)))
        chi_hi = np.where(rel_hi >= 1.0, 0.5 * np.pi, chi_hi)
        inside = (chi_hi > chi_lo) & (t_span != 0.0)
        piece, t_a, t_span, k, chi_lo, chi_hi = (v[inside] for v in (piece, t_a, t_span, k, chi_lo, chi_hi))
        if kind == 3:
            ends_lo = t_a + t_span * (2.0 / np.pi) * np.arctan(np.tan(chi_lo) / k)
            ends_hi = t_a + t_span * (2.0 / np.pi) * np.arctan(np.tan(np.minimum(chi_hi, 0.5 * np.pi - 1e-16)) / k)
        else:  # k = 1
            ends_lo, ends_hi = t_a + t_span * (2.0 / np.pi) * chi_lo, t_a + t_span * (2.0 / np.pi) * chi_hi
        split = np.ceil(nm_between(ends_lo, ends_hi, piece) / PANEL_NM).clip(1, None)
        if (split == 1).all():
            sub, sub_lo, sub_width = np.arange(piece.size), chi_lo, chi_hi - chi_lo
        else:
            sub, sub_lo, sub_width = _panels(np.arange(piece.size), chi_lo, chi_hi, split)
        x, w = _gauss_legendre(n * scale)
        chi = sub_lo[:, None] + sub_width[:, None] * x
        if kind == 3:
            kk = k[sub][:, None]
            cos_chi, sin_chi = _cos_sin(chi)
            psi = np.arctan2(sin_chi, kk * cos_chi)  # arctan(tan(chi) / k) in [0, pi / 2]
            jacobian = np.abs(t_span[sub][:, None]) * (2.0 / np.pi) * kk / (kk * kk * cos_chi * cos_chi + sin_chi * sin_chi)
        else:  # k = 1: psi = chi
            psi, jacobian = chi, np.abs(t_span[sub][:, None]) * (2.0 / np.pi)
        nodes_t.append((t_a[sub][:, None] + t_span[sub][:, None] * (2.0 / np.pi) * psi).ravel())
        nodes_w.append((sub_width[:, None] * w * jacobian).ravel())
        nodes_piece.append(np.repeat(piece[sub], x.size))
        nodes_kind.append(np.full(chi.size, kind, dtype=np.int8))
    t = np.concatenate(nodes_t)
    node_piece = np.concatenate(nodes_piece)
    omega = omega_at(t, node_piece)
    wavelength = 2.0 * np.pi / omega
    weight = np.concatenate(nodes_w) * np.abs(2.0 * span[node_piece] * t) * wavelength / omega
    node_line = piece_line[node_piece]
    value = _line_reflectance(lines, omega, node_line, np.concatenate(nodes_kind))
    xyz = _cmf_weighted_sums(wavelength, value * weight, node_line, n_lines)
    # Gaps beyond their exact part and the sharp dips' "1" reflect 1: the CMFs' integral in closed form.
    ones = cut < 1.0
    ones_piece.append(gap[ones])
    ones_lo.append(np.clip(cut[ones], t0[gap[ones]], t1[gap[ones]]))
    ones_hi.append(t1[gap[ones]])
    pieces, t_a, t_b = np.concatenate(ones_piece), np.concatenate(ones_lo), np.concatenate(ones_hi)
    if pieces.size:
        total = np.abs(_cmf_integral_to(2.0 * np.pi / omega_at(t_a, pieces)) - _cmf_integral_to(2.0 * np.pi / omega_at(t_b, pieces)))
        xyz += np.stack([np.bincount(piece_line[pieces], total[:, c], minlength=n_lines) for c in range(3)], axis=-1)
    return xyz


def _cmf_weighted_sums(wavelength: np.ndarray, value: np.ndarray, line: np.ndarray, n_lines: int) -> np.ndarray:
    """
    ``sum value * CMF(wavelength)`` per line, ``(n_lines, 3)``, with the CMFs interpolated linearly between their
    1-nm nodes (:func:`_cmf_linear`): each value split between its two nodes (two bincounts), then one product
    with the nodes' CMFs, instead of three interpolations and three bincounts.
    """
    c, _ = _cmf_nodes()
    x = np.clip(wavelength - colorimetry.HAT_LOW, 0.0, c.shape[0] - 1.0)
    i = np.minimum(x.astype(np.int64), c.shape[0] - 2)
    f = x - i
    index = line * c.shape[0] + i
    size = n_lines * c.shape[0]
    bins = np.bincount(index, value * (1.0 - f), minlength=size) + np.bincount(index + 1, value * f, minlength=size)
    return bins.reshape(n_lines, c.shape[0]) @ c


#: Nodes per block of :func:`_line_reflectance`: its ~20 temporaries stay in cache (2.5x faster than whole arrays
#: of ~1e5 nodes, measured).
NODE_BLOCK = 16384


def _line_reflectance(lines: _Lines, omega, line, kind) -> np.ndarray:
    """At each node by ``kind`` (:func:`_line_reflectance_block`), by blocks of :data:`NODE_BLOCK` nodes."""
    if omega.size <= NODE_BLOCK:
        return _line_reflectance_block(lines, omega, line, kind)
    out = np.empty(omega.shape)
    for start in range(0, omega.size, NODE_BLOCK):
        at = slice(start, start + NODE_BLOCK)
        out[at] = _line_reflectance_block(lines, omega[at], line[at], kind[at])
    return out


def _line_reflectance_block(lines: _Lines, omega, line, kind) -> np.ndarray:
    """
    At each node by ``kind``: 0, Yeh's R; 1, its fringe average; 2, 1; 3, R - 1. Real arithmetic (Eqs. 2, 8-10;
    ``|r1|^2 : |t1|^2 = 4 r12^2 sin^2 phi : (1 - r12^2)^2``, as :func:`_reflectance_real`). In a pass band Eq. 2 is
    written ``R = |r1|^2 sin^2 N u / (|r1|^2 sin^2 N u + |t1|^2 sin^2 u)``, finite at its transmission dips; in a gap
    with Eq. 9's scaled sinh ratio (:func:`chebyshev_U`).
    """
    out = np.ones(omega.shape)
    rows = np.flatnonzero(kind != 2)
    omega, line, kind = omega[rows], line[rows], kind[rows]
    # Eq. 8 from the layers' own phases (psi = omega p1, phi = omega p2; alpha - beta = Omega / 2): two sines and
    # cosines per node, sin phi among them.
    p2 = lines.p2[line]
    cos_psi, sin_psi = _cos_sin(omega * (lines.n_plus[line] - p2))
    cos_phi, sin_phi = _cos_sin(omega * p2)
    a = cos_psi * cos_phi - (lines.alpha[line] - lines.beta[line]) * (sin_psi * sin_phi)
    r12_2 = lines.r12_2[line]
    r1_2 = (4.0 * r12_2) * (sin_phi * sin_phi)
    t1_2 = (1.0 - r12_2) ** 2
    sin2_u = np.maximum(1.0 - a * a, 0.0)
    value = np.empty(omega.shape)
    N = float(lines.N)
    exact = kind != 1
    band = np.flatnonzero(exact & (np.abs(a) < 1.0))
    gap = np.flatnonzero(exact & (np.abs(a) >= 1.0))
    mean = np.flatnonzero(~exact)
    if lines.r_h1 is not None:
        out[rows] = _host_line_reflectance(lines, line, kind, a, sin2_u, cos_psi, sin_psi, cos_phi, sin_phi)
        return out
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        # Pass band: the deficit 1 - R = |t1|^2 sin^2 u / (|r1|^2 sin^2 N u + |t1|^2 sin^2 u).
        sin_Nu = _cos_sin(N * np.arccos(a[band]))[1]
        t_sin = t1_2[band] * sin2_u[band]
        deficit_band = t_sin / (r1_2[band] * sin_Nu * sin_Nu + t_sin)
        # Gap: Q = (sinh Im[K] Lambda / sinh N Im[K] Lambda)^2, scaled as chebyshev_U.
        xg = np.maximum(np.arccosh(np.abs(a[gap])), 1e-12)
        Q = (np.exp(-(N - 1.0) * xg) * one_minus_exp_minus_2x(xg) / one_minus_exp_minus_2x(N * xg)) ** 2
        deficit_gap = t1_2[gap] * Q / (r1_2[gap] + t1_2[gap] * Q)
        for where, deficit in ((band, deficit_band), (gap, deficit_gap)):
            value[where] = np.where(kind[where] == 3, -deficit, 1.0 - deficit)
        t_sin = t1_2[mean] * sin2_u[mean]
        denominator = r1_2[mean] + t_sin
        value[mean] = 1.0 - np.sqrt(np.where(denominator > 0.0, t_sin / denominator, 1.0))
    out[rows] = value
    return out


def _host_slab(lines: _Lines, line, cos_psi, sin_psi, cos_phi, sin_phi) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 10's ``r1 = r12 (1 - e^{2i phi}) / (1 - r12^2 e^{2i phi})`` and ``t_cell = t1 e^{i psi}`` (Appendix D)."""
    r12 = lines.r12[line]
    r12_2 = r12 * r12
    e_phi = cos_phi + 1j * sin_phi
    e_2phi = e_phi * e_phi
    inverse = 1.0 / (1.0 - r12_2 * e_2phi)
    return r12 * (1.0 - e_2phi) * inverse, (1.0 - r12_2) * e_phi * inverse * (cos_psi + 1j * sin_psi)


def _host_dip(lines: _Lines, omega, line) -> tuple[np.ndarray, np.ndarray]:
    """
    Where the transmission peaks of a mirror under a host lie and how sharp they are, in a pass band: with
    ``z = -S / B = p + i q`` (:func:`_host_line_reflectance`), ``1 - |r_hN|^2 = (1 - R_h1) / D(psi)``,
    ``D = (cos psi - p sin psi)^2 + q^2 sin^2 psi``, ``psi = N K Lambda``: a quadratic form in ``(cos psi, sin psi)``,
    smallest at ``psi0 = atan2(2p, p^2 + q^2 - 1) / 2`` (mod pi), with eigenvalues ``l1 l2 = q^2``,
    ``l1 + l2 = 1 + p^2 + q^2``. So ``D = l1 (1 + (k^2 - 1) sin^2(psi - psi0))`` with ``k = l2 / q``: the mirror's
    dip shape (``psi0 = 0``, ``k = sqrt(1 + F)`` without a host), shifted by ``psi0``.

    Returns
    -------
    psi0, k : ndarray
    """
    p2 = lines.p2[line]
    cos_psi, sin_psi = _cos_sin(omega * (lines.n_plus[line] - p2))
    cos_phi, sin_phi = _cos_sin(omega * p2)
    a = cos_psi * cos_phi - (lines.alpha[line] - lines.beta[line]) * (sin_psi * sin_phi)
    r1, t_cell = _host_slab(lines, line, cos_psi, sin_psi, cos_phi, sin_phi)
    B = np.sqrt(np.maximum(1.0 - a * a, 0.0)) * t_cell
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        z = -(1.0 - a * t_cell + lines.r_h1[line] * r1) / B
        p, q = np.real(z), np.abs(np.imag(z))
        s = 1.0 + p * p + q * q
        k = 0.5 * (s + np.sqrt(np.maximum(s * s - 4.0 * q * q, 0.0))) / q
        psi0 = 0.5 * np.arctan2(2.0 * p, p * p + q * q - 1.0)
    # At a band edge (B = 0) the peaks are the edge's own: no shift, and sharp.
    finite = np.isfinite(psi0) & np.isfinite(k)
    return np.where(finite, psi0, 0.0), np.where(finite, k, 1e300)


def _host_line_reflectance(lines: _Lines, line, kind, a, sin2_u, cos_psi, sin_psi, cos_phi, sin_phi) -> np.ndarray:
    """
    :func:`_line_reflectance_block`'s values under a host ``nh != n1`` (every wave propagating, so ``r12`` and ``r_h1``
    real): ``|r_hN|^2`` (Appendix D), the same ``r_hN = (r_N + r_h1) / (1 + r_h1 r_N)`` as :func:`reference_rgb`'s.
    With ``r_N = num / den``: in a pass band ``num = r1 sin N u``, ``den = A sin N u + B cos N u`` (``A = 1 - a t_cell``,
    ``B = sin u t_cell``, ``t_cell = t1 e^{i psi}``: Appendix D's ``r1 U_{N-1} / (U_{N-1} - U_{N-2} t_cell)`` times
    ``sin u``, finite at dips and edges); in a gap Eq. 9's scaled Chebyshev values (:func:`chebyshev_U`). The fringe
    average (kind 1) is :func:`fringe_average_under_host`'s for a lossless cell: with ``r_hN = (P + Q x) / (S + T x)``,
    ``x = cot N u``, ``1 - |r_hN|^2 = (1 - R_h1)(1 + x^2) / |x - z|^2``, ``z = -S / T``, whose Cauchy average over
    a fringe is ``(1 - R_h1) / |Im z|``: ``Rbar = 1 - (1 - R_h1) |B|^2 / |Im(S B*)|``, ``S = A + r_h1 r1``.
    A gap that reflects 1 still does under the (lossless) host interface: kind 2 stays 1, kind 3 is ``R - 1``.
    """
    r_h1 = lines.r_h1[line]
    r1, t_cell = _host_slab(lines, line, cos_psi, sin_psi, cos_phi, sin_phi)
    N = float(lines.N)
    A, B = 1.0 - a * t_cell, np.sqrt(sin2_u) * t_cell
    value = np.empty(a.shape)
    exact = kind != 1
    band = np.flatnonzero(exact & (np.abs(a) < 1.0))
    gap = np.flatnonzero(exact & (np.abs(a) >= 1.0))
    mean = np.flatnonzero(~exact)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        cos_Nu, sin_Nu = _cos_sin(N * np.arccos(a[band]))
        _, U_N2, _ = chebyshev_U(a[gap], N)  # U_{N-2} / U_{N-1}, scaled in the gap
        for where, num, den in ((band, r1[band] * sin_Nu, A[band] * sin_Nu + B[band] * cos_Nu),
                                (gap, r1[gap], 1.0 - U_N2 * t_cell[gap])):
            value[where] = np.abs(num + r_h1[where] * den) ** 2 / np.abs(den + r_h1[where] * num) ** 2
        B_m, r_h1_m = B[mean], r_h1[mean]
        im = np.abs(np.imag((A[mean] + r_h1_m * r1[mean]) * np.conj(B_m)))
        value[mean] = 1.0 - (1.0 - r_h1_m * r_h1_m) * np.abs(B_m) ** 2 / np.maximum(im, 1e-300)
    return np.where(kind == 3, value - 1.0, value)


#: Below this many cells the pieces integrate Yeh's R throughout (the fringe average's far harmonics still count).
PIECES_EXACT_N = 64
#: From this many cells the table's colours come from the band pieces. Below it the windowed rule costs less (its
#: integrand is Yeh's R itself up to N = 4 EDGE_FRINGES, and where fringes are wide: WINDOW_EXACT_SUBSTEPS); from
#: N ~ 64 the pieces do (default mirror, 65 angles: 19 against 30 ms at N = 100), whose cost stops growing.
PIECES_MIN_N = 64
#: ... under a host nh != n1, where the windowed rule's complex arithmetic costs 2-3.5x more than the pieces already at
#: N = 1-20 (n1 = 1.33, n2 = 1.8, nh = 1: 49 against 14 ms CPU at N = 1, 82 against 39 at N = 20; docs/performance.md).
PIECES_MIN_N_HOST = 1


def band_pieces_rgb(cos_theta: ArrayLike, mirror: BraggMirror, scale: int = 1) -> np.ndarray:
    """
    Linear sRGB of the converged spectral reference (:func:`reference_rgb` without a step) by Gauss quadrature
    over band pieces (the section's comment), for angles where every wave propagates (under a host ``nh != n1`` too:
    Appendix D's ``|r_hN|^2`` at the nodes, :func:`_host_line_reflectance`).

    Parameters
    ----------
    cos_theta : array_like
    mirror : BraggMirror
    scale : int
        Multiplies every panel's node count (convergence studies).

    Returns
    -------
    ndarray, shape ``(cos_theta.size, 3)``

    References
    ----------
    Fourneau et al. (2024), Section 3.1 (Eqs. 2, 8-10), Appendix A; Yeh (1988), Chapter 6.
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64).ravel()
    geometries = [cell_geometry(cos_theta, mirror, pol) for pol in POLARISATIONS]
    first = geometries[0]
    if not ((first.cos_theta_1.imag == 0).all() and (first.cos_theta_2.imag == 0).all()):
        raise ValueError("band_pieces_rgb: real angles only (no evanescent layer, no total reflection at the host)")
    p1 = np.concatenate([g.p1.real for g in geometries])
    p2 = np.concatenate([g.p2.real for g in geometries])
    Omega_ = np.concatenate([g.Omega.real for g in geometries])
    r12 = np.concatenate([g.r12.real for g in geometries])
    # Under a host (Appendix D) the nodes take |r_hN|^2; r_h1 is real where the wave in n1 propagates.
    r_h1 = None if first.host_is_n1 else np.concatenate([np.broadcast_to(g.r_h1.real, g.p1.shape) for g in geometries])
    lines = _Lines(p1 + p2, p1 - p2, 0.5 + 0.25 * Omega_, 0.5 - 0.25 * Omega_, p2, r12 * r12, int(mirror.N),
                   r12=r12, r_h1=r_h1)
    exact_everywhere = mirror.N < PIECES_EXACT_N or BAND_EDGE_FRINGES * np.pi / mirror.N >= 0.5 * np.pi
    xyz = _pieces_xyz(lines, exact_everywhere, scale)
    xyz = 0.5 * (xyz[: cos_theta.size] + xyz[cos_theta.size :])
    return colorimetry.xyz_to_rgb(xyz)
