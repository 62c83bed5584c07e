"""
Painting with structural colour: from target images (the colours wanted at one or two angles) to per-pixel
structure maps, as Dask tasks (``dask.distributed``: a local cluster, or an existing one by its address).

The stages (each timed; each a set of tasks whose results are cached in the output folder):

1. the image's distinct colours (a key per colour: its CIELAB at every angle to :data:`KEY_QUANTUM`, and its clipped
   bounds), so that a colour painted over many pixels is designed once;
2. their clusters in CIELAB (:func:`explorer.design.pixels.cluster_colours`: k-means, k doubling until every colour
   lies within :data:`CLUSTER_RADIUS` of its centroid, at most :data:`MAX_CLUSTERS`);
3. one design per cluster centre (:func:`explorer.design.design`, the search with its tries);
4. the polish, coarse to fine: the colours on a grid of about :data:`COARSEST_GRID` pixels a side from their
   cluster's structure and the nearest other clusters', then each finer grid's new colours from the nearest polished
   pixel's structure (:func:`explorer.design.pixels.polish_whole`: batched Levenberg-Marquardt over all the colours
   of a task at once, on the coarse model);
5. rounds in which a colour left above :data:`POLISHED_DELTA_E` starts again from its better neighbours' structures:
   neighbouring pixels stay in one basin, so the maps stay smooth;
6. the converged colours (the design model's ``converged`` reference), and where they miss, a
   batched correction by the difference between the models (:func:`explorer.design.pixels.polish_corrected`);
7. a full design for a few colours still above :data:`explorer.design.base.REACHABLE_DELTA_E`, and rounds that spread
   their structures to their neighbours; what stays above it is flagged as unreachable.

Everything is a pure function of its inputs and the seed: the same image and seed give the same maps, whatever
the number of workers.
"""

from __future__ import annotations

import hashlib
import pickle
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from explorer.design.base import REACHABLE_DELTA_E, DesignError, DesignParameter
from explorer.design.forward import design_model
from explorer.design.pixels import RowModel, cluster_centres, cluster_colours, delta_e_rows, polish_corrected, polish_whole
from explorer.design.targets import Target, parameter_box
from explorer.physics import colorimetry

#: A cluster holds colours within this many CIELAB units of its centroid at every angle.
CLUSTER_RADIUS = 12.0
#: At most this many clusters (designs).
MAX_CLUSTERS = 8
#: Colours per task (small enough that a stage's tasks spread over the workers, large enough that the batched
#: model runs on long arrays). Fixed, not from the number of workers: the maps must not depend on it.
CHUNK = 128
#: A colour whose coarse RMS CIEDE2000 stays above this tries its neighbours' structures.
POLISHED_DELTA_E = 0.5
#: Rounds of neighbours' starts.
NEIGHBOUR_ROUNDS = 3
#: A colour whose converged CIEDE2000 exceeds this at an angle is corrected for the coarse model's error, at most
#: this many times (:func:`explorer.design.pixels.polish_corrected`).
CORRECTED_DELTA_E = 0.5
CORRECTIONS = 2
#: The coarsest level of the polish holds about this many pixels a side; each finer level halves the stride.
COARSEST_GRID = 8
#: At most this many colours get a full design when still unreachable after the polish.
RESCUE_LIMIT = 8
#: Searches per cluster design (:func:`explorer.design.design`'s ``tries``).
CLUSTER_TRIES = 2
#: The colour key's CIELAB quantum: colours in one cell (at most sqrt(3) times this apart, a fraction of a just
#: noticeable difference) are designed once. Every pixel's CIEDE2000 is still measured against its own target.
KEY_QUANTUM = 0.2
#: What the cache's files hold; a new version ignores older ones.
CACHE_VERSION = 3


@dataclass
class PaintTargets:
    """Target images at angles: ``rgb`` ``(A, H, W, 3)`` linear, ``bounds`` ``(A, H, W, 3)`` int8 (clipped channels), ``mask`` ``(H, W)``."""

    angles: tuple[float, ...]
    rgb: np.ndarray
    bounds: np.ndarray
    mask: np.ndarray


