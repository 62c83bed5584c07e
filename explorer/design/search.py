"""
The search's problem (free parameters, fixed values, targets, residuals on both models) and its stages: the scale
scans, the descent, the refinement and the polish.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Callable, Mapping, Sequence

import numpy as np

from explorer.design.base import (
    BATCH,
    COARSE_DIFF_STEP,
    COARSE_STEP,
    DESCENT_SAMPLES,
    DESCENT_SIGMAS,
    DESCENT_SPAN,
    DISTINCT_STARTS,
    FINE_DIFF_STEP,
    POLISHED_ENOUGH,
    SCAN_BATCH,
    SCAN_BATCH_SAMPLES,
    SCAN_KEPT,
    SCAN_RELATIVE_STEP,
    SCAN_SMOOTH,
    SCAN_THREADS,
    SCREEN_SMOOTH,
    SCREEN_STEP,
    SECOND_COUNTS,
    SECOND_PERTURBED,
    SECOND_SPREAD,
    DesignCancelled,
    DesignModel,
    DesignParameter,
)
from explorer.design.targets import Target
from explorer.physics import colorimetry


class _Problem:
    """The free parameters, the fixed values and the targets, with the residuals of both models."""

    def __init__(self, model: DesignModel, box: list[DesignParameter], fixed: Mapping[str, float],
                 targets: Sequence[Target], cancelled: Callable[[], bool] | None, free: Sequence[str] = ()):
        self.model = model
        self.box = {p.name: p for p in box}
        self.fixed = {k: float(v) for k, v in fixed.items()}
        # The model's held parameters (an effect off) stay at 0 unless fixed otherwise or named free.
        self.held = [name for name in model.held if name not in self.fixed and name not in free]
        self.fixed.update({name: 0.0 for name in self.held})
        self.free = [p for p in box if p.name not in self.fixed]
        # A mirror whose period and thickness ratio are both free is searched by its optical period and
        # the first layer's share of it (see :meth:`values`): the band positions then depend on one
        # coordinate, and the indices move the angular shift and the contrast without moving the bands.
        names = [p.name for p in self.free]
        self.optical = model.optical and "Lambda" in names and "delta" in names
        if self.optical:
            indices = [self.box[n] if n not in self.fixed else DesignParameter(n, self.fixed[n], self.fixed[n]) for n in ("n1", "n2")]
            n_low, n_high = min(p.low for p in indices), max(p.high for p in indices)
            Lambda = self.box["Lambda"]
            self.free[names.index("Lambda")] = DesignParameter("optical_period", Lambda.low * n_low, Lambda.high * n_high, log=True)
            self.free[names.index("delta")] = DesignParameter("optical_fraction", 0.0, 1.0)
        self.scale_parameter = "optical_period" if self.optical else model.scale_parameter
        # Every angle of every layer depends on index ratios only (Snell's invariant nh sin theta over each
        # index), and every phase on optical thicknesses (Eq. 8), so multiplying n1, n2 and the host by one
        # factor k, at a fixed optical period, changes no colour (Lambda = P (f / n1 + (1 - f) / n2) moves
        # as 1 / k). With all three free, each scale of the scan picks its k inside the boxes
        # (:meth:`index_scale_bounds`, :meth:`at_scale`): a shape reaches every period some k allows.
        host = model.host_parameter
        self.index_scale = self.optical and {"n1", "n2"} <= set(names) and (
            host is None or host in names or self.fixed.get(host, 0.0) < model.host_threshold)
        self.targets = list(targets)
        self.cos_theta = np.cos(np.radians([t.theta_deg for t in self.targets]))
        self.target_rgb = np.array([t.rgb for t in self.targets], dtype=np.float64)
        self.target_lab = colorimetry.rgb_to_lab(self.target_rgb)
        self.bounds = np.array([t.bounds for t in self.targets], dtype=np.int8)
        self.cancelled = cancelled
        self.evaluations = 0
        self._lock = threading.Lock()  # the scans run in threads (:func:`_threaded_scan`)

    def values(self, U: np.ndarray, scale_value: float | np.ndarray | None = None, whole: bool = False) -> dict[str, np.ndarray]:
        """
        Unit-box rows ``(B, P)`` -> every design value as ``(B,)`` arrays. ``scale_value``: the scale
        coordinate at this value (one, or one per row) instead, unclipped (the scale scan's structures).
        ``whole``: integer parameters (``N``) at their nearest whole values; the search otherwise walks them
        continuously (a relaxation: a fractional count has colours no stack has).
        """
        U = np.atleast_2d(U)
        out = {name: np.full(U.shape[0], value) for name, value in self.fixed.items()}
        for k, p in enumerate(self.free):
            out[p.name] = p.whole(p.from_unit(U[:, k])) if whole else p.from_unit(U[:, k])
        if scale_value is not None:
            out[self.scale_parameter] = np.broadcast_to(np.asarray(scale_value, dtype=np.float64), (U.shape[0],)).copy()
        if self.optical:
            # Optical thicknesses n1 d1 = f P and n2 d2 = (1 - f) P at normal incidence (Eq. 8's phases):
            # Lambda = P (f / n1 + (1 - f) / n2), delta = (f / n1) / (f / n1 + (1 - f) / n2).
            f, P = out.pop("optical_fraction"), out.pop("optical_period")
            per_period = f / out["n1"] + (1.0 - f) / out["n2"]
            Lambda = self.box["Lambda"]
            out["Lambda"] = P * per_period if scale_value is not None else np.clip(P * per_period, Lambda.low, Lambda.high)
            out["delta"] = np.clip((f / out["n1"]) / per_period, 0.0, 1.0)
        return out

    def unit_row(self, structure: Mapping[str, float]) -> np.ndarray:
        """
        The unit row of a structure (design values by name): the inverse of :meth:`values`, the optical
        period ``P = Lambda (delta n1 + (1 - delta) n2)`` and share ``f = delta n1 Lambda / P`` where the
        search walks those.
        """
        named = dict(structure)
        if self.optical:
            n1, n2, Lambda, delta = (float(named[k]) for k in ("n1", "n2", "Lambda", "delta"))
            named["optical_period"] = Lambda * (delta * n1 + (1.0 - delta) * n2)
            named["optical_fraction"] = delta * n1 * Lambda / named["optical_period"]
        return np.array([float(p.to_unit(named[p.name])) for p in self.free])

    def index_scale_bounds(self, values: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """
        The factors ``k`` (per row, an interval) that keep ``k n1``, ``k n2`` and a host's ``k nh`` inside
        their boxes (a host stays a host: ``k nh`` at least the threshold); ``(1, 1)`` without
        :attr:`index_scale`.
        """
        rows = np.asarray(next(iter(values.values()))).shape[0]
        k_low, k_high = np.ones(rows), np.ones(rows)
        if not self.index_scale:
            return k_low, k_high
        k_low, k_high = np.zeros(rows), np.full(rows, np.inf)
        host = self.model.host_parameter
        for name in ("n1", "n2", host):
            if name is None or name not in self.box or name in self.fixed:
                continue
            v, p = np.asarray(values[name], dtype=np.float64), self.box[name]
            low = p.low
            if name == host:
                low = max(low, self.model.host_threshold)
                present = v >= self.model.host_threshold
                k_low = np.where(present, np.maximum(k_low, low / np.where(present, v, 1.0)), k_low)
                k_high = np.where(present, np.minimum(k_high, p.high / np.where(present, v, 1.0)), k_high)
            else:
                k_low, k_high = np.maximum(k_low, low / v), np.minimum(k_high, p.high / v)
        return k_low, k_high

    def at_scale(self, U: np.ndarray, scale_value: np.ndarray) -> np.ndarray:
        """
        Unit rows ``U`` with their scale coordinate at ``scale_value`` (one per row, physical); with
        :attr:`index_scale`, the indices multiplied by the ``k`` (geometric middle of those allowed) that
        puts ``Lambda`` inside its box at that optical period: the same colours, a structure in the box.
        """
        U = np.atleast_2d(U).copy()
        scale_value = np.broadcast_to(np.asarray(scale_value, dtype=np.float64), (U.shape[0],))
        if self.index_scale:
            values = self.values(U, scale_value=scale_value)
            k_low, k_high = self.index_scale_bounds(values)
            Lambda = self.box["Lambda"]
            # Lambda / k must lie in [low, high]: k in [Lambda / high, Lambda / low].
            k_low, k_high = np.maximum(k_low, values["Lambda"] / Lambda.high), np.minimum(k_high, values["Lambda"] / Lambda.low)
            k = np.sqrt(k_low * np.maximum(k_high, k_low))
            host = self.model.host_parameter
            for j, p in enumerate(self.free):
                if p.name in ("n1", "n2") or (p.name == host and host is not None):
                    scaled = values[p.name] * k
                    if p.name == host:
                        scaled = np.where(values[p.name] >= self.model.host_threshold, scaled, values[p.name])
                    U[:, j] = np.clip(p.to_unit(scaled), 0.0, 1.0)
        U[:, self.scale_index] = np.clip(self.free[self.scale_index].to_unit(scale_value), 0.0, 1.0)
        return U

    def _check(self):
        if self.cancelled is not None and self.cancelled():
            raise DesignCancelled()

    def coarse_rgb(self, U, step: float = COARSE_STEP, smooth: float | None = None, whole: bool = False) -> np.ndarray:
        U = np.atleast_2d(U)
        self.evaluations += U.shape[0]
        out = np.empty((U.shape[0], self.cos_theta.size, 3))
        for start in range(0, U.shape[0], BATCH):
            self._check()
            out[start : start + BATCH] = self.model.batch(self.values(U[start : start + BATCH], whole=whole), self.cos_theta, step, smooth)
        return out

    @property
    def scale_index(self) -> int | None:
        """The free coordinate that scales every length of the structure (None when it is fixed)."""
        return next((k for k, p in enumerate(self.free) if p.name == self.scale_parameter), None)

    def scale_scan(self, shapes: np.ndarray, relative_step: float | None = None,
                   smooth_relative: float | None = None, around: np.ndarray | None = None,
                   span: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """
        Screening scores ``(B, G)`` of ``shapes`` (unit rows; their scale coordinate ignored) at the scales
        ``s_bm = s_b r^m`` (``r = 1 + relative_step``, default :data:`SCAN_RELATIVE_STEP`; fringes averaged
        below ``smooth_relative`` lambda, default :data:`SCAN_SMOOTH`) that keep each shape's ``Lambda`` in its box (else
        the scale's whole range, or what index scaling allows: :attr:`index_scale`), and those scales
        ``(B, G)`` (physical: :meth:`at_scale` makes unit rows of them). ``around`` (per row) and ``span``:
        only the scales within a factor ``1 + span`` of ``around`` (a local search's window).

        Without dispersion a structure's spectrum depends on ``x = s / lambda`` only (every phase is
        ``2 pi n d cos theta / lambda``, Eq. 8, and ``d`` scales with ``s``): one spectrum per shape on the
        log grid ``x_k = (s_b / lambda_max) r^k``, against CMF weights on the log-spaced wavelengths
        ``lambda_j = lambda_max r^-j``, gives ``XYZ(s_bm) = sum_j W_j R(x_{m+j})``, a correlation (FFT) that
        yields every scale on the grid's own step. Scales that put ``Lambda`` outside its box score infinity.
        """
        from scipy import fft

        p = self.free[self.scale_index]
        ratio = 1.0 + (SCAN_RELATIVE_STEP if relative_step is None else relative_step)
        smooth_relative = SCAN_SMOOTH if smooth_relative is None else smooth_relative
        low, high = (self.box["Lambda"].low, self.box["Lambda"].high) if self.optical else (max(p.low, 1.0), p.high)
        # With index scaling, a shape's periods reach k_high / k_low further (at most n1's box ratio).
        widest = self.box["n1"].high / self.box["n1"].low if self.index_scale else 1.0
        G = int(np.ceil(np.log((high / low * widest) if around is None else (1.0 + span) ** 2) / np.log(ratio))) + 1
        nodes, weights = colorimetry.log_interpolant_nodes(ratio)  # ascending: node J - j is lambda_j
        J = nodes.size - 1
        # Row b's structure at scale s_b seen at lambda_max r^-k is its spectrum at x_k = (s_b / lambda_max) r^k.
        wavelengths = nodes[-1] / ratio ** np.arange(G + J)
        size = fft.next_fast_len(G + 2 * J)
        kernel = fft.rfft(weights, n=size, axis=0)  # (F, 3): the correlation as a convolution with W reversed
        scores = np.empty((shapes.shape[0], G))
        scales = np.empty((shapes.shape[0], G))
        # Rows per batch: SCAN_BATCH at the full range's length, more for a window's shorter spectra.
        batch = max(SCAN_BATCH, int(SCAN_BATCH * SCAN_BATCH_SAMPLES / (G + J)))
        for start in range(0, shapes.shape[0], batch):
            self._check()
            rows = slice(start, start + batch)
            U = shapes[rows]
            # The first scale: Lambda at its low end (optical period P = Lambda / per_period), or the range's.
            unit_values = self.values(U, scale_value=1.0)
            k_low, k_high = self.index_scale_bounds(unit_values)
            per_period = unit_values["Lambda"] if self.optical else np.ones(len(U))
            s_first = k_low * low / per_period if around is None else np.asarray(around, dtype=np.float64)[rows] / (1.0 + span)
            values = self.values(U, scale_value=s_first)
            R = self.model.spectra(values, self.cos_theta, wavelengths, smooth_relative)  # (B, A, X)
            with self._lock:
                self.evaluations += U.shape[0] * G
            spectrum = fft.rfft(R, n=size, axis=-1)  # (B, A, F)
            xyz = fft.irfft(spectrum[..., None] * kernel[None, None], n=size, axis=-2)[:, :, J : J + G]  # (B, A, G, 3)
            rgb = colorimetry.xyz_to_rgb(xyz).transpose(0, 2, 1, 3)  # (B, G, A, 3)
            s_rows = s_first[:, None] * ratio ** np.arange(G)[None, :]
            # CIEDE2000 at the scales whose CIELAB distance (cheap) is among the SCAN_KEPT smallest.
            proxy = np.sum((colorimetry.rgb_to_lab(np.maximum(rgb, -1.0)) - self.target_lab_for(rgb)) ** 2, axis=(-1, -2))
            # Lambda at k = 1 (or the scale) against the box's top, which k_high stretches.
            top = s_rows * per_period[:, None]
            inside = (top <= k_high[:, None] * high * (1.0 + 1e-9)) & (top >= k_low[:, None] * low * (1.0 - 1e-9))
            proxy = np.where(inside, proxy, np.inf)
            kept = np.argpartition(proxy, min(SCAN_KEPT, G) - 1, axis=1)[:, :SCAN_KEPT]
            chosen = np.take_along_axis(rgb, kept[:, :, None, None], axis=1)
            score = np.full(proxy.shape, np.inf)
            finite = np.isfinite(np.take_along_axis(proxy, kept, axis=1))
            np.put_along_axis(score, kept, np.where(finite, np.sum(self.residuals_of(chosen) ** 2, axis=-1), np.inf), axis=1)
            scores[rows] = score
            scales[rows] = s_rows
        return scores, scales

    def screen(self, U) -> np.ndarray:
        """Sum of squared CIEDE2000 of unit-box rows on the screening model."""
        return np.sum(self.residuals_of(self.coarse_rgb(U, SCREEN_STEP, SCREEN_SMOOTH)) ** 2, axis=-1)

    def residuals_of(self, rgb: np.ndarray) -> np.ndarray:
        """``(..., A, 3)`` colours -> ``(..., 3 A)`` residuals whose squared norm per target is CIEDE2000^2."""
        lab = colorimetry.rgb_to_lab(np.maximum(rgb, -1.0))
        target_lab = np.broadcast_to(self.target_lab_for(rgb), lab.shape)
        difference = lab - target_lab
        e76 = np.linalg.norm(difference, axis=-1)
        e00 = colorimetry.delta_E_2000_lab(lab, target_lab)
        scale = np.where(e76 > 1e-9, e00 / np.maximum(e76, 1e-300), 1.0)
        return (difference * scale[..., None]).reshape(rgb.shape[:-2] + (-1,))

    def target_lab_for(self, rgb: np.ndarray) -> np.ndarray:
        """
        The targets in CIELAB as seen from colours ``rgb`` ``(..., A, 3)``: a bounded channel (``Target.bounds``)
        takes the colour's own value where it lies beyond the bound, so that only the exact channels and the
        wrong side of a bound cost (one-sided).
        """
        if not self.bounds.any():
            return self.target_lab
        rgb = np.asarray(rgb, dtype=np.float64)
        target = np.where(self.bounds < 0, np.minimum(rgb, self.target_rgb),
                          np.where(self.bounds > 0, np.maximum(rgb, self.target_rgb), self.target_rgb))
        return colorimetry.rgb_to_lab(np.maximum(target, -1.0))

    def delta_e(self, rgb) -> np.ndarray:
        lab = colorimetry.rgb_to_lab(rgb)
        return colorimetry.delta_E_2000_lab(lab, np.broadcast_to(self.target_lab_for(rgb), lab.shape))

    def fine_values(self, u: np.ndarray) -> dict[str, float]:
        """The structure of one unit row, integer parameters whole (fixed ones are: :func:`design` checks)."""
        return {k: float(v[0]) for k, v in self.values(u, whole=True).items()}

    def fine_rgb(self, values: Mapping[str, float], final: bool = False) -> np.ndarray:
        self._check()
        self.evaluations += 1
        return self.model.converged(values, self.cos_theta, final=final)

    def fine_residuals(self, u: np.ndarray) -> tuple[dict[str, float], np.ndarray]:
        """One unit row's structure (integer parameters whole) and its residuals on the converged model."""
        values = self.fine_values(u[None])
        return values, self.residuals_of(self.fine_rgb(values)[None])[0]

    def fine_cost(self, u: np.ndarray) -> float:
        """Sum of squared CIEDE2000 of one unit row on the converged model (:meth:`fine_residuals`)."""
        return float(np.sum(self.fine_residuals(u)[1] ** 2))

    @property
    def polished_cost(self) -> float:
        """The cost below which the polish stops: :data:`POLISHED_ENOUGH` per target."""
        return POLISHED_ENOUGH**2 * len(self.targets)


def _least_squares(fun, jac, x0, lower, upper, max_nfev):
    from scipy.optimize import least_squares

    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    x0 = np.clip(x0, lower + 1e-9, upper - 1e-9)
    return least_squares(fun, x0, jac=jac, bounds=(lower, upper), max_nfev=max_nfev, x_scale=1.0, method="dogbox",
                         xtol=1e-10, ftol=1e-10, gtol=1e-10)


def _host_bounds(problem: _Problem, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    The unit box of a local refinement: a host parameter stays on the start's side of its threshold
    (below it the host is ``n1``, a branch, not a slope: there it is held).
    """
    lower, upper = np.zeros(u.size), np.ones(u.size)
    name = problem.model.host_parameter
    for k, p in enumerate(problem.free):
        if p.name == name:
            threshold = float(np.clip(p.to_unit(problem.model.host_threshold), 0.0, 1.0))
            if p.from_unit(u[k]) < problem.model.host_threshold:
                lower[k], upper[k] = max(u[k] - 1e-6, 0.0), min(u[k] + 1e-6, 1.0)
            else:
                lower[k] = threshold
    return lower, upper


def _refine_coarse(problem: _Problem, u0: np.ndarray, max_nfev: int) -> tuple[np.ndarray, float]:
    """The screening model's refinement, then the coarse model's (a continuation: smooth landscape first)."""
    # Without the screening model's level, its moves to basins far from the start were lost (measured with
    # 384 scan shapes: the CI subset's median 0.43 -> 0.85).
    u, _ = _refine_level(problem, u0, max_nfev, SCREEN_STEP, SCREEN_SMOOTH)
    return _refine_level(problem, u, max_nfev, COARSE_STEP, None)


def _refine_level(problem: _Problem, u0: np.ndarray, max_nfev: int, step: float, smooth) -> tuple[np.ndarray, float]:
    """Trust-region refinement (dogbox) on one batch model; Jacobian columns in one batch."""
    lower, upper = _host_bounds(problem, u0)
    P = u0.size
    cache: dict[bytes, np.ndarray] = {}

    def batch_residuals(U):
        return problem.residuals_of(problem.coarse_rgb(U, step, smooth))

    def fun(u):
        key = u.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = batch_residuals(u[None])[0]
        return cache[key]

    def jac(u):
        h = np.where(u + COARSE_DIFF_STEP <= upper, COARSE_DIFF_STEP, -COARSE_DIFF_STEP)
        U = np.repeat(u[None], P, axis=0) + np.diag(h)
        columns = batch_residuals(U)
        return ((columns - fun(u)[None]) / h[:, None]).T

    result = _least_squares(fun, jac, u0, lower, upper, max_nfev)
    return result.x, float(2.0 * result.cost)


def _polish(problem: _Problem, u0: np.ndarray, max_nfev: int, deadline: float) -> tuple[dict[str, float], float]:
    """
    The converged model, with integer parameters held at the better of their two neighbouring integers:
    damped Gauss-Newton steps on the converged model's residuals, its Jacobian by forward differences of
    :data:`FINE_DIFF_STEP` (far above its adaptive refinement's ~1e-4 steps in colour), until no step
    lowers the converged cost, after ``max_nfev`` steps, or at ``deadline`` (``time.process_time()``).
    The batch models' Jacobians pointed elsewhere for thick stacks, whose narrow bands and fringes they
    sample too coarsely: from 0.003 of the box around the truths of 8 thick misses, the 1-nm batch model's
    steps ended below 0.05 per target in 2 of 32 starts, these in 30 (docs/design.md, design_polish.py).
    """
    integer_free = [k for k, p in enumerate(problem.free) if p.integer]
    u0 = u0.copy()
    choices = [u0.copy()]
    for k in integer_free:
        p = problem.free[k]
        value = float(p.from_unit(u0[k]))
        options = sorted({max(p.low, min(p.high, float(math.floor(value)))), max(p.low, min(p.high, float(math.ceil(value))))})
        choices = [np.concatenate([c[:k], [p.to_unit(o)], c[k + 1:]]) for c in choices for o in options]

    def fine(u):
        values, residuals = problem.fine_residuals(u)
        return values, residuals, float(np.sum(residuals**2))

    best = min((fine(np.clip(c, 0.0, 1.0)) + (np.clip(c, 0.0, 1.0),) for c in choices), key=lambda item: item[2])
    values, residuals, cost, u = best
    keep = np.array([k for k in range(u.size) if k not in integer_free])
    if keep.size == 0:
        return values, cost
    lower, upper = _host_bounds(problem, u)
    damping = 1e-3
    for _ in range(max_nfev):
        if time.process_time() > deadline or cost < problem.polished_cost:
            break
        h = np.where(u[keep] + FINE_DIFF_STEP <= upper[keep], FINE_DIFF_STEP, -FINE_DIFF_STEP)
        U = np.repeat(u[None], keep.size, axis=0)
        U[np.arange(keep.size), keep] += h
        columns = np.array([fine(row)[1] for row in U])
        J = ((columns - residuals) / h[:, None]).T
        JTJ, JTr = J.T @ J, J.T @ residuals
        improved = False
        while damping < 1e6:
            step = -np.linalg.solve(JTJ + damping * np.diag(np.diag(JTJ) + 1e-12), JTr)
            trial = u.copy()
            trial[keep] = np.clip(u[keep] + step, lower[keep], upper[keep])
            t_values, t_residuals, t_cost = fine(trial)
            if t_cost < cost:
                u, values, residuals, cost = trial, t_values, t_residuals, t_cost
                damping = max(damping / 3.0, 1e-7)
                improved = True
                break
            damping *= 4.0
            if time.process_time() > deadline:
                break
        if not improved:
            break
    return values, cost


def _variants(problem: _Problem, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """
    Shapes near ``u``: each integer parameter on :data:`SECOND_COUNTS` log-spaced values, and
    :data:`SECOND_PERTURBED` copies moved by a normal step of :data:`SECOND_SPREAD` in the unit box.
    """
    rows = []
    for k, p in enumerate(problem.free):
        if p.integer:
            for value in np.unique(np.round(np.geomspace(p.low, p.high, SECOND_COUNTS))):
                row = u.copy()
                row[k] = p.to_unit(value)
                rows.append(row)
    rows += list(np.clip(u + rng.normal(0.0, SECOND_SPREAD, (SECOND_PERTURBED, u.size)), 0.0, 1.0))
    return np.array(rows)


def _distinct_indices(U: np.ndarray, scores: np.ndarray, count: int, spacing: float = DISTINCT_STARTS) -> list[int]:
    """The best-scoring rows of ``U``, each farther than ``spacing`` (max norm) from those before it."""
    chosen: list[int] = []
    for index in np.argsort(scores):
        if all(np.max(np.abs(U[index] - U[c])) > spacing for c in chosen):
            chosen.append(int(index))
        if len(chosen) == count:
            break
    return chosen


def _distinct(U: np.ndarray, scores: np.ndarray, count: int, spacing: float = DISTINCT_STARTS) -> list[np.ndarray]:
    """The rows of :func:`_distinct_indices`."""
    return [U[k] for k in _distinct_indices(U, scores, count, spacing)]


def _threaded_scan(problem: _Problem, shapes: np.ndarray, around: np.ndarray | None = None,
                   span: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """
    :meth:`_Problem.scale_scan` with its rows split over :data:`SCAN_THREADS` threads (numpy's array
    operations and the FFT release the GIL): the scan's wall time on a multi-core machine.
    """
    threads = min(SCAN_THREADS, len(shapes) // SCAN_BATCH)
    if threads <= 1:
        return problem.scale_scan(shapes, around=around, span=span)
    from concurrent.futures import ThreadPoolExecutor

    parts = np.array_split(np.arange(len(shapes)), threads)
    with ThreadPoolExecutor(threads) as pool:
        results = list(pool.map(lambda rows: problem.scale_scan(
            shapes[rows], around=None if around is None else np.asarray(around)[rows], span=span), parts))
    return np.concatenate([r[0] for r in results]), np.concatenate([r[1] for r in results])


def _scan_best(problem: _Problem, shapes: np.ndarray, progress: Callable[[float], None] | None = None,
               chunk: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Each shape at its best scale of :meth:`_Problem.scale_scan`, and that score."""
    shapes = shapes.copy()
    scores = np.empty(len(shapes))
    for start in range(0, len(shapes), chunk):
        block, grid = _threaded_scan(problem, shapes[start : start + chunk])
        best = np.argmin(block, axis=1)
        shapes[start : start + chunk] = problem.at_scale(shapes[start : start + chunk], grid[np.arange(len(block)), best])
        scores[start : start + chunk] = block[np.arange(len(block)), best]
        if progress is not None:
            progress(min(1.0, (start + chunk) / len(shapes)))
    return shapes, scores


def _scan_descent(problem: _Problem, U: np.ndarray, scores: np.ndarray, rng: np.random.Generator,
                  progress: Callable[[float], None] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """
    A (1 + lambda) evolution of each row of ``U`` (unit rows at their best scale, ``scores`` theirs): per
    step of :data:`DESCENT_SIGMAS`, :data:`DESCENT_SAMPLES` normal moves of its shape, each at its best scale
    within :data:`DESCENT_SPAN` of the row's (:meth:`_Problem.scale_scan`'s window); the best move replaces
    the row when it scores lower. The scan takes the period out of the landscape, whose remaining basins
    are some 0.01 of the box wide in the thickness share and a few times that in the indices and count:
    wider than a local refinement reaches, narrower than the first pass samples.
    """
    U, scores = U.copy(), scores.copy()
    scale = problem.scale_index
    p = problem.free[scale]
    rows = len(U)
    for step, sigma in enumerate(DESCENT_SIGMAS):
        moves = np.clip(np.repeat(U, DESCENT_SAMPLES, axis=0) + rng.normal(0.0, sigma, (rows * DESCENT_SAMPLES, U.shape[1])), 0.0, 1.0)
        around = np.repeat(p.from_unit(U[:, scale]), DESCENT_SAMPLES)
        block, grid = _threaded_scan(problem, moves, around=around, span=DESCENT_SPAN)
        best = np.argmin(block, axis=1)
        move_scores = block[np.arange(len(block)), best].reshape(rows, DESCENT_SAMPLES)
        winners = np.argmin(move_scores, axis=1)
        better = move_scores[np.arange(rows), winners] < scores
        j = (np.arange(rows) * DESCENT_SAMPLES + winners)[better]
        U[better] = problem.at_scale(moves[j], grid[j, best[j]])
        scores[better] = block[j, best[j]]
        if progress is not None:
            progress((step + 1) / len(DESCENT_SIGMAS))
    return U, scores
