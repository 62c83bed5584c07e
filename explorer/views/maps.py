"""
The colours of structure maps (:mod:`explorer.design.paint`'s output): each texel's structure, the fixed values
and the map's free parameters, seen at one angle. The flat textured view of a painted material: what a target image
of ``design --target-image`` shows, so that a map folder renders back to the image it was designed from.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np


def map_structures(fixed: Mapping[str, float], maps: Mapping[str, np.ndarray]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The texels that hold a structure (every map finite) and their design values (flat arrays, in texel order)."""
    shape = next(iter(maps.values())).shape
    inside = np.logical_and.reduce([np.isfinite(m) for m in maps.values()])
    values = {name: np.full(int(inside.sum()), float(v)) for name, v in fixed.items()}
    values.update({name: np.asarray(m, dtype=np.float64)[inside] for name, m in maps.items()})
    return inside.reshape(shape), values


def map_colours(model_name: str, fixed: Mapping[str, float], maps: Mapping[str, np.ndarray], theta_deg: float) -> np.ndarray:
    """
    ``(H, W, 3)`` linear RGB: each texel's converged spectral colour at ``theta_deg`` (the design's forward model,
    :attr:`explorer.design.base.DesignModel.converged` with ``final``: the reference); black where a map is NaN.
    """
    from explorer.design import design_model

    model = design_model(model_name)
    inside, values = map_structures(fixed, maps)
    cos_theta = np.array([np.cos(np.radians(theta_deg))])
    out = np.zeros(inside.shape + (3,))
    colours = np.empty((int(inside.sum()), 3))
    cache: dict[tuple, np.ndarray] = {}
    for i in range(colours.shape[0]):
        structure = {name: float(v[i]) for name, v in values.items()}
        key = tuple(sorted(structure.items()))
        if key not in cache:  # painted regions repeat one structure
            cache[key] = model.converged(structure, cos_theta, final=True)[0]
        colours[i] = cache[key]
    out[inside] = colours
    return out.astype(np.float32)
