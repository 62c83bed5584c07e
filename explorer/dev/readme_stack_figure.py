"""Regenerates .github/readme/stack.png: layered Bragg presets (shaders/bragg_stack.brd) in the env view.

Left to right: Figure 1's left mirror (d1 = 125 nm, d2 = 375 nm) at alpha = 0.025, 0.1, 0.4; its right
mirror (d1 = 101 nm, d2 = 143 nm) likewise; the stacked pair; Table 3's three jewel-beetle areas. The
shipped default sky (shaders/environments/default.hdr), progressive Monte Carlo, SPP samples per pixel.
Run: .venv/bin/python -m explorer.dev.readme_stack_figure   (a few minutes on llvmpipe)
"""

import sys
from pathlib import Path

import numpy as np
from PIL import Image

from explorer.gpu import Renderer
from explorer.gpu.env import render_env
from explorer.materials.models import BraggStackModel
from explorer.materials.presets import presets_for
from explorer.materials.twins import shipped_file
from explorer.physics.colorimetry import encode_srgb8

ROOT = Path(__file__).resolve().parents[2]
SIZE, SPP = 144, 96
NAMES = ["figure1_left_alpha0025", "figure1_left_alpha01", "figure1_left_alpha04",
         "figure1_right_alpha0025", "figure1_right_alpha01", "figure1_right_alpha04", "figure1_stacked_pair",
         "table3_green_blue", "table3_red", "table3_purple"]

presets = presets_for(shipped_file(BraggStackModel))
renderer = Renderer()
tiles = []
for name in NAMES:
    print(name, file=sys.stderr)
    image = render_env(presets.material, presets.presets[name].resolve(), SIZE, SIZE, spp=SPP, renderer=renderer)
    tiles.append(encode_srgb8(image))
rows = [np.concatenate(tiles[:5], axis=1), np.concatenate(tiles[5:], axis=1)]
Image.fromarray(np.concatenate(rows, axis=0)).save(ROOT / ".github" / "readme" / "stack.png", optimize=True)
print("wrote .github/readme/stack.png")
