"""
Benchmarks and accuracy studies: the paper's Table 1 on this machine, and the Figure 4 grid.

``bragg-explorer bench``: GPU time per frame of a sphere for every method of ``bragg_mirror.brd``
(interleaved repeats, medians, finish-bounded), each one's speed-up over the spectral reference (the
paper's 1-nm sum), the median and maximum ΔE2000 of each against the converged reference over θ, and the
table rebuild time of the tabulated method. ``bragg-explorer accuracy``: ΔE2000 of the approximations on the Figure 4 grid for
s = 2..8, both readings of the mode numbering and both variants.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from explorer.materials.methods import BraggMethod, ThinFilmMethod
from explorer.physics import bragg, colorimetry
from explorer.materials.brd import load_material
from explorer.files import atomic_output
from explorer.resources import SHADER_DIR

#: What matplotlib's figures (``accuracy --plot``, ``figure --out``) and Figure 4's strips are written as.
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
STRIP_SUFFIXES = (".png",)


def save_figure(figure, path, **options) -> None:
    """A matplotlib figure to ``path`` (a format of :data:`FIGURE_SUFFIXES`, by its suffix), atomically."""
    with atomic_output(path, FIGURE_SUFFIXES) as temporary:
        figure.savefig(temporary, format=Path(path).suffix.lower()[1:], **options)

BENCH_LAMBDAS = (244.0, 500.0, 988.0)
FIGURE4_LAMBDAS = (244.0, 500.0, 988.0)
FIGURE4_DELTAS = (0.25, 0.5, 0.75)
#: Incidence angles of the accuracy studies: theta in [0, 89.5] degrees.
THETA_DEGREES = np.linspace(0.0, 89.5, 180)


def _progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


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
    mirror_material = load_material(SHADER_DIR / "bragg_mirror.brd")
    schlick_material = load_material(SHADER_DIR / "schlick_fresnel.brd")
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
        from explorer.cli.markdown_tables import bench_markdown

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


# --------------------------------------------------------------------------------------------------
# The Figure 4 grid


def figure4_accuracy(s_values=range(2, 9)) -> list[dict]:
    """ΔE2000 (median, max) on the Figure 4 grid for every approximation, variant and numbering."""
    rows = []
    for Lambda in FIGURE4_LAMBDAS:
        for delta in FIGURE4_DELTAS:
            mirror = bragg.BraggMirror(1.0, 1.5, Lambda, delta, 20)
            _progress(f"accuracy: Lambda = {Lambda:g} nm, delta = {delta:g}")
            cos_theta = np.cos(np.radians(THETA_DEGREES))
            reference = bragg.reference_rgb(cos_theta, mirror)
            dE = colorimetry.delta_E_2000(reference, bragg.reference_rgb(cos_theta, mirror, step=1.0))
            rows.append({"Lambda": int(Lambda), "delta": delta, "variant": "1-nm sum", "mode_numbering": None, "s": None,
                         "dE_median": float(np.median(dE)), "dE_max": float(np.max(dE))})
            for variant in ("paper", "improved"):
                for numbering in ("relative", "absolute"):
                    for s in [0, *s_values]:
                        if s == 0 and numbering == "absolute":
                            continue  # the basic method has no subdivisions
                        rgb = bragg.approximate_rgb(cos_theta, mirror, s, numbering, variant)
                        dE = colorimetry.delta_E_2000(reference, rgb)
                        rows.append(
                            {"Lambda": int(Lambda), "delta": delta, "variant": variant, "mode_numbering": numbering,
                             "s": s, "dE_median": float(np.median(dE)), "dE_max": float(np.max(dE))}
                        )
    return rows


def plot_accuracy(rows: list[dict], path: Path) -> None:
    """Median ΔE2000 against s per mirror, paper vs improved (a PNG through matplotlib)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, 3, figsize=(13, 3.8), sharey=True)
    for axis, Lambda in zip(axes, FIGURE4_LAMBDAS):
        for delta, colour in zip(FIGURE4_DELTAS, ("tab:blue", "tab:orange", "tab:green")):
            for variant, style in (("paper", "--"), ("improved", "-")):
                subset = sorted(
                    (r for r in rows if r["Lambda"] == int(Lambda) and r["delta"] == delta
                     and r["variant"] == variant and r["mode_numbering"] == "relative"),
                    key=lambda r: r["s"],
                )
                axis.plot([r["s"] for r in subset], [r["dE_median"] for r in subset], style, color=colour,
                          marker="o", markersize=3, label=f"δ = {delta:g}, {variant}")
        axis.axhline(2.0, color="grey", linewidth=0.8)
        axis.set_title(f"Λ = {Lambda:g} nm (n1 = 1, n2 = 1.5, N = 20)")
        axis.set_xlabel("s (0 = basic)")
    axes[0].set_ylabel("median ΔE2000 vs reference")
    axes[-1].legend(fontsize=7, ncol=2)
    figure.tight_layout()
    try:
        save_figure(figure, path, dpi=110)
    finally:
        plt.close(figure)


def run_accuracy(as_json: bool = False, plot: Path | None = None, markdown: bool = False) -> list[dict]:
    """``accuracy``: the Figure 4 grid as JSON, or as the Markdown tables of :func:`accuracy_markdown` (with or without ``markdown``)."""
    rows = figure4_accuracy()
    if plot is not None:
        plot_accuracy(rows, plot)
        _progress(f"accuracy: wrote {plot}")
    if as_json:
        print(json.dumps({"rows": rows}, indent=2))
    else:  # the text output is the Markdown tables (--markdown says so explicitly)
        from explorer.cli.markdown_tables import accuracy_markdown

        print(accuracy_markdown(rows, FIGURE4_LAMBDAS, FIGURE4_DELTAS))
    return rows


