"""
Spatially varying mirrors (supplemental Figure 7): ``Lambda`` and ``delta`` from a texture value ``T`` in [0, 1], and
the tabulated method's table over ``(cos theta, T)``. Numpy only; GLSL twins of the same names in
``shaders/lib/bragg.glsl``.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.physics.bragg.mirror import BraggMirror
from explorer.physics.bragg.reference import _spectra
from explorer.physics.structure_maps import structure_texels
from explorer.physics.bragg.tables import TABLE_TOLERANCE, _interpolation_error_estimate, converged_rgb

# --------------------------------------------------------------------------------------------------
# Spatially varying mirrors (supplemental Figure 7): Lambda and delta from a texture value T in [0, 1]

#: Supplemental Figure 7's mappings of a texture value ``T``: which of ``Lambda(x) = Lambda (0.5 + 0.5 T(x))`` and
#: ``delta(x) = delta^T(x)`` apply; the shaders' ``texture_mapping`` is its bits (1: Lambda, 2: delta).
TEXTURE_MAPPINGS = {"none": 0, "lambda": 1, "delta": 2, "both": 3}
#: The tabulated method's textured table: at least this many rows of ``T = k / (rows - 1)`` (refined in T up to
#: TEXTURE_TABLE_MAX_ROWS), columns of ``cos theta = i / (columns - 1)``.
TEXTURE_TABLE_ROWS = 33
TEXTURE_TABLE_COLUMNS = 129


def textured_mirror(mirror: BraggMirror, T: ArrayLike, mapping: str) -> BraggMirror:
    """
    The mirror at texture values ``T`` (per sample) under ``mapping`` (:data:`TEXTURE_MAPPINGS`): ``Lambda`` and
    ``delta`` become arrays of ``T``'s shape, ``Lambda (0.5 + 0.5 T)`` and ``delta^T`` where the mapping says so
    (supplemental Figure 7; ``delta^0 = 1``: the whole cell is n1).
    """
    bits = TEXTURE_MAPPINGS[mapping]
    T = np.clip(np.asarray(T, dtype=np.float64), 0.0, 1.0)
    Lambda = mirror.Lambda * (0.5 + 0.5 * T) if bits & 1 else np.full(T.shape, float(mirror.Lambda))
    delta = np.power(float(mirror.delta), T) if bits & 2 else np.full(T.shape, float(mirror.delta))
    return BraggMirror(mirror.n1, mirror.n2, Lambda, delta, mirror.N, mirror.nh)


def _mirror_rows(mirror: BraggMirror, rows) -> BraggMirror:
    """A per-sample mirror's samples ``rows``."""
    return BraggMirror(mirror.n1, mirror.n2, np.asarray(mirror.Lambda)[rows], np.asarray(mirror.delta)[rows], mirror.N, mirror.nh)


def textured_reference_rgb(cos_theta: ArrayLike, mirror: BraggMirror, step: float) -> np.ndarray:
    """:func:`reference_rgb` at a fixed ``step`` of a per-sample mirror (:func:`textured_mirror`, ``cos_theta``'s shape)."""
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    flat = cos_theta.ravel()
    flat_mirror = BraggMirror(mirror.n1, mirror.n2, np.ravel(mirror.Lambda), np.ravel(mirror.delta), mirror.N, mirror.nh)
    spectra = colorimetry.fixed_step_spectra(
        lambda wavelengths, rows: _spectra(flat[rows], _mirror_rows(flat_mirror, rows), wavelengths, fast=False), flat.size, step
    )
    return colorimetry.spectrum_to_rgb(spectra).reshape(cos_theta.shape + (3,))


#: The textured table's refinement in T: first rows, the most rows (a uniform grid, so that the lookup stays one
#: bilinear fetch), and the (cos theta, T) entries computed in all (the others interpolated along T).
TEXTURE_TABLE_FIRST_ROWS = 17
TEXTURE_TABLE_MAX_ROWS = 129
TEXTURE_TABLE_BUDGET = 2 * TEXTURE_TABLE_COLUMNS * 33


def _textured_row(mirror: BraggMirror, T: float, mapping: str, cos_theta: np.ndarray) -> np.ndarray:
    """The converged colours (:func:`converged_rgb`) of the mirror at texture value ``T``, at ``cos_theta``."""
    m = textured_mirror(mirror, T, mapping)
    return converged_rgb(cos_theta, BraggMirror(mirror.n1, mirror.n2, float(m.Lambda), float(m.delta), mirror.N, mirror.nh))


