"""Regenerates .github/readme/inverse_classes.png and .github/readme/inverse_compare.png (the Inverse window's figures).

inverse_classes.png: equivalence classes drawn by ``bragg-explorer figure`` (Bati et al. 2021): Figure 4b's
conductor (kappa against eta per channel), a 2-layer lobe with coloured absorption as Figure 12 draws it
(per-channel regions, their intersection, tau_1 isolines, invalid hatched), and an achromatic one.

inverse_compare.png: two members of one class, as the Inverse window's "compare two members" shows them
(Figures 5, 8, 10): the stacks the window retrieves at class points A and B of the 2-layer coloured lobe,
in the env view (the shipped default sky, SPP samples per pixel): A | A left, B right | B. Same lobe at
normal incidence (R = [0.1, 0.2, 0.1], sigma = 0.03); they part at grazing angles.
inverse_app.png: the Inverse window on that lobe, in a scripted session under Xvfb.
Run: .venv/bin/python -m explorer.dev.readme_inverse_figure   (about a minute on llvmpipe)
"""

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from explorer.app.panels.inverse import LobeEdit, material_values, solve
from explorer.gpu import Renderer
from explorer.gpu.env import render_env
from explorer.materials.brd import load_material
from explorer.materials.lobes_model import LayeredLobesModel
from explorer.materials.twins import shipped_file
from explorer.physics.colorimetry import encode_srgb8
from explorer.physics.inverse import forward_lobes

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / ".github" / "readme"
SIZE, SPP = 208, 96
CLASSES = ["R=0.6,0.45,0.3 sigma=0.01 base=conductor", "R=0.1,0.2,0.1 sigma=0.03 layers=2", "R=0.15 sigma=0 layers=2"]
LOBE = LobeEdit([0.1, 0.2, 0.1], 0.03, 2)
POINTS = {"A": (0.05, 0.1), "B": (0.95, 0.9)}

# The class plots, through the figure command itself (in a child process: the scripts stand beside the command line).
with tempfile.TemporaryDirectory() as tmp:
    panels = []
    for i, spec in enumerate(CLASSES):
        path = Path(tmp) / f"class{i}.png"
        subprocess.run([sys.executable, "-m", "explorer.cli.commands", "figure", "--lobe", spec, "--out", str(path), "--samples", "96"],
                       cwd=ROOT, check=True)
        panels.append(np.asarray(Image.open(path).convert("RGB")))
height = min(p.shape[0] for p in panels)
Image.fromarray(np.concatenate([p[:height] for p in panels], axis=1)).save(OUT / "inverse_classes.png", optimize=True)
print("wrote .github/readme/inverse_classes.png")

# Two members of one class, rendered.
material = load_material(shipped_file(LayeredLobesModel))
renderer = Renderer()
images = {}
for name, point in POINTS.items():
    solution = solve([LOBE], points=[point])
    stack = solution.stack
    energies, _ = forward_lobes(stack, [2])
    print(name, solution.choices[0], "tau_1", np.round(stack.tau[1], 3).tolist(), "forward R", np.round(energies[0], 4).tolist(), file=sys.stderr)
    images[name] = encode_srgb8(render_env(material, material_values(material, stack), SIZE, SIZE, spp=SPP, renderer=renderer))
split = images["A"].copy()
split[:, SIZE // 2:] = images["B"][:, SIZE // 2:]
split[:, SIZE // 2 - 1: SIZE // 2 + 1] = 255  # the seam
Image.fromarray(np.concatenate([images["A"], split, images["B"]], axis=1)).save(OUT / "inverse_compare.png", optimize=True)
print("wrote .github/readme/inverse_compare.png")

# The Inverse window itself: the Figure-12 lobe typed in, its point walked, under a virtual display.
import json
import os

from explorer.app.xvfb import virtual_display

with tempfile.TemporaryDirectory() as tmp, virtual_display() as display:
    shot = Path(tmp) / "window.png"
    actions = [{"wait": 2}, {"view_size": 256}, {"click": "mode:env"}, {"focus": "Inverse"}, {"wait": 3},
               {"type": "inverse:R_1", "text": "0.1,0.2,0.1"}, {"wait": 1},
               {"drag": "inverse:t_1", "from": 0.3, "to": 0.12, "frames": 4}, {"wait": 60},
               {"window_screenshot": str(shot)}, {"quit": True}]
    (Path(tmp) / "script.json").write_text(json.dumps(actions))
    env = {**os.environ, "DISPLAY": display, "BRAGG_EXPLORER_NO_SETUP": "1", "PYTHONPATH": str(ROOT)}
    subprocess.run([sys.executable, "-m", "explorer.cli.commands", "open", str(shipped_file(LayeredLobesModel)),
                    "--script", str(Path(tmp) / "script.json"), "--window-size", "1280x1000"], cwd=tmp, env=env, check=True)
    window = Image.open(shot).convert("RGB")
    window.crop((window.width * 26 // 100, 0, window.width, 640)).save(OUT / "inverse_app.png", optimize=True)
print("wrote .github/readme/inverse_app.png")
