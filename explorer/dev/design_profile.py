"""
How narrow the misses' basins are once one coordinate is searched exhaustively (docs/design.md, "Where it
fails"): for the round trip's mirrors that miss (median ΔE2000 above 1 in docs/design_round_trip.txt), the
true shape's other coordinates moved by ``DISTANCES`` of the box in random directions, each scored by the
scan at its best period within :data:`explorer.design.DESCENT_SPAN` of the truth's and at its best
value of the profiled coordinate:

- the optical share f (``F_VALUES`` shares over [0, 1]), moving n1, n2, N and the host;
- the host index (``HOST_VALUES`` values within ``HOST_WINDOW`` of the box around the truth's, or around n1
  where the truth has none: a host of n1's index is no host), moving n1, n2, N and f. The host sets the
  angle inside each layer (Snell's invariant nh sin theta), so this profiles out the bands' angular shift;
- the count N (``COUNT_VALUES`` whole counts, log-spaced over its box), moving n1, n2, f and the host.

Prints the median score (sum over the 5 targets of ΔE2000², ~5 = 1 per target) per distance, and that of
random shapes.

    .venv/bin/python -m explorer.dev.design_profile       # ~2 minutes
"""

from __future__ import annotations

import numpy as np

from explorer import design
from explorer.design import search
from explorer.dev.design_fidelity import round_trip_misses, truth_problem

DISTANCES = (0.0, 0.005, 0.01, 0.02, 0.05)
DIRECTIONS = 4
F_VALUES = 256
HOST_VALUES = 61
HOST_WINDOW = 0.15
COUNT_VALUES = 48


def profiled(problem: search._Problem, u: np.ndarray, period: float, coordinate: int, values: np.ndarray) -> float:
    """The scan's best score of ``u`` over ``values`` of one unit coordinate and the periods near ``period``."""
    shapes = np.repeat(u[None], len(values), axis=0)
    shapes[:, coordinate] = values
    scores, _ = search._threaded_scan(problem, shapes, around=np.full(len(values), period), span=design.DESCENT_SPAN)
    return float(scores.min())


def profile_table(profiled_name: str) -> None:
    """The median scores per distance with ``profiled_name`` (``optical_fraction``, ``nh`` or ``N``) profiled."""
    ranges, model, indices, truths = round_trip_misses()
    table = {d: [] for d in DISTANCES}
    randoms = []
    print(f"{profiled_name} profiled")
    print("mirror  " + "  ".join(f"d={d:<5g}" for d in DISTANCES) + "  random shapes")
    for index in indices:
        truth = truths[index]
        problem = truth_problem(model, ranges, truth)
        u = problem.unit_row(truth)
        names = [p.name for p in problem.free]
        scale, coordinate = problem.scale_index, names.index(profiled_name)
        others = [k for k in range(len(names)) if k not in (scale, coordinate)]
        period = float(problem.free[scale].from_unit(u[scale]))
        if profiled_name == "nh":
            host = problem.free[coordinate]
            centre = u[coordinate] if truth["nh"] >= model.host_threshold else host.to_unit(truth["n1"])
            values = np.clip(centre + np.linspace(-HOST_WINDOW, HOST_WINDOW, HOST_VALUES), 0.0, 1.0)
        elif profiled_name == "N":
            count = problem.free[coordinate]
            values = count.to_unit(np.unique(np.round(np.geomspace(count.low, count.high, COUNT_VALUES))))
        else:
            values = (np.arange(F_VALUES) + 0.5) / F_VALUES
        rng = np.random.default_rng(index)
        line = []
        for d in DISTANCES:
            scores = []
            for _ in range(1 if d == 0.0 else DIRECTIONS):
                direction = rng.normal(size=len(others))
                v = u.copy()
                v[others] = np.clip(v[others] + d * direction / np.linalg.norm(direction), 0.0, 1.0)
                scores.append(profiled(problem, v, period, coordinate, values))
            table[d].append(np.median(scores))
            line.append(f"{np.median(scores):7.1f}")
        shapes = rng.uniform(size=(DIRECTIONS, u.size))
        random = np.median([profiled(problem, v, period, coordinate, values) for v in shapes])
        randoms.append(random)
        print(f"{index:6d}  " + "  ".join(line) + f"  {random:7.1f}", flush=True)
    print("median  " + "  ".join(f"{np.median(table[d]):7.1f}" for d in DISTANCES) + f"  {np.median(randoms):7.1f}")


def main() -> None:
    for name in ("optical_fraction", "nh", "N"):
        profile_table(name)


if __name__ == "__main__":
    main()
