"""Regenerates .github/readme/lobes.png: layered-lobes presets (shaders/layered_lobes.brd) in the env view.

Top: Figure 18's Queen, Rook and Knight (colour saturation of a 2-layer dielectric lobe), Figure 14(a)'s
conductor and the same lobe kept under a clear coat. Bottom: Figure 19's haze (sigma_2 = 0.01, 0.04, 0.1),
Figure 20's coloured highlight and coloured halo. Stacks retrieved by explorer.physics.inverse from the figures'
lobes (shaders/presets/layered_lobes.toml). The shipped default sky, AgX (explorer.dev.readme_env_tiles), SPP samples per pixel.
Run: .venv/bin/python -m explorer.dev.readme_lobes_figure   (about a minute on llvmpipe)
"""

from explorer.dev.readme_env_tiles import write_env_tiles
from explorer.materials.lobes_presets import PRESET_FILE
from explorer.materials.presets import load_presets

NAMES = ["figure18_queen", "figure18a_rook", "figure18a_knight", "figure14a_conductor", "figure14a_coated",
         "figure19a_subtle_haze", "figure19b_haze", "figure19c_strong_haze", "figure20_coloured_highlight", "figure20_coloured_halo"]

write_env_tiles(load_presets(PRESET_FILE), NAMES, 'lobes.png')
