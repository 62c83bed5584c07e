"""
``bragg-explorer design MATERIAL --target-image IMG [--target-image-2 IMG2] --out-maps DIR``: parsing, the Dask
cluster and the report of :func:`explorer.design.paint.paint` (registered on :mod:`explorer.cli.design`).
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import click
import numpy as np

PROG = "bragg-explorer"


def _fail(message: str) -> None:
    click.echo(f"{PROG}: error: {message}", err=True)
    sys.exit(1)


def parse_angles(text: str, images: int) -> tuple[float, ...]:
    try:
        angles = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise click.UsageError(f"--angles {text!r}: expected degrees, e.g. 0,45") from None
    if len(angles) < images:
        raise click.UsageError(f"--angles {text!r}: {images} target images need {images} angles")
    for a in angles:
        if not (np.isfinite(a) and 0.0 <= a < 90.0):
            raise click.UsageError(f"--angles {text!r}: each angle in [0, 90) degrees")
    return angles[:images] if images > 1 else angles[:1]


def read_targets(image: str, image_2: str | None, angles: tuple[float, ...]):
    """The :class:`explorer.design.paint.PaintTargets` of one or two images; a one-line error for a bad file or sizes."""
    from explorer.design.paint import PaintTargets
    from explorer.views.maps import read_target_image

    paths = [image] + ([image_2] if image_2 else [])
    read = []
    for option, path in zip(("--target-image", "--target-image-2"), paths):
        try:
            read.append(read_target_image(path))
        except (ValueError, OSError) as error:
            _fail(f"{option} {' '.join(str(error).split())[:200]}")
    if len(read) == 2 and read[0][0].shape != read[1][0].shape:
        (h1, w1), (h2, w2) = read[0][0].shape[:2], read[1][0].shape[:2]
        _fail(f"--target-image-2 {image_2}: {w2}x{h2} pixels, but --target-image {image} has {w1}x{h1}: the two targets must match")
    mask = np.logical_and.reduce([m for _, _, m in read])
    return PaintTargets(angles, np.stack([r for r, _, _ in read]), np.stack([c for _, c, _ in read]), mask)


def start_client(workers: int | None, scheduler: str | None):
    """A ``distributed.Client``: on ``scheduler``'s cluster, or on a local cluster of ``workers`` processes (one thread each)."""
    try:
        from distributed import Client

        from explorer.design.paint import local_cluster
    except ImportError:
        _fail("painting needs Dask: pip install 'bragg-explorer[paint]' (python3 -m explorer installs it)")
    import importlib.util
    import logging

    logging.getLogger("distributed").setLevel(logging.ERROR)
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as error:
            _fail(f"--scheduler {scheduler}: cannot connect ({' '.join(str(error).split())[:160]})")
        return client, None
    dashboard = ":0" if importlib.util.find_spec("bokeh") is not None else None
    cluster = local_cluster(workers or os.cpu_count() or 1, dashboard)
    return Client(cluster), cluster


