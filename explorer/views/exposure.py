"""
Automatic exposure for 8-bit images: the multiplier that brings an image's bright end (not its single
brightest pixel) to white. Display scaling only: the linear values (``.npy``, ``.exr``) never change.
"""

from __future__ import annotations

import numpy as np

#: The percentile of the drawn pixels' largest channel that auto-exposure maps to 1 (white): a highlight of
#: a few pixels may clip, the rest of the object keeps its gradation.
AUTO_EXPOSURE_PERCENTILE = 99.5
#: Pixels whose largest channel is at most this are background (the views' black outside the object).
BACKGROUND_LEVEL = 1e-6


def auto_exposure(image: np.ndarray) -> float:
    """
    The exposure that maps :data:`AUTO_EXPOSURE_PERCENTILE` of the drawn pixels' largest channel to 1;
    1 for an image with nothing drawn (all black, or no finite value).

    Parameters
    ----------
    image : (H, W, 3) linear RGB.
    """
    peak = np.asarray(image, dtype=np.float64).max(axis=-1)
    drawn = peak[np.isfinite(peak) & (peak > BACKGROUND_LEVEL)]
    if drawn.size == 0:
        return 1.0
    level = float(np.percentile(drawn, AUTO_EXPOSURE_PERCENTILE))
    return 1.0 / level if level > BACKGROUND_LEVEL else 1.0
