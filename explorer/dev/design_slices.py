"""
Two-dimensional slices of the design's landscape through true structures (docs/design.md, "Where it
fails"): the scan's score (the sum over the targets of CIEDE2000², each shape at its best optical
period) over the first layer's optical share f against each other free coordinate, ±0.05 of the unit box
around the truth, for round-trip mirrors the search misses. The basin is a few thousandths of the box
wide in f, a few hundredths in nh and n2; along n1 (and N for thick stacks) it is a long valley.

    .venv/bin/python -m explorer.dev.design_slices      # writes docs/figures/design_slices.png (~2 min)
"""

from __future__ import annotations

import numpy as np

from explorer.dev.design_fidelity import round_trip_truths, truth_problem
from explorer.resources import SOURCE_ROOT

#: Round-trip mirrors (seed 0) the search misses: a high-order stack under a dense host (13), a thin
#: stack (31), a thick high-order stack under a dense host (2).
MIRRORS = (13, 31, 2)
#: Offsets from the truth (unit box), per axis; 41 keeps the truth on the grid.
OFFSETS = np.linspace(-0.05, 0.05, 41)
AGAINST = ("n1", "n2", "nh", "N")
LABELS = {"n1": "n1", "n2": "n2", "nh": "nh", "N": "N (log)"}


def slice_scores(problem, u: np.ndarray, a: int, b: int) -> np.ndarray:
    """The scan's best score on the grid of offsets of coordinates ``a`` (rows) and ``b`` (columns)."""
    rows = np.repeat(u[None], OFFSETS.size ** 2, axis=0)
    rows[:, a] = np.clip(u[a] + np.repeat(OFFSETS, OFFSETS.size), 0.0, 1.0)
    rows[:, b] = np.clip(u[b] + np.tile(OFFSETS, OFFSETS.size), 0.0, 1.0)
    scores, _ = problem.scale_scan(rows)
    return scores.min(axis=1).reshape(OFFSETS.size, OFFSETS.size)


def main() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    ranges, model, truths = round_trip_truths(max(MIRRORS) + 1)
    figure, axes = plt.subplots(len(MIRRORS), len(AGAINST), figsize=(3.3 * len(AGAINST), 3.0 * len(MIRRORS)),
                                sharex=True, sharey=True, layout="constrained")
    norm = LogNorm(1.0, 3000.0)
    span = (OFFSETS[0], OFFSETS[-1], OFFSETS[0], OFFSETS[-1])
    for row, index in zip(axes, MIRRORS):
        truth = truths[index]
        problem = truth_problem(model, ranges, truth)
        u = problem.unit_row(truth)
        names = [p.name for p in problem.free]
        f = names.index("optical_fraction")
        for axis, name in zip(row, AGAINST):
            scores = slice_scores(problem, u, names.index(name), f)
            image = axis.imshow(np.maximum(scores, 1.0), origin="lower", extent=span, norm=norm, cmap="viridis")
            axis.contour(OFFSETS, OFFSETS, scores, levels=[5.0 * len(problem.targets)], colors="w", linewidths=0.6)
            axis.set_ylabel(f"{LABELS[name]} offset", fontsize=8)
            axis.set_xticks([-0.04, 0.0, 0.04])
            axis.set_yticks([-0.04, 0.0, 0.04])
            axis.tick_params(labelsize=7)
            print(f"mirror {index}, f against {name}: {np.mean(scores <= 5.0 * len(problem.targets)):.4f} of the slice within "
                  f"score {5 * len(problem.targets)}, truth {scores[OFFSETS.size // 2, OFFSETS.size // 2]:.2f}", flush=True)
        row[0].set_title(f"mirror {index}: n1 = {truth['n1']:.2f}, n2 = {truth['n2']:.2f}, Λ = {truth['Lambda']:.0f} nm, "
                         f"N = {truth['N']:.0f}, nh = {truth['nh']:.2f}", fontsize=8, loc="left")
    for axis in axes[-1]:
        axis.set_xlabel("f offset (first layer's optical share)", fontsize=8)
    figure.colorbar(image, ax=axes, shrink=0.6, label="scan score: Σ ΔE2000² over 5 targets")
    figure.suptitle("The landscape through the truth of three missed round-trip mirrors, each shape at its best period "
                    "(white: ~2.2 ΔE2000 per target)", fontsize=10)
    out = SOURCE_ROOT / "docs" / "figures" / "design_slices.png"
    figure.savefig(out, dpi=90)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
