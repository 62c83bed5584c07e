"""
``bench --thin-film``: thin films (Belcour & Barla 2017), each method's accuracy and its cost relative to GGX +
Schlick.
"""

from __future__ import annotations

import json

import numpy as np

from explorer.bench.common import THETA_DEGREES, _progress
from explorer.materials.brd import load_material
from explorer.materials.methods import ThinFilmMethod
from explorer.physics import colorimetry
from explorer.resources import SHADER_DIR
from explorer.materials.models import GGXSchlickModel
from explorer.materials.thinfilm_model import ThinFilmModel

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

    film_material = load_material(SHADER_DIR / f"{ThinFilmModel.name}.brd")
    presets = presets_for(SHADER_DIR / f"{ThinFilmModel.name}.brd").presets
    configurations = [("figure7", film_material.resolve({}))]  # the material's defaults are Figure 7's film
    configurations += [(name, p.resolve()) for name, p in presets.items() if name != "figure7"]
    accuracy = []
    for name, values in configurations:
        _progress(f"bench --thin-film: accuracy of {name}")
        for method, (median, maximum) in thin_film_accuracy(values).items():
            accuracy.append({"configuration": name, "method": method, "dE_median": median, "dE_max": maximum})

    renderer = Renderer()
    baseline_material = load_material(SHADER_DIR / f"{GGXSchlickModel.name}.brd")
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
        from explorer.bench.markdown_tables import thin_film_markdown

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
