"""
The tabulated method (ours): a homogeneous mirror's colour depends on ``cos(theta)`` alone, so the converged colours
are tabulated over it (:func:`tabulated_rgb_table`, its quick stand-in :func:`draft_rgb_table`). Numpy only; GLSL
twins of the same names in ``shaders/lib/bragg.glsl``.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.physics.bragg.band_pieces import PIECES_MIN_N, PIECES_MIN_N_HOST, band_pieces_rgb
from explorer.physics.bragg.mirror import BraggMirror, cell_geometry
from explorer.physics.bragg.windowed import windowed_converged_spectra

# --------------------------------------------------------------------------------------------------
# The tabulated method (ours): a homogeneous mirror's colour depends on cos(theta) alone.

#: Entries of the table over cos(theta) in [0, 1].
TABLE_SIZE = 256


#: The table's refinement: where linear interpolation between two entries may be off by more than this
#: fraction of the brightest channel (estimated from the entries' second differences), the midpoint is
#: computed, and the table doubles its resolution, up to :data:`TABLE_MAX_SIZE` entries.
TABLE_TOLERANCE = 5e-4
#: Entries computed first: the refinement adds the midpoints where the colour needs them (most of a
#: 256-entry table's entries are linear interpolations of their neighbours' to the tolerance).
TABLE_FIRST_SIZE = 65
#: 65 entries refined six times.
TABLE_MAX_SIZE = 64 * (TABLE_FIRST_SIZE - 1) + 1
#: At most this many midpoints computed in all: mirrors whose colour the table cannot follow anyway
#: (fringes unresolved at any sampling, e.g. N = 1000 and Lambda = 1500 nm) stop refining early.
TABLE_MAX_REFINED = 2 * (TABLE_SIZE - 1)


#: The table's finest sampling (samples per nm). Its integrand (:func:`windowed_converged_spectra`) has fringes
#: only within a few of a band edge: 1/128 nm keeps every N within ~3e-4 of the reference (1/1024 nm).
TABLE_MAX_SUBSTEPS = 1024


def converged_rgb(cos_theta: ArrayLike, mirror: BraggMirror) -> np.ndarray:
    """
    The converged reference's colours (:func:`reference_rgb`) at a cost that does not grow with ``N``: by Gauss
    quadrature over band pieces (:func:`band_pieces_rgb`) where every wave propagates, from :data:`PIECES_MIN_N` cells
    (:data:`PIECES_MIN_N_HOST` under a host ``nh != n1``, Appendix D); R = 1 under total reflection at the host
    interface; elsewhere (evanescent ``n2`` layers, fewer cells) from the fringe average plus the fringes near band
    edges (:func:`windowed_converged_spectra`), which costs less there (docs/performance.md).
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64).ravel()
    first = cell_geometry(cos_theta, mirror, "s")
    min_N = PIECES_MIN_N if first.host_is_n1 else PIECES_MIN_N_HOST
    # Total reflection at the host interface (nh > n1): the wave in n1, the medium below the mirror too, is evanescent,
    # so nothing is transmitted and the lossless mirror reflects R = 1 at every wavelength (the reference to ~1e-15).
    total = first.cos_theta_1.imag != 0
    real = ~total & (first.cos_theta_2.imag == 0) & (mirror.N >= min_N)
    rest = ~total & ~real
    rgb = np.empty((cos_theta.size, 3))
    if total.any():
        rgb[total] = colorimetry.spectrum_to_rgb(np.ones((1, colorimetry.WAVELENGTHS.size)))
    if real.any():
        rgb[real] = band_pieces_rgb(cos_theta[real], mirror)
    if rest.any():
        # Evanescent n2 layers, or fewer cells: the windowed rule (complex arithmetic where it must).
        spectra, _ = windowed_converged_spectra(cos_theta[rest], mirror, substeps_max=TABLE_MAX_SUBSTEPS)
        rgb[rest] = colorimetry.spectrum_to_rgb(spectra)
    return rgb


def _interpolation_error_estimate(table: np.ndarray) -> np.ndarray:
    """
    Per interval of a uniform table, the largest error of linear interpolation, ``|f''| h^2 / 8``, from
    the second differences at its two ends, relative to the brightest channel (floor 0.05).
    """
    second = np.abs(table[:-2] - 2.0 * table[1:-1] + table[2:]).max(axis=-1)
    second = np.concatenate([second[:1], second, second[-1:]])
    estimate = np.maximum(second[:-1], second[1:]) / 8.0
    brightest = np.maximum(np.abs(table[:-1]).max(axis=-1), np.abs(table[1:]).max(axis=-1))
    return estimate / np.maximum(brightest, colorimetry.CONVERGENCE_FLOOR)


#: A midpoint is taken from the cubic through its four neighbouring entries where that cubic's error,
#: estimated from fourth differences, is below this fraction of the brightest channel. 2e-4 (was 5e-5): computed
#: colours per table 139 -> 89 (N = 20), 135 -> 96 (N = 100, 1000), the table's error between entries against the
#: reference 5.0-5.1e-4 -> 5.2-5.8e-4 (linear interpolation's TABLE_TOLERANCE dominates it; docs/performance.md).
TABLE_CUBIC_TOLERANCE = 2e-4


