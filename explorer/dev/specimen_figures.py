"""Regenerates the real specimens' figures of docs/natural.md and prints their table.

For every preset of shaders/presets/bragg_mirror.toml with a ``citation`` (a specimen from published
measurements): its exact spectra at 0, 30 and 60 degrees with the band gaps (``spectrum --plot``), and its
colour strip (the gradient view, cos theta from 0 to 1) above its sphere (numpy twins, the tabulated
method's exact colours). Prints one markdown row per specimen: the 0-degree peak, its reflectance and its
shift at 45 degrees.
Run: .venv/bin/python -m explorer.dev.specimen_figures   (about a minute on 2 cores)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from PIL import Image

from explorer.views.spectrum_plot import describe, natural_mirror, spectrum_document, write_plot
from explorer.files import atomic_output
from explorer.materials.methods import BraggMethod
from explorer.materials.models import BraggMirrorModel
from explorer.materials.presets import presets_for
from explorer.materials.twins import shipped_file
from explorer.physics.colorimetry import encode_srgb8
from explorer.physics.natural import mirror_spectrum
from explorer.rendering import render_material

ROOT = Path(__file__).resolve().parents[2]
FIGURES = ROOT / "docs" / "figures"
STRIP, SPHERE = (256, 24), 128
THETAS = [0.0, 30.0, 60.0]


def specimens():
    """The bragg_mirror presets that cite a published specimen."""
    presets = presets_for(shipped_file(BraggMirrorModel))
    return [p for p in presets.presets.values() if p.citation]


def views_image(preset) -> np.ndarray:
    """The colour strip over the sphere, one 8-bit image (the strip stretched to the sphere's width)."""
    values = preset.resolve({"method": int(BraggMethod.TABULATED)})
    strip = encode_srgb8(render_material(preset.material, values, "gradient", STRIP[0], STRIP[1], "numpy"))
    sphere = encode_srgb8(render_material(preset.material, values, "sphere", SPHERE, SPHERE, "numpy"))
    strip = np.asarray(Image.fromarray(strip).resize((SPHERE, STRIP[1]), Image.Resampling.BILINEAR))
    return np.concatenate([strip, np.zeros((4, SPHERE, 3), np.uint8), sphere], axis=0)


def main() -> None:
    FIGURES.mkdir(parents=True, exist_ok=True)
    print("| preset | structure | peak at 0° (nm) | R there | peak at 45° (nm) |")
    print("|---|---|---|---|---|")
    for preset in specimens():
        print(preset.name, file=sys.stderr)
        mirror = natural_mirror(dict(preset.resolve()), {})
        document = spectrum_document(mirror, THETAS)
        write_plot(document, mirror, FIGURES / f"specimen_{preset.name}_spectrum.png", f"{preset.figure}: {describe(mirror)}")
        with atomic_output(FIGURES / f"specimen_{preset.name}_views.png", (".png",)) as temporary:
            Image.fromarray(views_image(preset)).save(temporary, format="png", optimize=True)
        wavelengths = np.asarray(document["wavelength_nm"])
        R45 = mirror_spectrum(mirror, wavelengths, [45.0])["R"][0]
        R0 = np.asarray(document["R"][0])
        print(f"| `{preset.name}` | {describe(mirror)} | {wavelengths[R0.argmax()]:.0f} | {R0.max():.3f} | "
              f"{wavelengths[R45.argmax()]:.0f} |")


if __name__ == "__main__":
    main()
