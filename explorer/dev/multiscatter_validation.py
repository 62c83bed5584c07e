"""
Multiple scattering on rough Bragg layers: single scattering (Eq. 34 as published) and the compensated
model (:mod:`explorer.physics.multiscatter_stack`, ``bragg_stack.brd`` with ``multiple_scattering``), each
against the microsurface random walk (:mod:`explorer.physics.microsurface` inside the position-free
reference, every bounce among every layer's facets), for shipped layer and stack presets with every
layer's roughness set to ``alpha``.

Per preset and ``alpha``: the directional albedo at :data:`THETA` by the three (the models by the numpy
quadrature of :func:`explorer.views.albedo.albedo_numpy`), the luminance gap ``Y(model) / Y(walk) - 1``
and ΔE2000 (colour-science, through :func:`explorer.physics.colorimetry.delta_E_2000`) per angle.

Regenerate (about 35 minutes of wall time on the shared 2 cores at load ~10)::

    python3 -m explorer.dev.multiscatter_validation           # docs/multiscatter_validation.json, docs/figures/multiscatter_validation.png
    python3 -m explorer.dev.multiscatter_validation --table   # the Markdown table of docs/layered_validation.md from the JSON
    python3 -m explorer.dev.multiscatter_validation --presets figure7_A --alphas 1.0   # only these rows; the others are kept
    python3 -m explorer.dev.multiscatter_validation --rescore   # the models again against the stored walks (minutes)

References
----------
Heitz, Hanika, d'Eon, Dachsbacher (2016), the random walk; Kulla & Conty (2017), the compensation's form.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from explorer.resources import SOURCE_ROOT, require_checkout

#: Incidence angles (degrees): theta <= 70.
THETA = (0.0, 20.0, 40.0, 55.0, 70.0)
ALPHAS = (0.2, 0.4, 0.5, 0.6, 0.7, 0.8, 1.0)
#: Three one-layer presets over a black base, a two-layer stack over a black base, a layer over a grey base.
PRESETS = ("figure1_left_alpha04", "figure1_right_alpha04", "figure7_A", "figure1_stacked_pair", "figure7_A_on_base")
SAMPLES = 131072
DOCS = SOURCE_ROOT / "docs"
RESULTS = DOCS / "multiscatter_validation.json"
FIGURE = DOCS / "figures" / "multiscatter_validation.png"
PAGE = DOCS / "layered_validation.md"
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
BEGIN, END = "<!-- multiscatter:begin -->", "<!-- multiscatter:end -->"


def compare(name: str, alpha: float, samples: int = SAMPLES, seed: int = 0, stored: dict | None = None) -> dict:
    """
    Single scattering and the compensated model against the random walk for preset ``name`` at ``alpha``;
    with ``stored`` (a row of the JSON), the models against that row's walk, which is not run again.
    """
    from explorer.materials.brd import load_material
    from explorer.materials.models import model_for
    from explorer.materials.presets import presets_for
    from explorer.physics import colorimetry
    from explorer.physics.position_free import PositionFree
    from explorer.materials.models import BraggStackModel
    from explorer.materials.twins import shipped_file
    from explorer.views.albedo import albedo_numpy

    material = load_material(shipped_file(BraggStackModel))
    values = dict(material.resolve(presets_for(material.path).get(name).values))
    for k in range(1, 4):
        values[f"alpha_{k}"] = float(alpha)
    compensated_model = model_for(material, {**values, "multiple_scattering": True})
    compensated_model.full_compensation = True  # the whole lobe at every alpha: what the fade leaves out at alpha <= 0.4
    single_model = model_for(material, {**values, "multiple_scattering": False})
    if stored is None:
        start = time.perf_counter()
        reference = PositionFree(compensated_model.stack, compensated_model.tables, "walk").albedo(THETA, samples, seed)
        seconds = time.perf_counter() - start
        row = {"preset": name, "alpha": alpha, "layers": len(compensated_model.stack.layers),
               "rho_d": list(compensated_model.stack.rho_d), "theta_deg": list(THETA), "reference_rgb": reference.value.tolist(),
               "reference_stderr": reference.stderr.tolist(),
               "reference_Y_stderr": np.sqrt(reference.stderr**2 @ LUMINANCE**2).tolist(), "reference_seconds": seconds}
    else:
        row = {key: value for key, value in stored.items() if not key.startswith(("single_", "compensated_"))}
    reference_rgb = np.asarray(row["reference_rgb"])
    single, compensated = albedo_numpy(single_model, THETA), albedo_numpy(compensated_model, THETA)
    Y = reference_rgb @ LUMINANCE
    for key, rgb in (("single", single), ("compensated", compensated)):
        row[f"{key}_rgb"] = rgb.tolist()
        row[f"{key}_dY"] = (rgb @ LUMINANCE / Y - 1.0).tolist()
        row[f"{key}_dE"] = colorimetry.delta_E_2000(reference_rgb, rgb).tolist()
    return row


def merged(rows: list[dict]) -> list[dict]:
    """``rows`` in place of the stored rows of the same preset and alpha, the others kept, in the default order."""
    stored = json.loads(RESULTS.read_text(encoding="utf-8")) if RESULTS.exists() else []
    by_key = {(r["preset"], float(r["alpha"])): r for r in stored}
    by_key.update({(r["preset"], float(r["alpha"])): r for r in rows})
    rank = {name: k for k, name in enumerate(PRESETS)}
    return sorted(by_key.values(), key=lambda r: (rank.get(r["preset"], len(rank)), r["preset"], float(r["alpha"])))


def table(rows: list[dict]) -> str:
    """The Markdown table: per preset and alpha, max |ΔY| and median ΔE2000 over theta, single and compensated."""
    lines = ["| preset | layers | ρ | α | walk Y at 0° / 70° (±σ) | single: max \\|ΔY\\| | single: median ΔE | compensated: max \\|ΔY\\| | compensated: median ΔE |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        Y = np.asarray(r["reference_rgb"]) @ LUMINANCE
        s = np.asarray(r["reference_Y_stderr"])
        lines.append(
            f"| `{r['preset']}` | {r['layers']} | {r['rho_d'][0]:g} | {r['alpha']:g} | {Y[0]:.3f} / {Y[-1]:.3f} (±{s.max():.3f}) "
            f"| {100 * np.abs(r['single_dY']).max():.1f} % | {np.median(r['single_dE']):.2f} "
            f"| {100 * np.abs(r['compensated_dY']).max():.1f} % | {np.median(r['compensated_dE']):.2f} |")
    return "\n".join(lines)


def figure(rows: list[dict], path) -> None:
    """Median ΔE2000 and max |ΔY| against alpha, per preset: single scattering dashed, compensated solid."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for k, name in enumerate(dict.fromkeys(r["preset"] for r in rows)):
        mine = [r for r in rows if r["preset"] == name]
        a = [r["alpha"] for r in mine]
        colour = f"C{k}"
        for key, style in (("single", "--"), ("compensated", "-")):
            axes[0].plot(a, [np.median(r[f"{key}_dE"]) for r in mine], style, color=colour, marker="o", ms=3,
                         label=f"{name} ({key})")
            axes[1].plot(a, [100 * np.abs(r[f"{key}_dY"]).max() for r in mine], style, color=colour, marker="o", ms=3)
    axes[0].set(xlabel="α", ylabel="median ΔE2000 vs random walk (θ ≤ 70°)", yscale="log")
    axes[1].set(xlabel="α", ylabel="max |ΔY| vs random walk (%)", yscale="log")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=6)
    fig.tight_layout()
    from explorer.files import atomic_output

    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(path) as temporary:
        fig.savefig(temporary, dpi=110, format="png")
    plt.close(fig)


