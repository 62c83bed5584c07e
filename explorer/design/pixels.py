"""
Many targets at once: the per-pixel polish of a painted image (:mod:`explorer.design.paint`). Each row is one target
colour per angle and one structure; a damped Gauss-Newton (Levenberg-Marquardt) walks every row's free parameters
together on the coarse batch model (:attr:`explorer.design.base.DesignModel.batch`), the Jacobians by forward
differences evaluated in one batch. Residuals are those of the design search (:meth:`explorer.design.search._Problem.residuals_of`):
CIELAB differences scaled by ``dE2000 / dE76``, so that a row's squared norm per angle is CIEDE2000 squared.
Also the clustering of target colours in CIELAB (k-means, scipy) that decides which structures are designed.
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

from explorer.design.base import COARSE_DIFF_STEP, COARSE_STEP, DesignModel, DesignParameter
from explorer.physics import colorimetry

#: Damped Gauss-Newton steps of :func:`polish_rows` (each ~P + 1 batch evaluations of the active rows).
POLISH_STEPS = 14
#: A row stops once its RMS CIEDE2000 per angle is below this.
POLISH_TOLERANCE = 0.1
#: ... or once an accepted step lowers its cost by less than this share (a minimum: a held count that does not fit).
POLISH_STALL = 0.01
#: ... or once its damping, raised fourfold by each rejected step, passes this (five rejections in a row from the
#: start: its steps have shrunk to nothing).
POLISH_DAMPING_LIMIT = 10.0
#: :func:`polish_whole` walks the counts of rows left above this RMS CIEDE2000 per angle by the held polish.
COUNT_WALK_DELTA_E = 0.25


def target_lab_rows(target_rgb: np.ndarray, bounds: np.ndarray | None, rgb: np.ndarray) -> np.ndarray:
    """
    Per row, the targets ``(B, A, 3)`` in CIELAB as seen from colours ``rgb`` ``(B, A, 3)``: a bounded channel
    (-1 at most, +1 at least, as :class:`explorer.design.targets.Target`) takes the colour's own value beyond its
    bound (:meth:`explorer.design.search._Problem.target_lab_for`, per row).
    """
    if bounds is None or not np.any(bounds):
        return colorimetry.rgb_to_lab(np.maximum(target_rgb, -1.0))
    target = np.where(bounds < 0, np.minimum(rgb, target_rgb), np.where(bounds > 0, np.maximum(rgb, target_rgb), target_rgb))
    return colorimetry.rgb_to_lab(np.maximum(target, -1.0))


def residual_rows(rgb: np.ndarray, target_rgb: np.ndarray, bounds: np.ndarray | None) -> np.ndarray:
    """``(B, A, 3)`` colours against per-row targets -> ``(B, 3 A)`` residuals whose squared norm per angle is CIEDE2000^2."""
    lab = colorimetry.rgb_to_lab(np.maximum(rgb, -1.0))
    target = target_lab_rows(target_rgb, bounds, rgb)
    difference = lab - target
    e76 = np.linalg.norm(difference, axis=-1)
    e00 = colorimetry.delta_E_2000_lab(lab, target)
    scale = np.where(e76 > 1e-9, e00 / np.maximum(e76, 1e-300), 1.0)
    return (difference * scale[..., None]).reshape(rgb.shape[0], -1)


def delta_e_rows(rgb: np.ndarray, target_rgb: np.ndarray, bounds: np.ndarray | None) -> np.ndarray:
    """CIEDE2000 ``(B, A)`` of colours against per-row targets (bounded channels one-sided)."""
    lab = colorimetry.rgb_to_lab(rgb)
    return colorimetry.delta_E_2000_lab(lab, target_lab_rows(target_rgb, bounds, rgb))


class RowModel:
    """A design model's coarse colours of many structures: free parameters in the unit box, the others fixed."""

    def __init__(self, model: DesignModel, free: Sequence[DesignParameter], fixed: Mapping[str, float], cos_theta: np.ndarray,
                 step: float = COARSE_STEP):
        self.model, self.free, self.fixed = model, list(free), {k: float(v) for k, v in fixed.items()}
        self.cos_theta, self.step = np.asarray(cos_theta, dtype=np.float64), step

    def values(self, U: np.ndarray, whole: bool = False) -> dict[str, np.ndarray]:
        U = np.atleast_2d(U)
        out = {name: np.full(U.shape[0], value) for name, value in self.fixed.items()}
        for k, p in enumerate(self.free):
            out[p.name] = p.whole(p.from_unit(U[:, k])) if whole else p.from_unit(U[:, k])
        return out

    def unit(self, values: Mapping[str, np.ndarray]) -> np.ndarray:
        """Unit rows ``(B, P)`` of structures given by name (the inverse of :meth:`values`), clipped to the box."""
        return np.clip(np.stack([np.atleast_1d(p.to_unit(np.asarray(values[p.name], float))) for p in self.free], axis=-1), 0.0, 1.0)

    def rgb(self, U: np.ndarray, batch: int = 256) -> np.ndarray:
        U = np.atleast_2d(U)
        out = np.empty((U.shape[0], self.cos_theta.size, 3))
        for start in range(0, U.shape[0], batch):
            out[start : start + batch] = self.model.batch(self.values(U[start : start + batch]), self.cos_theta, self.step)
        return out

    def rgb_and_jacobian(self, U: np.ndarray, columns: Sequence[int], batch: int = 256) -> tuple[np.ndarray, np.ndarray]:
        """
        Colours ``(B, A, 3)`` of unit rows ``U`` and their derivatives ``(B, c, A, 3)`` by the unit parameters
        ``columns``: the model's analytic gradient where it declares one for these rows (one evaluation), otherwise
        forward differences of :data:`COARSE_DIFF_STEP` (``c`` more; backwards at the box's upper edge).
        """
        U = np.atleast_2d(np.asarray(U, dtype=np.float64))
        columns = list(columns)
        if self.model.gradient is not None:
            rgb = np.empty((U.shape[0], self.cos_theta.size, 3))
            J = np.empty((U.shape[0], len(columns), self.cos_theta.size, 3))
            for start in range(0, U.shape[0], batch):
                part = U[start : start + batch]
                found = self.model.gradient(self.values(part), self.cos_theta, self.step)
                if found is None or any(self.free[k].name not in found[1] for k in columns):
                    break
                rgb[start : start + batch] = found[0]
                for j, k in enumerate(columns):
                    J[start : start + batch, j] = found[1][self.free[k].name] * self._slope(k, part[:, k])[:, None, None]
            else:
                return rgb, J
        rgb = self.rgb(U)
        B, P = U.shape
        h = np.where(U[:, columns] + COARSE_DIFF_STEP <= 1.0, COARSE_DIFF_STEP, -COARSE_DIFF_STEP)  # (B, c)
        shifted = np.repeat(U[:, None, :], len(columns), axis=1)
        shifted[:, np.arange(len(columns)), columns] += h
        moved = self.rgb(shifted.reshape(-1, P)).reshape(B, len(columns), self.cos_theta.size, 3)
        return rgb, (moved - rgb[:, None]) / h[:, :, None, None]

    def _slope(self, k: int, u: np.ndarray) -> np.ndarray:
        """``d value / d u`` of free parameter ``k`` at unit values ``u`` (:meth:`DesignParameter.from_unit`)."""
        p = self.free[k]
        if p.log:
            return p.from_unit(u) * (math.log(p.high) - math.log(p.low))
        return np.full(np.shape(u), p.high - p.low)