@dataclass
class PaintResult:
    """The maps ``(H, W)`` by parameter (NaN off the mask), the fixed values, the achieved colours and their CIEDE2000."""

    maps: dict[str, np.ndarray]
    fixed: dict[str, float]
    achieved: np.ndarray  # (A, H, W, 3)
    delta_e: np.ndarray  # (A, H, W), NaN off the mask
    unreachable: np.ndarray  # (H, W) bool
    stages: dict[str, float] = field(default_factory=dict)
    clusters: int = 0
    colours: int = 0
    tasks: int = 0
    critical_path: float = 0.0
    task_seconds: float = 0.0

    def report(self, angles: Sequence[float]) -> dict:
        """Median, 95th percentile and the share within 1 of the CIEDE2000 per angle, the unreachable share, the times."""
        inside = ~np.isnan(self.delta_e[0])
        per_angle = {}
        for a, theta in enumerate(angles):
            d = self.delta_e[a][inside]
            per_angle[f"{theta:g}"] = {"median": float(np.median(d)) if d.size else None,
                                       "p95": float(np.percentile(d, 95)) if d.size else None,
                                       "within_1": float(np.mean(d <= 1.0)) if d.size else None}
        both = np.max(self.delta_e, axis=0)[inside]
        return {"delta_e2000": per_angle, "within_1_at_every_angle": float(np.mean(both <= 1.0)) if both.size else None,
                "pixels": int(inside.sum()), "unreachable_pixels": int(self.unreachable.sum()), "colours": self.colours,
                "clusters": self.clusters, "tasks": self.tasks, "seconds": self.stages,
                "task_seconds": self.task_seconds, "critical_path_seconds": self.critical_path}


# --------------------------------------------------------------------------------------------------
# The tasks (module-level and pure: Dask ships them to workers by reference)


def _problem_parts(model_name, ranges, fixed, angles):
    model = design_model(model_name)
    box = parameter_box(model, ranges)
    free = [p for p in box if p.name not in fixed]
    return model, box, free, np.cos(np.radians(np.asarray(angles, dtype=np.float64)))


def design_task(model_name: str, ranges, fixed, angles, rgb: np.ndarray, bounds: np.ndarray, seed: int, tries: int) -> dict:
    """One design of colours ``rgb`` ``(A, 3)`` at ``angles``: the structure (design values) and its CIEDE2000."""
    from explorer.design.solve import design

    targets = [Target(float(t), tuple(float(c) for c in rgb[a]), tuple(int(b) for b in bounds[a])) for a, t in enumerate(angles)]
    start = time.perf_counter()
    result = design(model_name, targets, ranges, fixed, seed=seed, tries=tries)
    return {"values": {k: float(v) for k, v in result.values.items()}, "delta_e": result.delta_e2000.tolist(),
            "seconds": time.perf_counter() - start}


def polish_task(model_name: str, ranges, fixed, angles, rgb: np.ndarray, bounds: np.ndarray, starts: np.ndarray, walk: bool = True) -> dict:
    """
    Colours ``rgb`` ``(B, A, 3)`` polished from unit rows ``starts`` ``(B, P)`` on the coarse model; ``walk``: the
    counts may walk freely (starts from other regions' structures; :func:`explorer.design.pixels.polish_whole`).
    """
    start = time.perf_counter()
    model, _, free, cos_theta = _problem_parts(model_name, ranges, fixed, angles)
    rows = RowModel(model, free, fixed, cos_theta)
    U, cost = polish_whole(rows, rgb, bounds if np.any(bounds) else None, starts, walk=walk)
    return {"U": U, "cost": cost, "seconds": time.perf_counter() - start}


