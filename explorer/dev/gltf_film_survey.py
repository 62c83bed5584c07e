"""
How close glTF's one film comes to a thin film on a dielectric (docs/export.md, the glTF section): seeded random
films over a box, each fitted as ``export --to gltf`` fits it (:func:`explorer.materials.gltf_film.refine_film`);
per film the direct mapping's and the written film's median ΔE2000 over every degree 0-89 (the written one also
with the base's F0 guarded as the Khronos sample viewer and three.js guard it) and the fit's CPU seconds, then the
distribution. ``--exhaustive`` also searches each film above 1 with a dense grid of the
formula's parameters (path difference, film index, factor, the base's F0 per channel) and Nelder-Mead from its
best points: how far the export's search is from the best the formula reaches.

    .venv/bin/python -m explorer.dev.gltf_film_survey              # 30 films, seed 0: ~5 CPU minutes
    .venv/bin/python -m explorer.dev.gltf_film_survey --exhaustive    # and a dense grid per film over 1: minutes each
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from explorer.materials import gltf_film
from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.materials.thinfilm_model import ThinFilmModel
from explorer.physics import colorimetry
from explorer.resources import material_path

#: The box the films are drawn from: thickness (nm), film index, base index.
BOX = {"d": (100.0, 1000.0), "eta2": (1.2, 2.4), "eta3": (1.3, 1.8)}
#: A film hard for the formula (its colour at normal incidence already off), always surveyed first.
KNOWN = {"d": 561.0, "eta2": 1.364, "eta3": 1.55}


def films(count: int, seed: int) -> list[dict]:
    rng = np.random.default_rng(seed)
    return [KNOWN] + [{k: float(rng.uniform(*span)) for k, span in BOX.items()} for _ in range(count - 1)]


def _as_params(x: np.ndarray) -> np.ndarray:
    """(``D_inc = 2 n d``, film index, factor, base F0 per channel) -> the dielectric's 7 parameters (base index 3,
    its F0 coloured down by the specular colour)."""
    f0_top = gltf_film._ior_to_f0(gltf_film.IOR_RANGE[1], 1.0)
    return np.column_stack([x[:, 0] / (2.0 * x[:, 1]), x[:, 1:3], np.full(len(x), gltf_film.IOR_RANGE[1]),
                            x[:, 3:6] / f0_top])


def exhaustive(film: gltf_film.Film, dense_lab: np.ndarray) -> tuple[float, np.ndarray]:
    """The least median ΔE2000 (every degree) found by a dense grid (``D_inc`` every 10 nm from 0 to 2.5 x the
    film's, film index 1.0-3.0 every 0.05, factor 0.2-1.0 every 0.2, a grey base F0 0-0.25 every 0.01; the median
    on every fifth degree), then Nelder-Mead on every degree, the F0 per channel, from its 12 best points."""
    from scipy.optimize import minimize

    own = 2.0 * film.ior * film.thickness
    axes = (np.arange(0.0, 2.5 * own + 10.0, 10.0), np.arange(1.0, 3.001, 0.05), np.arange(0.2, 1.001, 0.2),
            np.arange(0.0, 0.2501, 0.01))
    cos = np.cos(np.radians(gltf_film.DENSE_THETA_DEG))
    best, points = np.empty(0), np.empty((0, 6))
    for d in axes[0]:  # one path difference at a time: the grid is millions of films
        grid = np.stack(np.meshgrid([d], *axes[1:], indexing="ij"), axis=-1).reshape(-1, 4)
        grid = np.column_stack([grid, grid[:, 3], grid[:, 3]])
        cost = np.median(gltf_film._films_delta_e(_as_params(grid), False, dense_lab[::5], cos[::5]), axis=1)
        keep = np.argsort(cost)[:12]
        best, points = np.concatenate([best, cost[keep]]), np.vstack([points, grid[keep]])
        order = np.argsort(best)[:12]
        best, points = best[order], points[order]

    f0_cap = gltf_film._ior_to_f0(gltf_film.IOR_RANGE[1], 1.0) * gltf_film.SPECULAR_COLOR_MAX

    def inside(x):
        return np.clip(x, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0], [np.inf, 3.0, 1.0, f0_cap, f0_cap, f0_cap])

    def median(x):
        return float(np.median(gltf_film._films_delta_e(_as_params(inside(x)[None]), False, dense_lab, cos)))

    results = [minimize(median, x0, method="Nelder-Mead", options={"maxfev": 1200}) for x0 in points]
    result = min(results, key=lambda r: r.fun)
    return float(result.fun), inside(result.x)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--count", type=int, default=30)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--exhaustive", action="store_true")
    parser.add_argument("--film", action="append", metavar="D,ETA2,ETA3", help="survey this film instead (repeatable)")
    args = parser.parse_args()
    chosen = ([dict(zip(("d", "eta2", "eta3"), map(float, f.split(",")))) for f in args.film] if args.film
              else films(args.count, args.seed))
    material = load_material(material_path(ThinFilmModel.name))
    medians, seconds, viewer_medians = [], [], []
    for index, values in enumerate(chosen):
        model = model_for(material, material.resolve(values))
        dense_target = gltf_film.target_rgb(model, gltf_film.DENSE_THETA_DEG)
        direct = gltf_film.direct_film(model)
        direct_median = float(np.median(gltf_film.dense_delta_e(direct, dense_target)))
        start = time.process_time()
        written = gltf_film.refine_film(gltf_film.direct_film(model), dense_target)
        seconds.append(time.process_time() - start)
        e = gltf_film.dense_delta_e(written, dense_target)
        medians.append(float(np.median(e)))
        viewer = gltf_film.specular_reflectance(written, np.cos(np.radians(gltf_film.DENSE_THETA_DEG)), viewer_guard=True)
        viewer_medians.append(float(np.median(colorimetry.delta_E_2000(viewer, dense_target))))
        colour_ = ", ".join(f"{c:.2f}" for c in written.specular_color)
        line = (f"{index:3d}  d {values['d']:6.1f} nm, {values['eta2']:.3f} on {values['eta3']:.3f}: direct {direct_median:.2f}, "
                f"written {medians[-1]:.2f} (sample viewer {viewer_medians[-1]:.2f}; p95 {np.percentile(e, 95):.2f}; {written.thickness:.1f} nm, film {written.ior:.3f}, "
                f"factor {written.factor:.3f}, base {written.base_ior:.3f}, specular colour ({colour_})), "
                f"{seconds[-1]:.1f} CPU s")
        if args.exhaustive and medians[-1] > 1.0:
            best, x = exhaustive(direct, gltf_film._lab(dense_target))
            line += (f"; dense grid's best {best:.2f} (D_inc {x[0]:.0f} nm, film {x[1]:.3f}, factor {x[2]:.3f}, "
                     f"base F0 {x[3]:.3f}, {x[4]:.3f}, {x[5]:.3f})")
        print(line, flush=True)
    medians = np.array(medians)
    print(f"{len(medians)} films (seed {args.seed}; d {BOX['d']}, film {BOX['eta2']}, base {BOX['eta3']}): median of the medians "
          f"{np.median(medians):.2f}, worst {medians.max():.2f}, {np.mean(medians <= 1.0) * 100:.0f} % at most 1 "
          f"({np.sum(medians <= 1.0)} of {len(medians)}; read as the sample viewer reads the base's F0: "
          f"{np.sum(np.array(viewer_medians) <= 1.0)}, worst {max(viewer_medians):.2f}); CPU s per export: median {np.median(seconds):.1f}, max {np.max(seconds):.1f}")


if __name__ == "__main__":
    main()
