"""
``bench --mitsuba``: Mitsuba's frame times per variant beside the GL env view's, and their agreement
(median per-pixel ΔE2000 of Mitsuba against GL), for every built-in material with a plugin.

Each row renders the env view of one material (its defaults, the Bragg ones with the tabulated method)
at ``size``² and ``spp`` samples per pixel: the GL view (:func:`explorer.gpu.env.render_env`), then each
variant (:func:`explorer.mitsuba.scene.render_env_mitsuba`); times are wall-clock seconds of one frame,
the first Mitsuba call per variant (plugin registration, JIT warm-up) and the GL program's compilation
excluded. docs/mitsuba.md holds a table of its output and the command that regenerates it.
"""

from __future__ import annotations

import json
import time
import warnings

from explorer.materials.methods import BraggMethod
import numpy as np

from explorer.materials.twins import capabilities_of
from explorer.mitsuba.bsdfs import plugin_names
from explorer.mitsuba.variants import llvm_works


#: The agreement asked of Mitsuba against GL: median per-pixel ΔE2000 (at 64x64, 1024 spp).
ACCEPTED_DELTA_E = 1.0


def median_delta_e(image: np.ndarray, reference: np.ndarray) -> float:
    """Median ΔE2000 over the pixels the reference covers (linear sRGB, clamped at 0, Lab under D65)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour

    inside = np.abs(reference).sum(axis=-1) > 0

    def lab(rgb):
        return colour.XYZ_to_Lab(colour.sRGB_to_XYZ(np.clip(rgb, 0.0, None), apply_cctf_decoding=False))

    return float(np.median(colour.delta_E(lab(image[inside]), lab(reference[inside]), method="CIE 2000")))


def run_mitsuba_bench(as_json: bool = False, size: int = 64, spp: int = 64, variants=None, materials=None,
                      echo=print) -> list[dict]:
    """Rows of (material, engine, seconds, median ΔE2000 against GL); printed as a table or JSON."""
    from explorer.gpu import Renderer
    from explorer.gpu.env import render_env
    from explorer.materials.brd import load_material
    from explorer.mitsuba.scene import render_env_mitsuba
    from explorer.resources import material_path

    if variants is None:
        variants = ("llvm_ad_rgb", "llvm_ad_spectral") if llvm_works() else ("scalar_rgb", "scalar_spectral")
    renderer = Renderer()
    rows = []
    warmed = set()
    for name in materials or plugin_names():
        material = load_material(material_path(name))
        values = material.resolve({"method": int(BraggMethod.TABULATED)} if capabilities_of(material).bragg_spectrum else {})
        render_env(material, values, 8, 8, spp=1, renderer=renderer)  # compiles the program: not timed
        start = time.perf_counter()
        gl = render_env(material, values, size, size, spp=spp, renderer=renderer)
        rows.append({"material": name, "engine": "gl", "seconds": time.perf_counter() - start, "delta_e_vs_gl": 0.0})
        for variant in variants:
            if variant not in warmed:
                render_env_mitsuba(material, values, 8, 8, 1, variant=variant)
                warmed.add(variant)
            start = time.perf_counter()
            image = render_env_mitsuba(material, values, size, size, spp, variant=variant)
            seconds = time.perf_counter() - start
            rows.append({"material": name, "engine": f"mitsuba {variant}", "seconds": seconds,
                         "delta_e_vs_gl": median_delta_e(image, gl)})
    if as_json:
        echo(json.dumps({"size": size, "spp": spp, "rows": rows}, indent=2))
    else:
        echo(f"env view, {size}x{size}, {spp} spp: seconds per frame; median per-pixel ΔE2000 against GL "
             f"(accepted: <= {ACCEPTED_DELTA_E:g} at 64x64, 1024 spp)")
        for row in rows:
            verdict = "" if row["engine"] == "gl" else "  ok" if row["delta_e_vs_gl"] <= ACCEPTED_DELTA_E else "  above"
            echo(f"  {row['material']:<14} {row['engine']:<26} {row['seconds']:8.3f} s   ΔE {row['delta_e_vs_gl']:.2f}{verdict}")
    return rows
