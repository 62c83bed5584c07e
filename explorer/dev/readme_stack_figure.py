"""Regenerates .github/readme/stack.png: layered Bragg presets (shaders/bragg_stack.brd) in the env view.

Left to right: Figure 1's left mirror (d1 = 125 nm, d2 = 375 nm) at alpha = 0.025, 0.1, 0.4; its right
mirror (d1 = 101 nm, d2 = 143 nm) likewise; the stacked pair; Table 3's three jewel-beetle areas. The
shipped default sky (shaders/environments/default.hdr) through AgX, progressive Monte Carlo
(explorer.dev.readme_env_tiles).
Run: .venv/bin/python -m explorer.dev.readme_stack_figure   (a few minutes on llvmpipe)
"""

from explorer.dev.readme_env_tiles import write_env_tiles
from explorer.materials.models import BraggStackModel
from explorer.materials.presets import presets_for
from explorer.materials.twins import shipped_file

NAMES = ["figure1_left_alpha0025", "figure1_left_alpha01", "figure1_left_alpha04",
         "figure1_right_alpha0025", "figure1_right_alpha01", "figure1_right_alpha04", "figure1_stacked_pair",
         "table3_green_blue", "table3_red", "table3_purple"]

write_env_tiles(presets_for(shipped_file(BraggStackModel)), NAMES, 'stack.png')
