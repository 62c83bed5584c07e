"""
The gallery of docs/design.md: five beetle- and butterfly-like colour gradients, each designed back by
``bragg-explorer design`` (explorer.design), printed as the Markdown table the docs show.

    .venv/bin/python -m explorer.dev.design_gallery

Each target is the converged colour, at 0, 15, 30, 45 and 60 degrees, of a structure: 1-3 the jewel-beetle
cuticle areas of Fourneau et al. (2024) Table 3 (smooth, in air), 4 and 5 illustrative structures of the
kinds published for Morpho scales and insect wings (our values, not measured ones). Only the colours go
to the design; it does not see the structure.
"""

from __future__ import annotations

from explorer import design
from explorer.design import ranges_of
from explorer.materials.brd import load_material
from explorer.materials.models import BraggMirrorModel
from explorer.materials.thinfilm_model import ThinFilmModel
from explorer.resources import material_path

MIRROR, FILM = BraggMirrorModel.name, ThinFilmModel.name
ANGLES = (0.0, 15.0, 30.0, 45.0, 60.0)


def table3(n1, n2, Lambda, delta, N):
    structure = dict(n1=n1, n2=n2, Lambda=Lambda, delta=delta, N=N, nh=1.0)
    return [design.Target(a, tuple(c)) for a, c in zip(ANGLES, design.forward_rgb(MIRROR, structure, ANGLES))]


def of_structure(material, structure):
    return [design.Target(a, tuple(c)) for a, c in zip(ANGLES, design.forward_rgb(material, structure, ANGLES))]


GALLERY = [
    ("Jewel beetle (Chrysochroa), green/blue area: Table 3 (a) in air", MIRROR,
     table3(1.59, 1.67, 160.0, 0.51, 8), {"nh": 1.0}),
    ("Jewel beetle, red area: Table 3 (b) in air", MIRROR, table3(1.60, 1.68, 190.0, 0.51, 8), {"nh": 1.0}),
    ("Jewel beetle, purple area: Table 3 (c) in air", MIRROR, table3(1.60, 1.68, 205.0, 0.51, 6), {"nh": 1.0}),
    ("Morpho-like lamellae: chitin (1.56) 80 nm, air 110 nm, N = 8 (illustrative values)", MIRROR,
     of_structure(MIRROR, dict(n1=1.0, n2=1.56, Lambda=190.0, delta=110.0 / 190.0, N=8, nh=0.0)), {"n1": 1.0, "nh": 0.0}),
    ("Insect-wing membrane: chitin (1.57) film of 350 nm in air (illustrative values)", FILM,
     of_structure(FILM, dict(d=350.0, eta1=1.0, eta2=1.57, eta3=1.0, kappa3=0.0)), {"eta1": 1.0, "eta3": 1.0, "kappa3": 0.0}),
]


def main() -> None:
    print("| target | designed structure | ΔE2000 at 0, 15, 30, 45, 60° | time |")
    print("|---|---|---|---|")
    for title, material, targets, fixed in GALLERY:
        result = design.design(material, targets, ranges_of(load_material(material_path(material))), fixed)
        values = ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}" for k, v in result.values.items())
        errors = ", ".join(f"{d:.2f}" for d in result.delta_e2000)
        flag = "" if result.reachable.all() else " (not reachable)"
        print(f"| {title} | {material}: {values} | {errors}{flag} | {result.seconds:.1f} s ({result.cpu_seconds:.1f} s CPU) |",
              flush=True)


if __name__ == "__main__":
    main()