def converged_task(model_name: str, ranges, fixed, angles, rgb: np.ndarray, bounds: np.ndarray, U: np.ndarray) -> dict:
    """
    The converged colours of unit rows ``U`` (whole counts) and their CIEDE2000; rows above :data:`CORRECTED_DELTA_E`
    corrected by the difference between the two models (:func:`explorer.design.pixels.polish_corrected`, batched, up
    to :data:`CORRECTIONS` times), each keeping its best structure.
    """
    start = time.perf_counter()
    model, _, free, cos_theta = _problem_parts(model_name, ranges, fixed, angles)
    rows = RowModel(model, free, fixed, cos_theta)
    limits = bounds if np.any(bounds) else None
    out_U = U.copy()
    achieved = _converged_rows(model, rows, out_U)
    delta_e = delta_e_rows(achieved, rgb, limits)
    for _ in range(CORRECTIONS):
        off = np.flatnonzero(np.max(delta_e, axis=1) > CORRECTED_DELTA_E)
        if off.size == 0:
            break
        V = polish_corrected(rows, rgb[off], None if limits is None else limits[off], out_U[off], achieved[off])
        colours = _converged_rows(model, rows, V)
        d = delta_e_rows(colours, rgb[off], None if limits is None else limits[off])
        better = np.sum(d**2, axis=1) < np.sum(delta_e[off] ** 2, axis=1)
        won = off[better]
        out_U[won], achieved[won], delta_e[won] = V[better], colours[better], d[better]
    return {"U": out_U, "achieved": achieved, "delta_e": delta_e, "seconds": time.perf_counter() - start}


def _converged_rows(model, rows: RowModel, U: np.ndarray) -> np.ndarray:
    """The converged colours ``(B, A, 3)`` of unit rows (counts whole)."""
    return model.converged_rows(rows.values(U, whole=True), rows.cos_theta)


# --------------------------------------------------------------------------------------------------
# Running tasks: on a Dask client, cached in the output folder

#: What Dask's nanny sets in each worker's environment by default (``distributed.nanny.pre-spawn-environ``) and a
#: local cluster here leaves out: ``MALLOC_TRIM_THRESHOLD_`` turns glibc's adaptive mmap threshold off, so every large
#: temporary of the batched models is mapped and zeroed afresh. Measured (``explorer.dev.paint_cost --round-trip 32``,
#: one process): 59.4 and 74.2 CPU s with it set against 40.8 and 49.1 s without, the same maps.
WORKER_ENVIRONMENT_UNSET = ("MALLOC_TRIM_THRESHOLD_",)


def local_cluster(workers: int, dashboard: str | None = None):
    """A ``distributed.LocalCluster`` of ``workers`` processes of one thread each (``dashboard``: its address, or None)."""
    import logging

    import dask
    from distributed import LocalCluster

    unset = {f"distributed.nanny.pre-spawn-environ.{name}": None for name in WORKER_ENVIRONMENT_UNSET}
    with dask.config.set(unset):  # read when each worker's nanny starts, inside this call
        return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=dashboard,
                            silence_logs=logging.ERROR)


