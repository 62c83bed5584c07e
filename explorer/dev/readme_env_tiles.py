"""
The README's preset galleries (``readme_stack_figure``, ``readme_lobes_figure``): a material's presets in the env
view under the shipped default sky, two rows of tiles, shown as a PNG shows them (``render --view env``'s default
display: AgX, :mod:`explorer.views.tonemap`), written to ``.github/readme/``.
"""

import sys
from pathlib import Path

import numpy as np
from PIL import Image

from explorer.gpu import Renderer
from explorer.gpu.env import render_env
from explorer.views.tonemap import default_tonemap, display_srgb8

ROOT = Path(__file__).resolve().parents[2]
SIZE, SPP = 144, 96
#: The exposure of every tile: one for the gallery, so that tiles compare (the env view's default).
EXPOSURE = 1.0


def write_env_tiles(presets, names: list[str], out: str, size: int = SIZE, spp: int = SPP) -> None:
    """Render ``names`` of ``presets`` (a :class:`explorer.materials.presets.PresetFile`) and write them in two rows to ``.github/readme/<out>``."""
    renderer = Renderer()
    tiles = []
    for name in names:
        print(name, file=sys.stderr)
        image = render_env(presets.material, presets.presets[name].resolve(), size, size, spp=spp, renderer=renderer)
        tiles.append(display_srgb8(image, EXPOSURE, default_tonemap("env")))
    half = (len(tiles) + 1) // 2
    rows = [np.concatenate(tiles[:half], axis=1), np.concatenate(tiles[half:], axis=1)]
    path = ROOT / ".github" / "readme" / out
    Image.fromarray(np.concatenate(rows, axis=0)).save(path, optimize=True)
    print(f"wrote {path.relative_to(ROOT)}")
