"""
``bragg-explorer accuracy``: ΔE2000 of the approximations on the Figure 4 grid for s = 2..8, both readings of the mode
numbering and both variants; the plot and the strips.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from explorer.bench.common import FIGURE4_DELTAS, FIGURE4_LAMBDAS, STRIP_SUFFIXES, THETA_DEGREES, _progress, save_figure
from explorer.files import atomic_output
from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.physics import bragg, colorimetry
from explorer.resources import SHADER_DIR
from explorer.materials.models import BraggMirrorModel

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
        from explorer.bench.markdown_tables import accuracy_markdown

        print(accuracy_markdown(rows, FIGURE4_LAMBDAS, FIGURE4_DELTAS))
    return rows


def figure4_strips(path: Path, width: int = 360, strip: int = 14) -> None:
    """
    The colour strips of Figure 4, rendered by the GPU shaders: per mirror (rows: Λ; columns: δ),
    the spectral reference, the basic, subdivided (s = 3) and improved (s = 3) approximations.
    """
    from PIL import Image

    from explorer.gpu import Renderer
    from explorer.physics.colorimetry import encode_srgb8

    renderer = Renderer()
    material = load_material(SHADER_DIR / f"{BraggMirrorModel.name}.brd")
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
