"""
Colorimetry: the product's one colour convention.

Every colour the explorer computes, in numpy or in GLSL, goes through this convention, and the tests
depend on it exactly:

- CIE 1931 2° colour-matching functions from colour-science, 360-830 nm at 1 nm;
- XYZ normalised so that a flat reflectance of 1 gives illuminant-E white with Y = 1;
- linear sRGB (Rec. 709 primaries) through colour-science with a Bradford adaptation from E to D65,
  scaled per channel so that a flat reflectance of 1 is exactly RGB (1, 1, 1);
- linear results are never clamped (vivid Bragg colours lie outside the sRGB gamut and come out
  negative); clamping happens only when encoding 8-bit images.

References
----------
Fourneau, Pacanowski, Barla (2024), Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors, Section 3.2.2 (Eqs. 15-16).
"""

from __future__ import annotations

import functools
import math
import warnings
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike

from explorer.tables import luts

with warnings.catch_warnings():
    # colour-science warns at import when matplotlib is absent; we never plot through it.
    warnings.simplefilter("ignore")
    import colour

CMFS_NAME = "CIE 1931 2 Degree Standard Observer"
WAVELENGTH_MIN = 360
WAVELENGTH_MAX = 830
#: The 471 wavelengths (nm) of the spectral reference.
WAVELENGTHS = np.arange(WAVELENGTH_MIN, WAVELENGTH_MAX + 1, dtype=np.float64)


@functools.lru_cache(maxsize=None)
def _cmfs_raw() -> np.ndarray:
    shape = colour.SpectralShape(WAVELENGTH_MIN, WAVELENGTH_MAX, 1)
    cmfs = colour.MSDS_CMFS[CMFS_NAME].copy().align(shape)
    values = np.asarray(cmfs.values, dtype=np.float64)
    values.setflags(write=False)
    return values


def colour_matching_functions() -> np.ndarray:
    """
    The CIE 1931 2° CMFs at 1 nm, normalised so that ``sum(ybar) == 1``.

    With this normalisation, ``reflectance @ colour_matching_functions()`` is the XYZ colour of a
    reflectance spectrum sampled at :data:`WAVELENGTHS` (a flat reflectance of 1 has Y = 1).

    Returns
    -------
    ndarray, shape (471, 3)
    """
    raw = _cmfs_raw()
    return raw / raw[:, 1].sum()


def white_xyz() -> np.ndarray:
    """XYZ of a flat reflectance of 1 (illuminant-E white, Y = 1)."""
    return colour_matching_functions().sum(axis=0)


@functools.lru_cache(maxsize=None)
def _xyz_to_rgb_matrix() -> np.ndarray:
    srgb = colour.RGB_COLOURSPACES["sRGB"]
    xy_e = colour.CCS_ILLUMINANTS[CMFS_NAME]["E"]
    adaptation = colour.adaptation.matrix_chromatic_adaptation_VonKries(
        colour.xy_to_XYZ(xy_e), colour.xy_to_XYZ(srgb.whitepoint), transform="Bradford"
    )
    matrix = srgb.matrix_XYZ_to_RGB @ adaptation
    # Per-channel scale: a flat reflectance of 1 must be exactly RGB (1, 1, 1).
    matrix = matrix / (matrix @ white_xyz())[:, None]
    matrix.setflags(write=False)
    return matrix


def xyz_to_rgb_matrix() -> np.ndarray:
    """The 3x3 matrix taking our XYZ (E white, Y = 1) to linear sRGB with white = (1, 1, 1)."""
    return _xyz_to_rgb_matrix().copy()


def xyz_to_rgb(xyz: np.ndarray) -> np.ndarray:
    """Linear sRGB of XYZ colours (last axis), unclamped."""
    return np.asarray(xyz) @ _xyz_to_rgb_matrix().T


def rgb_to_xyz(rgb: np.ndarray) -> np.ndarray:
    """Inverse of :func:`xyz_to_rgb`."""
    return np.asarray(rgb) @ np.linalg.inv(_xyz_to_rgb_matrix()).T


