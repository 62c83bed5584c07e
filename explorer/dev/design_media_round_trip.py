"""
The colour design's round trip with media: seeded random natural mirrors, their exact colours
(:func:`explorer.physics.natural.natural_rgb`) at the round trip's angles as targets, designed back with the
media fixed (``design --fix n2=chitin``) and the rest free. ``python3 -m explorer.dev.design_media_round_trip
[--count 10] [--tries 1] [--case chitin|melanin]`` prints one row per mirror and the share within ΔE2000 1.

- chitin: air layers (n1 = 1, fixed) and chitin, in air; Lambda 120-400 nm, delta 0.2-0.8, N 3-15 free.
- melanin: keratin over melanin (k ~ 0.15-0.4), in air; Lambda 120-300 nm, delta 0.2-0.8, N 2-10 free.
"""

from __future__ import annotations

import argparse

import numpy as np

from explorer import design
from explorer.design.media import mirror_with_media
from explorer.materials.models import BraggMirrorModel
from explorer.physics.dispersion import LIBRARY
from explorer.physics.natural import natural_rgb

#: The mirrors' media, their fixed numbers and the draws of the free values.
CASES = {
    "chitin": ({"n2": "chitin"}, {"n1": 1.0, "nh": 0.0}, {"Lambda": (120.0, 400.0), "delta": (0.2, 0.8), "N": (3, 15)}),
    "melanin": ({"n1": "keratin", "n2": "melanin"}, {"nh": 0.0}, {"Lambda": (120.0, 300.0), "delta": (0.2, 0.8), "N": (2, 10)}),
}
RANGES = dict(n1=(1, 2.5), n2=(1, 2.5), Lambda=(50, 1500), delta=(0, 1), N=(1, 1000), nh=(0, 2.5), k1=(0, 1), k2=(0, 1),
              sigma=(0, 0.3))


def round_trip(case: str, count: int, tries: int, seed: int = 0):
    """Per mirror ``(truth, result)``: each designed back from its colours with the case's media fixed."""
    names, numbers, draws = CASES[case]
    media = {k: LIBRARY[v] for k, v in names.items()}
    rng = np.random.default_rng(seed)
    rows = []
    for k in range(count):
        truth = {**numbers, "Lambda": float(rng.uniform(*draws["Lambda"])), "delta": float(rng.uniform(*draws["delta"])),
                 "N": int(rng.integers(draws["N"][0], draws["N"][1] + 1))}
        for name in media:
            truth[name] = 0.0
        colours = natural_rgb(np.cos(np.radians(design.ROUND_TRIP_ANGLES)), mirror_with_media(truth, media))
        targets = [design.Target(a, tuple(float(c) for c in rgb)) for a, rgb in zip(design.ROUND_TRIP_ANGLES, colours)]
        result = design.design(BraggMirrorModel.name, targets, RANGES, dict(numbers), seed=seed + k, tries=tries, media=media)
        rows.append((truth, result))
        yield truth, result


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--count", type=int, default=10)
    parser.add_argument("--tries", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--case", choices=sorted(CASES), default="chitin")
    args = parser.parse_args(argv)
    worst = []
    for k, (truth, result) in enumerate(round_trip(args.case, args.count, args.tries, args.seed)):
        worst.append(float(result.delta_e2000.max()))
        found = " ".join(f"{n}={v:.4g}" if isinstance(v, float) else f"{n}={v}" for n, v in result.values.items())
        print(f"{k:2d} Lambda={truth['Lambda']:.1f} delta={truth['delta']:.3f} N={truth['N']} -> {found}: "
              f"max ΔE2000 {worst[-1]:.3f}, {result.seconds:.1f} s, {result.tries} tries", flush=True)
    worst = np.array(worst)
    print(f"{args.case}: {int(np.sum(worst <= 1.0))} of {worst.size} within ΔE2000 1 at every angle "
          f"(median of the max {np.median(worst):.3f}), tries {args.tries}")


if __name__ == "__main__":
    main()
