"""
The measured documents of ``bench`` and ``accuracy`` as Markdown tables (``--markdown``), the form
``docs/validation.md`` shows them in (written by :mod:`explorer.dev.validation_doc`, not by hand).

Each formatter takes the JSON document its command builds (``run_bench``, ``run_thin_film_bench``,
``run_layers_bench``, ``run_app_bench``, ``figure4_accuracy``) and returns Markdown text; none measures
anything, so they are tested on small synthetic documents.

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. Computer Graphics Forum 43(2). Table 1 (speed-ups), Figure 4 (accuracy grid), Table 2.
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["markdown_table", "parse_markdown_table", "bench_markdown", "thin_film_markdown", "layers_markdown",
           "app_markdown", "accuracy_markdown"]


def _cell(value) -> str:
    # A pipe inside a cell would split it: escape it (GitHub Markdown reads \| as a literal pipe).
    return str(value).replace("|", "\\|").replace("\n", " ")


def markdown_table(header: Sequence[str], rows: Sequence[Sequence]) -> str:
    """A GitHub Markdown table: ``header``, its separator, one line per row (every row as wide as the header)."""
    width = len(header)
    lines = ["| " + " | ".join(_cell(h) for h in header) + " |", "|" + "---|" * width]
    for row in rows:
        if len(row) != width:
            raise ValueError(f"a row has {len(row)} cells, the header {width}")
        lines.append("| " + " | ".join(_cell(c) for c in row) + " |")
    return "\n".join(lines)


def parse_markdown_table(text: str) -> list[list[str]]:
    """
    The first Markdown table in ``text``: its header and rows as lists of cell strings.

    Raises ``ValueError`` when there is none, the separator line is malformed, or a row's width differs.
    """
    lines = [line.strip() for line in text.splitlines()]
    for i in range(len(lines) - 1):
        if lines[i].startswith("|") and lines[i + 1].startswith("|---"):
            break
    else:
        raise ValueError("no Markdown table")

    def cells(line: str) -> list[str]:
        if not (line.startswith("|") and line.endswith("|")):
            raise ValueError(f"not a table line: {line!r}")
        return [c.strip() for c in line[1:-1].replace("\\|", "\0").split("|")]

    header = cells(lines[i])
    separator = cells(lines[i + 1])
    if len(separator) != len(header) or any(set(c) - set("-:") or not c for c in separator):
        raise ValueError(f"bad separator line: {lines[i + 1]!r}")
    table = [header]
    for line in lines[i + 2:]:
        if not line.startswith("|"):
            break
        row = cells(line)
        if len(row) != len(header):
            raise ValueError(f"a row has {len(row)} cells, the header {len(header)}: {line!r}")
        table.append(row)
    return table


#: Table 1's column order (the paper's methods, then ours): a method not listed goes last.
METHOD_ORDER = ("basic", "subdivided", "improved", "tabulated")


def _dE_max(value: float) -> str:
    # One decimal as in the paper's tables, two below 1 where one would print a converged method as 0.0.
    return f"{value:.1f}" if value >= 1 else f"{value:.2f}"


def _method_label(name: str, s) -> str:
    return name if s is None else f"{name} s = {s}"


def bench_markdown(document: dict) -> str:
    """
    ``bench`` (Table 1): per Λ, the reference's frame time, every method's speed-up over it and the
    Schlick floor's time; then each method's median / max ΔE2000 against the converged reference.
    """
    rows = list(document["rows"]) + list(document.get("variants", []))
    lambdas = sorted({r["Lambda"] for r in rows})
    methods: list[tuple[str, object]] = []
    for r in rows:
        key = (r["method"], r["s"])
        if key not in methods and r["method"] not in ("reference", "schlick"):
            methods.append(key)
    methods.sort(key=lambda key: METHOD_ORDER.index(key[0]) if key[0] in METHOD_ORDER else len(METHOD_ORDER))
    by = {(r["Lambda"], r["method"], r["s"]): r for r in rows}

    def reference(Lambda):
        return next(r for r in rows if r["Lambda"] == Lambda and r["method"] == "reference")

    def schlick(Lambda):
        return next((r for r in rows if r["Lambda"] == Lambda and r["method"] == "schlick"), None)

    def ms(value):
        return f"{value / 1e3:.1f} s" if value >= 1e3 else f"{value:.1f} ms"

    size = document["size"]
    speed = []
    for L in lambdas:
        floor = schlick(L)
        speed.append([f"{L} nm", ms(reference(L)["ms"])]
                     + [f"×{by[(L, m, s)]['speedup']:.1f}" if (L, m, s) in by else "" for m, s in methods]
                     + [ms(floor["ms"]) if floor else ""])
    header = ["Λ", "reference"] + [_method_label(m, s) for m, s in methods] + ["Schlick floor"]
    out = [f"Frame time of a {size}² sphere on {document['device']} ({document['repeats']} interleaved repeats, medians): "
           "the reference's time and each method's speed-up over it.", "", markdown_table(header, speed), ""]
    accuracy = []
    for L in lambdas:
        accuracy.append([f"{L} nm"] + [f"{by[(L, m, s)]['dE_median']:.2f} / {_dE_max(by[(L, m, s)]['dE_max'])}"
                                       if (L, m, s) in by and by[(L, m, s)]["dE_median"] is not None else ""
                                       for m, s in [("reference", None), *methods]])
    out += ["Median / max ΔE2000 against the converged spectral reference over θ ∈ [0°, 89.5°] "
            "(reference: the shader's 1-nm sum).", "",
            markdown_table(["Λ", "reference (1-nm sum)"] + [_method_label(m, s) for m, s in methods], accuracy)]
    table_ms = document.get("table_rebuild_ms")
    if table_ms:
        out += ["", "Tabulated table rebuilds (converged, numpy): "
                + ", ".join(f"{v:.0f} ms at Λ = {k} nm" for k, v in table_ms.items()) + "."]
    return "\n".join(out)


def thin_film_markdown(document: dict) -> str:
    """``bench --thin-film``: ΔE2000 per configuration and method, and frame times relative to GGX + Schlick."""
    methods: list[str] = []
    cells: dict[str, dict[str, str]] = {}
    for row in document["accuracy"]:
        if row["method"] not in methods:
            methods.append(row["method"])
        cells.setdefault(row["configuration"], {})[row["method"]] = f"{row['dE_median']:.2g} / {row['dE_max']:.2g}"
    accuracy = [[name] + [row.get(m, "") for m in methods] for name, row in cells.items()]
    timing = [[r["method"], f"{r['ms']:.2f} ms", f"×{r['relative']:.2f}"] for r in document["timing"]]
    size = document["size"]
    return "\n".join([
        "Median / max ΔE2000 against the converged spectral reference over θ ∈ [0°, 89.5°]:", "",
        markdown_table(["configuration", *methods], accuracy), "",
        f"Frame time of a {size}² {document.get('view', 'lit')} sphere (Figure 7 film) on {document['device']} "
        f"({document['repeats']} interleaved repeats, medians), relative to GGX + Schlick:", "",
        markdown_table(["method", "frame", "relative"], timing)])


def layers_markdown(document: dict) -> str:
    """``bench --layers``: host-table timings, the slice view's accuracy and the stacks' study (three tables)."""
    from explorer.materials.models import BraggLayerModel, BraggStackModel

    timings = document["timings"]
    rows = []
    for key, label in (("transmission_filter_ms", "F_α"), ("layer_tables_ms", "layer tables")):
        goal, paper = timings["goal_ms"][key], timings["paper_ms"][key]
        for name, ms in timings[key].items():
            rows.append([f"{label}, {name}", f"{ms:.1f} ms", f"{goal:g} ms", f"{paper:g} ms"])
    out = [f"Host tables: wall-clock medians of {timings['repeats']} interleaved repeats (numpy).", "",
           markdown_table(["table", "this machine", "goal", "paper"], rows), ""]
    study = document["slice"]
    slice_rows = study["rows"]
    names = [n for n in slice_rows[0] if isinstance(slice_rows[0][n], dict) and "dE_median" in slice_rows[0][n]]
    body = [[f"{r['alpha']:g}", str(r["pixels"])] + [f"{r[n]['dE_median']:.2f} / {r[n]['dE_max']:.1f}" for n in names]
            + [f"{r['tabulated']['max_abs']:.3g} / {r['tabulated']['max_relative']:.1e}"] for r in slice_rows]
    size = slice_rows[0]["size"]
    out += [f"Slice view {size}×{size} (numpy twin of `{BraggLayerModel.name}.brd`), median / max ΔE2000 against the converged "
            f"reference over pixels with Y > {study['luminance_threshold']:g}; tabulated: max abs / max relative.", "",
            markdown_table(["α", "pixels", *names, "tabulated"], body)]
    stack = document.get("stack")
    if stack:
        size = stack[0]["size"]
        body = [[r["preset"], str(r["layers"]), f"{r['tables_ms']:.0f} ms", f"{r['frame_ms'] / 1e3:.2f} s", str(r["pairs"]),
                 f"{r['lut_dE_median']:.2f} / {r['lut_dE_max']:.2f}"] for r in stack]
        out += ["", f"`{BraggStackModel.name}.brd`: host table rebuild, GL `lit` frame {size}², and Model-LUT vs Model "
                "(ΔE2000 median / max over random direction pairs).", "",
                markdown_table(["preset", "layers", "tables", f"frame {size}²", "pairs", "Model-LUT vs Model"], body)]
    return "\n".join(out)


def app_markdown(rows: list[dict]) -> str:
    """``bench --app``: per mode and method, frame times while Λ is dragged and what the sphere shows meanwhile; the env mode's first pass."""
    body = [[r.get("mode", "sphere"), f"{r['method']} {r['name']}", f"{r['median_ms']:.1f} ms", f"{r['fps']:.1f}",
             f"{r['sphere_updates_per_s']:.1f}", r["while_dragging"]] for r in rows if r.get("mode") != "env"]
    body += [["env", f"{r['material']} {r['values']}, Λ_1 dragged", f"{r['median_ms']:.1f} ms", f"{r['fps']:.1f}",
              f"{r['sphere_updates_per_s']:.1f}", f"first pass {r['first_pass_ms']:.1f} ms (dragging: {r['drag_first_pass_median_ms']:.1f} ms)"]
             for r in rows if r.get("mode") == "env"]
    return markdown_table(["mode", "method", "median frame", "frames per second", "sphere updates per second",
                           "shown while dragging"], body)