def spectrum_to_xyz(reflectance: np.ndarray) -> np.ndarray:
    """
    XYZ of reflectance spectra sampled at every nanometre from 360 to 830 nm (last axis).

    Parameters
    ----------
    reflectance : array_like, shape (..., 471)

    Returns
    -------
    ndarray, shape (..., 3)
    """
    return np.asarray(reflectance) @ colour_matching_functions()


def spectrum_to_rgb(reflectance: np.ndarray) -> np.ndarray:
    """Linear sRGB of reflectance spectra sampled at :data:`WAVELENGTHS` (last axis), unclamped."""
    return xyz_to_rgb(spectrum_to_xyz(reflectance))


# --------------------------------------------------------------------------------------------------
# The converged spectral integral
#
# The CMFs are tabulated at 1 nm. Interpolated linearly between their nodes, and taken as zero one nm
# outside the range (359 and 831 nm), they are the sum of hat functions c_i h_i(lambda) of half-width 1 nm
# centred on the nodes, so the colour of a spectrum R is
#
#     X = integral R(lambda) sum_i c_i h_i(lambda) dlambda = sum_i c_i Rbar_i,  Rbar_i = integral R h_i,
#
# the paper's 1-nm sum (Eq. 15's reference) with each sample R(lambda_i) replaced by the hat average
# Rbar_i. A flat spectrum has Rbar_i = 1: the white and the XYZ -> RGB matrix stay exactly those of the
# 1-nm sum, and a smooth spectrum's colour barely changes. A spectrum sampled every 1/K nm integrates
# exactly against the hats (trapezoids of a piecewise-linear product): K = 1 gives back the 1-nm sum.

#: Ends of the piecewise-linear CMFs, where they are zero (nm).
HAT_LOW = WAVELENGTH_MIN - 1.0
HAT_HIGH = WAVELENGTH_MAX + 1.0
#: A spectral integral is converged once halving its step changes the colour by less than this fraction
#: of its brightest linear RGB channel, twice in a row (one halving can hit and miss resonances alike).
CONVERGENCE_TOLERANCE = 2e-4
#: Halvings in a row that must stay under the tolerance.
CONVERGENCE_PASSES = 2
#: Colours darker than this (white = 1) are held to the tolerance relative to it instead.
CONVERGENCE_FLOOR = 0.05
#: The finest sampling: 1/1024 nm.
MAX_SUBSTEPS = 1024
#: Each nm cell's budget is weighted by the CMFs at its nodes, at least this fraction of their largest.
WEIGHT_FLOOR = 0.05
#: Samples (rows x wavelengths) per call of a spectrum function: bounds the temporaries' memory.
CHUNK_SAMPLES = 1 << 18
#: Samples kept per block of rows while refining (float64: 128 MB).
MAX_BLOCK_SAMPLES = 1 << 24


def colour_matching_functions_at(wavelength: ArrayLike) -> np.ndarray:
    """
    The CMFs (:func:`colour_matching_functions`) interpolated linearly between their 1-nm nodes, zero
    from :data:`HAT_LOW` and :data:`HAT_HIGH` outwards: ``sum_i c_i h_i(lambda)``.

    Returns
    -------
    ndarray, shape ``wavelength.shape + (3,)``
    """
    nodes = np.concatenate([[HAT_LOW], WAVELENGTHS, [HAT_HIGH]])
    values = np.vstack([np.zeros(3), colour_matching_functions(), np.zeros(3)])
    wavelength = np.asarray(wavelength, dtype=np.float64)
    return np.stack([np.interp(wavelength, nodes, values[:, c], left=0.0, right=0.0) for c in range(3)], axis=-1)


def fine_wavelengths(substeps: int) -> np.ndarray:
    """The ``472 substeps + 1`` wavelengths ``359 + j / substeps`` nm that sample the hats' support."""
    return HAT_LOW + np.arange((WAVELENGTHS.size + 1) * substeps + 1) / substeps