def paint_command(loaded, fixed: dict, image: str, image_2: str | None, angles_text: str | None, out_maps: str,
                  workers: int | None, scheduler: str | None, seed: int, as_json: bool, tries: int | None = None) -> None:
    """What ``design --target-image`` runs for a loaded material and its fixed values; ``tries``: each cluster's searches (default :data:`explorer.design.paint.CLUSTER_TRIES`)."""
    from explorer.design import DesignError, ranges_of
    from explorer.design.paint import CLUSTER_TRIES, paint
    from explorer.views.maps import write_maps
    from explorer.errors import OutputError
    from explorer.resources import display_path

    if workers is not None and scheduler is not None:
        raise click.UsageError("--workers starts a local cluster; --scheduler uses an existing one: give one of them")
    angles = parse_angles(angles_text or ("0,45" if image_2 else "0"), 2 if image_2 else 1)
    targets = read_targets(image, image_2, angles)
    out = Path(out_maps)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        _fail(f"--out-maps {out_maps}: cannot create the folder ({error.strerror or error})")
    start = time.perf_counter()
    say = lambda message: click.echo(f"{PROG} paint: {message}", err=True)
    client, cluster = start_client(workers, scheduler)
    try:
        started = time.perf_counter() - start
        workers_up = len(client.scheduler_info().get("workers", {}))
        link = getattr(client, "dashboard_link", None) if (cluster is None or cluster.dashboard_link) else None
        say(f"{workers_up} Dask workers ({'at ' + scheduler if scheduler else 'local'}) up in {started:.1f} s"
            + (f"; dashboard {link}" if link else "; no dashboard (install bokeh for one)"))
        result = paint(loaded.model, ranges_of(loaded), fixed, targets, seed=seed, client=client, cache=out / "cache", progress=say,
                       tries=tries or CLUSTER_TRIES)
    except DesignError as error:
        _fail(str(error))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    result.stages = {"cluster start": started, **result.stages}
    try:
        write_maps(result, out, display_path(loaded.path), loaded.model, angles, seed)
    except OutputError as error:
        _fail(str(error))
    report = result.report(angles)
    if as_json:
        click.echo(json.dumps(report, indent=2))
        return
    for theta, row in report["delta_e2000"].items():
        if row["median"] is not None:
            click.echo(f"theta {theta}: ΔE2000 median {row['median']:.2f}, p95 {row['p95']:.2f}, "
                       f"{100 * row['within_1']:.0f} % within 1")
    click.echo(f"{report['pixels']} pixels, {report['colours']} colours in {report['clusters']} clusters, "
               f"{report['unreachable_pixels']} unreachable (flagged in unreachable.png)")
    click.echo("time: " + ", ".join(f"{k} {v:.1f} s" for k, v in result.stages.items()) + f"; total {time.perf_counter() - start:.1f} s")
    click.echo(f"maps: {out}/ ({', '.join(f'{n}.exr' for n in result.maps)}, params.json, report.json)")


def render_maps_command(material: str | None, maps: str, view: str, theta: float | None, out: str, engine: str, exposure: str | None,
                        assignments=()) -> None:
    """
    ``render MATERIAL --maps DIR --view textured --theta DEG``: the maps' colours at one angle, one pixel a texel. ``--engine
    numpy``: each texel's converged spectral colour (the design's forward model, what the round trip measures); ``--engine
    gl``: by the material's method (``--set method=N``; the flat textured view, twin of :func:`explorer.views.maps.flat_numpy`).
    """
    from explorer.design import DesignError, design_model
    from explorer.views.maps import read_maps
    from explorer.materials.brd import load_material
    from explorer.resources import material_path
    from explorer.errors import LocatedError, OutputError
    from explorer.views.images import write_image
    from explorer.views.maps import map_colours

    if view != "textured":
        raise click.UsageError(f"--maps with --theta renders the textured view flat (the maps' colours at --theta), not {view}")
    if engine not in ("numpy", "gl"):
        raise click.UsageError("--maps with --theta renders with --engine numpy (each texel's converged spectral colour) or gl "
                               "(by the material's method)")
    try:
        exposure_factor = 1.0 if exposure is None else float(exposure)
    except ValueError:
        raise click.UsageError(f"--exposure {exposure!r}: with --maps, a number") from None
    theta = 0.0 if theta is None else theta
    if not (np.isfinite(theta) and 0.0 <= theta < 90.0):
        raise click.UsageError(f"--theta {theta:g}: degrees in [0, 90)")
    try:
        params, arrays = read_maps(maps)
    except ValueError as error:
        _fail(str(error))
    try:
        loaded = load_material(material_path(material or params.get("material", "")))
        model = design_model(loaded.model)
    except (LocatedError, DesignError) as error:
        _fail(str(error))
    if model.name != params.get("model"):
        _fail(f"--maps {maps}: maps of a {params.get('model')}, not of {model.name} ({material})")
    if engine == "gl":
        from explorer.cli.materials import resolve_values
        from explorer.gpu import Renderer
        from explorer.views.maps import flat_gl
        from explorer.views.surface_texture import MapTexture

        try:
            texture, values = MapTexture.from_folder(maps, loaded, resolve_values(loaded, None, None, assignments))
            image = flat_gl(Renderer(), loaded, loaded.resolve(values), texture, theta)
        except LocatedError as error:
            _fail(str(error))
    else:
        image = map_colours(model.name, params.get("fixed", {}), arrays, theta)
    try:
        write_image(image, Path(out), exposure=exposure_factor)
    except OutputError as error:
        _fail(str(error))
    how = "by the material's method, gl" if engine == "gl" else "converged spectral colours, numpy"
    click.echo(f"wrote {out} ({image.shape[1]}x{image.shape[0]}, the maps' colours at {theta:g} degrees; {how})")
