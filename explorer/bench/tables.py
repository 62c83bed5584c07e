"""
``bench --tables``: host table rebuilds and the tabulated method's per-pixel cost.
"""

from __future__ import annotations

import json
import time

import numpy as np

from explorer.bench.common import BENCH_LAMBDAS, _progress
from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.physics import bragg
from explorer.resources import SHADER_DIR
from explorer.materials.models import BraggMirrorModel, SchlickFresnelModel

# --------------------------------------------------------------------------------------------------
# bench --tables: host table rebuilds and the tabulated method's per-pixel cost

#: The mirror of the table timings (n1 = 1, n2 = 1.5, delta = 0.5) at Lambda = 500 nm, and its N values.
TABLES_MIRROR = {"n1": 1.0, "n2": 1.5, "Lambda": 500.0, "delta": 0.5}
TABLES_N = (20, 100, 1000)
#: Lambda offsets (nm) per repeat: each repeat is a new mirror, so the cached table is rebuilt, as when a
#: slider moves; small enough that the timed mirror is Lambda = 500 nm to 1e-3.
TABLES_LAMBDA_STEP = 1e-4


def _timed_ms(build) -> tuple[float, float]:
    """Wall-clock and CPU time (ms; the process's, all threads) of ``build()``."""
    start, cpu = time.perf_counter(), time.process_time()
    build()
    return 1e3 * (time.perf_counter() - start), 1e3 * (time.process_time() - cpu)


def _timed_frame(renderer, material, values, size: int) -> tuple[float, float]:
    """A sphere frame's finish-bounded wall-clock time and the CPU time around it (llvmpipe: the rendering)."""
    cpu = time.process_time()
    wall = renderer.time_frame(material, values, "sphere", size, size)
    return wall, 1e3 * (time.process_time() - cpu)


def _medians(times: dict) -> dict:
    """``{key: [(wall, cpu), ...]}`` -> ``{key: median wall}``, ``{key: median cpu}``."""
    return ({k: float(np.median([t[0] for t in v])) for k, v in times.items()},
            {k: float(np.median([t[1] for t in v])) for k, v in times.items()})


def table_timings(repeats: int = 5) -> dict:
    """
    Medians (ms) over ``repeats`` interleaved rounds, after a warm-up round, of rebuilding the tabulated
    method's converged table (:func:`explorer.physics.bragg.tabulated_rgb_table`, through its cache, as the
    app does) at each N of :data:`TABLES_N`, and of one rough layer's tables (Figure 7's layer A,
    :func:`explorer.physics.layered.layer_tables`, its ``F_alpha`` cached as in the app): Lambda moves by
    :data:`TABLES_LAMBDA_STEP` every round, so every round rebuilds. Wall-clock, and CPU time (``*_cpu_ms``:
    what the machine's other processes do not inflate).
    """
    from explorer.physics import layered

    layer, n1 = layered.figure7_layers()["A (n1=1, d1=d2=250 nm, N=10, alpha=0.1)"]
    F = layered.transmission_filter_for(layer.alpha)
    times: dict[str, list] = {str(N): [] for N in TABLES_N}
    times["layer"] = []
    for round_ in range(repeats + 1):
        Lambda = TABLES_MIRROR["Lambda"] + TABLES_LAMBDA_STEP * (round_ + 1)
        for N in TABLES_N:
            mirror = bragg.BraggMirror(**{**TABLES_MIRROR, "Lambda": Lambda}, N=N)
            measured = _timed_ms(lambda: bragg.tabulated_rgb_table(mirror))
            if round_:
                times[str(N)].append(measured)
        moved = layered.RoughBraggLayer(layer.n2, layer.Lambda + TABLES_LAMBDA_STEP * (round_ + 1), layer.delta, layer.N, layer.alpha)
        measured = _timed_ms(lambda: layered.layer_tables(moved, n1, F))
        if round_:
            times["layer"].append(measured)
        _progress(f"bench --tables: round {round_}/{repeats} done")
    wall, cpu = _medians(times)
    return {
        "table_ms": {str(N): wall[str(N)] for N in TABLES_N},
        "layer_tables_ms": wall["layer"],
        "table_cpu_ms": {str(N): cpu[str(N)] for N in TABLES_N},
        "layer_tables_cpu_ms": cpu["layer"],
    }


