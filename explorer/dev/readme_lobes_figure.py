"""Regenerates .github/readme/lobes.png: layered-lobes presets (shaders/layered_lobes.brd) in the env view.

Top: Figure 18's Queen, Rook and Knight (colour saturation of a 2-layer dielectric lobe), Figure 14(a)'s
conductor and the same lobe kept under a clear coat. Bottom: Figure 19's haze (sigma_2 = 0.01, 0.04, 0.1),
Figure 20's coloured highlight and coloured halo. Stacks retrieved by explorer.physics.inverse from the figures'
lobes (shaders/presets/layered_lobes.toml). The shipped default sky, SPP samples per pixel.
Run: .venv/bin/python -m explorer.dev.readme_lobes_figure   (about a minute on llvmpipe)
"""

import sys
from pathlib import Path

import numpy as np
from PIL import Image

from explorer.gpu.env import render_env
from explorer.gpu.renderer import Renderer
from explorer.materials.lobes_presets import PRESET_FILE
from explorer.materials.presets import load_presets
from explorer.physics.colorimetry import encode_srgb8

ROOT = Path(__file__).resolve().parents[2]
SIZE, SPP = 144, 96
NAMES = ["figure18_queen", "figure18a_rook", "figure18a_knight", "figure14a_conductor", "figure14a_coated",
         "figure19a_subtle_haze", "figure19b_haze", "figure19c_strong_haze", "figure20_coloured_highlight", "figure20_coloured_halo"]

presets = load_presets(PRESET_FILE)
renderer = Renderer()
tiles = []
for name in NAMES:
    print(name, file=sys.stderr)
    image = render_env(presets.material, presets.presets[name].resolve(), SIZE, SIZE, spp=SPP, renderer=renderer)
    tiles.append(encode_srgb8(image))
rows = [np.concatenate(tiles[:5], axis=1), np.concatenate(tiles[5:], axis=1)]
Image.fromarray(np.concatenate(rows, axis=0)).save(ROOT / ".github" / "readme" / "lobes.png", optimize=True)
print("wrote .github/readme/lobes.png")
