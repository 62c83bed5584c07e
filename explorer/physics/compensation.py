"""
How much of the multiple-scattering compensation (:mod:`explorer.physics.multiscatter_stack`) the explorer's
rough Bragg layers add, by roughness (numpy; the GLSL twin is ``compensation_weight`` in
``shaders/lib/multiscatter.glsl``).

The paper validates Eq. 17 (one layer) and Eq. 34 (a structure) for alpha <= 0.4 "in all of our results", and
its figures are made there. The random walk shows more light than Eq. 17 even there (docs/layered_validation.md),
but the paper's figures are kept: the weight is exactly 0 up to alpha = 0.4 (Eqs. 17 and 34 as published, no
table built), exactly 1 from alpha = 0.5, where single scattering loses 30 % or more of the light, and
smoothstep between (C1: no visible step as the roughness slider crosses the range). A structure's weight is its
roughest layer's.

Reference: Fourneau, Pacanowski, Barla (2024), Section 4 ("alpha <= 0.4 in all of our results").
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

#: Up to this roughness the model is Eq. 17 / Eq. 34 as published (the paper's validated range).
FADE_START = 0.4
#: From this roughness the compensation is added in full.
FADE_END = 0.5


def compensation_weight(alpha: ArrayLike) -> np.ndarray:
    """The compensation's weight at GGX roughness ``alpha``: GLSL's ``smoothstep(FADE_START, FADE_END, alpha)``."""
    t = np.clip((np.asarray(alpha, dtype=np.float64) - FADE_START) / (FADE_END - FADE_START), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)