def tabulated_over_schlick(size: int = 512, repeats: int = 5) -> tuple[dict, str]:
    """
    Per Lambda of :data:`BENCH_LAMBDAS`: the median frame time of a ``size``-square sphere of
    ``bragg_mirror.brd``'s tabulated method (N = 20) over that of ``schlick_fresnel.brd`` in the same run
    (interleaved repeats, finish-bounded, tables built and programs compiled before timing), as
    ``tabulated_over_schlick``, and with the table in a 2D texture instead of a buffer texture (the path
    before buffer tables, and a .brdf export's) as ``tabulated_2d_over_schlick``; wall-clock ratios, and
    CPU-time ratios (``..._cpu``: llvmpipe renders on the CPU, robust to other processes). Returns them and
    the renderer's name.
    """
    from explorer.gpu import Renderer

    renderer = Renderer()
    texture_renderer = Renderer(renderer.ctx)  # the same context, tables as 2D textures
    texture_renderer.buffer_tables = False
    mirror_material = load_material(SHADER_DIR / f"{BraggMirrorModel.name}.brd")
    schlick_material = load_material(SHADER_DIR / f"{SchlickFresnelModel.name}.brd")
    schlick_values = schlick_material.resolve({})
    ratios: dict[str, dict] = {key: {} for key in ("tabulated_over_schlick", "tabulated_over_schlick_cpu",
                                                   "tabulated_2d_over_schlick", "tabulated_2d_over_schlick_cpu")}
    for Lambda in BENCH_LAMBDAS:
        values = mirror_material.resolve({**TABLES_MIRROR, "Lambda": Lambda, "N": 20, "method": int(BraggMethod.TABULATED)})
        cases = [(renderer, mirror_material, values), (renderer, schlick_material, schlick_values),
                 (texture_renderer, mirror_material, values)]
        for r, material, v in cases:  # compile, build the table, warm up
            r.time_frame(material, v, "sphere", size, size)
        times: dict[int, list] = {0: [], 1: [], 2: []}
        for _ in range(repeats):
            for i, (r, material, v) in enumerate(cases):
                times[i].append(_timed_frame(r, material, v, size))
        wall, cpu = _medians(times)
        key = f"{Lambda:g}"
        ratios["tabulated_over_schlick"][key], ratios["tabulated_over_schlick_cpu"][key] = wall[0] / wall[1], cpu[0] / cpu[1]
        ratios["tabulated_2d_over_schlick"][key], ratios["tabulated_2d_over_schlick_cpu"][key] = wall[2] / wall[1], cpu[2] / cpu[1]
        _progress(f"bench --tables: tabulated / schlick at Lambda = {Lambda:g} nm: x{wall[0] / wall[1]:.2f} "
                  f"(CPU time x{cpu[0] / cpu[1]:.2f}; 2D texture x{wall[2] / wall[1]:.2f}, CPU x{cpu[2] / cpu[1]:.2f})")
    texture_renderer.resources.close()
    return ratios, renderer.ctx.info.get("GL_RENDERER", "unknown")


def run_tables_bench(as_json: bool = False, size: int = 512, repeats: int = 5) -> dict:
    """``bragg-explorer bench --tables``: :func:`table_timings` and :func:`tabulated_over_schlick` from one run."""
    document = table_timings(repeats)
    shading, device = tabulated_over_schlick(size, repeats)
    document.update(shading)
    if as_json:
        print(json.dumps(document, indent=2))
    else:
        print(f"Host tables (wall-clock medians of {repeats} interleaved rebuilds; Lambda = 500 nm, n1 = 1, n2 = 1.5, delta = 0.5):")
        for N, ms in document["table_ms"].items():
            print(f"  converged table, N = {N:>4}: {ms:8.1f} ms  (CPU {document['table_cpu_ms'][N]:.1f} ms)")
        print(f"  one rough layer's tables (Figure 7's A, N = 10): {document['layer_tables_ms']:8.1f} ms  "
              f"(CPU {document['layer_tables_cpu_ms']:.1f} ms)")
        print(f"Tabulated method over Schlick's Fresnel, {size}x{size} sphere on {device}:")
        for Lambda, ratio in document["tabulated_over_schlick"].items():
            print(f"  Lambda = {Lambda:>3} nm: x{ratio:.2f}  (CPU time x{document['tabulated_over_schlick_cpu'][Lambda]:.2f}; "
                  f"table in a 2D texture x{document['tabulated_2d_over_schlick'][Lambda]:.2f}, "
                  f"CPU x{document['tabulated_2d_over_schlick_cpu'][Lambda]:.2f})")
    return document
