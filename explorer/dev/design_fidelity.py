"""
What the design's first pass sees of the true structure (docs/design.md, "Where it fails"): for each
round-trip mirror that misses (median ΔE2000 above 1 in docs/design_round_trip.txt), the scan's score of its
true shape (the sum over the 5 targets of CIEDE2000², at the best period of the scan's grid) with the scan's
own sampling and fringe averaging, and with finer ones. A score of a few means the search could find the
truth; hundreds mean the screening model hides it, whatever the search does.

    .venv/bin/python -m explorer.dev.design_fidelity       # prints the Markdown table
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from explorer import design
from explorer.design import search
from explorer.design import ranges_of
from explorer.materials.brd import load_material
from explorer.materials.models import BraggMirrorModel
from explorer.resources import SOURCE_ROOT, material_path

#: The material the round trip designs (its twin's name).
MIRROR = BraggMirrorModel.name
#: (relative step of the scan's log grid, fringes averaged below this fraction of lambda).
SETTINGS = ((design.SCAN_RELATIVE_STEP, design.SCAN_SMOOTH), (0.005, 0.003), (0.002, 0.003), (0.001, 0.001))


def misses(path: Path) -> list[int]:
    """The round trip's mirrors whose median ΔE2000 is above 1."""
    found = []
    for line in path.read_text(encoding="utf-8").splitlines():
        match = re.match(r"\s*(\d+)\s.*median ΔE2000 ([0-9.]+),", line)
        if match and float(match.group(2)) > 1.0:
            found.append(int(match.group(1)))
    return found


def round_trip_truths(count: int) -> tuple[dict, design.DesignModel, list[dict]]:
    """The mirror's ranges and model, and the round trip's first ``count`` true structures (seed 0)."""
    ranges = ranges_of(load_material(material_path(MIRROR)))
    rng = np.random.default_rng(0)
    truths = [design.random_structure(MIRROR, ranges, rng) for _ in range(count)]
    return ranges, design.design_model(MIRROR), truths


def round_trip_misses() -> tuple[dict, design.DesignModel, list[int], list[dict]]:
    """The mirror's ranges and model, the round trip's misses, and its true structures (seed 0) up to the last."""
    indices = misses(SOURCE_ROOT / "docs" / "design_round_trip.txt")
    ranges, model, truths = round_trip_truths(max(indices) + 1)
    return ranges, model, indices, truths


def truth_targets(truth: dict) -> list[design.Target]:
    """A true structure's converged colours at the round trip's angles, as targets."""
    colours = design.forward_rgb(MIRROR, truth, design.ROUND_TRIP_ANGLES)
    return [design.Target(float(a), tuple(float(c) for c in rgb)) for a, rgb in zip(design.ROUND_TRIP_ANGLES, colours)]


def truth_problem(model: design.DesignModel, ranges: dict, truth: dict) -> search._Problem:
    """The design problem (every parameter free over ``ranges``) whose targets are ``truth``'s colours."""
    return search._Problem(model, design.parameter_box(model, ranges), {}, truth_targets(truth), None)


def main() -> None:
    ranges, model, indices, truths = round_trip_misses()
    header = " | ".join(f"step {100 * step:g} %, averaged below {100 * smooth:g} %" for step, smooth in SETTINGS)
    print(f"| mirror | N | Λ (nm) | {header} |")
    print("|---|---|---|" + "---|" * len(SETTINGS))
    for index in indices:
        truth = truths[index]
        problem = truth_problem(model, ranges, truth)
        shape = problem.unit_row(truth)[None]
        scores = [problem.scale_scan(shape, relative_step=step, smooth_relative=smooth)[0].min() for step, smooth in SETTINGS]
        print(f"| {index} | {truth['N']:.0f} | {truth['Lambda']:.0f} | " + " | ".join(f"{s:.1f}" for s in scores) + " |")


if __name__ == "__main__":
    main()
