"""
``export thin_film --to materialx out.mtlx``: the thin film as a MaterialX ``standard_surface`` with its
standard thin-film inputs (``thin_film_thickness`` in nm, ``thin_film_IOR``).

Mapping (docs/export.md): ``d -> thin_film_thickness``, ``eta2 -> thin_film_IOR``, GGX ``alpha`` ->
``specular_roughness = sqrt(alpha)`` (standard_surface squares its roughness); a dielectric base
(``kappa3 = 0``) is ``specular_IOR = eta3`` over a black ``base``; a conductor (``kappa3 > 0``) is
``metalness = 1`` with ``base_color`` its normal-incidence Fresnel reflectance ``|(eta3 + i kappa3 - 1) /
(eta3 + i kappa3 + 1)|^2`` (grey: one index for every wavelength, as thin_film.brd). standard_surface
assumes the film sits in air: ``eta1`` other than 1 is refused.

MaterialX's shading-language implementations of the film (``mx_fresnel_airy``) follow Belcour & Barla
(2017) with the Gaussian fit of the CIE sensitivities: the explorer's method 4. :func:`airy_delta_e` measures
how far that lies from the spectral reference (method 0) per preset; ``python -m
explorer.materials.export_materialx`` prints the table of docs/export.md.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from explorer.files import write_text_atomic
from explorer.errors import LocatedError


class MaterialXExportError(LocatedError):
    """A material MaterialX's standard inputs cannot express (one line)."""


def materialx_document(material, values) -> str:
    """The ``.mtlx`` text for a thin-film material at ``values``."""
    from explorer.materials.twins import capabilities_of, supporting

    if not capabilities_of(material).supports("materialx"):
        raise MaterialXExportError(material.path, None, f"--to materialx exports a thin film ({', '.join(supporting('materialx'))}) only")
    eta1, eta2, eta3, kappa3 = (float(values[k]) for k in ("eta1", "eta2", "eta3", "kappa3"))
    if abs(eta1 - 1.0) > 1e-9:
        raise MaterialXExportError(material.path, None, f"standard_surface's film lies in air: eta1 must be 1, got {eta1:g}")
    d, alpha = float(values["d"]), float(values["alpha"])
    inputs = [
        ("thin_film_thickness", "float", f"{d:.9g}"),
        ("thin_film_IOR", "float", f"{eta2:.9g}"),
        ("specular", "float", "1"),
        ("specular_color", "color3", "1, 1, 1"),
        ("specular_roughness", "float", f"{math.sqrt(max(alpha, 0.0)):.9g}"),
    ]
    if kappa3 > 0.0:
        f0 = abs((complex(eta3, kappa3) - 1.0) / (complex(eta3, kappa3) + 1.0)) ** 2
        inputs += [("base", "float", "1"), ("metalness", "float", "1"), ("base_color", "color3", f"{f0:.9g}, {f0:.9g}, {f0:.9g}")]
    else:
        inputs += [("base", "float", "0"), ("metalness", "float", "0"), ("specular_IOR", "float", f"{eta3:.9g}")]
    lines = "\n".join(f'    <input name="{n}" type="{t}" value="{v}" />' for n, t, v in inputs)
    return f"""<?xml version="1.0"?>
<!-- {material.model} (Belcour & Barla 2017) exported by bragg-explorer: d = {d:g} nm, eta2 = {eta2:g}, eta3 = {eta3:g}, kappa3 = {kappa3:g}, alpha = {alpha:g} -->
<materialx version="1.39">
  <standard_surface name="SR_thin_film" type="surfaceshader">
{lines}
  </standard_surface>
  <surfacematerial name="M_thin_film" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_thin_film" />
  </surfacematerial>
</materialx>
"""


def validate_document(text: str, origin: str = "<mtlx>") -> None:
    """MaterialX's own ``validate()`` with its standard libraries; raises on an invalid document."""
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlString(doc, text)
    libraries = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), libraries)
    doc.importLibrary(libraries)
    valid, message = doc.validate()
    if not valid:
        raise MaterialXExportError(origin, None, "MaterialX validate() failed: " + " ".join(message.split()))


def export_materialx(material, values, out: Path) -> Path:
    """Write the document to ``out`` atomically, validated first when the ``materialx`` package is present."""

    if out.suffix.lower() != ".mtlx":
        raise MaterialXExportError(out, None, "a MaterialX document: name it .mtlx")
    text = materialx_document(material, values)
    try:
        validate_document(text, str(out))
    except ImportError:
        pass  # the materialx package is optional (the test extra has it)
    write_text_atomic(out, text)  # explorer.files: a temporary file renamed; OutputError (one line) otherwise
    return out


def airy_delta_e(values, samples: int = 91) -> tuple[float, float]:
    """Mean and max ΔE2000 over theta in [0, 90) deg of MaterialX's Airy model (method 4) against the reference (method 0)."""
    from explorer.physics import colorimetry, thinfilm

    film = tuple(float(values[k]) for k in ("eta1", "eta2", "eta3", "kappa3"))
    cos = np.cos(np.radians(np.linspace(0.0, 89.0, samples)))
    reference = thinfilm.reference_rgb(*film, cos, float(values["d"]), step=1.0)
    airy = thinfilm.fourier_rgb(*film, cos, float(values["d"]), m_max=3, sensitivity="gaussian")
    delta = colorimetry.delta_E_2000(airy, reference)
    return float(np.mean(delta)), float(np.max(delta))


if __name__ == "__main__":
    from explorer.materials.brd import load_material
    from explorer.materials.presets import presets_for
    from explorer.resources import material_path

    from explorer.materials.thinfilm_model import ThinFilmModel

    material = load_material(material_path(ThinFilmModel.name))
    print("| preset | mean ΔE2000 | max ΔE2000 |\n|---|---|---|")
    for name, preset in presets_for(material.path).presets.items():
        mean, top = airy_delta_e(material.resolve(preset.values))
        print(f"| {name} | {mean:.2f} | {top:.2f} |")
