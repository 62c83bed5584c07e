"""
Where the single-reflection model holds: Eq. 34 (plus the coating's Dirac reflection) against the
position-free reference of Section 4.2 (every bounce), for the paper's layered presets of
``shaders/presets/bragg_stack.toml`` (Figures 1, 7, 10-12 and Table 3 / Figure 9).

Per preset: the directional albedo at :data:`THETA` by both (single reflection: the numpy quadrature of
:func:`explorer.views.albedo.albedo_numpy`; reference: :meth:`explorer.physics.position_free.PositionFree.albedo`),
their ΔE2000 (colour-science, through :func:`explorer.physics.colorimetry.delta_E_2000`) and luminance
difference; and the BRDF in the plane of incidence (``theta_i`` by ``theta_o``, ``o`` on the mirror side
for positive ``theta_o``) by both, shown as ``pi f`` with its ΔE2000 map, one PNG per preset.

Regenerate (about 10 to 30 minutes on 2 cores)::

    python3 -m explorer.dev.layered_validation            # docs/layered_validation.json, docs/figures/layered_validation/*.png
    python3 -m explorer.dev.layered_validation --table    # the Markdown table of docs/layered_validation.md from the JSON

References
----------
Fourneau, Pacanowski, Barla (2024), Eq. 34 and Section 4.2.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from explorer.resources import SOURCE_ROOT, require_checkout

#: Incidence angles (degrees) of the albedo comparison.
THETA = (0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0)
#: The BRDF maps: theta_i rows and signed theta_o columns in the plane of incidence (degrees).
MAP_THETA_I = np.arange(0.0, 86.0, 5.0)
MAP_THETA_O = np.arange(-85.0, 86.0, 5.0)
#: Paths per albedo angle and per BRDF cell.
ALBEDO_SAMPLES = 16384
MAP_SPP = 256
#: The presets compared: the paper's layered figures (prefixes of preset names).
PREFIXES = ("figure1_", "figure7_", "figure10_", "figure11_", "figure12_", "table3_")
#: Cells of the BRDF maps counted in their median ΔE2000: pi f cos theta_i of the reference above this.
MAP_LUMINANCE_FLOOR = 0.01
DOCS = SOURCE_ROOT / "docs"
FIGURES = DOCS / "figures" / "layered_validation"
RESULTS = DOCS / "layered_validation.json"
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
#: What the JSON leaves out (the maps: megabytes; the figures show them).
MAP_KEYS = ("map_single", "map_reference", "map_reference_stderr")


def _write_atomic(path: Path, write) -> None:
    """``write(temporary)`` then the rename (:func:`explorer.files.atomic_output`: mode 0644 under the usual umask)."""
    from explorer.files import atomic_output

    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(path) as temporary:
        write(str(temporary))


def plane_directions(theta_i_deg, theta_o_deg) -> tuple[np.ndarray, np.ndarray]:
    """Unit ``i`` (azimuth 0) and ``o`` (azimuth pi for positive ``theta_o``: the mirror side) on a grid."""
    ti, to = np.meshgrid(np.radians(theta_i_deg), np.radians(theta_o_deg), indexing="ij")
    i = np.stack([np.sin(ti), 0.0 * ti, np.cos(ti)], axis=-1)
    o = np.stack([-np.sin(to), 0.0 * to, np.cos(to)], axis=-1)
    return i.reshape(-1, 3), o.reshape(-1, 3)


def compare_preset(name: str, samples: int = ALBEDO_SAMPLES, spp: int = MAP_SPP, seed: int = 0) -> dict:
    """Single reflection against position-free for one preset of bragg_stack.brd (see the module docstring)."""
    from explorer.materials.brd import load_material
    from explorer.materials.models import model_for
    from explorer.materials.presets import presets_for
    from explorer.physics import colorimetry, layered
    from explorer.physics.position_free import PositionFree
    from explorer.materials.models import BraggStackModel
    from explorer.materials.twins import shipped_file
    from explorer.views.albedo import albedo_numpy

    material = load_material(shipped_file(BraggStackModel))
    preset = presets_for(material.path).get(name)
    model = model_for(material, material.resolve(preset.values))
    walker = PositionFree(model.stack, model.tables)
    start = time.perf_counter()
    single = albedo_numpy(model, THETA)
    reference = walker.albedo(THETA, samples=samples, seed=seed)
    dE = colorimetry.delta_E_2000(reference.value, single)
    i, o = plane_directions(MAP_THETA_I, MAP_THETA_O)
    f_single = layered.single_reflection_brdf(model.stack, i, o, model.tables)
    f_reference = walker.brdf(i, o, samples=spp, seed=seed + 1)
    shape = (MAP_THETA_I.size, MAP_THETA_O.size, 3)
    # pi f cos theta_i: the radiance toward o under a unit irradiance from i, relative to a white Lambertian.
    cos_i = i[:, 2:3]
    map_single = (np.pi * f_single * cos_i).reshape(shape)
    map_reference = (np.pi * f_reference.value * cos_i).reshape(shape)
    map_dE = colorimetry.delta_E_2000(map_reference, map_single)
    lit = map_reference @ LUMINANCE > MAP_LUMINANCE_FLOOR
    return {
        "preset": name, "figure": preset.figure, "layers": len(model.stack.layers), "nh": model.stack.n1,
        "rho_d": list(model.stack.rho_d), "alphas": [layer.alpha for layer in model.stack.layers],
        "theta_deg": list(THETA), "single_rgb": single.tolist(), "reference_rgb": reference.value.tolist(),
        "reference_stderr": reference.stderr.tolist(), "delta_E": dE.tolist(),
        "single_Y": (single @ LUMINANCE).tolist(), "reference_Y": (reference.value @ LUMINANCE).tolist(),
        "map_theta_i": MAP_THETA_I.tolist(), "map_theta_o": MAP_THETA_O.tolist(),
        "map_single": map_single.tolist(), "map_reference": map_reference.tolist(),
        "map_reference_stderr": (np.pi * f_reference.stderr * cos_i).reshape(shape).tolist(),
        "map_delta_E_median": float(np.median(map_dE[lit])) if lit.any() else 0.0,
        "map_delta_E_p90": float(np.percentile(map_dE[lit], 90)) if lit.any() else 0.0,
        "paths_per_angle": reference.paths, "spp": spp, "seconds": time.perf_counter() - start,
    }


def plot_preset(row: dict, path: Path) -> None:
    """One preset's figure: both maps of pi f cos theta_i (sRGB), their ΔE2000 map, and the albedo's Y over theta."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from explorer.physics import colorimetry

    single, reference = np.asarray(row["map_single"]), np.asarray(row["map_reference"])
    dE = colorimetry.delta_E_2000(reference, single)
    peak = max(float(np.percentile(reference @ LUMINANCE, 99)), 1e-3)
    extent = (row["map_theta_o"][0] - 2.5, row["map_theta_o"][-1] + 2.5, row["map_theta_i"][-1] + 2.5, row["map_theta_i"][0] - 2.5)
    fig, axes = plt.subplots(1, 4, figsize=(13.0, 3.1), dpi=72)
    for ax, image, title in ((axes[0], single, "single reflection (Eq. 34)"), (axes[1], reference, "position-free")):
        ax.imshow(colorimetry.encode_srgb8(image / peak), extent=extent, aspect="auto", interpolation="nearest")
        ax.set_title(f"{title}\nπ f cos θi / {peak:.2g}", fontsize=8)
    shown = axes[2].imshow(dE, extent=extent, aspect="auto", cmap="magma", vmin=0.0, vmax=max(5.0, float(np.percentile(dE, 99))),
                           interpolation="nearest")
    axes[2].set_title("ΔE2000", fontsize=8)
    fig.colorbar(shown, ax=axes[2], fraction=0.05)
    for ax in axes[:3]:
        ax.set_xlabel("θo (deg; > 0 mirror side)", fontsize=7)
        ax.set_ylabel("θi (deg)", fontsize=7)
        ax.tick_params(labelsize=6)
    theta = np.asarray(row["theta_deg"])
    err = np.asarray(row["reference_stderr"]) @ np.abs(LUMINANCE)
    axes[3].errorbar(theta, row["reference_Y"], yerr=3 * err, fmt="o-", ms=3, label="position-free (±3σ)")
    axes[3].plot(theta, row["single_Y"], "s--", ms=3, label="single reflection")
    twin = axes[3].twinx()
    twin.plot(theta, row["delta_E"], "k:", lw=1)
    twin.set_ylabel("albedo ΔE2000 (dotted)", fontsize=7)
    twin.tick_params(labelsize=6)
    axes[3].set_xlabel("θi (deg)", fontsize=7)
    axes[3].set_ylabel("directional albedo Y", fontsize=7)
    axes[3].tick_params(labelsize=6)
    axes[3].legend(fontsize=6, loc="best")
    fig.suptitle(f"{row['preset']}: {row['figure']}", fontsize=9)
    fig.tight_layout()
    _write_atomic(path, lambda p: fig.savefig(p, format="png"))
    plt.close(fig)


