"""
``bench --paint``: painting with structural colour, timed (:mod:`explorer.design.paint`).

1. The round trip: smooth random maps of ``Lambda``, ``delta`` and ``N`` (:data:`ROUND_TRIP_BOX`) rendered at 0 and
   45 degrees as ``render --maps --view textured`` renders them (:func:`explorer.views.maps.map_colours`), designed
   back on a local Dask cluster, the designed maps rendered again: the share of pixels within CIEDE2000 1 of the
   targets at both angles, and the time.
2. A 256 x 256 image of 8 painted regions (each the colours of a random mirror in the box at 0 and 45 degrees).

A benchmark prints numbers; the measurements in docs/paint.md come from it.
"""

from __future__ import annotations

import json
import os
import time

import click
import numpy as np

#: The round trip's box (the material's other values at its defaults: n1 = 1, n2 = 1.5, no host).
ROUND_TRIP_BOX = {"Lambda": (150.0, 320.0), "delta": (0.3, 0.7), "N": (6.0, 30.0)}
ANGLES = (0.0, 45.0)
#: The smooth fields' correlation length, as a share of the image's side.
SMOOTHNESS = 0.15


def smooth_random_maps(size: int, seed: int, box=ROUND_TRIP_BOX) -> dict[str, np.ndarray]:
    """Gaussian-filtered noise per parameter, stretched over its box (``N`` whole): smooth random structure maps."""
    from scipy.ndimage import gaussian_filter

    rng = np.random.default_rng(seed)
    maps = {}
    for name, (low, high) in box.items():
        field = gaussian_filter(rng.normal(size=(size, size)), SMOOTHNESS * size, mode="wrap")
        field = (field - field.min()) / max(field.max() - field.min(), 1e-12)
        value = low + field * (high - low)
        maps[name] = np.round(value) if name == "N" else value
    return maps


def region_maps(size: int, regions: int, seed: int, box=ROUND_TRIP_BOX) -> dict[str, np.ndarray]:
    """``regions`` Voronoi regions, each one random structure of the box."""
    rng = np.random.default_rng(seed)
    centres = rng.random((regions, 2)) * size
    y, x = np.mgrid[0:size, 0:size] + 0.5
    label = np.argmin((x[..., None] - centres[:, 0]) ** 2 + (y[..., None] - centres[:, 1]) ** 2, axis=-1)
    maps = {}
    for name, (low, high) in box.items():
        values = low + rng.random(regions) * (high - low)
        maps[name] = (np.round(values) if name == "N" else values)[label]
    return maps


def _targets(model_name, fixed, maps):
    from explorer.design.paint import PaintTargets
    from explorer.views.maps import map_colours

    rgb = np.stack([map_colours(model_name, fixed, maps, a) for a in ANGLES]).astype(np.float64)
    shape = rgb.shape[1:3]
    return PaintTargets(ANGLES, rgb, np.zeros(rgb.shape, np.int8), np.ones(shape, bool))


