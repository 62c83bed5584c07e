"""
How far the polish reaches (docs/design.md, "Where it fails"): for the round trip's mirrors that miss (median
ΔE2000 above 1 in docs/design_round_trip.txt), the true structure moved by a normal step of ``SIGMA`` of the
box in every free coordinate but N, then polished on the converged model (``search._polish``, no time
limit). Prints the RMS CIEDE2000 per target before and after, four steps per mirror and spread.

    .venv/bin/python -m explorer.dev.design_polish       # ~2 minutes
"""

from __future__ import annotations

import numpy as np

from explorer.design import search
from explorer.dev.design_fidelity import round_trip_misses, truth_problem

SIGMAS = (0.003, 0.01, 0.03)
TRIES = 4


def main() -> None:
    ranges, model, indices, truths = round_trip_misses()
    reached = {sigma: 0 for sigma in SIGMAS}
    for index in indices:
        truth = truths[index]
        problem = truth_problem(model, ranges, truth)
        u = problem.unit_row(truth)
        whole = [k for k, p in enumerate(problem.free) if p.integer]
        line = []
        for sigma in SIGMAS:
            for attempt in range(TRIES):
                step = np.random.default_rng(attempt).normal(0.0, sigma, u.size)
                step[whole] = 0.0
                start = np.clip(u + step, 0.0, 1.0)
                _, cost = search._polish(problem, start, max_nfev=20, deadline=float("inf"))
                before, after = (np.sqrt(c / len(problem.targets)) for c in (problem.fine_cost(start), cost))
                reached[sigma] += after < 0.05
                line.append(f"{before:.1f}->{after:.2f}")
        print(f"{index:3d}  " + "  ".join(line), flush=True)
    total = len(indices) * TRIES
    print("below 0.05 after the polish: " + ", ".join(f"{reached[s]}/{total} from {s:g} of the box" for s in SIGMAS))


if __name__ == "__main__":
    main()
