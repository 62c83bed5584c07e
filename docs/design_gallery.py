"""
The gallery of docs/design.md: five beetle- and butterfly-like colour gradients, each designed back by
``bragg-explorer design`` (explorer.physics.design), printed as the Markdown table the docs show.

    .venv/bin/python docs/design_gallery.py

Targets 1-3 are the colours, at 0-60 degrees, of the jewel-beetle cuticle structures of Fourneau et al.
(2024) Table 3 (smooth, in air); 4 and 5 are our qualitative renditions of published descriptions (the
colours are ours, not measured values).
"""

from __future__ import annotations

import numpy as np

from explorer.cli.commands import _load
from explorer.cli.design import parse_colour, ranges_of
from explorer.physics import design

ANGLES = (0.0, 15.0, 30.0, 45.0, 60.0)


def table3(n1, n2, Lambda, delta, N):
    structure = dict(n1=n1, n2=n2, Lambda=Lambda, delta=delta, N=N, nh=1.0)
    return [design.Target(a, tuple(c)) for a, c in zip(ANGLES, design.forward_rgb("bragg_mirror", structure, ANGLES))]


def qualitative(pairs):
    return [design.Target(theta, tuple(parse_colour(colour))) for theta, colour in pairs]


GALLERY = [
    ("Jewel beetle (Chrysochroa), green/blue area: Table 3 (a) in air", "bragg_mirror",
     table3(1.59, 1.67, 160.0, 0.51, 8), {"nh": 1.0}),
    ("Jewel beetle, red area: Table 3 (b) in air", "bragg_mirror", table3(1.60, 1.68, 190.0, 0.51, 8), {"nh": 1.0}),
    ("Jewel beetle, purple area: Table 3 (c) in air", "bragg_mirror", table3(1.60, 1.68, 205.0, 0.51, 6), {"nh": 1.0}),
    ("Morpho-like blue turning violet (air-chitin lamellae; qualitative)", "bragg_mirror",
     qualitative([(0.0, "#2a7fd8"), (20.0, "#2f6fd0"), (40.0, "#3a4fc0"), (60.0, "#4a3aa0")]), {"n1": 1.0, "nh": 0.0}),
    ("Insect-wing film, magenta turning blue-green (chitin membrane in air; qualitative)", "thin_film",
     qualitative([(0.0, "#b0308a"), (30.0, "#6a3aa8"), (60.0, "#2a7a9a")]), {"eta1": 1.0, "eta3": 1.0, "kappa3": 0.0}),
]


def main() -> None:
    print("| target | designed structure | ΔE2000 per target | time |")
    print("|---|---|---|---|")
    for title, material, targets, fixed in GALLERY:
        result = design.design(material, targets, ranges_of(_load(material)), fixed)
        values = ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}" for k, v in result.values.items())
        errors = ", ".join(f"{t.theta_deg:g}°: {d:.2f}" for t, d in zip(targets, result.delta_e2000))
        flag = "" if result.reachable.all() else " (not reachable)"
        print(f"| {title} | {material}: {values} | {errors}{flag} | {result.seconds:.1f} s ({result.cpu_seconds:.1f} s CPU) |",
              flush=True)


if __name__ == "__main__":
    main()