def _cubic_midpoints(table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Per interval of a uniform table: the midpoint of the cubic through the entries ``i - 1 .. i + 2``,
    ``(-f[i-1] + 9 f[i] + 9 f[i+1] - f[i+2]) / 16``, and whether its error ``3/128 h^4 |f^(4)|`` (from the
    larger of the two fourth differences around the interval, doubled) is below :data:`TABLE_CUBIC_TOLERANCE`
    of the brightest channel (at least 0.05). The first two and last two intervals are never trusted.
    """
    n = table.shape[0]
    cubic = np.zeros((n - 1, 3))
    trusted = np.zeros(n - 1, dtype=bool)
    if n < 6:
        return cubic, trusted
    cubic[1:-1] = (-table[:-3] + 9.0 * table[1:-2] + 9.0 * table[2:-1] - table[3:]) / 16.0
    fourth = np.abs(table[:-4] - 4.0 * table[1:-3] + 6.0 * table[2:-2] - 4.0 * table[3:-1] + table[4:]).max(axis=-1)
    # Interval i (entries i, i + 1) sees the fourth differences centred on entries i and i + 1.
    estimate = 2.0 * (3.0 / 128.0) * np.maximum(fourth[:-1], fourth[1:])
    brightest = np.maximum(np.abs(table[2:-3]).max(axis=-1), np.abs(table[3:-2]).max(axis=-1))
    trusted[2:-2] = estimate <= TABLE_CUBIC_TOLERANCE * np.maximum(brightest, colorimetry.CONVERGENCE_FLOOR)
    return cubic, trusted


@functools.lru_cache(maxsize=32)
def tabulated_rgb_table(mirror: BraggMirror, size: int = TABLE_SIZE, max_size: int = TABLE_MAX_SIZE) -> np.ndarray:
    """
    The converged spectral reference (:func:`reference_rgb`) over ``cos theta`` in [0, 1], entry ``k`` of
    ``n`` at ``cos theta = k / (n - 1)``, for the host to upload as a 1D texture.

    :data:`TABLE_FIRST_SIZE` entries first; then, while some interval's interpolation error may exceed
    :data:`TABLE_TOLERANCE` (:func:`_interpolation_error_estimate`), or while the table has fewer than
    ``size`` entries, every interval is halved: its midpoint computed where the estimate says so,
    interpolated linearly elsewhere (which leaves the texture's lookups unchanged there). The resolution
    so follows the colour, which varies fastest near Brewster's and the critical angles for large ``N``,
    within :data:`TABLE_MAX_REFINED` computed midpoints. Cached per mirror (32 of them).
    """
    cos_theta = np.linspace(0.0, 1.0, min(TABLE_FIRST_SIZE, size))
    table = converged_rgb(cos_theta, mirror)
    budget = TABLE_MAX_REFINED
    while 2 * table.shape[0] - 1 <= max_size:
        refine = _interpolation_error_estimate(table) > TABLE_TOLERANCE
        if refine.sum() > budget or not (refine.any() or table.shape[0] < size):
            break
        budget -= int(refine.sum())
        midpoints = 0.5 * (cos_theta[:-1] + cos_theta[1:])
        values = 0.5 * (table[:-1] + table[1:])
        if refine.any():
            # Midpoints the cubic through four neighbours already gives to TABLE_CUBIC_TOLERANCE are not computed.
            cubic, trusted = _cubic_midpoints(table)
            values[refine & trusted] = cubic[refine & trusted]
            computed = refine & ~trusted
            if computed.any():
                values[computed] = converged_rgb(midpoints[computed], mirror)
        finer = np.empty((2 * table.shape[0] - 1, 3))
        finer[0::2], finer[1::2] = table, values
        table = finer
        cos_theta = np.linspace(0.0, 1.0, table.shape[0])
    table = table.astype(np.float32)
    table.setflags(write=False)  # cached: read-only
    return table


#: The draft table: entries, finest sampling (samples per nm) and one halving under the tolerance.
DRAFT_SIZE = 129
DRAFT_MAX_SUBSTEPS = 4


def draft_rgb_table(mirror: BraggMirror, size: int = DRAFT_SIZE) -> np.ndarray:
    """
    A quick stand-in for :func:`tabulated_rgb_table` over ``cos theta`` in [0, 1] at ``size`` entries, for an
    interactive host to show while a slider moves: the table's integrand
    (:func:`windowed_converged_spectra`) sampled to at most 1/:data:`DRAFT_MAX_SUBSTEPS` nm,
    stopped at the first halving under the tolerance, without refinement in angle. ~20-30 ms at any N,
    within ~1e-2 of the converged reference (the 1-nm sum it replaces: ~4e-2 at N >= 100). Never a reference.
    """
    spectra, _ = windowed_converged_spectra(np.linspace(0.0, 1.0, size), mirror, passes=1, substeps_max=DRAFT_MAX_SUBSTEPS)
    table = colorimetry.spectrum_to_rgb(spectra).astype(np.float32)
    table.setflags(write=False)
    return table


def tabulated_rgb(table: np.ndarray, cos_theta: ArrayLike) -> np.ndarray:
    """Linear interpolation in the table, as a linearly filtered texture fetch does."""
    size = table.shape[0]
    x = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0) * (size - 1)
    i = np.minimum(np.floor(x).astype(np.int64), size - 2)
    f = (x - i)[..., None]
    return table[i].astype(np.float64) * (1.0 - f) + table[i + 1].astype(np.float64) * f
