"""
``bragg-explorer bench``: GPU time per frame of a sphere for every method of ``bragg_mirror.brd`` (interleaved
repeats, medians, finish-bounded), each one's speed-up over the spectral reference (the paper's 1-nm sum), the median
and maximum ΔE2000 of each against the converged reference over θ, and the table rebuild time of the tabulated method:
the paper's Table 1 on this machine.
"""

from __future__ import annotations

import json
import time

import numpy as np

from explorer.bench.common import BENCH_LAMBDAS, THETA_DEGREES, _progress
from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.physics import bragg, colorimetry
from explorer.resources import SHADER_DIR
from explorer.materials.models import BraggMirrorModel, SchlickFresnelModel


def delta_E_over_theta(mirror: bragg.BraggMirror, rgb_function) -> tuple[float, float]:
    """Median and maximum ΔE2000 of ``rgb_function(cos_theta)`` against the converged spectral reference."""
    cos_theta = np.cos(np.radians(THETA_DEGREES))
    reference = bragg.reference_rgb(cos_theta, mirror)
    dE = colorimetry.delta_E_2000(reference, rgb_function(cos_theta))
    return float(np.median(dE)), float(np.max(dE))


def _methods() -> list[tuple[str, int | None, dict]]:
    """(method name, s, parameter overrides) in table order."""
    B = BraggMethod
    rows = [("reference", None, {"method": int(B.REFERENCE)}), ("basic", None, {"method": int(B.BASIC)})]
    rows += [("subdivided", s, {"method": int(B.SUBDIVIDED), "s": s}) for s in (2, 3, 4, 5)]
    rows += [("improved", 3, {"method": int(B.IMPROVED), "s": 3})]
    rows += [("tabulated", None, {"method": int(B.TABULATED)})]
    return rows


def _accuracy(mirror: bragg.BraggMirror, method: str, s: int | None, table: np.ndarray | None):
    if method == "reference":  # the shader's reference at its default step: the paper's 1-nm sum
        return delta_E_over_theta(mirror, lambda c: bragg.reference_rgb(c, mirror, step=1.0))
    if method == "basic":
        return delta_E_over_theta(mirror, lambda c: bragg.approximate_rgb(c, mirror, 0))
    if method == "subdivided":
        return delta_E_over_theta(mirror, lambda c: bragg.approximate_rgb(c, mirror, s))
    if method == "improved":
        return delta_E_over_theta(mirror, lambda c: bragg.approximate_rgb(c, mirror, s, variant="improved"))
    if method == "tabulated":
        return delta_E_over_theta(mirror, lambda c: bragg.tabulated_rgb(table, c))
    return None, None


def table_rebuild_ms(mirror: bragg.BraggMirror, repeats: int = 5) -> float:
    """Median time (ms) to rebuild the tabulated method's table (from scratch: its cache bypassed)."""
    build = bragg.tabulated_rgb_table.__wrapped__
    build(mirror)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        build(mirror)
        times.append(time.perf_counter() - start)
    return float(np.median(times) * 1e3)


def run_bench(as_json: bool = False, size: int = 512, repeats: int = 3, markdown: bool = False) -> dict:
    """Measure and print Table 1 (see the module docstring). Returns the JSON document."""
    from explorer.gpu import Renderer

    renderer = Renderer()
    mirror_material = load_material(SHADER_DIR / f"{BraggMirrorModel.name}.brd")
    schlick_material = load_material(SHADER_DIR / f"{SchlickFresnelModel.name}.brd")
    device = renderer.ctx.info.get("GL_RENDERER", "unknown")
    _progress(f"bench: {size}x{size} sphere on {device}, {repeats} interleaved repeats per method")

    rows: list[dict] = []
    table_ms: dict[str, float] = {}
    for Lambda in BENCH_LAMBDAS:
        base = {"n1": 1.0, "n2": 1.5, "Lambda": Lambda, "delta": 0.5, "N": 20}
        mirror = bragg.BraggMirror(1.0, 1.5, Lambda, 0.5, 20)
        table = bragg.tabulated_rgb_table(mirror)
        table_ms[f"{Lambda:g}"] = table_rebuild_ms(mirror)
        cases = [(name, s, mirror_material, mirror_material.resolve({**base, **o})) for name, s, o in _methods()]
        cases.append(("schlick", None, schlick_material, schlick_material.resolve({})))
        for _, _, material, values in cases:  # compile, JIT and warm every program first
            renderer.time_frame(material, values, "sphere", 16, 16)
        times: dict[int, list[float]] = {i: [] for i in range(len(cases))}
        for r in range(repeats):
            for i, (name, s, material, values) in enumerate(cases):
                times[i].append(renderer.time_frame(material, values, "sphere", size, size))
            _progress(f"bench: Lambda = {Lambda:g} nm, repeat {r + 1}/{repeats} done")
        reference_ms = float(np.median(times[0]))
        for i, (name, s, _, _) in enumerate(cases):
            ms = float(np.median(times[i]))
            dE_median, dE_max = _accuracy(mirror, name, s, table)
            rows.append(
                {"Lambda": int(Lambda), "method": name, "s": s, "ms": ms, "speedup": reference_ms / ms,
                 "dE_median": dE_median, "dE_max": dE_max}
            )
    standard = [r for r in rows if r["method"] != "improved"]
    document = {
        "device": device,
        "size": size,
        "repeats": repeats,
        "rows": standard,
        "variants": [r for r in rows if r["method"] == "improved"],
        "table_rebuild_ms": table_ms,
    }
    if as_json:
        print(json.dumps(document, indent=2))
    elif markdown:
        from explorer.bench.markdown_tables import bench_markdown

        print(bench_markdown(document))
    else:
        print(format_table(rows, device, size, table_ms))
    return document


def format_table(rows: list[dict], device: str, size: int, table_ms: dict[str, float]) -> str:
    """A readable Table 1."""
    lines = [f"Frame time of a {size}x{size} sphere on {device}; ΔE2000 against the converged spectral reference over "
             "θ ∈ [0°, 89.5°] (the reference row: the shader's 1-nm sum, timed, and its own error)", ""]
    header = f"{'Λ (nm)':>7}  {'method':<11} {'s':>2}  {'ms/frame':>9}  {'speed-up':>8}  {'ΔE median':>9}  {'ΔE max':>7}"
    lines += [header, "-" * len(header)]
    for r in rows:
        s = "" if r["s"] is None else str(r["s"])
        dE_median = "" if r["dE_median"] is None else f"{r['dE_median']:.2f}"
        dE_max = "" if r["dE_max"] is None else f"{r['dE_max']:.2f}"
        lines.append(
            f"{r['Lambda']:>7}  {r['method']:<11} {s:>2}  {r['ms']:>9.2f}  {r['speedup']:>7.1f}x  {dE_median:>9}  {dE_max:>7}"
        )
    lines.append("")
    lines.append("tabulated: table rebuild (converged, refined, numpy) " + ", ".join(f"{v:.1f} ms at Λ = {k} nm" for k, v in table_ms.items()))
    return "\n".join(lines)