def preset_names(prefixes=PREFIXES) -> list[str]:
    from explorer.materials.presets import presets_for
    from explorer.materials.models import BraggStackModel
    from explorer.materials.twins import shipped_file

    return [name for name in presets_for(shipped_file(BraggStackModel)).presets if name.startswith(tuple(prefixes))]


def summary(row: dict) -> dict:
    """A preset's table row: albedo ΔE2000 (median, max), the largest luminance gap, the map's ΔE2000."""
    gap = np.asarray(row["reference_Y"]) - np.asarray(row["single_Y"])
    k = int(np.argmax(np.abs(gap)))
    err = float(np.max(np.asarray(row["reference_stderr"]) @ np.abs(LUMINANCE)))
    return {
        "preset": row["preset"], "layers": row["layers"], "nh": row["nh"], "rho_d": row["rho_d"],
        "dE_median": float(np.median(row["delta_E"])), "dE_max": float(np.max(row["delta_E"])),
        "dY": float(gap[k]), "dY_relative": float(gap[k] / max(row["reference_Y"][k], 1e-6)), "dY_theta": row["theta_deg"][k],
        "Y_stderr": err, "single_Y_max": float(np.max(row["single_Y"])), "reference_Y_max": float(np.max(row["reference_Y"])),
        "map_dE_median": row["map_delta_E_median"], "map_dE_p90": row["map_delta_E_p90"],
    }