def _run(name, model_name, ranges, fixed, maps, client, seed, rows, workers):
    from explorer.design.paint import paint
    from explorer.physics.colorimetry import delta_E_2000
    from explorer.views.maps import map_colours

    start = time.perf_counter()
    targets = _targets(model_name, fixed, maps)
    rendered = time.perf_counter() - start
    load_before = os.getloadavg()[0]
    cpu_before = _cpu_seconds(client)
    start = time.perf_counter()
    result = paint(model_name, ranges, fixed, targets, seed=seed, client=client,
                   progress=lambda message: click.echo(f"bench --paint: {name}, {workers} worker(s): {message}", err=True))
    painted = time.perf_counter() - start
    cpu = _cpu_seconds(client) - cpu_before
    start = time.perf_counter()
    again = np.stack([map_colours(model_name, result.fixed, result.maps, a) for a in ANGLES]).astype(np.float64)
    rerendered = time.perf_counter() - start
    delta = delta_E_2000(again, targets.rgb)  # (A, H, W)
    within = float(np.mean(np.all(delta <= 1.0, axis=0)))
    row = {"image": name, "workers": workers, "size": list(delta.shape[1:]), "colours": result.colours, "clusters": result.clusters,
           "within_1_both_angles": within, "median": [float(np.median(d)) for d in delta],
           "p95": [float(np.percentile(d, 95)) for d in delta], "unreachable_pixels": int(result.unreachable.sum()),
           "render_seconds": rendered, "paint_seconds": painted, "paint_cpu_seconds": cpu, "rerender_seconds": rerendered,
           "load_average": [load_before, os.getloadavg()[0]], "stages": result.stages,
           "task_seconds": result.task_seconds, "critical_path_seconds": result.critical_path,
           "total_variation": {k: total_variation(v) for k, v in result.maps.items()},
           "target_total_variation": {k: total_variation(v) for k, v in maps.items() if k in result.maps}}
    rows.append(row)
    return row, result


def _cpu_seconds(client) -> float:
    """CPU seconds used so far by this process and the cluster's workers."""
    import resource

    def used():
        usage = resource.getrusage(resource.RUSAGE_SELF)
        return usage.ru_utime + usage.ru_stime

    return used() + float(sum(client.run(used).values()))


def total_variation(image: np.ndarray) -> float:
    """Mean absolute difference between 4-neighbours (finite pixels), relative to the map's range."""
    finite = np.isfinite(image)
    span = float(np.nanmax(image) - np.nanmin(image)) if finite.any() else 0.0
    diffs = [np.abs(np.diff(image, axis=a))[np.isfinite(np.diff(image, axis=a))] for a in (0, 1)]
    values = np.concatenate(diffs)
    return float(values.mean() / span) if values.size and span > 0 else 0.0


#: The per-pixel-independent designs: this many consecutive pixels of the round trip's middle row.
INDEPENDENT_PIXELS = 12


def line_variation(values: np.ndarray, span: float) -> float:
    """Mean absolute difference between consecutive pixels of a line, relative to ``span``."""
    return float(np.mean(np.abs(np.diff(values))) / span)


def independent_line(model_name, ranges, fixed, targets, result, maps, client, seed) -> dict:
    """
    The maps' smoothness against a per-pixel-independent design: :data:`INDEPENDENT_PIXELS` consecutive pixels of the
    middle row, each designed on its own (``design``'s full search, as Dask tasks), and the variation along that
    line of the painted maps, of the independent designs and of the maps the targets were rendered from (each
    relative to the parameter's span in :data:`ROUND_TRIP_BOX`).
    """
    from explorer.design.paint import design_task

    H, W = targets.rgb.shape[1:3]
    y, x0 = H // 2, (W - INDEPENDENT_PIXELS) // 2
    columns = range(x0, x0 + INDEPENDENT_PIXELS)
    futures = [client.submit(design_task, model_name, dict(ranges), fixed, ANGLES, targets.rgb[:, y, x], targets.bounds[:, y, x], seed, 1,
                             pure=False) for x in columns]
    start = time.perf_counter()
    designs = client.gather(futures)
    seconds = time.perf_counter() - start
    out = {"pixels": INDEPENDENT_PIXELS, "row": y, "seconds": seconds,
           "independent_within_1": float(np.mean([max(d["delta_e"]) <= 1.0 for d in designs]))}
    for name in result.maps:
        low, high = ROUND_TRIP_BOX[name]
        out[name] = {"painted": line_variation(result.maps[name][y, x0 : x0 + INDEPENDENT_PIXELS], high - low),
                     "independent": line_variation(np.array([d["values"][name] for d in designs]), high - low),
                     "target": line_variation(maps[name][y, x0 : x0 + INDEPENDENT_PIXELS], high - low)}
    return out