def figure4_strips(path: Path, width: int = 360, strip: int = 14) -> None:
    """
    The colour strips of Figure 4, rendered by the GPU shaders: per mirror (rows: Λ; columns: δ),
    the spectral reference, the basic, subdivided (s = 3) and improved (s = 3) approximations.
    """
    from PIL import Image

    from explorer.physics.colorimetry import encode_srgb8
    from explorer.gpu import Renderer

    renderer = Renderer()
    material = load_material(SHADER_DIR / "bragg_mirror.brd")
    gap = 6
    rows = []
    for Lambda in FIGURE4_LAMBDAS:
        cells = []
        for delta in FIGURE4_DELTAS:
            strips = []
            for method in (BraggMethod.REFERENCE, BraggMethod.BASIC, BraggMethod.SUBDIVIDED, BraggMethod.IMPROVED):
                values = material.resolve({"Lambda": Lambda, "delta": delta, "N": 20, "method": int(method), "s": 3})
                strips.append(renderer.render(material, values, "gradient", width, strip))
                strips.append(np.ones((2, width, 3), np.float32))
            cells.append(np.concatenate(strips))
            cells.append(np.ones((cells[-1].shape[0], gap, 3), np.float32))
        rows.append(np.concatenate(cells[:-1], axis=1))
        rows.append(np.ones((gap, rows[-1].shape[1], 3), np.float32))
    with atomic_output(path, STRIP_SUFFIXES) as temporary:
        Image.fromarray(encode_srgb8(np.concatenate(rows[:-1]))).save(temporary, format="PNG")


# --------------------------------------------------------------------------------------------------
# Thin films (Belcour & Barla 2017): accuracy of each method and its cost relative to GGX + Schlick

#: (name, method of thin_film.brd) in table order; the first is the spectral reference.
THIN_FILM_METHODS = tuple((m.label, int(m)) for m in ThinFilmMethod)


def thin_film_accuracy(values: dict) -> dict[str, tuple[float, float]]:
    """
    Median and maximum ΔE2000 of each approximate method, and of the shader's 1-nm reference (method 0),
    against the converged reference (:func:`explorer.physics.thinfilm.reference_rgb`) over θ (numpy).
    """
    from explorer.materials.thinfilm_model import ThinFilmModel
    from explorer.physics import thinfilm

    cos_theta = np.cos(np.radians(THETA_DEGREES))
    film = ThinFilmModel({**values, "method": int(ThinFilmMethod.REFERENCE)})
    reference = thinfilm.reference_rgb(*film.film, cos_theta, film.thickness_d)
    result = {}
    for name, method in THIN_FILM_METHODS[1:] + (("1-nm sum", int(ThinFilmMethod.REFERENCE)),):
        dE = colorimetry.delta_E_2000(reference, ThinFilmModel({**values, "method": method}).reflectance(cos_theta))
        result[name] = (float(np.median(dE)), float(np.max(dE)))
    return result


def run_thin_film_bench(as_json: bool = False, size: int = 512, repeats: int = 3, markdown: bool = False) -> dict:
    """
    ``bragg-explorer bench --thin-film``: ΔE2000 of every method on the Figure 7 film and on every
    thin-film preset; the frame time of every method of ``thin_film.brd`` (Figure 7 film) on a lit
    sphere relative to ``ggx_schlick.brd`` (plain GGX with Schlick's Fresnel), interleaved repeats, medians.
    """
    from explorer.gpu import Renderer
    from explorer.materials.presets import presets_for

    film_material = load_material(SHADER_DIR / "thin_film.brd")
    presets = presets_for(SHADER_DIR / "thin_film.brd").presets
    configurations = [("figure7", film_material.resolve({}))]  # the material's defaults are Figure 7's film
    configurations += [(name, p.resolve()) for name, p in presets.items() if name != "figure7"]
    accuracy = []
    for name, values in configurations:
        _progress(f"bench --thin-film: accuracy of {name}")
        for method, (median, maximum) in thin_film_accuracy(values).items():
            accuracy.append({"configuration": name, "method": method, "dE_median": median, "dE_max": maximum})

    renderer = Renderer()
    baseline_material = load_material(SHADER_DIR / "ggx_schlick.brd")
    device = renderer.ctx.info.get("GL_RENDERER", "unknown")
    figure7 = presets["figure7"].resolve() if "figure7" in presets else film_material.resolve({})
    cases = [(name, film_material, {**figure7, "method": float(m)}) for name, m in THIN_FILM_METHODS]
    cases.append(("ggx+schlick", baseline_material, baseline_material.resolve({"alpha": figure7["alpha"]})))
    _progress(f"bench --thin-film: {size}x{size} lit sphere on {device}, {repeats} interleaved repeats per method")
    for _, material, values in cases:  # compile, JIT and warm every program first
        renderer.time_frame(material, values, "lit", 16, 16)
    times: dict[str, list[float]] = {name: [] for name, _, _ in cases}
    for r in range(repeats):
        for name, material, values in cases:
            times[name].append(renderer.time_frame(material, values, "lit", size, size))
        _progress(f"bench --thin-film: repeat {r + 1}/{repeats} done")
    baseline_ms = float(np.median(times["ggx+schlick"]))
    timing = [
        {"method": name, "ms": float(np.median(times[name])), "relative": float(np.median(times[name])) / baseline_ms}
        for name, _, _ in cases
    ]
    document = {"device": device, "size": size, "repeats": repeats, "view": "lit",
                "theta_degrees": [float(THETA_DEGREES[0]), float(THETA_DEGREES[-1]), len(THETA_DEGREES)],
                "accuracy": accuracy, "timing": timing}
    if markdown and not as_json:
        from explorer.cli.markdown_tables import thin_film_markdown

        print(thin_film_markdown(document))
        return document
    print(json.dumps(document, indent=2) if as_json else format_thin_film(document))
    return document


def format_thin_film(document: dict) -> str:
    """The thin-film tables: ΔE2000 per configuration and method, and the relative frame times."""
    methods = [name for name, _ in THIN_FILM_METHODS[1:]] + ["1-nm sum"]
    lines = ["Thin film: median / max ΔE2000 against the converged spectral reference over θ ∈ [0°, 89.5°]", ""]
    header = f"{'configuration':<22}" + "".join(f"{m:>17}" for m in methods)
    lines += [header, "-" * len(header)]
    cells: dict[str, dict[str, str]] = {}
    for row in document["accuracy"]:
        cells.setdefault(row["configuration"], {})[row["method"]] = f"{row['dE_median']:.2g} / {row['dE_max']:.2g}"
    for configuration, row in cells.items():
        lines.append(f"{configuration:<22}" + "".join(f"{row[m]:>17}" for m in methods))
    size = document["size"]
    lines += ["", f"Frame time of a {size}x{size} lit sphere (Figure 7 film) on {document['device']}, relative to GGX + Schlick", ""]
    for row in document["timing"]:
        lines.append(f"{row['method']:<14} {row['ms']:>10.2f} ms  ×{row['relative']:.2f}")
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------------
# Rough layers: host-table timings and the slice view's accuracy

