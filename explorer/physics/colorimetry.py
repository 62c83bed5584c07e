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