def write_page(rows: list[dict]) -> None:
    """Replace the table between the markers of ``docs/layered_validation.md``."""
    from explorer.files import write_text_atomic

    text = PAGE.read_text(encoding="utf-8")
    start, end = text.index(BEGIN) + len(BEGIN), text.index(END)
    write_text_atomic(PAGE, text[:start] + "\n" + table(rows) + "\n" + text[end:])


def shader_cost(size: int = 256, repeats: int = 7, layers: int = 2) -> dict:
    """
    The lit view's frame time (ms, finish-bounded, median of ``repeats`` interleaved rounds after a warm-up)
    of ``bragg_stack`` with ``layers`` layers, with and without multiple scattering, and their ratio.
    """
    from explorer.gpu import Renderer
    from explorer.materials.brd import load_material
    from explorer.materials.models import BraggStackModel
    from explorer.materials.twins import shipped_file

    material = load_material(shipped_file(BraggStackModel))
    renderer = Renderer()
    cases = {on: material.resolve({"layers": layers, "alpha_1": 0.7, "alpha_2": 0.5, "alpha_3": 0.9, "rho_d": 0.3,
                                   "multiple_scattering": on}) for on in (0, 1)}
    times: dict[int, list[float]] = {0: [], 1: []}
    for round_ in range(repeats + 1):
        for on, values in cases.items():
            ms = renderer.time_frame(material, values, "lit", size, size)
            if round_:
                times[on].append(ms)
    single, compensated = float(np.median(times[0])), float(np.median(times[1]))
    return {"size": size, "layers": layers, "repeats": repeats, "single_ms": single, "compensated_ms": compensated,
            "ratio": compensated / single}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python3 -m explorer.dev.multiscatter_validation", description=__doc__.split("\n\n")[0])
    parser.add_argument("--table", action="store_true", help="rewrite the table of docs/layered_validation.md from the JSON")
    parser.add_argument("--presets", nargs="+", default=list(PRESETS))
    parser.add_argument("--alphas", nargs="+", type=float, default=list(ALPHAS))
    parser.add_argument("--samples", type=int, default=SAMPLES)
    parser.add_argument("--rescore", action="store_true",
                        help="the models again against the stored walks (after a change to the model; the walks are not rerun)")
    parser.add_argument("--cost", action="store_true", help="instead: the shader's cost with and without multiple scattering")
    args = parser.parse_args(argv)
    if args.cost:
        from explorer.materials.models import BraggStackModel

        for layers in (1, 3):
            cost = shader_cost(layers=layers)
            print(f"{BraggStackModel.name} lit view {cost['size']}^2, {layers} layer(s), median of {cost['repeats']} interleaved rounds: "
                  f"single scattering {cost['single_ms']:.1f} ms, compensated {cost['compensated_ms']:.1f} ms, "
                  f"ratio {cost['ratio']:.2f}")
        return 0
    require_checkout("python3 -m explorer.dev.multiscatter_validation")
    from explorer.files import write_text_atomic

    if not args.table:
        rows = []
        stored = {(r["preset"], float(r["alpha"])): r for r in json.loads(RESULTS.read_text(encoding="utf-8"))} if args.rescore else {}
        for name in args.presets:
            for alpha in args.alphas:
                if args.rescore and (name, float(alpha)) not in stored:
                    print(f"{RESULTS}: no stored walk for {name} at alpha {alpha:g}; run it without --rescore", file=sys.stderr)
                    return 2
                rows.append(compare(name, alpha, args.samples, stored=stored.get((name, float(alpha)))))
                r = rows[-1]
                print(f"{name} alpha={alpha:g}: single max|dY| {100 * np.abs(r['single_dY']).max():.1f} % median dE "
                      f"{np.median(r['single_dE']):.2f}; compensated {100 * np.abs(r['compensated_dY']).max():.1f} % "
                      f"{np.median(r['compensated_dE']):.2f}", file=sys.stderr, flush=True)
        rows = merged(rows)
        write_text_atomic(RESULTS, json.dumps(rows, indent=1) + "\n")
        figure(rows, FIGURE)
    rows = json.loads(RESULTS.read_text(encoding="utf-8"))
    write_page(rows)
    print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