#: Roughnesses of the slice study and of the F_alpha timings.
LAYER_ALPHAS = (0.025, 0.1, 0.4)
#: The Figure 8 configuration of the slice study (rho_d = 0: the specular lobe alone).
FIGURE8_LAYER = {"n1": 1.0, "n2": 1.5, "Lambda": 500.0, "delta": 0.5, "N": 20, "rho_d": "0", "s": 3}
#: Pixels whose reference luminance Y (white = 1) is at or below this are left out (L* <= 9).
SLICE_LUMINANCE_THRESHOLD = 0.01
#: (name, method of bragg_layer.brd) compared with the spectral reference by ΔE2000.
SLICE_METHODS = (("basic", int(BraggMethod.BASIC)), ("subdivided s=3", int(BraggMethod.SUBDIVIDED)),
                 ("improved s=3", int(BraggMethod.IMPROVED)), ("1-nm sum", int(BraggMethod.REFERENCE)))
LAYER_GOALS = {"transmission_filter_ms": 100.0, "layer_tables_ms": 10.0}
LAYER_PAPER = {"transmission_filter_ms": 600.0, "layer_tables_ms": 40.0}


def slice_accuracy(alpha: float, size: int = 64) -> dict:
    """
    ΔE2000 of methods 1, 2 (s = 3), 4 (s = 3) and 0 (the paper's 1-nm sum) of ``bragg_layer.brd`` against
    the converged spectral reference in the ``slice`` view (numpy twin) of the Figure 8 layer at ``alpha``, per pixel over pixels with reference luminance
    Y > :data:`SLICE_LUMINANCE_THRESHOLD`; the pixels are the BRDF values as rendered (unit exposure,
    white = 1). And the tabulated method (3) against the reference: the maximum absolute linear
    difference, and the maximum relative to a pixel's largest channel (the twin tests' rule).
    """
    from explorer.materials.models import model_for
    from explorer.views.render import render_numpy

    material = load_material(SHADER_DIR / "bragg_layer.brd")

    def image(method: int, converged: bool = False) -> np.ndarray:
        values = material.resolve({**FIGURE8_LAYER, "alpha": alpha, "method": method})
        model = model_for(material, values)
        if converged:
            model.wavelength_step = None  # the converged reference instead of the shader's 1-nm sum
        return render_numpy(model, "slice", size, size).astype(np.float64)

    reference = image(0, converged=True)
    counted = colorimetry.rgb_to_xyz(reference)[..., 1] > SLICE_LUMINANCE_THRESHOLD
    row: dict = {"alpha": alpha, "size": size, "pixels": int(counted.sum())}
    for name, method in SLICE_METHODS:
        dE = colorimetry.delta_E_2000(reference, image(method))[counted]
        row[name] = {"dE_median": float(np.median(dE)), "dE_max": float(np.max(dE))}
    difference = np.abs(image(3) - reference).max(axis=-1)
    peak = np.abs(reference).max(axis=-1)
    relative = np.where(peak > 1e-3, difference / np.maximum(peak, 1e-30), difference)
    row["tabulated"] = {"max_abs": float(difference.max()), "max_relative": float(relative.max())}
    return row