def accuracy_markdown(rows: list[dict], lambdas: Sequence[float], deltas: Sequence[float]) -> str:
    """
    ``accuracy`` (the Figure 4 grid): per variant and mode numbering, median / max ΔE2000 of the basic
    method and s = 2..8 per mirror, and the 1-nm sum's own error against the same converged reference.
    """
    out = []
    one_nm = {(r["Lambda"], r["delta"]): r for r in rows if r["variant"] == "1-nm sum"}
    for variant, numbering in (("paper", "relative"), ("paper", "absolute"), ("improved", "relative")):
        subset = [r for r in rows if r["variant"] == variant and (r["mode_numbering"] == numbering or r["s"] == 0)]
        if not subset:
            continue
        s_values = sorted({r["s"] for r in subset if r["s"] > 0})
        how = "sub-boxes by share of CMF mass" if variant == "improved" else f"mode numbering **{numbering}**"
        body = []
        for Lambda in lambdas:
            for delta in deltas:
                cell = {r["s"]: r for r in subset if r["Lambda"] == int(Lambda) and r["delta"] == delta}
                if not cell:
                    continue
                values = [f"{cell[s]['dE_median']:.2f} / {cell[s]['dE_max']:.1f}" if s in cell else "" for s in [0, *s_values]]
                own = one_nm.get((int(Lambda), delta))
                values.append(f"{own['dE_median']:.2f} / {own['dE_max']:.2f}" if own else "")
                body.append([f"{Lambda:g}", f"{delta:g}", *values])
        out += [f"**{variant}** variant, {how} — median / max ΔE2000 over θ ∈ [0°, 89.5°] against the converged reference", "",
                markdown_table(["Λ (nm)", "δ", "basic", *(f"s = {s}" for s in s_values), "1-nm sum"], body), ""]
    return "\n".join(out)
