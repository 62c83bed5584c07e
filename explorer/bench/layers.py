"""
``bench --layers``: rough layers' host-table timings and the slice view's accuracy, and the layered stacks' study.
"""

from __future__ import annotations

import json
import time

import numpy as np

from explorer.bench.common import _progress
from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.physics import colorimetry
from explorer.resources import SHADER_DIR
from explorer.materials.models import BraggLayerModel, BraggStackModel

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

    material = load_material(SHADER_DIR / f"{BraggLayerModel.name}.brd")

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
    _progress(f"bench --layers: {BraggStackModel.name}.brd, Figure 7's presets and Table 3's green area")
    document = {
        "timings": {**timings, "goal_ms": LAYER_GOALS, "paper_ms": LAYER_PAPER},
        "slice": {"configuration": {k: v for k, v in FIGURE8_LAYER.items() if k != "s"},
                  "luminance_threshold": SLICE_LUMINANCE_THRESHOLD, "rows": accuracy},
        "stack": stack_study(repeats=max(repeats // 2, 1)),
    }
    if markdown and not as_json:
        from explorer.bench.markdown_tables import layers_markdown

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
    from explorer.gpu import Renderer
    from explorer.materials.models import BraggStackModel, _layer_tables
    from explorer.materials.presets import load_presets
    from explorer.physics import layered

    preset_file = load_presets(SHADER_DIR / "presets" / f"{BraggStackModel.name}.toml")
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
    lines += ["", f"slice view {rows[0]['size']}x{rows[0]['size']} (numpy twin of {BraggLayerModel.name}.brd, Λ = 500 nm, δ = 0.5, "
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
        lines += ["", f"{BraggStackModel.name}.brd (Eq. 34, 471 wavelengths per pixel): host table rebuild (all layers), GL lit frame "
                  f"{stack[0]['size']}x{stack[0]['size']} (this machine's renderer), and ΔE2000 of the tabulated R_λ (Model-LUT) "
                  f"against Yeh's R_λ at the exact half-vector angle (Model), median / max over random pairs with Y > "
                  f"{SLICE_LUMINANCE_THRESHOLD:g}", ""]
        header = f"{'preset':<26}{'layers':>7}{'tables':>11}{'frame':>11}{'pairs':>7}{'LUT ΔE2000':>16}"
        lines += [header, "-" * len(header)]
        for r in stack:
            lines.append(f"{r['preset']:<26}{r['layers']:>7}{r['tables_ms']:>8.1f} ms{r['frame_ms']:>8.0f} ms{r['pairs']:>7}"
                         f"{r['lut_dE_median']:>9.2f} / {r['lut_dE_max']:<5.2f}")
    return "\n".join(lines)
