"""
Automatic exposure for 8-bit images: the multiplier that brings an image's bright end (not its single
brightest pixel) to white (or near it, under a tone map). Display scaling only: the linear values (``.npy``, ``.exr``) never change.
"""

from __future__ import annotations

import numpy as np

#: The percentile of the drawn pixels' largest channel that auto-exposure maps to 1 (white): a highlight of
#: a few pixels may clip, the rest of the object keeps its gradation.
AUTO_EXPOSURE_PERCENTILE = 99.5
#: Pixels whose largest channel is at most this are background (the views' black outside the object).
BACKGROUND_LEVEL = 1e-6


#: The exposed value auto-exposure brings the bright end to, per tone map: 1 (white) when clamped; under a
#: curve that rolls off, where it is near white (AgX's 4 shows at 0.86 of white, ACES's at 0.93).
AUTO_WHITE = {"none": 1.0, "agx": 4.0, "aces": 4.0}


def auto_exposure(image: np.ndarray, tonemap: str = "none") -> float:
    """
    The exposure that maps :data:`AUTO_EXPOSURE_PERCENTILE` of the drawn pixels' largest channel to
    ``AUTO_WHITE[tonemap]`` (1 without a tone map); 1 for an image with nothing drawn (all black, or no
    finite value).

    Parameters
    ----------
    image : (H, W, 3) linear RGB.
    tonemap : the display curve the exposure is for (:mod:`explorer.views.tonemap`).
    """
    peak = np.asarray(image, dtype=np.float64).max(axis=-1)
    drawn = peak[np.isfinite(peak) & (peak > BACKGROUND_LEVEL)]
    if drawn.size == 0:
        return 1.0
    level = float(np.percentile(drawn, AUTO_EXPOSURE_PERCENTILE))
    return AUTO_WHITE[tonemap] / level if level > BACKGROUND_LEVEL else 1.0
