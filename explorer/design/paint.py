"""
Painting with structural colour: from target images (the colours wanted at one or two angles) to per-pixel
structure maps, as Dask tasks (``dask.distributed``: a local cluster, or an existing one by its address).

The stages (each timed; each a set of tasks whose results are cached in the output folder):

1. the image's distinct colours (a key per colour: its CIELAB at every angle to 0.01, and its clipped bounds);
2. their clusters in CIELAB (:func:`explorer.design.pixels.cluster_colours`: k-means, k doubling until every colour
   lies within :data:`CLUSTER_RADIUS` of its centroid);
3. one design per cluster centre (:func:`explorer.design.design`, the search with its tries);
4. the colours on a coarse grid of the image polished from their cluster's structure
   (:func:`explorer.design.pixels.polish_whole`, least squares on the coarse model, many colours per task), then
   every other colour from its nearest grid colour's structure;
5. rounds in which a colour left above :data:`POLISHED_DELTA_E` starts again from its image neighbours' structures
   (and the nearest other clusters'): neighbouring pixels stay in one basin, so the maps stay smooth;
6. the converged colours (the design model's ``converged`` reference), with a polish on the
   converged model where the coarse one misjudged (:func:`explorer.design.search._polish`);
7. a full design for the few colours still above :data:`explorer.design.base.REACHABLE_DELTA_E`; what stays above
   it is flagged as unreachable.

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

from explorer.design.base import REACHABLE_DELTA_E, REACHED_DELTA_E, DesignError, DesignParameter
from explorer.design.forward import design_model
from explorer.design.pixels import RowModel, cluster_centres, cluster_colours, delta_e_rows, polish_whole
from explorer.design.targets import Target, parameter_box
from explorer.physics import colorimetry

#: A cluster holds colours within this many CIELAB units of its centroid at every angle.
CLUSTER_RADIUS = 12.0
#: At most this many clusters (designs).
MAX_CLUSTERS = 16
#: Colours polished per task (small enough that a stage's tasks spread over the workers).
CHUNK = 64
#: A colour whose coarse RMS CIEDE2000 stays above this tries its neighbours' structures.
POLISHED_DELTA_E = 0.5
#: Rounds of neighbours' starts.
NEIGHBOUR_ROUNDS = 3
#: Converged-model polish: evaluations and CPU seconds per colour.
CONVERGED_NFEV = 4
CONVERGED_SECONDS = 0.25
#: At most this many colours get a full design when still unreachable after the polish.
RESCUE_LIMIT = 16
#: Searches per cluster design (:func:`explorer.design.design`'s ``tries``).
CLUSTER_TRIES = 2
#: The colour key's CIELAB quantum.
KEY_QUANTUM = 0.01
#: What the cache's files hold; a new version ignores older ones.
CACHE_VERSION = 1


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


def polish_task(model_name: str, ranges, fixed, angles, rgb: np.ndarray, bounds: np.ndarray, starts: np.ndarray) -> dict:
    """Colours ``rgb`` ``(B, A, 3)`` polished from unit rows ``starts`` ``(B, P)`` on the coarse model."""
    start = time.perf_counter()
    model, _, free, cos_theta = _problem_parts(model_name, ranges, fixed, angles)
    rows = RowModel(model, free, fixed, cos_theta)
    U, cost = polish_whole(rows, rgb, bounds if np.any(bounds) else None, starts)
    return {"U": U, "cost": cost, "seconds": time.perf_counter() - start}


def converged_task(model_name: str, ranges, fixed, angles, rgb: np.ndarray, bounds: np.ndarray, U: np.ndarray) -> dict:
    """
    The converged colours of unit rows ``U`` (whole counts) and their CIEDE2000; rows above :data:`REACHED_DELTA_E`
    polished on the converged model (:func:`explorer.design.search._polish`) from there.
    """
    from explorer.design.search import _polish, _Problem

    start = time.perf_counter()
    model, box, free, cos_theta = _problem_parts(model_name, ranges, fixed, angles)
    rows = RowModel(model, free, fixed, cos_theta)
    values = rows.values(U, whole=True)
    names = list(values)
    achieved = np.empty(rgb.shape)
    out_U = U.copy()
    for i in range(U.shape[0]):
        structure = {k: float(values[k][i]) for k in names}
        achieved[i] = model.converged(structure, cos_theta, final=True)
    delta_e = delta_e_rows(achieved, rgb, bounds if np.any(bounds) else None)
    for i in np.flatnonzero(np.max(delta_e, axis=1) > REACHED_DELTA_E):
        targets = [Target(float(t), tuple(float(c) for c in rgb[i, a]), tuple(int(b) for b in bounds[i, a])) for a, t in enumerate(angles)]
        problem = _Problem(model, box, fixed, targets, None)
        structure = {k: float(values[k][i]) for k in names}
        polished, _ = _polish(problem, np.clip(problem.unit_row(structure), 0.0, 1.0), max_nfev=CONVERGED_NFEV,
                              deadline=time.process_time() + CONVERGED_SECONDS)
        colours = model.converged(polished, cos_theta, final=True)
        d = problem.delta_e(colours)
        if np.sum(d**2) < np.sum(delta_e[i] ** 2):
            achieved[i], delta_e[i] = colours, d
            out_U[i] = rows.unit({k: np.array([polished[k]]) for k in polished})[0]
    return {"U": out_U, "achieved": achieved, "delta_e": delta_e, "seconds": time.perf_counter() - start}


# --------------------------------------------------------------------------------------------------
# Running tasks: on a Dask client, cached in the output folder


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

    # 4. Seed colours (on a coarse grid of the image) from their cluster's structure, then every other colour from
    # its nearest seed's: neighbouring pixels start in the same basin, and a start that close needs few steps.
    U = np.zeros((C, len(free)))
    cost = np.full(C, np.inf)
    pixel_colour = np.full(H * W, -1)
    pixel_colour[pixels] = inverse
    pixel_colour = pixel_colour.reshape(H, W)
    if live.size:
        seeds, nearest_seed = _seed_colours(pixel_colour, colour_possible)
        seed_starts = centre_U[labels[seeds]]
        U[seeds], cost[seeds] = _polish_many(runner, "polish seeds", model_name, ranges, fixed, angles, colour_rgb[seeds],
                                             colour_bounds[seeds], seed_starts)
        rest = np.setdiff1d(live, seeds)
        if rest.size:
            U[rest], cost[rest] = _polish_many(runner, "polish", model_name, ranges, fixed, angles, colour_rgb[rest],
                                               colour_bounds[rest], U[nearest_seed[rest]])
    lap("polish")

    # 5. Neighbours' structures for colours left above POLISHED_DELTA_E.
    neighbour_pairs = _neighbour_colours(pixel_colour)
    for round_ in range(NEIGHBOUR_ROUNDS):
        poor = live[np.sqrt(cost[live] / len(angles)) > POLISHED_DELTA_E]
        if poor.size == 0:
            break
        candidates_of = _candidates(poor, cost, neighbour_pairs, labels, centre_U, colour_lab, centres, U, len(angles))
        tried = [(c, u) for c in poor for u in candidates_of[c]]
        if not tried:
            break
        index = np.array([c for c, _ in tried])
        trial_U, trial_cost = _polish_many(runner, f"neighbours {round_ + 1}", model_name, ranges, fixed, angles,
                                           colour_rgb[index], colour_bounds[index], np.array([u for _, u in tried]))
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

    # 7. A full design for the few colours still beyond reach.
    far = live[np.max(delta_e[live], axis=1) > REACHABLE_DELTA_E] if live.size else live
    far = far[np.argsort(-counts[far], kind="stable")][:RESCUE_LIMIT]
    if far.size:
        rescued = runner.map("full designs", design_task, [(model_name, dict(ranges), fixed, angles, colour_rgb[c], colour_bounds[c],
                                                            seed, rescue_tries) for c in far])
        for c, d in zip(far, rescued):
            if np.sum(np.square(d["delta_e"])) < np.sum(delta_e[c] ** 2):
                U[c] = rows_of.unit({k: np.array([v]) for k, v in d["values"].items()})[0]
                structure = {k: float(v[0]) for k, v in rows_of.values(U[c][None], whole=True).items()}
                achieved[c] = model.converged(structure, rows_of.cos_theta, final=True)
                delta_e[c] = delta_e_rows(achieved[c][None], colour_rgb[c][None], colour_bounds[c][None])[0]
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
    delta_image = np.full((A, H * W), np.nan)
    delta_image[:, pixels] = delta_e[inverse].T
    unreachable = np.zeros(H * W, bool)
    unreachable[pixels] = np.max(delta_e[inverse], axis=1) > REACHABLE_DELTA_E
    for p in free:  # unreachable pixels keep the closest structure found; impossible colours have none
        maps[p.name].ravel()[pixels[~possible]] = np.nan
    return PaintResult(maps=maps, fixed=fixed, achieved=achieved_image.reshape(A, H, W, 3), delta_e=delta_image.reshape(A, H, W),
                       unreachable=unreachable.reshape(H, W), stages=stages, clusters=len(centres), colours=C,
                       tasks=runner.tasks, critical_path=runner.critical_path, task_seconds=runner.task_seconds)


def _polish_many(runner, stage, model_name, ranges, fixed, angles, rgb, bounds, starts):
    """:func:`polish_task` over chunks of :data:`CHUNK` rows."""
    pieces = [slice(s, s + CHUNK) for s in range(0, rgb.shape[0], CHUNK)]
    results = runner.map(stage, polish_task, [(model_name, dict(ranges), fixed, angles, rgb[s], bounds[s], starts[s]) for s in pieces])
    return np.concatenate([r["U"] for r in results]), np.concatenate([r["cost"] for r in results])


#: Seed colours lie on a grid of about this many pixels a side.
SEED_GRID = 16


def _seed_colours(pixel_colour: np.ndarray, possible: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    The colours of the pixels on a grid of about :data:`SEED_GRID` a side (possible colours only; every colour
    when the image has few), and per colour the seed colour nearest its first pixel.
    """
    from scipy.ndimage import distance_transform_edt

    H, W = pixel_colour.shape
    C = possible.size
    if C <= SEED_GRID * SEED_GRID:
        return np.flatnonzero(possible), np.arange(C)
    stride = max(1, int(round(max(H, W) / SEED_GRID)))
    grid = np.zeros((H, W), bool)
    grid[stride // 2 :: stride, stride // 2 :: stride] = True
    grid &= pixel_colour >= 0
    grid[pixel_colour >= 0] &= possible[pixel_colour[pixel_colour >= 0]]
    seeds = np.unique(pixel_colour[grid])
    if seeds.size == 0:
        return np.flatnonzero(possible), np.arange(C)
    # The nearest grid pixel of every pixel (a distance transform's indices), then per colour its first pixel's.
    _, (iy, ix) = distance_transform_edt(~grid, return_indices=True)
    nearest_pixel_colour = pixel_colour[iy, ix]
    nearest = np.arange(C)
    flat = pixel_colour.ravel()
    order = np.flatnonzero(flat >= 0)
    colours, first = np.unique(flat[order], return_index=True)
    nearest[colours] = nearest_pixel_colour.ravel()[order[first]]
    return seeds, nearest


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


#: Starts tried per poor colour and round: its best neighbours' structures, then the nearest other clusters'.
NEIGHBOUR_STARTS = 3
OTHER_CLUSTERS = 2  # (besides its own cluster's, when it started elsewhere)


def _candidates(poor, cost, pairs, labels, centre_U, colour_lab, centres, U, angles) -> dict[int, list[np.ndarray]]:
    """Per poor colour, distinct starts: neighbours that are better polished, then the nearest other clusters' designs."""
    out = {}
    for c in poor:
        starts = []
        neighbours = sorted((n for n in pairs.get(int(c), ()) if cost[n] < cost[c]), key=lambda n: (cost[n], n))
        for n in neighbours[:NEIGHBOUR_STARTS]:
            starts.append(U[n])
        if labels[c] >= 0:
            starts.append(centre_U[labels[c]])
        if centres.size > 1:
            distance = np.sum((colour_lab[centres] - colour_lab[c]) ** 2, axis=(1, 2))
            for k in np.argsort(distance, kind="stable"):
                if k != labels[c] and len(starts) < NEIGHBOUR_STARTS + OTHER_CLUSTERS + 1:
                    starts.append(centre_U[k])
        distinct = []
        for s in starts:
            if all(np.max(np.abs(s - d)) > 1e-6 for d in distinct) and np.max(np.abs(s - U[c])) > 1e-6:
                distinct.append(s)
        out[int(c)] = distinct
    return out
