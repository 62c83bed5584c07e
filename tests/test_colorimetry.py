"""The colour convention (explorer.physics.colorimetry) against colour-science and published reference data.

Our convention: CIE 1931 2° CMFs at 1 nm from 360 to 830 nm, illuminant E, Y(flat 1) = 1; linear
sRGB through a Bradford adaptation from E to D65, scaled per channel so that a flat reflectance of 1
is exactly (1, 1, 1).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    import colour

from explorer.physics import colorimetry

#: Our sums against colour-science's 'Integration' method on the same 1 nm grid (relative).
XYZ_RTOL = 1e-9
#: Matrices and white points computed two ways in float64.
MATRIX_ATOL = 1e-12
#: "Exactly" (1, 1, 1) and Y = 1: float64 rounding of one matrix product.
WHITE_ATOL = 1e-14
#: Sharma, Wu and Dalal (2005) give Delta E 2000 to 4 decimals.
SHARMA_ATOL = 1e-4

SHAPE = colour.SpectralShape(colorimetry.WAVELENGTH_MIN, colorimetry.WAVELENGTH_MAX, 1)
CMFS = colour.MSDS_CMFS[colorimetry.CMFS_NAME]
ILLUMINANT_E = colour.sd_constant(1.0, SHAPE)
XY_E = colour.CCS_ILLUMINANTS[colorimetry.CMFS_NAME]["E"]


def colour_science_xyz(values: np.ndarray) -> np.ndarray:
    """XYZ of a reflectance through colour-science, under E, normalised so that Y(flat 1) = 1."""
    sd = colour.SpectralDistribution(values, colorimetry.WAVELENGTHS)
    return colour.sd_to_XYZ(sd, CMFS, ILLUMINANT_E, method="Integration") / 100.0


def spectra() -> dict[str, np.ndarray]:
    w = colorimetry.WAVELENGTHS
    rng = np.random.default_rng(7)
    return {
        "gaussian 550/30": np.exp(-0.5 * ((w - 550.0) / 30.0) ** 2),
        "gaussian 450/10": np.exp(-0.5 * ((w - 450.0) / 10.0) ** 2),
        "ramp": (w - w[0]) / (w[-1] - w[0]),
        "box 600-650": ((w >= 600) & (w <= 650)).astype(float),
        "random": rng.uniform(0.0, 1.0, w.size),
        "flat 0.3": np.full(w.size, 0.3),
    }


def test_flat_reflectance_is_white():
    flat = np.ones(colorimetry.WAVELENGTHS.size)
    rgb = colorimetry.spectrum_to_rgb(flat)
    np.testing.assert_allclose(rgb, 1.0, rtol=0, atol=WHITE_ATOL)
    xyz = colorimetry.spectrum_to_xyz(flat)
    assert xyz[1] == pytest.approx(1.0, abs=WHITE_ATOL)
    np.testing.assert_allclose(xyz, colorimetry.white_xyz(), rtol=0, atol=WHITE_ATOL)
    # Illuminant E: equal-energy white, chromaticity (1/3, 1/3) up to the CMF table's rounding.
    np.testing.assert_allclose(colour.XYZ_to_xy(xyz), XY_E, atol=1e-4)
    # A flat reflectance of 0 is black, and colours are linear in the spectrum.
    np.testing.assert_array_equal(colorimetry.spectrum_to_rgb(np.zeros_like(flat)), 0.0)
    np.testing.assert_allclose(colorimetry.spectrum_to_rgb(0.25 * flat), 0.25, atol=WHITE_ATOL)


def test_cmfs_are_colour_sciences():
    cmf = colorimetry.colour_matching_functions()
    assert cmf.shape == (colorimetry.WAVELENGTHS.size, 3)
    raw = CMFS.copy().align(SHAPE).values
    np.testing.assert_allclose(cmf * raw[:, 1].sum(), raw, rtol=1e-12, atol=1e-15)
    assert cmf[:, 1].sum() == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("name", list(spectra()))
def test_xyz_matches_colour_science(name):
    values = spectra()[name]
    np.testing.assert_allclose(colorimetry.spectrum_to_xyz(values), colour_science_xyz(values), rtol=XYZ_RTOL, atol=1e-15)


def test_xyz_of_flat_one_matches_colour_science():
    xyz = colour_science_xyz(np.ones(colorimetry.WAVELENGTHS.size))
    assert xyz[1] == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(colorimetry.white_xyz(), xyz, rtol=XYZ_RTOL)


def test_spectrum_to_xyz_broadcasts():
    stack = np.stack(list(spectra().values())).reshape(2, 3, -1)
    xyz = colorimetry.spectrum_to_xyz(stack)
    assert xyz.shape == (2, 3, 3)
    for index in np.ndindex(2, 3):
        np.testing.assert_allclose(xyz[index], colour_science_xyz(stack[index]), rtol=XYZ_RTOL, atol=1e-15)


def test_xyz_to_rgb_matches_colour_science():
    """colour.XYZ_to_RGB (sRGB, E white, Bradford) up to the per-channel white scale."""
    rng = np.random.default_rng(11)
    xyz = np.concatenate([np.eye(3), rng.uniform(0.0, 1.0, (20, 3)), colorimetry.white_xyz()[None]])
    theirs = colour.XYZ_to_RGB(xyz, "sRGB", illuminant=XY_E, chromatic_adaptation_transform="Bradford")
    white = theirs[-1]
    ours = colorimetry.xyz_to_rgb(xyz)
    np.testing.assert_allclose(ours, theirs / white, rtol=0, atol=MATRIX_ATOL)
    np.testing.assert_allclose(ours[-1], 1.0, atol=WHITE_ATOL)
    # The matrix, its inverse, and the round trip.
    matrix = colorimetry.xyz_to_rgb_matrix()
    np.testing.assert_allclose(matrix, (theirs[:3] / white).T, atol=MATRIX_ATOL)
    np.testing.assert_allclose(colorimetry.rgb_to_xyz(ours), xyz, atol=MATRIX_ATOL)
    # The scale is a small correction: E is nearly the CMF table's white.
    np.testing.assert_allclose(white, 1.0, atol=2e-3)


def test_xyz_to_rgb_matrix_is_a_copy():
    matrix = colorimetry.xyz_to_rgb_matrix()
    matrix[:] = 0.0
    assert np.abs(colorimetry.xyz_to_rgb_matrix()).sum() > 0


def _lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB relative to the flat-1 white, from the CIE 1976 definition (not colour-science)."""
    xyz = colorimetry.rgb_to_xyz(rgb)
    t = xyz / colorimetry.white_xyz()
    delta = 6.0 / 29.0
    f = np.where(t > delta**3, np.cbrt(t), t / (3.0 * delta**2) + 4.0 / 29.0)
    return np.stack([116.0 * f[..., 1] - 16.0, 500.0 * (f[..., 0] - f[..., 1]), 200.0 * (f[..., 1] - f[..., 2])], axis=-1)


