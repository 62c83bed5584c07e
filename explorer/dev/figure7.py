"""
Supplemental Figure 7 of Fourneau et al. (2024) by ``render``: a smooth Bragg mirror (n1 = 1, n2 = 1.5,
Lambda = 500 nm, delta = 0.15) homogeneous, with Lambda(x) = Lambda (0.5 + 0.5 T(x)), with delta(x) = delta^T(x),
and with both, T the shipped noise texture, on the GPU: the textured view (the lit sphere, light head-on)
in the first row, the env view (the mirror reflecting the shipped environment, as the paper's figure) in
the second. Writes ``docs/figures/figure7_textured_bragg.png`` (the texture, then the four spheres), and
prints the ``render`` commands it runs (their images are the same).

    python -m explorer.dev.figure7 [--method 3] [--size 256] [--out docs/figures/figure7_textured_bragg.png]
    python -m explorer.dev.figure7 --accuracy   # ΔE2000 of methods 1, 3, 4 against the reference (docs/textured_bragg.md)
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

FIGURE7 = {"n1": 1.0, "n2": 1.5, "Lambda": 500.0, "delta": 0.15}
MAPPINGS = (("none", "(a) homogeneous"), ("lambda", "(c) Lambda mapped"), ("delta", "(d) delta mapped"), ("both", "(e) both"))
LIGHT = (0.0, 0.0)


def main(argv=None) -> None:
    from PIL import Image, ImageDraw

    from explorer.rendering import render_material
    from explorer.files import atomic_output
    from explorer.materials.brd import load_material
    from explorer.physics.colorimetry import encode_srgb8
    from explorer.materials.models import BraggMirrorModel
    from explorer.materials.twins import shipped_file
    from explorer.resources import DEFAULT_TEXTURE
    from explorer.views.surface_texture import BraggTexture
    from explorer.views.thickness import load_grey

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--method", type=int, default=3)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--out", type=Path, default=Path("docs/figures/figure7_textured_bragg.png"))
    parser.add_argument("--accuracy", action="store_true", help="print the methods' ΔE2000 against the reference instead")
    args = parser.parse_args(argv)
    if args.accuracy:
        accuracy()
        return
    material = load_material(shipped_file(BraggMirrorModel))
    values = material.resolve({**FIGURE7, "method": args.method})
    size, label = args.size, 24
    texture = np.round(255 * load_grey(DEFAULT_TEXTURE)).astype(np.uint8)
    panels = [("(b) texture T", Image.fromarray(texture, "L").convert("RGB").resize((size, size), Image.BILINEAR))]
    env_panels = [("under the environment (env view)", Image.new("RGB", (size, size), "white"))]
    sets = " ".join(f"--set {k}={v:g}" for k, v in {**FIGURE7, "method": args.method}.items())
    for mapping, caption in MAPPINGS:
        surface = BraggTexture.from_file(DEFAULT_TEXTURE, mapping)
        for view, row in (("textured", panels), ("env", env_panels)):
            start = time.perf_counter()
            light = LIGHT if view == "textured" else None
            image = render_material(material, values, view, size, size, "gl", light, surface, spp=1)
            options = "--light 0,0" if view == "textured" else "--texture shaders/textures/thickness_noise.png --spp 1"
            print(f"python3 -m explorer render {material.model} --view {view} --mapping {mapping} {sets} {options} "
                  f"--size {size} --out {mapping}_{view}.png  # {time.perf_counter() - start:.2f} s")
            row.append((caption if view == "textured" else "", Image.fromarray(encode_srgb8(image), "RGB")))
    sheet = Image.new("RGB", (len(panels) * size, 2 * (size + label)), "white")
    draw = ImageDraw.Draw(sheet)
    for r, row in enumerate((panels, env_panels)):
        for k, (caption, panel) in enumerate(row):
            sheet.paste(panel, (k * size, label + r * (size + label)))
            draw.text((k * size + 6, 5 + r * (size + label)), caption, fill="black")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(args.out, (".png",)) as temporary:
        sheet.save(temporary, format="PNG")
    print(f"wrote {args.out}")


def accuracy(size: int = 128) -> None:
    """
    ΔE2000 (median, 99th percentile, max over the disc) of the textured sphere by methods 1, 3 and 4 against the
    spectral reference at 1/4 nm (method 0), per mapping, light head-on, on the GPU; and the table's build time.
    """
    from explorer.rendering import render_material
    from explorer.materials.brd import load_material
    from explorer.physics import bragg
    from explorer.physics.colorimetry import delta_E_2000
    from explorer.materials.models import BraggMirrorModel
    from explorer.materials.twins import shipped_file
    from explorer.resources import DEFAULT_TEXTURE
    from explorer.views.geometry import disc
    from explorer.views.surface_texture import BraggTexture

    material = load_material(shipped_file(BraggMirrorModel))
    _, _, r2 = disc(size, size)
    inside = r2 < 0.98
    start = time.perf_counter()
    table = bragg.textured_rgb_table(bragg.BraggMirror(1.0, 1.5, 500.0 + 1e-6, 0.15, 20), "both")
    print(f"(cos theta, T) table, mapping both: {table.shape[1]} x {table.shape[0]} entries, built in {time.perf_counter() - start:.2f} s")
    print("| mapping | method | ΔE2000 median | p99 | max |\n|---|---|---|---|---|")
    for mapping in ("lambda", "delta", "both"):
        texture = BraggTexture.from_file(DEFAULT_TEXTURE, mapping)
        images = {m: render_material(material, material.resolve({**FIGURE7, "method": m, "wavelength_step": 0.25 if m == 0 else 1.0}),
                                     "textured", size, size, "gl", LIGHT, texture).astype(np.float64) for m in (0, 1, 3, 4)}
        for m in (1, 3, 4):
            de = delta_E_2000(images[m][inside], images[0][inside])
            print(f"| {mapping} | {m} | {np.median(de):.2f} | {np.percentile(de, 99):.2f} | {de.max():.2f} |")


if __name__ == "__main__":  # pragma: no cover
    main()
