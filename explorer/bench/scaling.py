"""
``bench --scaling``: how the converged table's and the shading's cost grow with ``N``, angles and sphere size.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from explorer.bench.common import _progress
from explorer.bench.tables import TABLES_LAMBDA_STEP, TABLES_MIRROR, _medians, _timed_frame, _timed_ms
from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.physics import bragg, colorimetry
from explorer.resources import SHADER_DIR
from explorer.materials.models import BraggMirrorModel, SchlickFresnelModel

# --------------------------------------------------------------------------------------------------
# bench --scaling: how the table and the shading cost grow

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
                        _timed_ms(lambda: bragg.converged_rgb(first, mirror))]
            if round_:
                for key, value in zip(("table", "rule", "nodes"), measured):
                    times.setdefault((key, N), []).append(value)
        _progress(f"bench --scaling: table against N, round {round_}/{repeats}")
    for round_ in range(repeats + 1):
        for N in (20, 1000):
            for n in SCALING_ANGLES:
                measured = _timed_ms(lambda: bragg.converged_rgb(np.linspace(0.0, 1.0, n), bragg.BraggMirror(**TABLES_MIRROR, N=N)))
                if round_:
                    times.setdefault(("angles", N, n), []).append(measured)
        _progress(f"bench --scaling: table against its size, round {round_}/{repeats}")
    renderer = Renderer() if renderer is None else renderer
    mirror_material = load_material(SHADER_DIR / f"{BraggMirrorModel.name}.brd")
    schlick_material = load_material(SHADER_DIR / f"{SchlickFresnelModel.name}.brd")
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
    from explorer.files import save_figure

    save_figure(figure, path, None, format="png", dpi=110)


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
