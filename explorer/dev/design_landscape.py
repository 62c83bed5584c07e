"""
The design's landscape near a true structure (docs/design.md, "Where it fails"): the scan's score (the sum
over the targets of CIEDE2000², each shape at its best optical period) along each free coordinate of the
unit box, through the true shape of three round-trip mirrors, with the descent's first and last spreads
marked. The basins are some 0.01 of the box wide; a random shape scores hundreds.

    .venv/bin/python -m explorer.dev.design_landscape      # writes docs/figures/design_landscape.png
"""

from __future__ import annotations

import numpy as np

from explorer import design
from explorer.dev.design_fidelity import round_trip_truths, truth_problem
from explorer.resources import SOURCE_ROOT

#: Round-trip mirrors (seed 0): a thin stack, a vivid first-order stack under a host, a high-order mirror.
MIRRORS = (31, 10, 40)
OFFSETS = np.linspace(-0.1, 0.1, 81)
LABELS = {"n1": "n1", "n2": "n2", "optical_fraction": "first layer's optical share f", "N": "N (log)", "nh": "nh"}


def main() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ranges, model, truths = round_trip_truths(max(MIRRORS) + 1)
    figure, axes = plt.subplots(1, len(MIRRORS), figsize=(5.2 * len(MIRRORS), 4.6), sharey=True)
    for axis, index in zip(axes, MIRRORS):
        truth = truths[index]
        problem = truth_problem(model, ranges, truth)
        u = problem.unit_row(truth)
        for k, p in enumerate(problem.free):
            if p.name not in LABELS:
                continue
            rows = np.repeat(u[None], OFFSETS.size, axis=0)
            rows[:, k] = np.clip(rows[:, k] + OFFSETS, 0.0, 1.0)
            scores, _ = problem.scale_scan(rows)
            axis.semilogy(OFFSETS, np.maximum(scores.min(axis=1), 1e-2), label=LABELS[p.name])
        for spread in (design.DESCENT_SIGMAS[0], design.DESCENT_SIGMAS[-1]):
            axis.axvspan(-spread, spread, color="0.5", alpha=0.08)
        axis.axhline(len(problem.targets), color="k", lw=0.8, ls=":")
        axis.set_title(f"round-trip mirror {index}: Λ = {truth['Lambda']:.0f} nm, N = {truth['N']:.0f}, "
                       f"nh = {truth['nh']:.2f}", fontsize=9)
        axis.set_xlabel("offset from the true shape (unit box)")
    axes[0].set_ylabel("scan score: Σ ΔE2000² over 5 targets (dotted: 1 per target)")
    handles, labels = axes[-1].get_legend_handles_labels()
    figure.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=9, frameon=False)
    figure.suptitle("The design landscape through the true structure, each shape at its best period "
                    "(shaded: the descent's first and last spreads, 0.08 and 0.01)", fontsize=10)
    figure.tight_layout(rect=(0.0, 0.06, 1.0, 1.0))
    out = SOURCE_ROOT / "docs" / "figures" / "design_landscape.png"
    figure.savefig(out, dpi=110)
    print(out)


if __name__ == "__main__":
    main()