def polish_rows(rows: RowModel, target_rgb: np.ndarray, bounds: np.ndarray | None, U0: np.ndarray,
                held: Sequence[bool] | None = None, steps: int = POLISH_STEPS) -> tuple[np.ndarray, np.ndarray]:
    """
    Levenberg-Marquardt on every row at once from ``U0`` ``(B, P)``: rows move only while their step lowers their
    cost, each with its own damping. ``held``: parameters that do not move (an integer count once rounded).
    The Jacobian is taken by forward differences (one batch evaluation per moving parameter) at the start and
    after a rejected step; otherwise Broyden's rank-one update carries it on from the last step's residuals, so
    that an accepted step costs one evaluation. A row stops below :data:`POLISH_TOLERANCE`, or once its steps
    stop paying (:data:`POLISH_STALL`).
    Returns the unit rows and their costs (sum of squared CIEDE2000 over the angles, coarse model).
    """
    U = np.clip(np.array(U0, dtype=np.float64), 0.0, 1.0)
    B, P = U.shape
    moving = np.ones(P, bool) if held is None else ~np.asarray(held, bool)
    columns = np.flatnonzero(moving)
    angles = rows.cos_theta.size
    residuals = residual_rows(rows.rgb(U), target_rgb, bounds)
    cost = np.sum(residuals**2, axis=1)
    damping = np.full(B, 1e-2)
    tolerance = POLISH_TOLERANCE**2 * angles
    if columns.size == 0:
        return U, cost
    c = columns.size
    J = np.zeros((B, c, residuals.shape[1]))  # rows of J^T per row
    fresh = np.ones(B, bool)  # needs a finite-difference Jacobian
    live = np.ones(B, bool)
    for _ in range(steps):
        active = np.flatnonzero(live & (cost > tolerance) & (damping < POLISH_DAMPING_LIMIT))
        if active.size == 0:
            break
        differenced = active[fresh[active]]
        exact = fresh[active].copy()  # this step's Jacobian by differences, not carried on by Broyden
        if differenced.size:
            # The colours' Jacobian from the model (analytic where it declares one); the residuals' by differences
            # along it, in colour space (no model evaluation): r(rgb + h dRGB/du) - r(rgb), over h.
            rgb_d, J_rgb = rows.rgb_and_jacobian(U[differenced], columns)
            h = COARSE_DIFF_STEP
            stepped = (rgb_d[:, None] + h * J_rgb).reshape(-1, angles, 3)
            tr = np.repeat(target_rgb[differenced], c, axis=0)
            tb = None if bounds is None else np.repeat(bounds[differenced], c, axis=0)
            r_shift = residual_rows(stepped, tr, tb).reshape(differenced.size, c, -1)
            r_here = residual_rows(rgb_d, target_rgb[differenced], None if bounds is None else bounds[differenced])
            J[differenced] = (r_shift - r_here[:, None, :]) / h
            fresh[differenced] = False
        Ua, ra, Ja = U[active], residuals[active], J[active]
        JTJ = np.einsum("bcr,bdr->bcd", Ja, Ja)
        JTr = np.einsum("bcr,br->bc", Ja, ra)
        diagonal = np.einsum("bcc->bc", JTJ)
        A = JTJ + damping[active, None, None] * (np.eye(c)[None] * (diagonal[:, :, None] + 1e-9))
        step = -np.linalg.solve(A, JTr[..., None])[..., 0]
        trial = Ua.copy()
        trial[:, columns] = np.clip(Ua[:, columns] + step, 0.0, 1.0)
        r_trial = residual_rows(rows.rgb(trial), target_rgb[active], None if bounds is None else bounds[active])
        c_trial = np.sum(r_trial**2, axis=1)
        # Broyden: J += s (y - J^T s)^T / |s|^2 for the step s taken (after clipping) and the residuals' change y.
        s = trial[:, columns] - Ua[:, columns]
        norm = np.sum(s**2, axis=1)
        moved = norm > 1e-24
        y = r_trial - ra - np.einsum("bcr,bc->br", Ja, s)
        J[active[moved]] = Ja[moved] + s[moved, :, None] * y[moved, None, :] / norm[moved, None, None]
        better = c_trial < cost[active]
        won = active[better]
        gain = (cost[won] - c_trial[better]) / np.maximum(cost[won], 1e-300)
        U[won], residuals[won], cost[won] = trial[better], r_trial[better], c_trial[better]
        damping[won] = np.maximum(damping[won] / 3.0, 1e-7)
        # A small gain on a differenced Jacobian is a minimum; on a carried one, the Jacobian is stale: difference it again.
        slow = gain < POLISH_STALL
        live[won[slow & exact[better]]] = False
        fresh[won[slow & ~exact[better]]] = True
        lost = active[~better]
        damping[lost] *= 4.0
        fresh[lost] = True
        live[active[~moved]] = False
    return U, cost