def run_layers_bench(as_json: bool = False, repeats: int = 5, size: int = 64, markdown: bool = False) -> dict:
    """
    ``bragg-explorer bench --layers``: the host tables' build times (F_alpha for a new alpha, one layer's
    tables for Figure 7's A, B, A'; interleaved repeats, medians; :func:`explorer.physics.layered.measure_timings`)
    and the slice view's accuracy at each of :data:`LAYER_ALPHAS` (:func:`slice_accuracy`).
    """
    from explorer.physics import layered

    _progress(f"bench --layers: host tables, {repeats} interleaved repeats")
    timings = layered.measure_timings(alphas=LAYER_ALPHAS, repeats=repeats)
    accuracy = []
    for alpha in LAYER_ALPHAS:
        _progress(f"bench --layers: slice view {size}x{size}, alpha = {alpha:g}")
        accuracy.append(slice_accuracy(alpha, size))
    _progress("bench --layers: bragg_stack.brd, Figure 7's presets and Table 3's green area")
    document = {
        "timings": {**timings, "goal_ms": LAYER_GOALS, "paper_ms": LAYER_PAPER},
        "slice": {"configuration": {k: v for k, v in FIGURE8_LAYER.items() if k != "s"},
                  "luminance_threshold": SLICE_LUMINANCE_THRESHOLD, "rows": accuracy},
        "stack": stack_study(repeats=max(repeats // 2, 1)),
    }
    if markdown and not as_json:
        from explorer.cli.markdown_tables import layers_markdown

        print(layers_markdown(document))
        return document
    print(json.dumps(document, indent=2) if as_json else format_layers(document))
    return document


#: Presets of bragg_stack.brd timed and compared by :func:`stack_study`.
STACK_PRESETS = ("figure7_A", "figure7_A_on_B", "figure7_A_prime", "table3_green_blue", "figure12_middle_alpha01")
#: Direction pairs of the LUT study (cos theta in [0.05, 1], uniform azimuths; fixed seed).
STACK_PAIRS = 4000


def stack_study(repeats: int = 2, size: int = 256, presets=STACK_PRESETS) -> list[dict]:
    """
    Per preset of ``bragg_stack.brd``: the host's table rebuild when a parameter changes (every layer's
    tables, F_alpha cached), the GL time of a ``size``-square ``lit`` frame (finish-bounded, median of
    ``repeats``), and the ΔE2000 between Eq. 34 with Yeh's reflectance read from the 0.25-degree table
    (Table 2's "Model-LUT", what the shader does) and computed exactly at the half-vector angle ("Model"),
    over :data:`STACK_PAIRS` random direction pairs where the exact BRDF's luminance exceeds 0.01.
    """
    from explorer.physics import layered
    from explorer.gpu import Renderer
    from explorer.materials.models import BraggStackModel, _layer_tables
    from explorer.materials.presets import load_presets

    preset_file = load_presets(SHADER_DIR / "presets" / "bragg_stack.toml")
    material = preset_file.material
    renderer = Renderer()
    rng = np.random.default_rng(2024)

    def directions(count):
        cos_theta = rng.uniform(0.05, 1.0, count)
        phi = rng.uniform(0.0, 2.0 * np.pi, count)
        sin_theta = np.sqrt(1.0 - cos_theta**2)
        return np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=-1)

    i, o = directions(STACK_PAIRS), directions(STACK_PAIRS)
    rows = []
    for name in presets:
        values = preset_file.presets[name].resolve()
        rebuilds = []
        for _ in range(repeats + 1):
            _layer_tables.cache_clear()
            layered._reflectance_at_theta_nodes.cache_clear()
            start = time.perf_counter()
            model = BraggStackModel(values)
            model.tables  # built on first use
            rebuilds.append(1e3 * (time.perf_counter() - start))
        renderer.render(material, values, "lit", 8, 8)  # compile and upload once
        frames = [renderer.time_frame(material, values, "lit", size, size) for _ in range(repeats)]
        lut = layered.single_reflection_brdf(model.stack, i, o, model.tables)
        exact = layered.single_reflection_brdf(model.stack, i, o, model.tables, exact_reflectance=True)
        counted = colorimetry.rgb_to_xyz(exact)[..., 1] > SLICE_LUMINANCE_THRESHOLD
        dE = colorimetry.delta_E_2000(exact[counted], lut[counted])
        rows.append({
            "preset": name, "layers": len(model.stack.layers), "tables_ms": float(np.median(rebuilds[1:])),
            "frame_ms": float(np.median(frames)), "size": size, "pairs": int(counted.sum()),
            "lut_dE_median": float(np.median(dE)), "lut_dE_max": float(np.max(dE)),
        })
    return rows


def format_layers(document: dict) -> str:
    """The three tables of ``bench --layers``."""
    timings = document["timings"]
    lines = [f"Host tables: wall-clock medians of {timings['repeats']} interleaved repeats (numpy, this machine)", ""]
    for key, label in (("transmission_filter_ms", "F_alpha (new alpha)"), ("layer_tables_ms", "layer tables")):
        goal, paper = timings["goal_ms"][key], timings["paper_ms"][key]
        for name, ms in timings[key].items():
            lines.append(f"{label:<20} {name:<44} {ms:>7.1f} ms  (goal {goal:g} ms; paper {paper:g} ms)")
    study = document["slice"]
    rows = study["rows"]
    lines += ["", f"slice view {rows[0]['size']}x{rows[0]['size']} (numpy twin of bragg_layer.brd, Λ = 500 nm, δ = 0.5, "
              f"n1 = 1, n2 = 1.5, N = 20, rho_d = 0): median / max ΔE2000 against the spectral reference over pixels "
              f"with reference Y > {study['luminance_threshold']:g}", ""]
    names = [name for name, _ in SLICE_METHODS]
    header = f"{'alpha':>6} {'pixels':>7}" + "".join(f"{n:>17}" for n in names) + f"{'tabulated abs':>15}{'tabulated rel':>15}"
    lines += [header, "-" * len(header)]
    for r in rows:
        cells = "".join(f"{r[n]['dE_median']:>9.2f} / {r[n]['dE_max']:<5.1f}" for n in names)
        lines.append(f"{r['alpha']:>6g} {r['pixels']:>7}{cells}{r['tabulated']['max_abs']:>15.3g}{r['tabulated']['max_relative']:>15.2e}")
    stack = document.get("stack")
    if stack:
        lines += ["", f"bragg_stack.brd (Eq. 34, 471 wavelengths per pixel): host table rebuild (all layers), GL lit frame "
                  f"{stack[0]['size']}x{stack[0]['size']} (this machine's renderer), and ΔE2000 of the tabulated R_λ (Model-LUT) "
                  f"against Yeh's R_λ at the exact half-vector angle (Model), median / max over random pairs with Y > "
                  f"{SLICE_LUMINANCE_THRESHOLD:g}", ""]
        header = f"{'preset':<26}{'layers':>7}{'tables':>11}{'frame':>11}{'pairs':>7}{'LUT ΔE2000':>16}"
        lines += [header, "-" * len(header)]
        for r in stack:
            lines.append(f"{r['preset']:<26}{r['layers']:>7}{r['tables_ms']:>8.1f} ms{r['frame_ms']:>8.0f} ms{r['pairs']:>7}"
                         f"{r['lut_dE_median']:>9.2f} / {r['lut_dE_max']:<5.2f}")
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------------
# bench --app: the explorer's frame times while a slider is dragged


#: The methods of bragg_mirror.brd timed by ``bench --app``, fastest first.
APP_METHODS = tuple((int(m), name) for m, name in (
    (BraggMethod.TABULATED, "tabulated"), (BraggMethod.BASIC, "basic"), (BraggMethod.SUBDIVIDED, "subdivided s = 3"),
    (BraggMethod.IMPROVED, "improved s = 3"), (BraggMethod.REFERENCE, "reference")))
#: The sphere's modes timed per method (the env mode is timed on the stack: :data:`APP_ENV_VALUES`).
APP_MODES = ("sphere", "lit")
#: The env mode's material (``shaders/bragg_stack.brd``) and values: the two-layer stack, Lambda_1 dragged.
APP_ENV_MATERIAL = "bragg_stack.brd"
APP_ENV_VALUES = {"layers": 2}
APP_ENV_SLIDER = "param:Lambda_1"
#: The goals of issue 22: frames while a slider moves, and the env view's first pass.
APP_GOAL_FPS = 30.0
APP_GOAL_FIRST_PASS_MS = 33.0


def _drag(mark: str, slider: str, frames: int) -> list:
    # About 2 px a frame: an integer slider (1 nm steps, ~8 nm a pixel) changes on every frame.
    return [{"mark": mark}, {"drag": slider, "from": 0.15, "to": 0.85, "frames": frames}, {"mark": None}, {"wait": 3}]


def app_bench_script(frames: int = 60) -> list:
    """The scripted session of ``bench --app``: per mode of :data:`APP_MODES` and method, drag Lambda through the UI for ``frames`` frames."""
    script: list = [{"wait": 3}, {"wait_complete": True, "timeout": 600}]
    for mode in APP_MODES:
        script += [{"click": f"mode:{mode}"}, {"wait": 3}]
        for method, _name in APP_METHODS:
            script += [{"set": {"method": method}}, {"wait": 8}] + _drag(f"{mode} {method}", "param:Lambda", frames)
    return script + app_view_steps(frames) + app_mesh_steps(frames) + [{"quit": True}]


def app_env_script(frames: int = 60) -> list:
    """The env session of ``bench --app`` (on :data:`APP_ENV_MATERIAL`): the mode's first frames, then a drag of :data:`APP_ENV_SLIDER`."""
    return ([{"wait": 3}, {"set": dict(APP_ENV_VALUES)}, {"wait": 3}, {"mark": "env open"}, {"click": "mode:env"}, {"wait": 10},
             {"mark": None}] + _drag("env", APP_ENV_SLIDER, frames) + [{"quit": True}])


def _frame_row(chosen: list[dict], drag: list[dict], env: bool = False) -> dict:
    """Frame times (ms) of the frames ``chosen`` (a drag's, where the values changed) and how often the sphere changed."""
    ms = np.array([f["ms"] for f in chosen[2:] or chosen])
    # How often the sphere shows new values: its tables may be one frame late (built on a worker thread).
    if env:  # the env render restarts on new values
        updates = sum(1 for f in drag[1:] if f["env"]["first_pass"])
    else:
        generations = [f["main"].get("generation", 0) for f in drag]
        updates = sum(1 for a, b in zip(generations, generations[1:]) if b != a)
    seconds = 1e-3 * sum(f["ms"] for f in drag[1:])
    return {
        "frames": int(ms.size), "median_ms": float(np.median(ms)), "p90_ms": float(np.percentile(ms, 90)),
        "max_ms": float(ms.max()), "fps": float(1e3 / np.median(ms)),
        "sphere_updates_per_s": updates / seconds if seconds > 0 else 0.0,
        "gl_ms": float(np.median([f["gl_ms"] for f in chosen])), "ui_ms": float(np.median([f["ui_ms"] for f in chosen])),
    }


def summarise_app_frames(frames: list[dict]) -> list[dict]:
    """Per mode and method: frame times (ms) of the frames spent dragging, and the resolution shown meanwhile."""
    rows = []
    for mode in APP_MODES:
        for method, name in APP_METHODS:
            mark = f"{mode} {method}"
            # Only frames where the parameter changed: a frame that redraws nothing new is not a drag frame.
            drag = [f for f in frames if f.get("mark") == mark and f.get("dragging")]
            chosen = [f for f in drag if f.get("changed")]
            if not chosen:
                continue
            # What most of those frames showed (a draw slowed by other processes may make one a preview).
            previews = [tuple(f["main"]["preview"]) for f in chosen if f["main"]["has_preview"] and not f["main"]["complete"]]
            shown = (f"{previews[-1][0]}x{previews[-1][1]} preview" if 2 * len(previews) > len(chosen)
                     else f"{chosen[-1]['main']['size'][0]}x{chosen[-1]['main']['size'][1]} full")
            rows.append({"mode": mode, "method": method, "name": name, **_frame_row(chosen, drag), "while_dragging": shown})
    return rows


def summarise_env_frames(frames: list[dict]) -> dict | None:
    """The env session: its first pass on opening (ms), the first passes while the slider moves, and the frame times."""
    opening = [f["env"]["ms"] for f in frames if f.get("mark") == "env open" and f.get("env", {}).get("first_pass")]
    drag = [f for f in frames if f.get("mark") == "env" and f.get("dragging")]
    chosen = [f for f in drag if f.get("changed")]
    if not opening or not chosen:
        return None
    first_passes = [f["env"]["ms"] for f in drag if f["env"]["first_pass"]]
    return {"mode": "env", "material": APP_ENV_MATERIAL, "values": dict(APP_ENV_VALUES), **_frame_row(chosen, drag, env=True),
            "first_pass_ms": float(opening[0]), "drag_first_pass_median_ms": float(np.median(first_passes or [np.nan])),
            "drag_first_pass_max_ms": float(np.max(first_passes or [np.nan])),
            "samples_after_drag": int(drag[-1]["env"]["samples"])}


def _app_session(material, script: list, size: int) -> dict:
    """One scripted session of the explorer on ``material``; its report."""
    import tempfile

    from explorer.app import App

    with tempfile.TemporaryDirectory() as directory:
        report = Path(directory) / "report.json"
        App(material, script=script, report=report, view_size=size, is_default=True).run()
        return json.loads(report.read_text())


def run_app_bench(as_json: bool = False, size: int = 512, frames: int = 60) -> list[dict]:
    """
    Open the explorer (on a virtual display when there is none) on the default mirror with a ``size``²
    sphere, drag the Lambda slider through the UI for ``frames`` frames per mode (:data:`APP_MODES`) and
    method, with each new view (:func:`app_view_cases`: the Plots window's plots, the Texture window's textured
    mirror) beside the sphere, then on the two-layer stack in the env mode (its first pass on opening, then a
    drag of Lambda_1), and print the frame times (wall clock between frames: UI, drawing, table rebuilds and all).
    """
    from explorer.resources import DEFAULT_MATERIAL
    from explorer.app.xvfb import display_environment

    with display_environment() as display:
        _progress(f"bench --app: scripted session on DISPLAY={display}, {size}x{size} sphere, {frames} frames of drag per mode and method")
        document = _app_session(DEFAULT_MATERIAL, app_bench_script(frames), size)
        _progress(f"bench --app: the env mode on {APP_ENV_MATERIAL} ({APP_ENV_VALUES})")
        env_document = _app_session(SHADER_DIR / APP_ENV_MATERIAL, app_env_script(frames), size)
    rows = summarise_app_frames(document["frames"])
    env = summarise_env_frames(env_document["frames"])
    mesh_rows = summarise_mesh_frames(document["frames"])
    views = summarise_view_frames(document["frames"])
    if as_json:
        print(json.dumps({"size": size, "window": list(document.get("window", [])), "rows": rows, "env": env,
                          "mesh_rows": mesh_rows, "views": views}, indent=2))
        return rows + ([env] if env else [])
    print(f"Explorer frame times while dragging Lambda ({size}x{size} sphere, 1280x800 window, {os.cpu_count()} CPUs; goal >= {APP_GOAL_FPS:g} fps):")
    print(f"{'mode':<7}{'method':<22} {'median':>8} {'p90':>8} {'max':>8} {'fps':>6} {'sphere/s':>9}  {'GL work':>8} {'UI':>6}  shown while dragging")
    for row in rows + mesh_rows:
        print(f"{row['mode']:<7}{row['method']} {row['name']:<20} {row['median_ms']:7.1f}ms {row['p90_ms']:7.1f}ms {row['max_ms']:7.1f}ms "
              f"{row['fps']:6.1f} {row['sphere_updates_per_s']:9.1f}  {row['gl_ms']:7.1f}ms {row['ui_ms']:5.1f}ms  {row['while_dragging']}")
    if env:
        print(f"{'env':<7}{APP_ENV_MATERIAL + ' layers = 2':<22} {env['median_ms']:7.1f}ms {env['p90_ms']:7.1f}ms {env['max_ms']:7.1f}ms "
              f"{env['fps']:6.1f} {env['sphere_updates_per_s']:9.1f}  {env['gl_ms']:7.1f}ms {env['ui_ms']:5.1f}ms")
        print(f"env first pass: {env['first_pass_ms']:.1f} ms on opening; while dragging median {env['drag_first_pass_median_ms']:.1f} ms, "
              f"max {env['drag_first_pass_max_ms']:.1f} ms (goal <= {APP_GOAL_FIRST_PASS_MS:g} ms)")
    print("fps: frames while the slider moves; sphere/s: frames that show new parameter values on the sphere")
    print_view_frames(views, size)
    return rows + ([env] if env else [])


def print_view_frames(views: list[dict], size: int) -> None:
    """The table of :func:`summarise_view_frames`."""
    print(f"New views (Plots, Texture) in their windows beside the {size}x{size} sphere, tabulated method, Lambda dragged "
          f"(goal >= {APP_GOAL_FPS:g} fps; the textured view shows draft tables while dragging):")
    print(f"{'view':<10} {'shown':>9} {'median':>8} {'p90':>8} {'max':>8} {'fps':>6} {'sphere/s':>9} {'view/s':>7} {'draft':>6}")
    for row in views:
        print(f"{row['view']:<10} {row['size'][0]:>4}x{row['size'][1]:<4} {row['median_ms']:7.1f}ms {row['p90_ms']:7.1f}ms "
              f"{row['max_ms']:7.1f}ms {row['fps']:6.1f} {row['sphere_updates_per_s']:9.1f} {row['view_updates_per_s']:7.1f} "
              f"{100 * row['draft_fraction']:5.0f}%")
    print("view/s: frames that show new parameter values in the view's window; draft: drag frames showing a draft table")


#: ``bench --app``'s new views (issue 18): the Plots window's plots (:data:`explorer.views.geometry.PLOT_VIEWS`),
#: then the Texture window's textured mirror, as (mark, window, the scheduler's job, plot to choose or None).
def app_view_cases() -> tuple[tuple[str, str, str, str | None], ...]:
    from explorer.views.geometry import PLOT_VIEWS

    return tuple((view, "Plots", "plot", view) for view in PLOT_VIEWS) + (("textured", "Texture", "textured", None),)


def app_view_steps(frames: int) -> list:
    """Drag Lambda (tabulated method, sphere mode) with each plot shown in the Plots window, then the Texture window."""
    steps: list = [{"click": "mode:sphere"}, {"set": {"method": int(BraggMethod.TABULATED)}}, {"wait": 3}]
    for mark, window, _job, plot in app_view_cases():
        steps += [{"focus": window}, {"wait": 3}]
        if plot is not None:
            steps += [{"click": "plot_combo"}, {"wait": 2}, {"click": f"plot:{plot}"}, {"wait": 3}]
        report = "plots" if window == "Plots" else "texture_view"
        steps += [{"wait_for": report}] + _drag(f"view {mark}", "param:Lambda", frames) + [{"wait_for": report}]
    return steps


def summarise_view_frames(frames: list[dict]) -> list[dict]:
    """Per case of :func:`app_view_cases`: the frame times while dragging, how often the view followed, and its drafts."""
    rows = []
    for mark, _window, job, _plot in app_view_cases():
        drag = [f for f in frames if f.get("mark") == f"view {mark}" and f.get("dragging")]
        chosen = [f for f in drag if f.get("changed")]
        if not chosen:
            continue
        views = [f["main"].get("views", {}).get(job, {}) for f in drag]
        generations = [v.get("generation", 0) for v in views]
        seconds = 1e-3 * sum(f["ms"] for f in drag[1:])
        updates = sum(1 for a, b in zip(generations, generations[1:]) if b != a)
        rows.append({"view": mark, "job": job, "size": views[-1].get("size", [0, 0]), **_frame_row(chosen, drag),
                     "view_updates_per_s": updates / seconds if seconds > 0 else 0.0,
                     "draft_fraction": float(np.mean([bool(v.get("draft")) for v in views]))})
    return rows


#: ``bench --app``'s mesh cases (issue 18): the Sphere window's teapot, lit and under the environment (tabulated method).
APP_MESH_CASES = (("teapot lit", "mode:lit"), ("teapot env", "mode:env"))


def app_mesh_steps(frames: int) -> list:
    """Drag Lambda with the teapot shown (Switch model), lit and in the env mode (its progressive first passes)."""
    steps: list = [{"set": {"method": int(BraggMethod.TABULATED)}}, {"click": "model_combo"}, {"click": "model:teapot"}]
    for mark, mode in APP_MESH_CASES:
        steps += [{"click": mode}, {"wait": 8}] + _drag(mark, "param:Lambda", frames)
    return steps


def summarise_mesh_frames(frames: list[dict]) -> list[dict]:
    """The mesh cases' frame times while dragging (:data:`APP_MESH_CASES`)."""
    rows = []
    for mark, mode in APP_MESH_CASES:
        drag = [f for f in frames if f.get("mark") == mark and f.get("dragging")]
        chosen = [f for f in drag if f.get("changed")]
        if chosen:
            rows.append({"mode": mode.split(":")[1], "method": int(BraggMethod.TABULATED), "name": mark,
                         **_frame_row(chosen, drag, env=mode == "mode:env"), "while_dragging": mark})
    return rows


#: The position-free benchmark: 9 incidence angles, a standard-error goal, a time goal (this 2-core machine).
POSITION_FREE_THETA = tuple(float(t) for t in np.linspace(0.0, 80.0, 9))
POSITION_FREE_TARGET = 2e-3
POSITION_FREE_GOAL_S = 30.0
#: Its configurations: bragg_stack.brd's three default layers (no shipped preset has three) over a black
#: base, and the same three over Figure 7's grey base under Figure 7's coating (the hard case: many bounces).
POSITION_FREE_CASES = (
    ("bragg_stack defaults, layers = 3 (rho_d = 0, nh = 1)", {"layers": 3}),
    ("figure7_A_prime's host and base with three layers (nh = 1.35, rho_d = 0.5)",
     {"preset": "figure7_A_prime", "layers": 3}),
)


def _cpu_seconds() -> float:
    """CPU seconds of this process and of its finished children (the position-free walk's workers)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def run_position_free_bench(as_json: bool = False, target: float = POSITION_FREE_TARGET,
                            budget_s: float = 4.0 * POSITION_FREE_GOAL_S, samples: int = 8192) -> list[dict]:
    """
    ``bragg-explorer bench --position-free``: the wall-clock time the position-free reference
    (:class:`explorer.physics.position_free.PositionFree`) takes for the directional albedo at the 9 angles of
    :data:`POSITION_FREE_THETA` to a standard error of ``target`` in every channel (progressive rounds of
    ``samples`` paths per angle, stopped at the target or after ``budget_s``), per configuration of
    :data:`POSITION_FREE_CASES`; the layer tables' build time apart.
    """
    from explorer.materials.models import model_for
    from explorer.materials.presets import presets_for
    from explorer.physics.position_free import PositionFree

    material = load_material(SHADER_DIR / "bragg_stack.brd")
    rows = []
    for name, spec in POSITION_FREE_CASES:
        spec = dict(spec)
        preset = spec.pop("preset", None)
        overrides = {**(presets_for(material.path).get(preset).values if preset else {}), **spec}
        start = time.perf_counter()
        model = model_for(material, material.resolve(overrides))
        tables_s = time.perf_counter() - start
        _progress(f"bench --position-free: {name}")
        cpu = _cpu_seconds()
        result = PositionFree(model.stack, model.tables).albedo(
            POSITION_FREE_THETA, samples=samples, seed=0, target_stderr=target, max_seconds=budget_s)
        cpu = _cpu_seconds() - cpu
        rows.append({
            "configuration": name, "values": overrides, "theta_deg": list(POSITION_FREE_THETA),
            "rgb": result.value.tolist(), "stderr": result.stderr.tolist(), "max_stderr": float(result.stderr.max()),
            "paths_per_angle": result.paths, "seconds": result.seconds, "cpu_seconds": cpu, "tables_seconds": tables_s,
            "target_stderr": target, "goal_seconds": POSITION_FREE_GOAL_S,
        })
    if as_json:
        print(json.dumps(rows, indent=2))
        return rows
    print(f"position-free directional albedo, {len(POSITION_FREE_THETA)} angles (0-80 deg), to a standard error of {target:g} per channel")
    print(f"{'configuration':<78} {'paths/angle':>11} {'max stderr':>10} {'seconds':>8} {'CPU s':>6}  goal")
    for row in rows:
        ok = row["max_stderr"] <= target and row["seconds"] <= POSITION_FREE_GOAL_S
        print(f"{row['configuration']:<78} {row['paths_per_angle']:>11} {row['max_stderr']:>10.2e} {row['seconds']:>8.1f} "
              f"{row['cpu_seconds']:>6.1f}  {'met' if ok else 'missed'} (<= {POSITION_FREE_GOAL_S:g} s wall)")
    return rows
# --------------------------------------------------------------------------------------------------
# bench --tables: host table rebuilds and the tabulated method's per-pixel cost (issue 22)

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
    mirror_material = load_material(SHADER_DIR / "bragg_mirror.brd")
    schlick_material = load_material(SHADER_DIR / "schlick_fresnel.brd")
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


# --------------------------------------------------------------------------------------------------
# bench --scaling: how the table and the shading cost grow (issue 22)

SCALING_N = (1, 2, 5, 10, 20, 50, 100, 200, 300, 500, 1000)
#: Entries (angles) of the converged table computed at once: its first size is 65.
SCALING_ANGLES = (17, 33, 65, 129, 257, 513)
SCALING_SPHERES = (128, 256, 512, 1024, 2048)


def _converged_rule_rgb(cos_theta, mirror: bragg.BraggMirror) -> np.ndarray:
    """The converged reference's own rule (Yeh's R sampled from its fringe floor), as the tables used before."""
    spectra, _ = bragg.converged_reflectance_spectra(cos_theta, mirror, substeps_max=bragg.TABLE_MAX_SUBSTEPS)
    return colorimetry.spectrum_to_rgb(spectra)


def scaling_study(repeats: int = 3, renderer=None) -> dict:
    """
    Medians (ms, interleaved repeats after a warm-up; wall-clock and CPU time) of: the converged table
    (:func:`explorer.physics.bragg.tabulated_rgb_table`, Lambda moved each round) and, for comparison, the
    converged reference's own rule at the table's 65 first angles, against N; the table's node function at
    :data:`SCALING_ANGLES` angles (N = 20 and 1000); frame times of the tabulated method and of Schlick's
    Fresnel on spheres of :data:`SCALING_SPHERES` pixels a side (GL; ``renderer``, a new one by default).
    Lambda = 500 nm, n1 = 1, n2 = 1.5, delta = 0.5.
    """
    from explorer.gpu import Renderer

    document: dict = {"repeats": repeats}
    times: dict = {}
    first = np.linspace(0.0, 1.0, bragg.TABLE_FIRST_SIZE)
    for round_ in range(repeats + 1):
        Lambda = TABLES_MIRROR["Lambda"] + TABLES_LAMBDA_STEP * (round_ + 1)
        for N in SCALING_N:
            mirror = bragg.BraggMirror(**{**TABLES_MIRROR, "Lambda": Lambda}, N=N)
            measured = [_timed_ms(lambda: bragg.tabulated_rgb_table(mirror)), _timed_ms(lambda: _converged_rule_rgb(first, mirror)),
                        _timed_ms(lambda: bragg._converged_rgb(first, mirror))]
            if round_:
                for key, value in zip(("table", "rule", "nodes"), measured):
                    times.setdefault((key, N), []).append(value)
        _progress(f"bench --scaling: table against N, round {round_}/{repeats}")
    for round_ in range(repeats + 1):
        for N in (20, 1000):
            for n in SCALING_ANGLES:
                measured = _timed_ms(lambda: bragg._converged_rgb(np.linspace(0.0, 1.0, n), bragg.BraggMirror(**TABLES_MIRROR, N=N)))
                if round_:
                    times.setdefault(("angles", N, n), []).append(measured)
        _progress(f"bench --scaling: table against its size, round {round_}/{repeats}")
    renderer = Renderer() if renderer is None else renderer
    mirror_material = load_material(SHADER_DIR / "bragg_mirror.brd")
    schlick_material = load_material(SHADER_DIR / "schlick_fresnel.brd")
    cases = [("tabulated", mirror_material, mirror_material.resolve({**TABLES_MIRROR, "N": 20, "method": int(BraggMethod.TABULATED)})),
             ("schlick", schlick_material, schlick_material.resolve({}))]
    for _, material, values in cases:
        renderer.time_frame(material, values, "sphere", 16, 16)
    for round_ in range(repeats + 1):
        for size in SCALING_SPHERES:
            for name, material, values in cases:
                measured = _timed_frame(renderer, material, values, size)
                if round_:
                    times.setdefault((name, size), []).append(measured)
        _progress(f"bench --scaling: spheres, round {round_}/{repeats}")
    wall, cpu = _medians(times)
    document["N"] = [{"N": N, "table_ms": wall[("table", N)], "table_cpu_ms": cpu[("table", N)],
                      "table_rule_65_ms": wall[("nodes", N)], "table_rule_65_cpu_ms": cpu[("nodes", N)],
                      "reference_rule_65_ms": wall[("rule", N)], "reference_rule_65_cpu_ms": cpu[("rule", N)]} for N in SCALING_N]
    document["angles"] = [{"N": N, "angles": n, "wavelengths": colorimetry.WAVELENGTHS.size, "ms": wall[("angles", N, n)],
                           "cpu_ms": cpu[("angles", N, n)]} for N in (20, 1000) for n in SCALING_ANGLES]
    document["device"] = renderer.ctx.info.get("GL_RENDERER", "unknown")
    document["spheres"] = [{"size": size, **{name: wall[(name, size)] for name, _, _ in cases},
                            **{f"{name}_cpu": cpu[(name, size)] for name, _, _ in cases}} for size in SCALING_SPHERES]
    return document


def plot_scaling(document: dict, path: Path) -> None:
    """The three curves of :func:`scaling_study` (log-log), as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, 3, figsize=(14, 4))
    rows = document["N"]
    axes[0].loglog([r["N"] for r in rows], [r["table_cpu_ms"] for r in rows], "o-", label="converged table, refined")
    axes[0].loglog([r["N"] for r in rows], [r["table_rule_65_cpu_ms"] for r in rows], "^-", label="its rule (windowed), 65 angles")
    axes[0].loglog([r["N"] for r in rows], [r["reference_rule_65_cpu_ms"] for r in rows], "s--", label="reference's rule, 65 angles")
    axes[0].set(xlabel="N (cells)", ylabel="CPU ms", title="Table rebuild against N (Λ = 500 nm)")
    for N in sorted({r["N"] for r in document["angles"]}):
        rows = [r for r in document["angles"] if r["N"] == N]
        axes[1].loglog([r["angles"] for r in rows], [r["cpu_ms"] for r in rows], "o-", label=f"N = {N}")
    axes[1].set(xlabel="angles (× 471 wavelengths)", ylabel="CPU ms", title="Converged colours against table size")
    rows = document["spheres"]
    for name in ("tabulated", "schlick"):
        axes[2].loglog([r["size"] ** 2 for r in rows], [r[f"{name}_cpu"] for r in rows], "o-", label=name)
    axes[2].set(xlabel="pixels", ylabel="CPU ms / frame", title=f"Sphere frame ({document['device'][:24]})")
    from matplotlib.ticker import LogLocator, NullFormatter

    for axis in axes:
        axis.xaxis.set_minor_formatter(NullFormatter())
        axis.xaxis.set_major_locator(LogLocator(base=10.0, numticks=6))
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=8)
    figure.tight_layout()
    # Atomically: a temporary file beside the plot, renamed over it.
    import os
    import tempfile

    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".png", dir=path.parent)
    try:
        with os.fdopen(handle, "wb") as stream:
            figure.savefig(stream, dpi=110, format="png")
        os.replace(temporary, path)
    finally:
        Path(temporary).unlink(missing_ok=True)
        plt.close(figure)