def hat_average(fine: np.ndarray, substeps: int) -> np.ndarray:
    """
    The hat averages ``Rbar_i`` (last axis: 471) of spectra sampled at :func:`fine_wavelengths`.

    ``Rbar_i = sum_j (K - |j|) / K^2 R(lambda_i + j / K)`` for ``|j| < K``: the exact integral of the
    hat ``h_i`` against the piecewise-linear interpolant of the samples.
    """
    fine = np.asarray(fine)
    K, count = int(substeps), WAVELENGTHS.size
    total = np.zeros(fine.shape[:-1] + (count,))
    for j in range(-K + 1, K):
        total += ((K - abs(j)) / (K * K)) * fine[..., K + j : K + j + count * K : K]
    return total


#: The coarse colours' wavelength step (nm): a spectrum at nodes this far apart, interpolated linearly, against the
#: 1-nm CMFs (:func:`interpolant_nodes`; the batch forward models of inverse design).
COARSE_STEP = 2.0


def _interpolant_weights_at(nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    ``(nodes, weights)`` such that ``XYZ = R(nodes) @ weights`` integrates the linear interpolant of a spectrum
    sampled at ascending ``nodes`` (nm, spanning the CMFs' range): the interpolant sampled every ``1 / K`` nm and
    integrated against the CMFs' hats as the converged colours are (:func:`hat_average`), ``K`` the power of two
    that puts a sample in every node interval (``K = 1``, the 1-nm sum, for nodes 1 nm apart or more).
    """
    count = nodes.size
    K = 2 ** max(0, math.ceil(math.log2(1.0 / float(np.min(np.diff(nodes))))))
    fine = fine_wavelengths(K)
    position = np.interp(fine, nodes, np.arange(count))
    left = np.minimum(np.floor(position).astype(int), count - 2)
    frac = position - left
    interpolation = np.zeros((fine.size, count))
    interpolation[np.arange(fine.size), left] = 1.0 - frac
    interpolation[np.arange(fine.size), left + 1] += frac
    # Fortran order: at K = 1 the same product, bit for bit, as the 1-nm sum of the interpolant.
    return nodes, np.asfortranarray(hat_average(interpolation.T, K)) @ colour_matching_functions()


@functools.lru_cache(maxsize=None)
def interpolant_nodes(step: float = COARSE_STEP) -> tuple[np.ndarray, np.ndarray]:
    """
    Nodes every ``step`` nm over the CMFs' range and the XYZ weights that integrate the spectrum's linear
    interpolant between them against the 1-nm CMFs: ``XYZ = R(nodes) @ weights`` (cached).
    """
    count = int(math.ceil((WAVELENGTH_MAX - WAVELENGTH_MIN) / step)) + 1
    return _interpolant_weights_at(np.linspace(WAVELENGTH_MIN, WAVELENGTH_MAX, count))


@functools.lru_cache(maxsize=None)
def log_interpolant_nodes(ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """
    :func:`interpolant_nodes` at the wavelengths ``lambda_max r^-j`` (ascending) down to below ``lambda_min``
    (the scale scan's of inverse design: its spectra are functions of ``s / lambda``).
    """
    count = int(np.ceil(np.log(WAVELENGTH_MAX / WAVELENGTH_MIN) / np.log(ratio))) + 1
    return _interpolant_weights_at(WAVELENGTH_MAX / ratio ** np.arange(count)[::-1])


def _power_of_two_at_least(x: float) -> int:
    return int(2 ** np.ceil(np.log2(max(float(x), 1.0))))


def substeps_for_fringes(optical_path: float) -> int:
    """
    The coarsest sampling (samples per nm, a power of 2) that puts four samples in every fringe of a
    spectrum whose phase is ``2 pi optical_path / lambda`` (nm): fringes are ``lambda^2 / optical_path``
    apart, narrowest at 360 nm. A floor under the adaptive refinement of :func:`converged_spectra`, so
    that it never compares two samplings that both miss every fringe.
    """
    return min(_power_of_two_at_least(4.0 * float(optical_path) / WAVELENGTH_MIN**2), MAX_SUBSTEPS)


def _evaluate(spectrum, wavelengths: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``spectrum(wavelengths, rows)`` in chunks of wavelengths of at most :data:`CHUNK_SAMPLES` samples."""
    step = max(1, CHUNK_SAMPLES // max(rows.size, 1))
    return np.concatenate(
        [np.asarray(spectrum(wavelengths[i : i + step], rows), dtype=np.float64) for i in range(0, wavelengths.size, step)],
        axis=-1,
    )


def fixed_step_spectra(spectrum: Callable[[np.ndarray, np.ndarray], np.ndarray], row_count: int, step: float) -> np.ndarray:
    """
    Hat-averaged spectra from samples every ``1 / K`` nm, ``K = round(1 / step)``, without refinement
    (``step = 1``: the 1-nm point samples themselves). ``spectrum`` as in :func:`converged_spectra`.
    """
    K = max(1, int(round(1.0 / float(step))))
    return hat_average(_evaluate(spectrum, fine_wavelengths(K), np.arange(row_count)), K)


def _evaluate_points(spectrum, wavelengths: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """
    ``spectrum`` at a different set of wavelengths per row: ``wavelengths`` of shape ``(rows.size, M)``
    (rows may repeat), in chunks of at most :data:`CHUNK_SAMPLES` samples.
    """
    step = max(1, CHUNK_SAMPLES // max(wavelengths.shape[-1], 1))
    out = np.empty(wavelengths.shape)
    for i in range(0, rows.size, step):
        out[i : i + step] = spectrum(wavelengths[i : i + step], rows[i : i + step])
    return out


def _cell_moments(fine: np.ndarray, K: int) -> tuple[np.ndarray, np.ndarray]:
    """
    Per 1-nm cell ``[359 + c, 360 + c]`` (472 of them), the trapezoid integrals of ``R (1 - t)`` and ``R t``
    (``t`` from 0 to 1 across the cell) from samples at :func:`fine_wavelengths` ``(K)``: the cell's shares
    of the hat averages of its left and right nodes.
    """
    cells = WAVELENGTHS.size + 1
    body = fine[..., :-1].reshape(fine.shape[:-1] + (cells, K))
    ends = fine[..., K::K]
    t = np.arange(K) / K
    weight_left = (1.0 - t) / K
    weight_left[0] *= 0.5
    weight_right = t / K
    return body @ weight_left, body @ weight_right + ends * (0.5 / K)


def _padded_cmfs() -> np.ndarray:
    """The CMFs at the 473 nodes 359..831 nm (zero at both ends)."""
    return np.vstack([np.zeros(3), colour_matching_functions(), np.zeros(3)])


def converged_spectra(
    spectrum: Callable[[np.ndarray, np.ndarray], np.ndarray],
    row_count: int,
    substeps_min: int = 1,
    tolerance: float = CONVERGENCE_TOLERANCE,
    passes: int = CONVERGENCE_PASSES,
    substeps_max: int = MAX_SUBSTEPS,
) -> tuple[np.ndarray, np.ndarray]:
    """
    Hat-averaged spectra (:func:`hat_average`) refined, nm cell by nm cell, until their colour has converged.

    Each hat average ``Rbar_i`` is the sum of two cells' integrals: ``R (1 - t)`` over the 1-nm cell right of
    node ``i`` and ``R t`` over the cell left of it (``t`` rising from 0 to 1 across a cell). A cell's
    integrals are trapezoid sums at samplings ``K, 2K, 4K...`` (samples per nm, each reusing the previous
    one's samples), Richardson-extrapolated between successive ones (Simpson's rule: the integrands are
    smooth within a cell, whose ends are the CMFs' nodes). A cell's sampling doubles until ``passes - 1``
    comparisons in a row (at least one; each spans two halvings) change its share of the row's linear sRGB
    (its integrals' changes times the brightest channel of the CMFs at its two nodes) by less than its
    budget: ``tolerance`` times the row's brightest channel (at least :data:`CONVERGENCE_FLOOR`), divided
    equally among the 472 cells, so that the cells' changes summed stay under the row's tolerance. Smooth
    cells stop after a few samples per nm; those beside band edges or under narrow resonances go on, to
    ``substeps_max``. Active cells share one sampling at each step and are refined together (vectorised),
    only their new wavelengths evaluated.

    ``substeps_min`` is the sampling that resolves the spectra's fringes at :data:`WAVELENGTH_MIN`
    (:func:`substeps_for_fringes`): fringes ``lambda^2 / path`` apart widen towards the red, so a cell at
    ``lambda`` may stop from ``substeps_min (WAVELENGTH_MIN / lambda)^2`` samples per nm (a power of 2),
    its first comparison made from a quarter of that. Cells whose trapezoid sums move less than their
    budget between the first two samplings stop there (flat spectra: band gaps, the CMFs' dark ends). With
    ``passes <= 1`` (quick tables) a whole row also stops at the first halving that moves its colour by
    less than ``tolerance`` (what a uniform refinement would do; its fringes' changes cancel).

    Parameters
    ----------
    spectrum : callable
        ``spectrum(wavelengths, rows)`` -> ``(rows.size, wavelengths.shape[-1])``: the spectra of the rows
        (integer indices, which may repeat) at the wavelengths (nm), either one set shared by every row
        (1D) or one set per row (2D, shape ``(rows.size, M)``).
    row_count : int
    substeps_min, substeps_max : int
        Powers of 2, samples per nm.

    Returns
    -------
    spectra : ndarray, shape (row_count, 471)
        ``spectra @ colour_matching_functions()`` is the converged integral against the CMFs
        interpolated linearly.
    substeps : ndarray of int, shape (row_count,)
        The finest sampling any cell of the row ended at.
    """
    cells = WAVELENGTHS.size + 1
    substeps_max = max(1, int(substeps_max))
    centres = HAT_LOW + 0.5 + np.arange(cells)
    floor = np.array([_power_of_two_at_least(x) for x in int(substeps_min) * (WAVELENGTH_MIN / centres) ** 2])
    floor = np.minimum(floor, substeps_max)
    K0 = max(1, int(floor.min()) // 4)
    rows = np.arange(row_count)
    if K0 >= substeps_max // 2:
        return fixed_step_spectra(spectrum, row_count, 1.0 / substeps_max), np.full(row_count, substeps_max)
    cmfs = _padded_cmfs()
    to_rgb = _xyz_to_rgb_matrix()
    # Bounds on the change of the brightest channel per unit change of each integral of a cell: (cells,).
    weight_left = np.abs(cmfs[:-1] @ to_rgb.T).max(axis=-1)
    weight_right = np.abs(cmfs[1:] @ to_rgb.T).max(axis=-1)
    # Held to at least a fraction of the largest, so that the hat averages under the CMFs' dark ends
    # converge too (the layer tables' spectra are used per wavelength, not only through their colour).
    weight_left = np.maximum(weight_left, WEIGHT_FLOOR * weight_left.max())
    weight_right = np.maximum(weight_right, WEIGHT_FLOOR * weight_right.max())

    # The first two samplings of every cell share their wavelengths across rows.
    trap = np.empty((2, row_count, cells))  # trapezoid sums at 2 K0: left and right integrals
    coarse = np.empty((2, row_count, cells))  # at K0
    block = max(1, CHUNK_SAMPLES * 4 // (cells * 2 * K0))
    for start in range(0, row_count, block):
        active = rows[start : start + block]
        fine = _evaluate(spectrum, fine_wavelengths(2 * K0), active)
        coarse[0, active], coarse[1, active] = _cell_moments(fine[:, ::2], K0)
        trap[0, active], trap[1, active] = _cell_moments(fine, 2 * K0)
    K = 2 * K0
    result = (4.0 * trap - coarse) / 3.0  # Simpson's values: the result, refined in place
    substeps = np.full(row_count, K)

    def budgets():
        colour = xyz_to_rgb((result[0][:, 1:] + result[1][:, :-1]) @ colour_matching_functions())
        return tolerance * np.maximum(np.abs(colour).max(axis=-1), CONVERGENCE_FLOOR) / cells

    # Cells whose trapezoid sums already moved less than their budget from K0 to 2 K0 (flat spectra: band
    # gaps; the CMFs' dark ends) are done: Simpson's error is below the trapezoid's, itself ~1/3 of that change.
    change = np.abs(trap[0] - coarse[0]) * weight_left + np.abs(trap[1] - coarse[1]) * weight_right
    done = (change < budgets()[:, None]) & (K >= floor)
    if passes <= 1:
        # One pass (the host's quick tables): a row whose colour moved less than the tolerance from K0 to
        # 2 K0 samples per nm is done, as a uniform refinement would stop there (its fringes' changes cancel).
        def row_colour(moments):
            return xyz_to_rgb((moments[0][:, 1:] + moments[1][:, :-1]) @ colour_matching_functions())

        fine_colour = row_colour(trap)
        brightest = np.maximum(np.abs(fine_colour).max(axis=-1), CONVERGENCE_FLOOR)
        row_done = np.abs(fine_colour - row_colour(coarse)).max(axis=-1) < tolerance * brightest
        stopped = row_done[:, None] & (K >= floor) & ~done
        # Cells not converged themselves keep their trapezoid sums: Simpson's extrapolation from samplings
        # that miss their fringes would move them further (the row's colour is converged either way).
        result[:, stopped] = trap[:, stopped]
        done |= stopped
    # The active (row, cell) pairs, flat.
    pair = np.flatnonzero(~done.ravel())
    trap_l, trap_r = trap[0].ravel()[pair], trap[1].ravel()[pair]
    simp_l, simp_r = result[0].ravel()[pair], result[1].ravel()[pair]
    result_l, result_r = result[0].reshape(-1), result[1].reshape(-1)
    streak = np.zeros(pair.size, dtype=np.int64)
    needed = max(1, int(passes) - 1)
    row_colour = xyz_to_rgb((result[0][:, 1:] + result[1][:, :-1]) @ colour_matching_functions())
    while pair.size and K < substeps_max:
        budget = budgets()
        pair_row, pair_cell = np.divmod(pair, cells)
        t = (np.arange(K) + 0.5) / K
        values = _evaluate_points(spectrum, (HAT_LOW + pair_cell)[:, None] + t, pair_row)
        new_l = 0.5 * trap_l + values @ ((1.0 - t) / (2.0 * K))
        new_r = 0.5 * trap_r + values @ (t / (2.0 * K))
        new_simp_l = (4.0 * new_l - trap_l) / 3.0
        new_simp_r = (4.0 * new_r - trap_r) / 3.0
        change = np.abs(new_simp_l - simp_l) * weight_left[pair_cell] + np.abs(new_simp_r - simp_r) * weight_right[pair_cell]
        K *= 2
        result_l[pair], result_r[pair] = new_simp_l, new_simp_r
        substeps[pair_row] = K
        passed = (change < budget[pair_row]) & (K >= floor[pair_cell])
        streak = np.where(passed, streak + 1, 0)
        keep = streak < needed
        if passes <= 1:
            # One pass: a row whose colour this halving moved less than the tolerance stops (uniform criterion).
            colour = xyz_to_rgb((result[0][:, 1:] + result[1][:, :-1]) @ colour_matching_functions())
            brightest = np.maximum(np.abs(colour).max(axis=-1), CONVERGENCE_FLOOR)
            row_done = np.abs(colour - row_colour).max(axis=-1) < tolerance * brightest
            row_colour = colour
            stopped = keep & row_done[pair_row] & (K >= floor[pair_cell])
            result_l[pair[stopped]], result_r[pair[stopped]] = new_l[stopped], new_r[stopped]
            keep &= ~stopped
        pair, streak = pair[keep], streak[keep]
        trap_l, trap_r, simp_l, simp_r = new_l[keep], new_r[keep], new_simp_l[keep], new_simp_r[keep]
    return result[0][:, 1:] + result[1][:, :-1], substeps


def rgb_to_lab(rgb: ArrayLike) -> np.ndarray:
    """
    CIELAB of linear RGB colours of this convention: back to XYZ (E white, Y = 1), then CIELAB relative to
    that white, through colour-science. Reflectances are relative colours, so the white is the flat
    reflectance of 1.
    """
    return colour.XYZ_to_Lab(rgb_to_xyz(np.asarray(rgb, dtype=np.float64)), colour.XYZ_to_xy(white_xyz()))


def delta_E_2000_lab(lab_a: ArrayLike, lab_b: ArrayLike) -> np.ndarray:
    """CIE ΔE2000 between CIELAB colours (colour-science)."""
    return np.asarray(colour.delta_E(lab_a, lab_b, method="CIE 2000"))


def delta_E_2000(rgb_a: np.ndarray, rgb_b: np.ndarray) -> np.ndarray:
    """CIE ΔE2000 between linear RGB colours of this convention, in CIELAB (:func:`rgb_to_lab`)."""
    return delta_E_2000_lab(rgb_to_lab(rgb_a), rgb_to_lab(rgb_b))


def encode_srgb8(rgb: np.ndarray) -> np.ndarray:
    """8-bit sRGB-encoded image of linear RGB: the only place where colours are clamped."""
    encoded = colour.cctf_encoding(np.clip(np.asarray(rgb, dtype=np.float64), 0.0, 1.0), function="sRGB")
    return np.round(encoded * 255.0).astype(np.uint8)


def out_of_gamut(rgb: np.ndarray, tolerance: float = 1e-6) -> np.ndarray:
    """Mask of colours outside the sRGB gamut (a negative channel, or above white)."""
    rgb = np.asarray(rgb)
    return np.any((rgb < -tolerance) | (rgb > 1.0 + tolerance), axis=-1)


# --------------------------------------------------------------------------------------------------
# The CMF tables of luts/ (the spectral reference and the approximations' cumulative integrals)

#: First node of ``cmf_cumulative`` (nm) and its spacing.
CUMULATIVE_START = WAVELENGTH_MIN - 0.5
CUMULATIVE_STEP = 1.0


def _cmf_source() -> str:
    import colour

    return f"colour-science {colour.__version__}: colour.MSDS_CMFS['{CMFS_NAME}']"


def _generate_cmf_1nm() -> np.ndarray:
    return colour_matching_functions().astype(np.float64)


def _generate_cmf_cumulative() -> np.ndarray:
    cmf = colour_matching_functions()
    return np.concatenate([np.zeros((1, 3)), np.cumsum(cmf, axis=0)]).astype(np.float64)


luts.register("cmf_1nm", _generate_cmf_1nm, {
    "quantity": "CIE 1931 2 degree CMFs, normalised so that sum(ybar) = 1",
    "range_nm": [WAVELENGTH_MIN, WAVELENGTH_MAX],
    "resolution_nm": 1.0,
    "shape": [471, 3],
}, _cmf_source)
# The cumulative integrals C(lambda) of the CMFs (Eq. 16 of Fourneau et al. 2024) at the 472 bin edges
# 359.5 + k nm: the CMFs are constant over each 1 nm bin, so C is exactly piecewise linear between nodes
# and a box spectrum integrates to C(hi) - C(lo) (Eq. 15).
luts.register("cmf_cumulative", _generate_cmf_cumulative, {
    "quantity": "cumulative integral of the normalised CMFs (Eq. 16), at 1 nm bin edges",
    "range_nm": [CUMULATIVE_START, WAVELENGTH_MAX + 0.5],
    "resolution_nm": CUMULATIVE_STEP,
    "shape": [472, 3],
}, _cmf_source)


def cmf_cumulative_at(wavelength: ArrayLike) -> np.ndarray:
    """
    ``C(lambda)`` by linear interpolation between the ``cmf_cumulative`` table's nodes, clamped outside
    them: exactly what a linearly filtered, edge-clamped texture of the table returns.

    Returns
    -------
    ndarray, shape ``wavelength.shape + (3,)``
    """
    table = luts.load("cmf_cumulative")
    x = (np.asarray(wavelength, dtype=np.float64) - CUMULATIVE_START) / CUMULATIVE_STEP
    x = np.clip(x, 0.0, table.shape[0] - 1.0)
    i = np.minimum(np.floor(x).astype(np.int64), table.shape[0] - 2)
    f = (x - i)[..., None]
    return table[i] * (1.0 - f) + table[i + 1] * f