def test_delta_E_2000_identical_is_zero():
    rng = np.random.default_rng(3)
    rgb = rng.uniform(-0.1, 1.2, (50, 3))
    np.testing.assert_array_equal(colorimetry.delta_E_2000(rgb, rgb), 0.0)


def test_delta_E_2000_matches_colour_science_on_independent_lab():
    rng = np.random.default_rng(5)
    a = rng.uniform(0.0, 1.0, (200, 3))
    b = np.clip(a + rng.normal(0.0, 0.05, a.shape), 0.0, 1.0)
    expected = colour.delta_E(_lab(a), _lab(b), method="CIE 2000")
    np.testing.assert_allclose(colorimetry.delta_E_2000(a, b), expected, rtol=1e-9, atol=1e-9)
    # Symmetric, and positive for distinct colours.
    np.testing.assert_allclose(colorimetry.delta_E_2000(b, a), colorimetry.delta_E_2000(a, b), rtol=1e-12)
    assert (colorimetry.delta_E_2000(a, b)[np.any(a != b, axis=-1)] > 0).all()


#: Sharma, Wu, Dalal (2005), The CIEDE2000 colour-difference formula: implementation notes,
#: supplementary test data, and mathematical observations. Color Res. Appl. 30(1), Table 1.
SHARMA_PAIRS = [
    ((50.0000, 2.6772, -79.7751), (50.0000, 0.0000, -82.7485), 2.0425),
    ((50.0000, 3.1571, -77.2803), (50.0000, 0.0000, -82.7485), 2.8615),
    ((50.0000, 2.8361, -74.0200), (50.0000, 0.0000, -82.7485), 3.4412),
    ((50.0000, 0.0000, 0.0000), (50.0000, -1.0000, 2.0000), 2.3669),
    ((50.0000, 2.5000, 0.0000), (73.0000, 25.0000, -18.0000), 27.1492),
    ((50.0000, 2.5000, 0.0000), (61.0000, -5.0000, 29.0000), 22.8977),
]


@pytest.mark.parametrize("lab_a,lab_b,expected", SHARMA_PAIRS)
def test_delta_E_2000_published_pairs(lab_a, lab_b, expected):
    """Through our RGB convention: Lab (relative to the flat-1 white) -> XYZ -> our linear RGB."""
    white_xy = colour.XYZ_to_xy(colorimetry.white_xyz())
    rgb_a = colorimetry.xyz_to_rgb(colour.Lab_to_XYZ(np.array(lab_a), white_xy))
    rgb_b = colorimetry.xyz_to_rgb(colour.Lab_to_XYZ(np.array(lab_b), white_xy))
    assert float(colorimetry.delta_E_2000(rgb_a, rgb_b)) == pytest.approx(expected, abs=SHARMA_ATOL)


def _srgb_oetf(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 encoding."""
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0), 1.0 / 2.4) - 0.055)


def test_encode_srgb8_clamps_and_matches_cctf():
    rng = np.random.default_rng(9)
    inside = rng.uniform(0.0, 1.0, (64, 3))
    encoded = colorimetry.encode_srgb8(inside)
    assert encoded.dtype == np.uint8 and encoded.shape == inside.shape
    expected = np.round(colour.cctf_encoding(inside, function="sRGB") * 255.0)
    np.testing.assert_array_equal(encoded, expected)
    # The standard's formula, independently (random values never sit on a rounding tie).
    np.testing.assert_array_equal(encoded, np.round(_srgb_oetf(inside) * 255.0))
    # Clamping: negative (out-of-gamut) channels to 0, above white to 255.
    out_of_range = np.array([[-0.5, 1.5, 2.0], [-1e-9, 1.0 + 1e-9, 0.0], [1.0, 0.0, 0.5]])
    np.testing.assert_array_equal(
        colorimetry.encode_srgb8(out_of_range),
        [[0, 255, 255], [0, 255, 0], [255, 0, round(_srgb_oetf(np.array(0.5)) * 255.0)]],
    )


def test_out_of_gamut_mask():
    rgb = np.array([[0.5, 0.5, 0.5], [-0.01, 0.5, 0.5], [0.5, 1.01, 0.5], [0.0, 1.0, 1e-9]])
    np.testing.assert_array_equal(colorimetry.out_of_gamut(rgb), [False, True, True, False])
