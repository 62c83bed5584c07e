"""
docs/figures/paint_example.png: the worked example of docs/paint.md. A 64 x 64 image of 8 painted regions at 0 and
45 degrees (each the colours of a random mirror, :func:`explorer.bench.paint.region_maps`) designed back on a local
Dask cluster: the targets, the maps, the colours the maps show and the CIEDE2000 maps, with the time per stage.

    .venv/bin/python -m explorer.dev.paint_figure [--workers 2] [--size 64]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path


#: Run from the checkout's root, as the other figures' commands.
OUT = Path("docs/figures/paint_example.png")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from distributed import Client

    from explorer.bench.paint import ANGLES, ROUND_TRIP_BOX, _targets, region_maps
    from explorer.design import ranges_of
    from explorer.design.paint import local_cluster, paint
    from explorer.views.maps import map_colours
    from explorer.views.tonemap import display_srgb8

    from explorer.materials.brd import load_material
    from explorer.materials.models import BraggMirrorModel
    from explorer.materials.twins import shipped_file

    material = load_material(shipped_file(BraggMirrorModel))
    defaults = material.resolve({})
    fixed = {name: float(defaults[name]) for name in ("n1", "n2", "nh")}
    maps = region_maps(args.size, 8, args.seed, ROUND_TRIP_BOX)
    targets = _targets(material.model, fixed, maps)
    start = time.perf_counter()
    cluster = local_cluster(args.workers)
    client = Client(cluster)
    up = time.perf_counter() - start
    try:
        result = paint(material.model, ranges_of(material), fixed, targets, seed=args.seed, client=client, progress=print)
    finally:
        client.close()
        cluster.close()
    again = [map_colours(material.model, result.fixed, result.maps, a) for a in ANGLES]
    figure, axes = plt.subplots(2, 5, figsize=(15, 6.4))
    for row, theta in enumerate(ANGLES):
        axes[row, 0].imshow(display_srgb8(targets.rgb[row], 1.0, "none"))
        axes[row, 0].set_title(f"target, {theta:g}°")
        axes[row, 1].imshow(display_srgb8(again[row], 1.0, "none"))
        axes[row, 1].set_title(f"the maps' colours, {theta:g}°")
        shown = axes[row, 2].imshow(result.delta_e[row], vmin=0.0, vmax=2.0, cmap="magma")
        axes[row, 2].set_title(f"ΔE2000, {theta:g}°")
        figure.colorbar(shown, ax=axes[row, 2], fraction=0.046)
    for k, name in enumerate(result.maps):
        ax = axes.flat[3 + k if k < 2 else 8 + (k - 2)]
        shown = ax.imshow(result.maps[name], cmap="viridis")
        ax.set_title({"Lambda": "Λ (nm)", "delta": "δ", "N": "N"}.get(name, name))
        figure.colorbar(shown, ax=ax, fraction=0.046)
    if len(result.maps) < 3:
        axes.flat[9].axis("off")
    for ax in axes.flat:
        ax.set_xticks([])
        ax.set_yticks([])
    stages = ", ".join(f"{k} {v:.1f} s" for k, v in result.stages.items())
    figure.suptitle(f"{args.size}x{args.size}, 8 regions, {args.workers} workers (start {up:.1f} s): {stages}", fontsize=9)
    figure.tight_layout()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(OUT, dpi=80)
    print(f"wrote {OUT}")
    print(result.report(ANGLES))


if __name__ == "__main__":
    main()