def markdown_table(rows: list[dict]) -> str:
    lines = [
        "| preset | layers | nh | rho_d | albedo ΔE2000 median / max | largest ΔY (PF − SR) at θ | ±σ(Y) | max Y SR / PF | BRDF map ΔE2000 median / p90 |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        s = summary(row)
        rho = s["rho_d"][0] if len(set(s["rho_d"])) == 1 else "(" + ", ".join(f"{x:g}" for x in s["rho_d"]) + ")"
        lines.append(
            f"| {s['preset']} | {s['layers']} | {s['nh']:g} | {rho} | {s['dE_median']:.2f} / {s['dE_max']:.2f} | "
            f"{s['dY']:+.4f} ({100 * s['dY_relative']:+.1f} %) at {s['dY_theta']:g}° | {s['Y_stderr']:.4f} | "
            f"{s['single_Y_max']:.3f} / {s['reference_Y_max']:.3f} | {s['map_dE_median']:.2f} / {s['map_dE_p90']:.2f} |"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python3 -m explorer.dev.layered_validation", description=__doc__.split("\n\n")[0])
    parser.add_argument("--presets", nargs="*", help="preset names (default: the paper's layered figures)")
    parser.add_argument("--samples", type=int, default=ALBEDO_SAMPLES, help="paths per albedo angle")
    parser.add_argument("--spp", type=int, default=MAP_SPP, help="paths per BRDF map cell")
    parser.add_argument("--table", action="store_true", help="print the Markdown table of the saved results and stop")
    args = parser.parse_args(argv)
    require_checkout("python -m explorer.dev.layered_validation")
    if args.table:
        if not RESULTS.is_file():
            print(f"layered_validation: error: no {RESULTS}; run without --table first", file=sys.stderr)
            return 1
        print(markdown_table(json.loads(RESULTS.read_text(encoding="utf-8"))))
        return 0
    names = args.presets or preset_names()
    known = set(preset_names(("",)))
    unknown = [n for n in names if n not in known]
    if unknown:
        print(f"layered_validation: error: unknown preset {unknown[0]!r}", file=sys.stderr)
        return 1
    rows = json.loads(RESULTS.read_text(encoding="utf-8")) if RESULTS.is_file() else []
    rows = [r for r in rows if r["preset"] not in names]
    for k, name in enumerate(names, start=1):
        row = compare_preset(name, args.samples, args.spp)
        plot_preset(row, FIGURES / f"{name}.png")
        rows.append({key: value for key, value in row.items() if key not in MAP_KEYS})  # the maps live in the figures
        s = summary(row)
        print(f"[{k}/{len(names)}] {name}: albedo dE2000 median {s['dE_median']:.2f} max {s['dE_max']:.2f}, "
              f"dY {s['dY']:+.4f} at {s['dY_theta']:g} deg, map dE median {s['map_dE_median']:.2f} ({row['seconds']:.0f} s)",
              file=sys.stderr, flush=True)
        order = {n: i for i, n in enumerate(preset_names(("",)))}
        rows.sort(key=lambda r: order.get(r["preset"], 1 << 30))
        _write_atomic(RESULTS, lambda p: Path(p).write_text(json.dumps(rows), encoding="utf-8"))
    print(markdown_table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
