"""
How narrow the misses' basins are once the optical share f is searched exhaustively (docs/design.md, "Where
it fails"): for the round trip's mirrors that miss (median ΔE2000 above 1 in docs/design_round_trip.txt),
the true shape's other coordinates (n1, n2, N, the host) moved by ``DISTANCES`` of the box in random
directions, each scored by the scan at its best of ``F_VALUES`` shares f and of the periods within
:data:`explorer.physics.design.DESCENT_SPAN` of the truth's: the landscape with f and the period profiled
out. Prints the median score (sum over the 5 targets of ΔE2000², ~5 = 1 per target) per distance, and that
of random shapes.

    .venv/bin/python docs/design_profile.py       # ~2 minutes
"""

from __future__ import annotations

import numpy as np

from design_fidelity import round_trip_misses, truth_problem
from explorer.physics import design

DISTANCES = (0.0, 0.005, 0.01, 0.02, 0.05)
DIRECTIONS = 4
F_VALUES = 256


def profiled(problem: design._Problem, u: np.ndarray, period: float) -> float:
    """The scan's best score of ``u`` over ``F_VALUES`` shares f and the periods near ``period``."""
    share = [p.name for p in problem.free].index("optical_fraction")
    shapes = np.repeat(u[None], F_VALUES, axis=0)
    shapes[:, share] = (np.arange(F_VALUES) + 0.5) / F_VALUES
    scores, _ = design._threaded_scan(problem, shapes, around=np.full(F_VALUES, period), span=design.DESCENT_SPAN)
    return float(scores.min())


def main() -> None:
    ranges, model, indices, truths = round_trip_misses()
    table = {d: [] for d in DISTANCES}
    randoms = []
    print("mirror  " + "  ".join(f"d={d:<5g}" for d in DISTANCES) + "  random shapes")
    for index in indices:
        truth = truths[index]
        problem = truth_problem(model, ranges, truth)
        u = problem.unit_row(truth)
        names = [p.name for p in problem.free]
        scale = problem.scale_index
        others = [k for k, name in enumerate(names) if k != scale and name != "optical_fraction"]
        period = float(problem.free[scale].from_unit(u[scale]))
        rng = np.random.default_rng(index)
        line = []
        for d in DISTANCES:
            scores = []
            for _ in range(1 if d == 0.0 else DIRECTIONS):
                direction = rng.normal(size=len(others))
                v = u.copy()
                v[others] = np.clip(v[others] + d * direction / np.linalg.norm(direction), 0.0, 1.0)
                scores.append(profiled(problem, v, period))
            table[d].append(np.median(scores))
            line.append(f"{np.median(scores):7.1f}")
        shapes = rng.uniform(size=(DIRECTIONS, u.size))
        random = np.median([profiled(problem, v, period) for v in shapes])
        randoms.append(random)
        print(f"{index:6d}  " + "  ".join(line) + f"  {random:7.1f}", flush=True)
    print("median  " + "  ".join(f"{np.median(table[d]):7.1f}" for d in DISTANCES) + f"  {np.median(randoms):7.1f}")


if __name__ == "__main__":
    main()