def polish_whole(rows: RowModel, target_rgb: np.ndarray, bounds: np.ndarray | None, U0: np.ndarray,
                 steps: int = POLISH_STEPS, walk: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """
    Every row polished from ``U0`` (whole counts: a neighbour's or a design's structure) with its integer
    parameters (``N``) held, which is all a start that close needs; the rows left above
    :data:`COUNT_WALK_DELTA_E` then try their counts one step either way (held again, from where they stopped: a
    smooth map's neighbours differ by a cell or none), and with ``walk`` those still above it walk their counts
    freely (:func:`polish_rounded`: for starts from another region's structure; from a neighbour's it rescues few
    rows at the cost of the two steps before). Each row keeps its best.
    Returns the rows' structures with whole counts, and their coarse costs.
    """
    held = [p.integer for p in rows.free]
    U, cost = polish_rows(rows, target_rgb, bounds, U0, held=held if any(held) else None, steps=steps)
    if not any(held):
        return U, cost
    limit = COUNT_WALK_DELTA_E**2 * rows.cos_theta.size
    poor = np.flatnonzero(cost > limit)
    if poor.size:
        V = np.concatenate([_count_step(rows, U[poor], side) for side in (-1.0, 1.0)])
        twice = np.concatenate([poor, poor])
        V, c = polish_rows(rows, target_rgb[twice], None if bounds is None else bounds[twice], V, held=held, steps=steps)
        for k, row in enumerate(twice):
            if c[k] < cost[row]:
                U[row], cost[row] = V[k], c[k]
    poor = np.flatnonzero(cost > limit) if walk else []
    if len(poor):
        V, c = polish_rounded(rows, target_rgb[poor], None if bounds is None else bounds[poor], U0[poor], max(4, steps // 2))
        better = c < cost[poor]
        U[poor[better]], cost[poor[better]] = V[better], c[better]
    return U, cost


def _count_step(rows: RowModel, U: np.ndarray, side: float) -> np.ndarray:
    """Unit rows ``U`` with each integer parameter one whole step to ``side`` (within its range)."""
    V = U.copy()
    for k, p in enumerate(rows.free):
        if p.integer:
            V[:, k] = np.clip(p.to_unit(np.clip(np.round(p.from_unit(U[:, k])) + side, p.low, p.high)), 0.0, 1.0)
    return V


def polish_rounded(rows: RowModel, target_rgb: np.ndarray, bounds: np.ndarray | None, U0: np.ndarray,
                   steps: int = POLISH_STEPS) -> tuple[np.ndarray, np.ndarray]:
    """
    :func:`polish_rows` with every parameter free (a count relaxed to a real number), then each integer parameter
    at the better of its two neighbouring whole values with the others polished again.
    """
    U, cost = polish_rows(rows, target_rgb, bounds, U0, steps=steps)
    integer = [k for k, p in enumerate(rows.free) if p.integer]
    if not integer:
        return U, cost
    held = [p.integer for p in rows.free]
    best_U, best_cost = None, None
    for rounding in (np.floor, np.ceil):
        V = U.copy()
        for k in integer:
            p = rows.free[k]
            V[:, k] = np.clip(p.to_unit(np.clip(rounding(p.from_unit(U[:, k]) + 1e-9), p.low, p.high)), 0.0, 1.0)
        V, c = polish_rows(rows, target_rgb, bounds, V, held=held, steps=max(4, steps // 2))
        if best_U is None:
            best_U, best_cost = V, c
        else:
            better = c < best_cost
            best_U[better], best_cost[better] = V[better], c[better]
    return best_U, best_cost


def polish_corrected(rows: RowModel, target_rgb: np.ndarray, bounds: np.ndarray | None, U: np.ndarray, achieved: np.ndarray,
                     steps: int = POLISH_STEPS // 2) -> np.ndarray:
    """
    A defect correction: rows ``U`` whose converged colours ``achieved`` ``(B, A, 3)`` differ from their coarse ones
    polished again on the coarse model towards targets moved by that difference (integer parameters held), so
    that the converged colours of the result land on the targets where the difference varies slowly near ``U``.
    The cheap batched model does the walking; the converged one only measures. Returns the new unit rows.
    """
    held = [p.integer for p in rows.free]
    moved = target_rgb - (achieved - rows.rgb(U))
    V, _ = polish_rows(rows, moved, bounds, U, held=held if any(held) else None, steps=steps)
    return V


# --------------------------------------------------------------------------------------------------
# Clustering


def cluster_colours(lab: np.ndarray, weights: np.ndarray, radius: float, max_clusters: int, seed: int) -> np.ndarray:
    """
    Labels of colours ``lab`` ``(U, A, 3)`` (CIELAB per angle; ``weights``: pixels per colour) in the fewest k-means
    clusters (k doubling from 1, at most ``max_clusters``) whose every member lies within ``radius`` CIELAB units
    of its cluster's centroid at every angle. Deterministic for ``seed``.
    """
    from scipy.cluster.vq import kmeans2

    count = lab.shape[0]
    flat = lab.reshape(count, -1)
    labels = np.zeros(count, dtype=np.int64)
    k = 1
    while True:
        if k > 1:
            # Weighted by repetition: a painted region's colour pulls as many pixels as it covers (capped so that
            # a flat region does not drown the gradients).
            repeats = np.minimum(np.maximum(np.round(weights / max(1.0, np.median(weights))).astype(int), 1), 8)
            data = np.repeat(flat, repeats, axis=0)
            centroids, _ = kmeans2(data, min(k, count), minit="++", seed=np.random.default_rng(seed + k))
            labels = np.argmin(np.sum((flat[:, None, :] - centroids[None]) ** 2, axis=-1), axis=1)
        _, labels = np.unique(labels, return_inverse=True)
        spread = 0.0
        for c in range(labels.max() + 1):
            members = lab[labels == c]
            spread = max(spread, float(np.max(np.linalg.norm(members - members.mean(axis=0), axis=-1))))
        if spread <= radius or k >= min(max_clusters, count):
            return labels
        k = min(2 * k, max_clusters, count)


def cluster_centres(lab: np.ndarray, labels: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Per cluster, the index of its member colour nearest its (weighted) centroid: a target the image holds."""
    centres = []
    for c in range(labels.max() + 1):
        members = np.flatnonzero(labels == c)
        w = weights[members][:, None, None]
        centroid = np.sum(lab[members] * w, axis=0) / np.sum(w)
        centres.append(int(members[np.argmin(np.sum((lab[members] - centroid) ** 2, axis=(1, 2)))]))
    return np.array(centres, dtype=np.int64)
