"""
Structure maps (``design --target-image``'s output) as the shaders read them: each texel its own structure, the
values of the parameters a material declares it maps (:class:`explorer.materials.twins.StructureMaps`), packed in a
table of two RGBA texels a map texel. Numpy only; GLSL twins of the same names in ``shaders/lib/structure_maps.glsl``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

#: The shaders' ``texture_mapping`` of structure maps: each texel's structure from its maps (a bit beside supplemental
#: Figure 7's 1 and 2; ``TEXTURE_MAPS`` in lib/structure_maps.glsl). The surface value is then the nearest texel's index.
MAPS_MAPPING = 4
#: RGBA texels a map texel takes in the table: its fields in order, the last slot its inside flag (1 on the mask).
STRUCTURE_TEXELS = 2
#: The most fields a structure may have (the slots less the inside flag).
MAX_STRUCTURE_FIELDS = 4 * STRUCTURE_TEXELS - 1


def structure_table(fields: Sequence[str], values: Mapping[str, float], maps: Mapping[str, np.ndarray],
                    integers: Sequence[str] = ()) -> np.ndarray:
    """
    Per texel of ``maps`` (name: ``(H, W)``, NaN off the mask; names among ``fields``) the structure's ``fields``,
    ``values`` where no map is given, ``integers`` rounded (a count), 0 off the mask: float32 ``(H, 2 W, 4)``, the
    fields in order over the two RGBA texels and the last slot the inside flag. What ``structure_texels``
    (lib/structure_maps.glsl) reads.
    """
    if len(fields) > MAX_STRUCTURE_FIELDS:
        raise ValueError(f"a structure of {len(fields)} fields: at most {MAX_STRUCTURE_FIELDS} fit its {STRUCTURE_TEXELS} texels")
    shape = next(iter(maps.values())).shape
    inside = np.logical_and.reduce([np.isfinite(m) for m in maps.values()])
    slots = np.zeros(shape + (4 * STRUCTURE_TEXELS,))
    for k, name in enumerate(fields):
        column = np.where(inside, maps[name], 0.0) if name in maps else np.full(shape, float(values[name]))
        slots[..., k] = np.rint(column) if name in integers else column
    slots[..., -1] = inside
    table = np.ascontiguousarray(slots.astype(np.float32).reshape(shape[0], STRUCTURE_TEXELS * shape[1], 4))
    table.setflags(write=False)
    return table


def structure_texels(table: np.ndarray, T: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """
    The twin of ``structure_texels`` (lib/structure_maps.glsl): at texel indices ``T`` (per sample, row-major) whether the
    texel is on the mask and its slots (float32 values as the shader reads them, in float64), ``(..., 4 STRUCTURE_TEXELS)``.
    """
    width = table.shape[1] // STRUCTURE_TEXELS
    index = np.asarray(T, dtype=np.float64).astype(np.int64)
    slots = table.reshape(-1, width, 4 * STRUCTURE_TEXELS)[index // width, index % width].astype(np.float64)
    return slots[..., -1] > 0.5, slots