@functools.lru_cache(maxsize=8)
def textured_rgb_table(mirror: BraggMirror, mapping: str, rows: int = TEXTURE_TABLE_ROWS,
                       columns: int = TEXTURE_TABLE_COLUMNS, max_rows: int = TEXTURE_TABLE_MAX_ROWS,
                       budget: int = TEXTURE_TABLE_BUDGET) -> np.ndarray:
    """
    The tabulated method's table of a textured mirror, ``(R, columns, 3)`` float32: the converged reference
    (:func:`converged_rgb`, as :func:`tabulated_rgb_table`) at ``T = k / (R - 1)`` and ``cos theta = i /
    (columns - 1)``. Every mapping makes ``Lambda`` and ``delta`` functions of the one value ``T``, so the colour
    is a function of ``(cos theta, T)`` alone: one bilinear lookup a pixel (:func:`textured_tabulated_rgb`),
    built once per mirror and mapping.

    Refined in ``T`` as :func:`tabulated_rgb_table` is in ``cos theta``: :data:`TEXTURE_TABLE_FIRST_ROWS` rows first,
    then, while the table has fewer than ``rows`` rows or some entry's interpolation between two rows may be off by
    more than :data:`TABLE_TOLERANCE` (:func:`_interpolation_error_estimate` along ``T``), every row interval is
    halved (up to ``max_rows``): the new row's entries computed where the estimate says so, interpolated elsewhere
    (which leaves the lookups unchanged there), within ``budget`` computed entries in all. One row when
    nothing varies.
    """
    cos_theta = np.linspace(0.0, 1.0, columns)
    if TEXTURE_MAPPINGS[mapping] == 0:
        table = np.broadcast_to(converged_rgb(cos_theta, mirror)[None], (2, columns, 3))
    else:
        count = min(TEXTURE_TABLE_FIRST_ROWS, rows)
        table = np.stack([_textured_row(mirror, t, mapping, cos_theta) for t in np.linspace(0.0, 1.0, count)])
        left = budget - table.shape[0] * columns
        while 2 * table.shape[0] - 1 <= max_rows:
            # Per entry, the error estimate of its two neighbouring rows' interpolation (along T, per column).
            estimate = np.stack([_interpolation_error_estimate(table[:, i]) for i in range(columns)], axis=1)
            refine = estimate > TABLE_TOLERANCE
            if refine.sum() > left:  # the budget goes to the largest estimates
                worst = np.argsort(np.where(refine, estimate, -1.0), axis=None)[::-1][:max(left, 0)]
                refine = np.zeros_like(refine)
                refine.flat[worst] = True
            if table.shape[0] >= rows and not refine.any():
                break
            left -= int(refine.sum())
            T = np.linspace(0.0, 1.0, table.shape[0])
            middle = 0.5 * (table[:-1] + table[1:])
            for j in np.flatnonzero(refine.any(axis=1)):
                middle[j, refine[j]] = _textured_row(mirror, 0.5 * (T[j] + T[j + 1]), mapping, cos_theta[refine[j]])
            finer = np.empty((2 * table.shape[0] - 1, columns, 3))
            finer[0::2], finer[1::2] = table, middle
            table = finer
    table = np.ascontiguousarray(table, dtype=np.float32)
    table.setflags(write=False)
    return table


def textured_tabulated_rgb(table: np.ndarray, cos_theta: ArrayLike, T: ArrayLike) -> np.ndarray:
    """Bilinear interpolation in :func:`textured_rgb_table` at ``(cos theta, T)``: the twin of ``textured_tabulated_rgb`` (lib/bragg.glsl)."""
    rows, columns = table.shape[:2]
    x = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0) * (columns - 1)
    y = np.clip(np.asarray(T, dtype=np.float64), 0.0, 1.0) * (rows - 1)
    i = np.minimum(np.floor(x).astype(np.int64), columns - 2)
    j = np.minimum(np.floor(y).astype(np.int64), rows - 2)
    fx, fy = (x - i)[..., None], (y - j)[..., None]
    t = table.astype(np.float64)
    top = t[j, i] * (1.0 - fx) + t[j, i + 1] * fx
    bottom = t[j + 1, i] * (1.0 - fx) + t[j + 1, i + 1] * fx
    return top * (1.0 - fy) + bottom * fy


# --------------------------------------------------------------------------------------------------
# Structure maps (``design --target-image``'s output): each texel its own mirror

#: The mirror's values a structure table holds per texel, in order (:func:`explorer.physics.structure_maps.structure_table`;
#: ``nh`` below 1: the host is n1; ``N`` rounded, a count of cells).
STRUCTURE_FIELDS = ("n1", "n2", "Lambda", "delta", "N", "nh")


def mapped_mirrors(table: np.ndarray, T: ArrayLike) -> Iterator[tuple[np.ndarray, BraggMirror]]:
    """
    The twin of ``mapped_mirror`` (lib/bragg.glsl): the mirrors at texel indices ``T`` (per sample, row-major) of a
    structure table of :data:`STRUCTURE_FIELDS`, grouped by what the approximations take as scalars. Yields
    ``(samples, mirror)``: a bool mask of ``T``'s shape and a mirror whose ``Lambda`` and ``delta`` are those samples'
    (float32 values, as the shader reads them); texels off the mask yield none.
    """
    inside, slots = structure_texels(table, T)
    scalars = slots[..., [0, 1, 4, 5]]  # n1, n2, N, nh
    for key in np.unique(scalars[inside], axis=0):
        samples = inside & np.all(scalars == key, axis=-1)
        n1, n2, N, nh = (float(v) for v in key)
        yield samples, BraggMirror(n1, n2, slots[..., 2][samples], slots[..., 3][samples], max(int(N), 1), None if nh < 1.0 else nh)