class _Runner:
    """Submits tasks to a Dask client (or runs them here without one), each result cached under ``cache`` by its inputs' hash."""

    def __init__(self, client, cache: Path | None, progress: Callable[[str], None]):
        self.client, self.cache, self.progress = client, cache, progress
        self.tasks = 0
        self.task_seconds = 0.0
        self.critical_path = 0.0

    def key(self, name: str, args) -> str:
        digest = hashlib.sha256(pickle.dumps((CACHE_VERSION, name, args), protocol=4)).hexdigest()[:24]
        return f"{name}-{digest}"

    def map(self, stage: str, function, argument_lists: list[tuple]) -> list[dict]:
        """``function(*args)`` for each argument list, in order; cached results are read, the others computed."""
        keys = [self.key(function.__name__, args) for args in argument_lists]
        results: list[dict | None] = [self._read(k) for k in keys]
        todo = [i for i, r in enumerate(results) if r is None]
        cached = len(keys) - len(todo)
        self.progress(f"{stage}: {len(keys)} tasks" + (f" ({cached} from the cache)" if cached else ""))
        if todo:
            if self.client is None:
                for n, i in enumerate(todo):
                    results[i] = function(*argument_lists[i])
                    self._write(keys[i], results[i])
                    self.progress(f"{stage}: {n + 1}/{len(todo)}")
            else:
                from distributed import as_completed

                futures = {self.client.submit(function, *argument_lists[i], key=keys[i], pure=False): i for i in todo}
                for n, future in enumerate(as_completed(list(futures))):
                    i = futures[future]
                    results[i] = future.result()
                    self._write(keys[i], results[i])
                    if n + 1 == len(todo) or (n + 1) % max(1, len(todo) // 10) == 0:
                        self.progress(f"{stage}: {n + 1}/{len(todo)}")
                    future.release()
        seconds = [float(r.get("seconds", 0.0)) for r in results]
        self.tasks += len(keys)
        self.task_seconds += float(sum(seconds))
        # Each stage waits for the one before: the critical path is the sum of each stage's longest task.
        self.critical_path += max(seconds, default=0.0)
        return results

    def _path(self, key: str) -> Path | None:
        return None if self.cache is None else self.cache / f"{key}.pkl"

    def _read(self, key: str) -> dict | None:
        path = self._path(key)
        if path is None or not path.is_file():
            return None
        try:
            with open(path, "rb") as stream:
                return pickle.load(stream)
        except (OSError, pickle.UnpicklingError, EOFError):
            return None

    def _write(self, key: str, result: dict) -> None:
        from explorer.files import write_bytes_atomic

        path = self._path(key)
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            write_bytes_atomic(path, pickle.dumps(result, protocol=4))


# --------------------------------------------------------------------------------------------------
# The painting


def colour_keys(lab: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """Per pixel ``(n, A, 3)``, the integer key rows of its CIELAB (to :data:`KEY_QUANTUM`) and its clipped bounds."""
    quantised = np.round(lab / KEY_QUANTUM).astype(np.int64).reshape(lab.shape[0], -1)
    return np.concatenate([quantised, bounds.reshape(bounds.shape[0], -1).astype(np.int64)], axis=1)


def paint(model_name: str, ranges: Mapping[str, tuple[float, float]], fixed: Mapping[str, float], targets: PaintTargets,
          seed: int = 0, client=None, cache: Path | None = None, progress: Callable[[str], None] | None = None,
          tries: int = CLUSTER_TRIES, rescue_tries: int = 4) -> PaintResult:
    """
    The structure maps that show ``targets`` (see the module's stages). ``client``: a ``distributed.Client`` (None:
    every task here, in turn). ``cache``: a folder where each task's result is kept by its inputs' hash, so that a
    run stopped midway resumes. Deterministic for ``seed``.
    """
    say = progress or (lambda message: None)
    runner = _Runner(client, cache, say)
    stages: dict[str, float] = {}
    clock = time.perf_counter()

    def lap(name):
        nonlocal clock
        now = time.perf_counter()
        stages[name] = now - clock
        clock = now

    model = design_model(model_name)
    # The held parameters (absorption, disorder) stay at 0 unless fixed: painting searches the structure only.
    fixed = {**{name: 0.0 for name in model.held}, **{k: float(v) for k, v in fixed.items()}}
    box = parameter_box(model, ranges)
    for name in fixed:
        if name not in {p.name for p in box}:
            raise DesignError(f"cannot fix {name}: not a design parameter of {model.name} ({', '.join(model.parameters)})")
    free: list[DesignParameter] = [p for p in box if p.name not in fixed]
    if not free:
        raise DesignError("every design parameter is fixed: free at least one")
    angles = tuple(float(a) for a in targets.angles)
    for a in angles:
        if not (np.isfinite(a) and 0.0 <= a < 90.0):
            raise DesignError(f"angle {a:g}: must be in [0, 90) degrees")
    A, H, W = targets.rgb.shape[:3]
    rows_of = RowModel(model, free, fixed, np.cos(np.radians(angles)))

    # 1. Distinct colours of the masked pixels; colours no passive reflector has are unreachable at once.
    pixels = np.flatnonzero(targets.mask.ravel())
    rgb = targets.rgb.reshape(A, -1, 3)[:, pixels].transpose(1, 0, 2)  # (n, A, 3)
    bounds = targets.bounds.reshape(A, -1, 3)[:, pixels].transpose(1, 0, 2).astype(np.int8)
    Y = colorimetry.rgb_to_xyz(rgb)[..., 1]
    possible = np.all((Y <= 1.0 + 1e-6) & (Y >= -1e-6), axis=1)
    lab = colorimetry.rgb_to_lab(np.maximum(rgb, -1.0))
    keys = colour_keys(lab, bounds)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    order = np.argsort(first)  # colours in image order: deterministic, and neighbours near each other
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    first, inverse = first[order], rank[inverse]
    colour_rgb, colour_bounds, colour_lab = rgb[first], bounds[first], lab[first]
    colour_possible = possible[first]
    counts = np.bincount(inverse, minlength=first.size).astype(np.float64)
    say(f"{pixels.size} pixels, {first.size} distinct colours at {len(angles)} angle(s)")
    lap("colours")

    # 2. Clusters of the reachable-looking colours.
    C = first.size
    labels = np.full(C, -1)
    live = np.flatnonzero(colour_possible)
    if live.size:
        labels[live] = cluster_colours(colour_lab[live], counts[live], CLUSTER_RADIUS, MAX_CLUSTERS, seed)
        centres = live[cluster_centres(colour_lab[live], labels[live], counts[live])]
    else:
        centres = np.zeros(0, dtype=np.int64)
    say(f"{len(centres)} clusters (radius {CLUSTER_RADIUS:g} CIELAB units)")
    lap("clusters")

    # 3. A design per cluster centre.
    designs = runner.map("designs", design_task, [(model_name, dict(ranges), fixed, angles, colour_rgb[c], colour_bounds[c], seed, tries)
                                                  for c in centres])
    centre_U = np.array([rows_of.unit({k: np.array([v]) for k, v in d["values"].items()})[0] for d in designs]).reshape(len(centres), len(free))
    lap("designs")

    # 4. Coarse to fine: the colours of a coarse grid of the image from their cluster's structure (and the nearest
    # other clusters'), then each finer grid's new colours from the nearest polished pixel's structure. Neighbours
    # start in the same basin, so the maps stay smooth, and a start that close needs a step or two.
    U = np.zeros((C, len(free)))
    cost = np.full(C, np.inf)
    pixel_colour = np.full(H * W, -1)
    pixel_colour[pixels] = inverse
    pixel_colour = pixel_colour.reshape(H, W)
    if live.size:
        levels = _levels(pixel_colour, colour_possible)
        done = np.zeros(C, bool)
        for level, (members, where) in enumerate(levels):
            if level == 0:
                tried = [(c, u) for c in members for u in _cluster_starts(c, labels, centre_U, colour_lab, centres)]
            else:
                nearest = _nearest_done(pixel_colour, done)
                tried = [(c, U[nearest[y, x]]) for c, (y, x) in zip(members, where)]
            index = np.array([c for c, _ in tried], dtype=np.int64)
            trial_U, trial_cost = _polish_many(runner, f"polish level {level + 1} of {len(levels)}", model_name, ranges, fixed, angles,
                                               colour_rgb[index], colour_bounds[index], np.array([u for _, u in tried]), walk=level == 0)
            for k, c in enumerate(index):
                if trial_cost[k] < cost[c]:
                    U[c], cost[c] = trial_U[k], trial_cost[k]
            done[members] = True
    lap("polish")

    # 5. Neighbours' structures for colours left above POLISHED_DELTA_E.
    neighbour_pairs = _neighbour_colours(pixel_colour)
    tried_starts: dict[int, list[np.ndarray]] = {}
    for round_ in range(NEIGHBOUR_ROUNDS):
        poor = live[np.sqrt(cost[live] / len(angles)) > POLISHED_DELTA_E]
        if poor.size == 0:
            break
        candidates_of = _candidates(poor, cost, neighbour_pairs, labels, centre_U, U, tried_starts)
        tried = [(c, u) for c in poor for u in candidates_of[c]]
        if not tried:  # no new start: another round would repeat this one
            break
        index = np.array([c for c, _ in tried])
        trial_U, trial_cost = _polish_many(runner, f"neighbours {round_ + 1}", model_name, ranges, fixed, angles,
                                           colour_rgb[index], colour_bounds[index], np.array([u for _, u in tried]), walk=True)
        for k, c in enumerate(index):
            if trial_cost[k] < cost[c] - 1e-12:
                U[c], cost[c] = trial_U[k], trial_cost[k]
    lap("neighbours")

    # 6. The converged colours.
    achieved = np.zeros((C, A, 3))
    delta_e = np.full((C, A), np.inf)
    if live.size:
        chunks = [live[s : s + CHUNK] for s in range(0, live.size, CHUNK)]
        results = runner.map("converged", converged_task, [(model_name, dict(ranges), fixed, angles, colour_rgb[c], colour_bounds[c], U[c])
                                                          for c in chunks])
        for c, r in zip(chunks, results):
            U[c], achieved[c], delta_e[c] = r["U"], r["achieved"], r["delta_e"]
    lap("converged")

    # 7. A full design for a few of the colours still beyond reach (the most frequent, not neighbours of each other),
    # then rounds in which the others start from their neighbours' structures, as in 5: a region the polish lost
    # is found again from the few designed in it.
    far = live[np.max(delta_e[live], axis=1) > REACHABLE_DELTA_E] if live.size else live
    chosen: list[int] = []
    for c in far[np.argsort(-counts[far], kind="stable")]:
        if len(chosen) < RESCUE_LIMIT and not any(int(c) in neighbour_pairs.get(k, ()) for k in chosen):
            chosen.append(int(c))
    if chosen:
        rescued = runner.map("full designs", design_task, [(model_name, dict(ranges), fixed, angles, colour_rgb[c], colour_bounds[c],
                                                            seed, rescue_tries) for c in chosen])
        for c, d in zip(chosen, rescued):
            if np.sum(np.square(d["delta_e"])) < np.sum(delta_e[c] ** 2):
                U[c] = rows_of.unit({k: np.array([v]) for k, v in d["values"].items()})[0]
                structure = {k: float(v[0]) for k, v in rows_of.values(U[c][None], whole=True).items()}
                achieved[c] = model.converged(structure, rows_of.cos_theta, final=True)
                delta_e[c] = delta_e_rows(achieved[c][None], colour_rgb[c][None], colour_bounds[c][None])[0]
    spread_starts: dict[int, list[np.ndarray]] = {}
    for round_ in range(NEIGHBOUR_ROUNDS if chosen else 0):
        score = np.sum(delta_e**2, axis=1)
        poor = live[np.max(delta_e[live], axis=1) > REACHABLE_DELTA_E]
        tried = [(c, u) for c, starts in _candidates(poor, score, neighbour_pairs, labels, centre_U, U, spread_starts).items() for u in starts]
        if not tried:
            break
        index = np.array([c for c, _ in tried], dtype=np.int64)
        trial_U, _ = _polish_many(runner, f"spread {round_ + 1}", model_name, ranges, fixed, angles, colour_rgb[index],
                                  colour_bounds[index], np.array([u for _, u in tried]), walk=True)
        pieces = [slice(s, s + CHUNK) for s in range(0, index.size, CHUNK)]
        results = runner.map(f"spread {round_ + 1} converged", converged_task,
                             [(model_name, dict(ranges), fixed, angles, colour_rgb[index[s]], colour_bounds[index[s]], trial_U[s]) for s in pieces])
        for s, r in zip(pieces, results):
            for k, c in enumerate(index[s]):
                if np.sum(r["delta_e"][k] ** 2) < np.sum(delta_e[c] ** 2):
                    U[c], achieved[c], delta_e[c] = r["U"][k], r["achieved"][k], r["delta_e"][k]
    lap("full designs")

    # The maps.
    values = rows_of.values(U, whole=True)
    maps = {}
    for p in free:
        image = np.full(H * W, np.nan)
        image[pixels] = values[p.name][inverse]
        maps[p.name] = image.reshape(H, W)
    achieved_image = np.zeros((A, H * W, 3))
    achieved_image[:, pixels] = achieved[inverse].transpose(1, 0, 2)
    # Each pixel against its own target (its colour's structure was designed for its cell's first pixel).
    pixel_delta = delta_e[inverse].copy()
    shown = np.isfinite(pixel_delta).all(axis=1)
    pixel_delta[shown] = delta_e_rows(achieved[inverse[shown]], rgb[shown], bounds[shown] if np.any(bounds) else None)
    delta_image = np.full((A, H * W), np.nan)
    delta_image[:, pixels] = pixel_delta.T
    unreachable = np.zeros(H * W, bool)
    unreachable[pixels] = np.max(pixel_delta, axis=1) > REACHABLE_DELTA_E
    for p in free:  # unreachable pixels keep the closest structure found; impossible colours have none
        maps[p.name].ravel()[pixels[~possible]] = np.nan
    return PaintResult(maps=maps, fixed=fixed, achieved=achieved_image.reshape(A, H, W, 3), delta_e=delta_image.reshape(A, H, W),
                       unreachable=unreachable.reshape(H, W), stages=stages, clusters=len(centres), colours=C,
                       tasks=runner.tasks, critical_path=runner.critical_path, task_seconds=runner.task_seconds)


def _polish_many(runner, stage, model_name, ranges, fixed, angles, rgb, bounds, starts, walk):
    """
    :func:`polish_task` over chunks of :data:`CHUNK` rows. ``walk``: counts walk freely where a start may lie in
    another region (the clusters' structures, and the retries of colours their neighbours' start left poor); a
    finer level's start from its nearest polished pixel only tries its count one either way.
    """
    pieces = [slice(s, s + CHUNK) for s in range(0, rgb.shape[0], CHUNK)]
    results = runner.map(stage, polish_task, [(model_name, dict(ranges), fixed, angles, rgb[s], bounds[s], starts[s], walk) for s in pieces])
    return np.concatenate([r["U"] for r in results]), np.concatenate([r["cost"] for r in results])


def _levels(pixel_colour: np.ndarray, possible: np.ndarray) -> list[tuple[np.ndarray, list[tuple[int, int]]]]:
    """
    The polish's levels, coarse to fine: per level, the possible colours first met on its grid (strides halving from
    about :data:`COARSEST_GRID` cells a side down to 1) and each one's first pixel on that grid.
    """
    H, W = pixel_colour.shape
    if np.count_nonzero(possible) <= COARSEST_GRID**2:  # few colours: every one from the clusters
        return [_first_pixels(pixel_colour, possible, np.zeros((H, W), dtype=np.int64))[0]]
    stride = 1 << max(0, int(np.floor(np.log2(max(H, W) / COARSEST_GRID))))
    strides = [stride >> d for d in range(stride.bit_length())]
    y, x = np.mgrid[0:H, 0:W]
    level = np.zeros((H, W), dtype=np.int64)
    for d in reversed(range(len(strides))):  # a pixel's level: the coarsest (nested) grid it lies on
        level[(y % strides[d] == 0) & (x % strides[d] == 0)] = d
    return _first_pixels(pixel_colour, possible, level)


def _first_pixels(pixel_colour: np.ndarray, possible: np.ndarray, level: np.ndarray) -> list[tuple[np.ndarray, list[tuple[int, int]]]]:
    """Per level of pixels, the possible colours whose coarsest level it is, with their first pixel there."""
    W = pixel_colour.shape[1]
    flat, lev = pixel_colour.ravel(), level.ravel()
    inside = np.flatnonzero((flat >= 0))
    inside = inside[possible[flat[inside]]]
    # Per colour, its coarsest level and its first pixel there (raster order breaks ties).
    order = inside[np.lexsort((inside, lev[inside], flat[inside]))]
    colours, first = np.unique(flat[order], return_index=True)
    first_pixel = order[first]
    colour_level = lev[first_pixel]
    out = []
    for d in range(int(colour_level.max()) + 1 if colours.size else 0):
        pick = np.flatnonzero(colour_level == d)
        if pick.size:
            out.append((colours[pick], [(int(p // W), int(p % W)) for p in first_pixel[pick]]))
    return out


def _nearest_done(pixel_colour: np.ndarray, done: np.ndarray) -> np.ndarray:
    """Per pixel, the colour of the nearest pixel whose colour is polished (a distance transform's indices)."""
    from scipy.ndimage import distance_transform_edt

    solved = pixel_colour >= 0
    solved[solved] = done[pixel_colour[solved]]
    _, (iy, ix) = distance_transform_edt(~solved, return_indices=True)
    return pixel_colour[iy, ix]


def _cluster_starts(c, labels, centre_U, colour_lab, centres) -> list[np.ndarray]:
    """A colour's own cluster's structure, then the nearest other clusters' (:data:`OTHER_CLUSTERS`)."""
    starts = [centre_U[labels[c]]]
    distance = np.sum((colour_lab[centres] - colour_lab[c]) ** 2, axis=(1, 2))
    for k in np.argsort(distance, kind="stable"):
        if k != labels[c] and len(starts) < OTHER_CLUSTERS + 1:
            starts.append(centre_U[k])
    return starts


def _neighbour_colours(pixel_colour: np.ndarray) -> dict[int, set[int]]:
    """Per colour, the colours of its pixels' 4-neighbours (masked pixels have none)."""
    pairs: dict[int, set[int]] = {}
    for a, b in ((pixel_colour[:, :-1], pixel_colour[:, 1:]), (pixel_colour[:-1, :], pixel_colour[1:, :])):
        both = (a >= 0) & (b >= 0) & (a != b)
        edges = np.unique(np.stack([a[both], b[both]], axis=1), axis=0)
        for x, y in edges:
            pairs.setdefault(int(x), set()).add(int(y))
            pairs.setdefault(int(y), set()).add(int(x))
    return pairs


#: Starts tried per poor colour and round: its best neighbours' structures.
NEIGHBOUR_STARTS = 2
#: The coarsest level's colours also start from this many nearest other clusters' structures.
OTHER_CLUSTERS = 2


def _candidates(poor, cost, pairs, labels, centre_U, U, tried: dict[int, list[np.ndarray]] | None = None) -> dict[int, list[np.ndarray]]:
    """
    Per poor colour, distinct starts: its better polished neighbours' structures (its cluster's when it has none),
    less those it has already been polished from (``tried``, updated: a round repeats no polish).
    """
    out = {}
    for c in poor:
        neighbours = sorted((n for n in pairs.get(int(c), ()) if cost[n] < cost[c]), key=lambda n: (cost[n], n))
        starts = [U[n].copy() for n in neighbours[:NEIGHBOUR_STARTS]]  # copies: U's rows change as colours improve
        if not starts and labels[c] >= 0:
            starts.append(centre_U[labels[c]].copy())
        before = [] if tried is None else tried.setdefault(int(c), [])
        distinct = []
        for s in starts:
            if all(np.max(np.abs(s - d)) > 1e-6 for d in distinct + before) and np.max(np.abs(s - U[c])) > 1e-6:
                distinct.append(s)
        before.extend(distinct)
        out[int(c)] = distinct
    return out
