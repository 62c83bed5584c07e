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
import warnings

import numpy as np

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
#: Samples (rows x wavelengths) per call of a spectrum function: bounds the temporaries' memory.
CHUNK_SAMPLES = 1 << 18
#: Samples kept per block of rows while refining (float64: 128 MB).
MAX_BLOCK_SAMPLES = 1 << 24


def colour_matching_functions_at(wavelength) -> np.ndarray:
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


def _power_of_two_at_least(x: float) -> int:
    return int(2 ** np.ceil(np.log2(max(float(x), 1.0))))


def substeps_for_fringes(optical_path) -> int:
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


def fixed_step_spectra(spectrum, row_count: int, step: float) -> np.ndarray:
    """
    Hat-averaged spectra from samples every ``1 / K`` nm, ``K = round(1 / step)``, without refinement
    (``step = 1``: the 1-nm point samples themselves). ``spectrum`` as in :func:`converged_spectra`.
    """
    K = max(1, int(round(1.0 / float(step))))
    return hat_average(_evaluate(spectrum, fine_wavelengths(K), np.arange(row_count)), K)


def converged_spectra(
    spectrum,
    row_count: int,
    substeps_min: int = 1,
    tolerance: float = CONVERGENCE_TOLERANCE,
    passes: int = CONVERGENCE_PASSES,
    substeps_max: int = MAX_SUBSTEPS,
) -> tuple[np.ndarray, np.ndarray]:
    """
    Hat-averaged spectra (:func:`hat_average`) refined until their colour has converged.

    Each row starts sampled every ``1 / substeps_min`` nm; the step is halved (reusing every sample)
    until ``passes`` halvings in a row change its linear sRGB by less than ``tolerance`` times its
    brightest channel (at least :data:`CONVERGENCE_FLOOR`), or the step reaches ``1 / substeps_max`` nm.

    Parameters
    ----------
    spectrum : callable
        ``spectrum(wavelengths, rows)`` -> ``(rows.size, wavelengths.size)``: the spectra of the rows
        (integer indices) at the wavelengths (nm).
    row_count : int
    substeps_min, substeps_max : int
        Powers of 2: the coarsest and finest samplings, in samples per nm.

    Returns
    -------
    spectra : ndarray, shape (row_count, 471)
        ``spectra @ colour_matching_functions()`` is the converged integral against the CMFs
        interpolated linearly.
    substeps : ndarray of int, shape (row_count,)
        The sampling each row ended at.
    """
    K0 = int(substeps_min)
    rows = np.arange(row_count)
    result = np.empty((row_count, WAVELENGTHS.size))
    substeps = np.full(row_count, K0)
    # Blocks of rows, so that a block's finest samples stay within a few tens of MB.
    block = max(1, min(row_count, (1 << 22) // ((WAVELENGTHS.size + 1) * max(K0, 8))))
    for start in range(0, row_count, block):
        active = rows[start : start + block]
        K = K0
        fine = _evaluate(spectrum, fine_wavelengths(K), active)
        averaged = hat_average(fine, K)
        result[active] = averaged
        colour = xyz_to_rgb(averaged @ colour_matching_functions())
        streak = np.zeros(active.size, dtype=int)
        while active.size and K < substeps_max:
            if active.size > 1 and active.size * fine.shape[-1] * 2 > MAX_BLOCK_SAMPLES:
                # Too many samples to refine these rows together: refine them in halves, from this sampling.
                for half in np.array_split(active, 2):
                    sub_spectra, sub_substeps = converged_spectra(
                        lambda wavelengths, sub_rows, half=half: spectrum(wavelengths, half[sub_rows]),
                        half.size, K, tolerance, passes, substeps_max,
                    )
                    result[half], substeps[half] = sub_spectra, sub_substeps
                break
            midpoints = HAT_LOW + (np.arange((WAVELENGTHS.size + 1) * K) + 0.5) / K
            finer = np.empty((active.size, 2 * fine.shape[-1] - 1))
            finer[:, 0::2] = fine
            finer[:, 1::2] = _evaluate(spectrum, midpoints, active)
            fine, K = finer, 2 * K
            averaged = hat_average(fine, K)
            finer_colour = xyz_to_rgb(averaged @ colour_matching_functions())
            brightest = np.maximum(np.abs(finer_colour).max(axis=-1), CONVERGENCE_FLOOR)
            change = np.abs(finer_colour - colour).max(axis=-1) / brightest
            streak = np.where(change < tolerance, streak + 1, 0)
            result[active] = averaged
            substeps[active] = K
            keep = streak < passes
            active, fine, colour, streak = active[keep], fine[keep], finer_colour[keep], streak[keep]
    return result, substeps


def delta_E_2000(rgb_a: np.ndarray, rgb_b: np.ndarray) -> np.ndarray:
    """
    CIE ΔE2000 between linear RGB colours of this convention.

    Colours go back to XYZ (E white, Y = 1) and to CIELAB relative to that white, through
    colour-science. Reflectances are relative colours, so the white is the flat reflectance of 1.
    """
    white_xy = colour.XYZ_to_xy(white_xyz())
    lab_a = colour.XYZ_to_Lab(rgb_to_xyz(rgb_a), white_xy)
    lab_b = colour.XYZ_to_Lab(rgb_to_xyz(rgb_b), white_xy)
    return np.asarray(colour.delta_E(lab_a, lab_b, method="CIE 2000"))


def encode_srgb8(rgb: np.ndarray) -> np.ndarray:
    """8-bit sRGB-encoded image of linear RGB: the only place where colours are clamped."""
    encoded = colour.cctf_encoding(np.clip(np.asarray(rgb, dtype=np.float64), 0.0, 1.0), function="sRGB")
    return np.round(encoded * 255.0).astype(np.uint8)


def out_of_gamut(rgb: np.ndarray, tolerance: float = 1e-6) -> np.ndarray:
    """Mask of colours outside the sRGB gamut (a negative channel, or above white)."""
    rgb = np.asarray(rgb)
    return np.any((rgb < -tolerance) | (rgb > 1.0 + tolerance), axis=-1)
