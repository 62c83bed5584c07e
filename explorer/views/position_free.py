"""
The position-free engine's images: the lit or slice view of a layered Bragg stack with its BRDF estimated by the
position-free reference (:class:`explorer.physics.position_free.PositionFree`, next-event estimation), under the
views' rule. Numpy only; :func:`explorer.rendering.render_material` dispatches to it.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

#: The views the position-free engine renders, and its paths per pixel by default.
POSITION_FREE_VIEWS = ("lit", "slice")
DEFAULT_SPP = 64


def twin_of(material, values):
    """The material's numpy twin at ``values`` (:func:`explorer.materials.models.model_for`), a bad value a one-line error."""
    from explorer.materials.brd import MaterialError
    from explorer.materials.models import model_for

    try:
        model = model_for(material, values)
    except ValueError as error:
        raise MaterialError(material.path, None, str(error)) from None
    return model


def check_position_free(material, model) -> None:
    """A one-line error unless the material's twin declares the position-free engine."""
    from explorer.materials.brd import MaterialError
    from explorer.materials.twins import capabilities_of, supporting

    if not capabilities_of(model).supports("position-free"):
        raise MaterialError(material.path, None, "the position-free engine simulates layered Bragg structures "
                            f"({', '.join(supporting('position-free'))}) only")


def render_position_free(material, values, view: str, width: int, height: int, light, spp: int | None,
                         progress_printer: Callable[[str, str], Callable[[int, int], None]] | None = None) -> np.ndarray:
    """
    The lit or slice view of a layered Bragg stack with its BRDF estimated by the position-free reference
    (``spp`` paths per pixel), under the views' rule; ``progress_printer(label, unit)`` makes the progress of its
    paths. Small sizes: each pixel costs ``spp`` random walks.
    """
    from explorer.physics.position_free import PositionFree
    from explorer.views.geometry import brdf_view_geometry

    if view not in POSITION_FREE_VIEWS:
        raise ValueError(f"the position-free engine renders the {' and '.join(POSITION_FREE_VIEWS)} views")
    model = twin_of(material, values)
    check_position_free(material, model)
    L, V, N, X, Y, inside, factor = brdf_view_geometry(view, width, height, light)

    def local(d):
        d = np.asarray(d, dtype=np.float64)
        return np.stack([np.sum(d * X, -1), np.sum(d * Y, -1), np.sum(d * N, -1)], axis=-1)

    # The views' rule in the shaders' precision (float32): 0 unless N.L > 0 and N.V > 0.
    shown = inside & (np.sum(N * L, -1) > 0) & (np.sum(N * V, -1) > 0)
    image = np.zeros((height, width, 3), dtype=np.float32)
    if shown.any():
        walker = PositionFree(model.stack, model.tables)
        result = walker.brdf(local(L)[shown], local(V)[shown], samples=spp or DEFAULT_SPP,
                             progress=progress_printer("position-free", "paths") if progress_printer else None)
        image[shown] = result.value * factor[shown][:, None]
    return image
