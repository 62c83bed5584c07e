"""
The measurements of docs/blender.md: every built-in material exported to Blender, rendered headless with
Cycles (CPU) and compared with the GL env view of the same scene under the default sky, median and p95
ΔE2000 over the pixels wholly inside the disc, at three roughnesses (every roughness parameter set to it;
a smooth material once). ``python -m explorer.dev.blender_measured [--write] [--cache FILE]`` prints the
Markdown table (``--write`` puts it in docs/blender.md between its markers; ``--cache`` keeps the rows
measured, for a rerun). Tens of minutes on two cores.

Both sides carry noise: the GL view at :data:`GL_SPP` samples a pixel, Cycles at :data:`CYCLES_SAMPLES`;
a smooth mirror against the view's exact value (a Dirac: no samples); the table's last column is the ΔE2000 between two Cycles renders of different seeds (median), which bounds
the part of the numbers that is noise.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

SIZE = 64
GL_SPP = 256
CYCLES_SAMPLES = 64
ROUGHNESSES = (0.05, 0.2, 0.5)
BEGIN, END = "<!-- blender_measured: begin -->", "<!-- blender_measured: end -->"
DOC = Path(__file__).resolve().parents[2] / "docs" / "blender.md"


def inside(size: int = SIZE) -> np.ndarray:
    """Pixels wholly inside the unit disc."""
    c = np.abs((np.arange(size) + 0.5) / size * 2.0 - 1.0) + 1.0 / size
    return c[None, :] ** 2 + c[:, None] ** 2 < 1.0


def delta_e(image: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """ΔE2000 per pixel as the Mitsuba and Blender tests take it (explorer.mitsuba.bench.median_delta_e): linear
    sRGB clamped at 0 (Cycles' closures clip the negative channels of colours outside sRGB), Lab under D65."""
    import colour

    def lab(rgb):
        return colour.XYZ_to_Lab(colour.sRGB_to_XYZ(np.clip(rgb, 0.0, None), apply_cctf_decoding=False))

    return np.asarray(colour.delta_E(lab(image), lab(reference), method="CIE 2000"))


def measure(material, values, film: str = "table", size: int = SIZE, gl_spp: int = GL_SPP, samples: int = CYCLES_SAMPLES,
            folder: Path | None = None) -> dict:
    """Cycles against GL (median, p95 ΔE2000) and Cycles' own noise (median ΔE2000 between two seeds)."""
    from explorer.blender import preview_scene, render
    from explorer.gpu.env import render_env
    from explorer.views.env import EnvironmentMap

    folder = Path(tempfile.mkdtemp()) if folder is None else folder
    environment = EnvironmentMap.default()
    from explorer.materials.models import model_for
    from explorer.materials.twins import capabilities_of
    from explorer.views.env import env_integral_numpy

    if capabilities_of(material).dirac:  # a Dirac: the view's exact value, 4 x 4 centres a pixel (Cycles filters its pixels)
        exact = env_integral_numpy(model_for(material, values), environment, 4 * size, 4 * size)
        gl = np.asarray(exact, np.float64).reshape(size, 4, size, 4, 3).mean(axis=(1, 3))
    else:
        gl = np.asarray(render_env(material, values, size, size, spp=gl_spp, environment=environment), np.float64)[..., :3]
    scene = preview_scene(material, values, environment, size, samples, film=film)
    first = render(scene, folder / "a.exr")
    scene.cycles.seed = 1 + scene.cycles.seed
    second = render(scene, folder / "b.exr")
    disc = inside(size)
    delta = delta_e(first[disc], gl[disc])
    noise = delta_e(first[disc], second[disc])
    return {"median": float(np.median(delta)), "p95": float(np.percentile(delta, 95)), "noise": float(np.median(noise))}


def cases():
    """``(material name, roughness or None, overrides, film path)`` of the table."""
    from explorer.materials.brd import load_material
    from explorer.materials.export_table import roughness_names
    from explorer.materials.thinfilm_model import ThinFilmModel
    from explorer.resources import builtin_materials

    for name, path in sorted(builtin_materials().items()):
        names = roughness_names(load_material(path))
        if not names:
            yield name, None, {}, "table"
            continue
        for alpha in ROUGHNESSES:
            overrides = {n: alpha for n in names}
            yield name, alpha, overrides, "table"
            if name == ThinFilmModel.name:  # the one with Principled's own film beside the table
                yield name, alpha, overrides, "principled"


def table(echo=print, cache_file: Path | None = None) -> str:
    """The Markdown table; ``cache_file`` (JSON) keeps each row measured, so that a rerun measures only the rest."""
    from explorer.blender import mapping_of
    from explorer.materials.brd import load_material
    from explorer.resources import builtin_materials

    paths = builtin_materials()
    cache = json.loads(cache_file.read_text()) if cache_file is not None and cache_file.is_file() else {}
    lines = [f"{SIZE} x {SIZE}, the default sky, GL at {GL_SPP} samples a pixel, Cycles (CPU) at {CYCLES_SAMPLES}; "
             "pixels wholly inside the disc, ΔE2000 of linear sRGB clamped at 0 "
             "(`python -m explorer.dev.blender_measured`).", "",
             "| material | alpha | mapping | median ΔE2000 | p95 | Cycles noise (median) |", "|---|---|---|---|---|---|"]
    for name, alpha, overrides, film in cases():
        material = load_material(paths[name])
        values = material.resolve(overrides)
        kind = mapping_of(material, values)
        how = {"table": "reflectance table, Glossy at 0", "converged": "converged table, GGX Glossy",
               "diffuse": "albedo table, Diffuse"}[kind]
        if kind == "converged" and film == "principled":
            how = "Principled Thin Film"
        key = f"{name} {alpha} {film}"
        row = cache.get(key) or measure(material, values, film)
        cache[key] = row
        if cache_file is not None:
            cache_file.write_text(json.dumps(cache))
        line = (f"| {name} | {'smooth' if alpha is None else f'{alpha:g}'} | {how} | {row['median']:.2f} | {row['p95']:.2f} | "
                f"{row['noise']:.2f} |")
        echo(line)
        lines.append(line)
    return "\n".join(lines)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    cache = Path(argv[argv.index("--cache") + 1]) if "--cache" in argv else None
    text = table(echo=lambda line: print(line, file=sys.stderr, flush=True), cache_file=cache)
    print(text)
    if "--write" in argv:
        from explorer.files import write_text_atomic

        doc = DOC.read_text()
        start, stop = doc.index(BEGIN) + len(BEGIN), doc.index(END)
        write_text_atomic(DOC, doc[:start] + "\n" + text + "\n" + doc[stop:])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
