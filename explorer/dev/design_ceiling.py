"""
What the design reaches when the first pass already holds the answer (docs/design.md, "Where it fails"):
the round trip's 50 mirrors (seed 0, as ``bench --design 50``), each designed with its true structure
among the first pass's shapes (``design(..., guesses=[truth])``). The share within ΔE2000 1 is the ceiling
of everything after the first pass: the descent, the refinements, the choice of candidates, the polish.

    .venv/bin/python -m explorer.dev.design_ceiling       # ~4 minutes; prints a line per mirror, then the summary
"""

from __future__ import annotations

import numpy as np

from explorer import design
from explorer.design import ranges_of
from explorer.dev.design_fidelity import truth_targets
from explorer.materials.brd import load_material
from explorer.materials.models import BraggMirrorModel
from explorer.resources import material_path

COUNT, SEED = 50, 0
MIRROR = BraggMirrorModel.name


def main() -> None:
    ranges = ranges_of(load_material(material_path(MIRROR)))
    rng = np.random.default_rng(SEED)
    medians = []
    for index in range(COUNT):
        truth = design.random_structure(MIRROR, ranges, rng)
        result = design.design(MIRROR, truth_targets(truth), ranges, seed=SEED + index, guesses=[truth])
        medians.append(result.median_delta_e2000)
        print(f"{index:3d}  median ΔE2000 {result.median_delta_e2000:.3f}, {result.seconds:.2f} s", flush=True)
    medians = np.array(medians)
    print(f"{COUNT} mirrors (seed {SEED}), the truth among the first pass's shapes: median of the medians "
          f"{np.median(medians):.3f}, {100 * np.mean(medians <= 1.0):.0f} % at most 1; misses: "
          + " ".join(str(k) for k in np.flatnonzero(medians > 1.0)))


if __name__ == "__main__":
    main()