def run_scaling_bench(as_json: bool = False, repeats: int = 3, plot: Path | None = None, renderer=None) -> dict:
    """``bragg-explorer bench --scaling [--plot PNG]``: :func:`scaling_study`, printed (and plotted)."""
    if plot is not None:
        from explorer.views.images import check_output

        check_output(plot)  # a bad path fails now, not after the study
    document = scaling_study(repeats, renderer)
    if plot is not None:
        plot_scaling(document, plot)
        _progress(f"bench --scaling: wrote {plot}")
    if as_json:
        print(json.dumps(document, indent=2))
        return document
    print(f"Converged table against N (medians of {repeats} interleaved repeats; wall-clock / CPU time):")
    for r in document["N"]:
        print(f"  N = {r['N']:>4}: table {r['table_ms']:8.1f} / {r['table_cpu_ms']:7.1f} ms   at 65 angles: its rule "
              f"{r['table_rule_65_ms']:8.1f} / {r['table_rule_65_cpu_ms']:7.1f} ms, the reference's "
              f"{r['reference_rule_65_ms']:8.1f} / {r['reference_rule_65_cpu_ms']:7.1f} ms")
    print("Converged colours against the number of angles (471 wavelengths each):")
    for r in document["angles"]:
        print(f"  N = {r['N']:>4}, {r['angles']:>4} angles: {r['ms']:8.1f} / {r['cpu_ms']:7.1f} ms")
    print(f"Sphere frame times on {document['device']} (wall-clock / CPU time):")
    for r in document["spheres"]:
        print(f"  {r['size']:>4}^2: tabulated {r['tabulated']:8.2f} / {r['tabulated_cpu']:7.2f} ms   schlick {r['schlick']:8.2f} / "
              f"{r['schlick_cpu']:7.2f} ms   CPU x{r['tabulated_cpu'] / r['schlick_cpu']:.2f}")
    return document