def run_paint_bench(workers: int = 2, seed: int = 0, size: int = 64, as_json: bool = False, regions_size: int = 256) -> None:
    """
    The round trip at ``size`` and the 256 x 256 8-region image on a local cluster of 1 worker, then of ``workers``;
    with the most workers, the smoothness against per-pixel-independent designs.
    """
    from distributed import Client

    from explorer.design import ranges_of
    from explorer.design.paint import local_cluster
    from explorer.design.forward import design_model
    from explorer.materials.brd import load_material
    from explorer.materials.models import BraggMirrorModel
    from explorer.materials.twins import shipped_file

    material = load_material(shipped_file(BraggMirrorModel))
    model = design_model(material.model)
    defaults = material.resolve({})
    fixed = {name: float(defaults[name]) for name in model.parameters if name not in ROUND_TRIP_BOX}
    ranges = ranges_of(material)
    images = ((f"round trip {size}x{size}", smooth_random_maps(size, seed)), (f"8 regions {regions_size}x{regions_size}", region_maps(regions_size, 8, seed)))
    rows: list[dict] = []
    lines = {}
    for count in sorted({1, workers}, reverse=True):  # the most workers first: the headline numbers
        start = time.perf_counter()
        cluster = local_cluster(count)
        client = Client(cluster)
        up = time.perf_counter() - start
        try:
            for k, (name, maps) in enumerate(images):
                row, result = _run(name, model.name, ranges, fixed, maps, client, seed, rows, count)
                row["cluster_start_seconds"] = up
                if not as_json:
                    _say(row)
                if k == 0 and count == max(1, workers):
                    lines = independent_line(model.name, ranges, fixed, _targets(model.name, fixed, maps), result, maps, client, seed)
                    if not as_json:
                        _say_line(lines)
        finally:
            client.close()
            cluster.close()
    if as_json:
        click.echo(json.dumps({"workers": sorted({1, workers}), "cores": os.cpu_count(), "runs": rows, "independent_line": lines}, indent=2))


def _say(row: dict) -> None:
    click.echo(f"{row['image']}, {row['workers']} worker(s): {100 * row['within_1_both_angles']:.1f} % of pixels within ΔE2000 1 at 0 and 45 "
               f"degrees (median {row['median'][0]:.2f} / {row['median'][1]:.2f}, p95 {row['p95'][0]:.2f} / {row['p95'][1]:.2f}); "
               f"{row['colours']} colours, {row['clusters']} clusters, {row['unreachable_pixels']} unreachable")
    click.echo(f"  design {row['paint_seconds']:.1f} s wall, {row['paint_cpu_seconds']:.1f} s CPU (cluster start {row['cluster_start_seconds']:.1f} s; "
               f"target render {row['render_seconds']:.1f} s, re-render {row['rerender_seconds']:.1f} s); load average "
               f"{row['load_average'][0]:.1f} -> {row['load_average'][1]:.1f} on {os.cpu_count()} cores")
    click.echo("  stages: " + ", ".join(f"{k} {v:.1f} s" for k, v in row["stages"].items())
               + f"; task time {row['task_seconds']:.1f} s, critical path {row['critical_path_seconds']:.1f} s")
    click.echo("  total variation (mean neighbour step / map range): "
               + ", ".join(f"{k} {v:.4f} (target's {row['target_total_variation'].get(k, float('nan')):.4f})"
                           for k, v in row["total_variation"].items()))


def _say_line(line: dict) -> None:
    click.echo(f"  smoothness along {line['pixels']} pixels of row {line['row']} (mean step / the box's span), painted against "
               f"per-pixel-independent designs ({line['seconds']:.1f} s; {100 * line['independent_within_1']:.0f} % of them within 1):")
    for name in ROUND_TRIP_BOX:
        if name in line:
            v = line[name]
            click.echo(f"    {name}: painted {v['painted']:.4f}, independent {v['independent']:.4f}, target maps {v['target']:.4f}")
