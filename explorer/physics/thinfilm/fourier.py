"""
A thin film's colours (Belcour & Barla 2017): the RGB sensitivities in Fourier space (Eqs. 7-8, the
``sensitivity_fourier`` table of ``luts/``), the analytic spectral integration (Eq. 10), the spectral reference, the
naive method, the parametrisation by ``D_inc`` and the multi-scale rendering (Section 5). Numpy only; GLSL twins of
the same names in ``shaders/lib/thinfilm.glsl``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.physics.thinfilm.airy import C_0, POLARISATIONS, C_m, FilmTerms, _real_array, airy_reflectance, film_terms, validate_film
from explorer.tables import luts

# The sensitivity_fourier table of luts/ (registered below, after its generator): the Fourier transform
# S^_j(mu) of the linear sRGB sensitivities s_j of the colour convention as functions of nu = 1/lambda
# (Eqs. 7-8), S^_j(mu) = sum_lambda s_j(lambda) exp(-2 pi i mu / lambda) over the 471 nodes of the
# spectral reference, with s_j = (M cmf)_j and M the XYZ -> RGB matrix, so S^_j(0) = 1 (white). Being the
# transform of the very sum the 1 nm reference computes, Eq. 10 with it converges to that reference as m
# grows. Sampled at OPDs mu = 10 k nm, k = 0..4095, and stored demodulated, E_j(mu) = S^_j(mu)
# exp(+2 pi i mu / carrier_j), each channel's carrier near its centroid in nu: E_j is smooth, so linear
# interpolation between nodes is within 6e-5 of the transform (2.5e-3 without demodulation). Shape
# (2, 4096, 3): real parts, imaginary parts (the paper's N x 2 three-channel texture, Section 5); zero
# beyond the last node. The carriers: the sensitivities' centroids in nu, 653.2, 545.7, 440.6 nm, rounded.
SENSITIVITY_FOURIER_STEP = 10.0
SENSITIVITY_FOURIER_COUNT = 4096
SENSITIVITY_FOURIER_CARRIER_NM = (653.0, 546.0, 441.0)


def _generate_sensitivity_fourier() -> np.ndarray:
    # Element-wise products and numpy's pairwise sums, not BLAS: the same bits on every machine.
    cmf, matrix = colorimetry.colour_matching_functions(), colorimetry.xyz_to_rgb_matrix()
    sensitivities = (cmf[:, None, :] * matrix[None, :, :]).sum(axis=-1)
    mu = np.arange(SENSITIVITY_FOURIER_COUNT, dtype=np.float64) * SENSITIVITY_FOURIER_STEP
    nu = 1.0 / colorimetry.WAVELENGTHS
    envelope = np.empty((mu.size, 3), dtype=np.complex128)
    for j, carrier in enumerate(SENSITIVITY_FOURIER_CARRIER_NM):
        # exp(-2 pi i mu nu) exp(+2 pi i mu / carrier), in one phase: no large phases cancel.
        phase = np.exp(-2j * np.pi * mu[:, None] * (nu - 1.0 / carrier)[None, :])
        envelope[:, j] = (phase * sensitivities[None, :, j]).sum(axis=-1)
    return np.stack([envelope.real, envelope.imag]).astype(np.float64)


luts.register("sensitivity_fourier", _generate_sensitivity_fourier, {
    "quantity": "Fourier transform over nu = 1/lambda of the linear sRGB sensitivities (Belcour & "
    "Barla 2017, Eqs. 7-8), demodulated by exp(+2 pi i mu / carrier); [real, imag]",
    "range_nm": [0.0, SENSITIVITY_FOURIER_STEP * (SENSITIVITY_FOURIER_COUNT - 1)],
    "resolution_nm": SENSITIVITY_FOURIER_STEP,
    "carrier_nm": list(SENSITIVITY_FOURIER_CARRIER_NM),
    "shape": [2, SENSITIVITY_FOURIER_COUNT, 3],
}, colorimetry._cmf_source)
#: Width (nm of ``D_inc``) of the smoothstep that takes ``eta_2`` to ``eta_1`` as ``D_inc -> 0``
#: (Section 5); the authors' code blends over ``D_inc`` in [0, 0.03] um.
D_INC_BLEND = 30.0
#: The naive method's wavelengths (nm) for R, G, B: the peaks of this convention's linear sRGB
#: sensitivities (``M`` times the CIE 1931 CMFs), the paper's rule ("the peak of each sensitivity
#: curve", Section 4) applied to the channels the product outputs.
NAIVE_WAVELENGTHS = (606.0, 539.0, 445.0)
#: The paper's wavelengths for the X, Y, Z bands (Section 4, Validation), for ``naive_rgb(space='xyz')``.
PAPER_XYZ_WAVELENGTHS = (600.0, 560.0, 450.0)
#: The paper's Gaussian fits of the XYZ sensitivities in Fourier space (Fig. 5(b-c); the GLSL of its
#: supplemental material): amplitude, position (1/m) and variance (1/m^2) of one Gaussian per band,
#: plus a second one for X, and the normalisation that makes ``S^_Y(0) = 1``.
GAUSSIAN_FIT_VAL = (5.4856e-13, 4.4201e-13, 5.2481e-13)
GAUSSIAN_FIT_POS = (1.6810e06, 1.7953e06, 2.2084e06)
GAUSSIAN_FIT_VAR = (4.3278e09, 9.3046e09, 6.6121e09)
GAUSSIAN_FIT_X2 = (9.7470e-14, 2.2399e06, 4.5282e09)
GAUSSIAN_FIT_NORM = 1.0685e-7
SENSITIVITIES = ("table", "gaussian", "exact")


# --------------------------------------------------------------------------------------------------
# The sensitivities in Fourier space (Eqs. 7-8, Section 5)


def sensitivities_rgb() -> np.ndarray:
    """
    The spectral sensitivities ``s_j`` of this convention's linear sRGB channels at the 471 wavelengths
    of the reference: ``R_j = sum_lambda R(lambda) s_j(lambda)``, and ``sum s_j = 1`` (white).

    Returns
    -------
    ndarray, shape (471, 3)
    """
    return colorimetry.colour_matching_functions() @ colorimetry.xyz_to_rgb_matrix().T


def sensitivity_fourier_transform_exact(mu: ArrayLike) -> np.ndarray:
    """
    ``S^_j(mu) = sum_lambda s_j(lambda) exp(-2 pi i mu / lambda)``: the Fourier transform over
    ``nu = 1/lambda`` (Eqs. 7-8) of the discrete measure the 1 nm reference integrates against, so
    that Eq. 10 with it converges to :func:`reference_rgb` exactly as ``m_max`` grows.

    Returns
    -------
    ndarray of complex, shape ``mu.shape + (3,)``
    """
    mu = np.asarray(mu, dtype=np.float64)
    nu = 1.0 / colorimetry.WAVELENGTHS
    return np.exp(-2j * np.pi * mu[..., None] * nu) @ sensitivities_rgb().astype(np.complex128)


def sensitivity_fourier_transform_table(mu: ArrayLike) -> np.ndarray:
    """
    ``S^_j(mu)`` from the ``sensitivity_fourier`` table (:mod:`explorer.tables.luts`): the demodulated envelope
    ``E_j`` interpolated linearly between nodes, as a linearly filtered texture fetch does, times the
    carrier ``exp(-2 pi i mu / carrier_j)``; zero beyond the last node (``|S^| < 1e-4`` there).

    Returns
    -------
    ndarray of complex, shape ``mu.shape + (3,)``
    """
    table = luts.load("sensitivity_fourier")
    mu = np.asarray(mu, dtype=np.float64)
    x = mu / SENSITIVITY_FOURIER_STEP
    last = table.shape[1] - 1
    inside = (x >= 0.0) & (x <= last)
    x = np.clip(x, 0.0, last)
    i = np.minimum(np.floor(x).astype(np.int64), last - 1)
    f = (x - i)[..., None]
    envelope = (table[0, i] * (1.0 - f) + table[0, i + 1] * f) + 1j * (table[1, i] * (1.0 - f) + table[1, i + 1] * f)
    carrier = np.exp(-2j * np.pi * mu[..., None] / np.asarray(SENSITIVITY_FOURIER_CARRIER_NM))
    return np.where(inside[..., None], envelope * carrier, 0.0)


def sensitivity_fourier_transform_gaussian_xyz(mu: ArrayLike) -> np.ndarray:
    """
    The paper's Gaussian fits of the XYZ sensitivities in Fourier space (Section 5, Fig. 5(b-c)):
    ``S^(mu) = sum val sqrt(2 pi var) exp(-var phase^2) exp(-i pos phase) / norm``,
    ``phase = 2 pi mu`` (``mu`` in m), two Gaussians for X and one for Y and Z.

    Returns
    -------
    ndarray of complex, shape ``mu.shape + (3,)``; ``S^_Y(0) = 1``.
    """
    phase = 2.0 * np.pi * np.asarray(mu, dtype=np.float64)[..., None] * 1e-9
    val, pos, var = (np.asarray(v) for v in (GAUSSIAN_FIT_VAL, GAUSSIAN_FIT_POS, GAUSSIAN_FIT_VAR))
    xyz = val * np.sqrt(2.0 * np.pi * var) * np.exp(-var * phase**2) * np.exp(-1j * pos * phase)
    val_2, pos_2, var_2 = GAUSSIAN_FIT_X2
    x2 = val_2 * np.sqrt(2.0 * np.pi * var_2) * np.exp(-var_2 * phase[..., 0] ** 2) * np.exp(-1j * pos_2 * phase[..., 0])
    xyz[..., 0] += x2
    return xyz / GAUSSIAN_FIT_NORM


def sensitivity_fourier_transform(mu: ArrayLike, sensitivity: str = "table") -> np.ndarray:
    """
    The Fourier transform ``S^_j(mu)`` of the linear sRGB sensitivities at OPD ``mu`` (nm), Eq. 8.

    Parameters
    ----------
    mu : array_like
        Optical path difference (the Fourier variable conjugate to ``nu = 1/lambda``), nm.
    sensitivity : {'table', 'gaussian', 'exact'}
        ``'table'``: the ``sensitivity_fourier`` table of ``luts/`` (what a shader fetches);
        ``'gaussian'``: the paper's Gaussian fits of the XYZ bands taken to RGB with this convention's
        matrix; ``'exact'``: the direct sum over the 471 wavelengths.

    Returns
    -------
    ndarray of complex, shape ``mu.shape + (3,)``

    References
    ----------
    Belcour & Barla (2017), Eqs. 7-8, Fig. 5(b-c) and Section 5 (BRDF evaluation).
    """
    if sensitivity == "table":
        return sensitivity_fourier_transform_table(mu)
    if sensitivity == "exact":
        return sensitivity_fourier_transform_exact(mu)
    if sensitivity == "gaussian":
        return sensitivity_fourier_transform_gaussian_xyz(mu) @ colorimetry.xyz_to_rgb_matrix().T.astype(np.complex128)
    raise ValueError(f"sensitivity must be one of {', '.join(SENSITIVITIES)}, not {sensitivity!r}")


def D_max(epsilon: float = 0.05, sensitivity: str = "table") -> float:
    """
    The OPD beyond which iridescence is negligible (Section 5): the least ``mu`` such that
    ``|S^_j(mu')| <= epsilon`` for every ``mu' >= mu`` and every channel, on the table's nodes.
    """
    mu = np.arange(SENSITIVITY_FOURIER_COUNT) * SENSITIVITY_FOURIER_STEP
    above = np.any(np.abs(sensitivity_fourier_transform(mu, sensitivity)) > epsilon, axis=-1)
    return float(mu[np.nonzero(above)[0][-1] + 1]) if above.any() else 0.0


# --------------------------------------------------------------------------------------------------
# Analytic spectral integration (Eq. 10)


def spectral_integration_fourier(
    terms: FilmTerms, m_max: int = 3, sensitivity: str = "table", sigma_D_inc: ArrayLike | None = None, remainder: bool = True
) -> np.ndarray:
    """
    Eq. 10 for one polarisation: ``R_j = C_0 S^_j(0) + 2 sum_{m=1}^{m_max} C_m [cos(m phi_2) Re S^_j(mD)
    + sin(m phi_2) Im S^_j(mD)]``, with ``S^_j(0) = 1`` for the table (white), plus the series' remainder
    (:func:`fourier_remainder`) unless ``remainder`` is False (the paper's plain truncation).

    With ``sigma_D_inc`` (the standard deviation of ``D_inc``, nm; Section 5) each ``S^_j(mD)`` is the
    pre-filtered table at standard deviation ``m cos(theta_2) sigma_D_inc``
    (:func:`sensitivity_fourier_transform_prefiltered`; the table sensitivity only).

    Valid where the film propagates (Eq. 5 is a Fourier series in ``nu`` only there).

    Returns
    -------
    ndarray, shape ``terms.R12.shape + (3,)``: linear sRGB.

    References
    ----------
    Belcour & Barla (2017), Eqs. 9-10.
    """
    if int(m_max) < 0:
        raise ValueError(f"m_max must be >= 0, got {m_max}")
    D = terms.D
    phi_2 = terms.phi_2
    rgb = C_0(terms)[..., None] * np.real(sensitivity_fourier_transform(np.zeros_like(D), sensitivity))
    if sigma_D_inc is not None:
        sigma_D = sigma_D_inc * np.where(terms.film_propagates, terms.cos_theta_2.real, 0.0)
    def harmonic(m):  # z_m = e^{-i m phi_2} S^_j(m D): the m-th term is 2 C_m Re z_m
        if sigma_D_inc is None:
            S = sensitivity_fourier_transform(m * D, sensitivity)
        else:
            S = sensitivity_fourier_transform_prefiltered(m * D, m * sigma_D)
        return np.exp(-1j * m * phi_2)[..., None] * S

    z = harmonic(0)
    for m in range(1, int(m_max) + 1):
        z = harmonic(m)
        rgb = rgb + 2.0 * C_m(terms, m)[..., None] * z.real
    if remainder:
        rgb = rgb + fourier_remainder(terms, int(m_max), z, harmonic(int(m_max) + 1))
    return rgb


#: The least ``|z_M|`` for which :func:`fourier_remainder` extrapolates (GLSL: the same, in float32).
REMAINDER_MIN = 1e-15


def fourier_remainder(terms: FilmTerms, m_max: int, z_M: ArrayLike, z_next: ArrayLike) -> np.ndarray:
    """
    The terms of Eq. 10 beyond ``m_max``, summed in closed form.

    The coefficients are geometric, ``C_m = C_M R_l^(m - M)`` (Eq. 6), and the harmonics
    ``z_m = e^{-i m phi_2} S^_j(m D)`` are extrapolated geometrically from the last two,
    ``z_m ~ z_M r^(m - M)`` with ``r = z_(M+1) / z_M`` (``|r| <= 1``), so
    ``sum_{m > M} 2 C_m Re z_m = 2 C_M Re(z_M q / (1 - q))``, ``q = R_l r``.

    The extrapolation is exact as ``D -> 0`` (``S^_j(m D) ~ e^{-2 pi i m D nu_j}``: a flat spectrum, the
    Airy reflectance at one phase) and vanishes where ``S^_j(M D)`` has decayed, where the paper's
    truncation is accurate. Near total internal reflection inside the film (``R_l -> 1``, ``D -> 0``)
    the truncated series overshoots, up to a luminance of 1.05 for a flat white; the remainder brings
    it back under 1 and to within ~1e-2 of the converged reference.

    Parameters
    ----------
    terms : FilmTerms
    m_max : int
        ``M``, the last harmonic summed explicitly (0 sums all of them here).
    z_M, z_next : ndarray of complex, shape ``terms.R12.shape + (3,)``
        ``z_M`` and ``z_(M+1)``.

    Returns
    -------
    ndarray, shape ``terms.R12.shape + (3,)``

    References
    ----------
    Belcour & Barla (2017), Eqs. 5-6 and 10 (the series this sums).
    """
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        # Below 1e-15 the remainder is negligible (it is of the order of z_M) and r ill-defined.
        resolved = np.abs(z_M) > REMAINDER_MIN
        r = np.where(resolved, z_next / np.where(resolved, z_M, 1.0), 0.0)
        r = r / np.maximum(np.abs(r), 1.0)
        q = terms.R_l[..., None] * r
        return 2.0 * C_m(terms, m_max)[..., None] * (z_M * q / (1.0 - q)).real


# --------------------------------------------------------------------------------------------------
# Colours: spectral reference, Fourier method, naive method


def _with_axis(*arrays):
    return tuple(np.asarray(a, dtype=np.float64)[..., None] for a in arrays)


def reference_rgb(
    eta_1: ArrayLike, eta_2: ArrayLike, eta_3: ArrayLike, kappa_3: ArrayLike, cos_theta_1: ArrayLike, thickness_d: ArrayLike,
    step: float | None = None,
) -> np.ndarray:
    """
    The spectral reference: the exact Airy reflectance, both polarisations averaged, integrated against
    the CMFs (:mod:`explorer.physics.colorimetry`), in linear sRGB.

    Parameters
    ----------
    eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d : array_like
        As in :func:`airy_reflectance`, broadcast against each other.
    step : float, optional
        ``None``: the converged integral against the CMFs interpolated linearly
        (:func:`explorer.physics.colorimetry.converged_spectra`; a thick film's fringes are narrower than a
        nanometre). A number: samples every ``1 / round(1 / step)`` nm; ``step = 1`` is the paper's
        sum over every nm from 360 to 830, what the shader's method 0 computes.

    Returns
    -------
    ndarray, shape ``broadcast shape + (3,)``

    References
    ----------
    Belcour & Barla (2017), Eq. 4 with a 1 nm step (their ground truth, Section 4).
    """
    validate_film(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d)
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d)))
    shape, flat = arrays[0].shape, [a.ravel() for a in arrays]

    def spectrum(wavelengths, rows):
        return airy_reflectance(*(a[rows][:, None] for a in flat), wavelengths)

    count = flat[0].size
    if step is None:
        # Fringes as from the optical path 2 eta_2 d cos theta_2 <= 2 eta_2 d.
        path = 2.0 * float(np.max(flat[1] * flat[5], initial=0.0))
        spectra, _ = colorimetry.converged_spectra(spectrum, count, substeps_min=colorimetry.substeps_for_fringes(path))
    else:
        spectra = colorimetry.fixed_step_spectra(spectrum, count, step)
    return colorimetry.spectrum_to_rgb(spectra).reshape(shape + (3,))


def naive_rgb(
    eta_1: ArrayLike, eta_2: ArrayLike, eta_3: ArrayLike, kappa_3: ArrayLike, cos_theta_1: ArrayLike, thickness_d: ArrayLike,
    wavelengths: ArrayLike = NAIVE_WAVELENGTHS, space: str = "rgb",
) -> np.ndarray:
    """
    The naive RGB method: the exact Airy reflectance at one wavelength per channel (Section 4, Fig. 7(a)).

    Parameters
    ----------
    eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d : array_like
        As in :func:`airy_reflectance`.
    wavelengths : sequence of 3 floats
        One wavelength (nm) per channel. The default :data:`NAIVE_WAVELENGTHS` (606, 539, 445 nm) are
        the peaks of this convention's R, G, B sensitivities: the paper's rule (the peak of each
        sensitivity curve) for the channels the product outputs, so flat spectra give exact greys.
    space : {'rgb', 'xyz'}
        ``'rgb'``: the samples are the linear sRGB channels. ``'xyz'``: they are X, Y, Z (the paper's
        Fig. 7(a), with :data:`PAPER_XYZ_WAVELENGTHS`), scaled by the white's XYZ and taken to RGB.

    Returns
    -------
    ndarray, shape ``broadcast shape + (3,)``: linear sRGB, unclamped.

    References
    ----------
    Belcour & Barla (2017), Section 4 (Validation) and Fig. 7(a); Fig. 2(a).
    """
    validate_film(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d)
    samples = airy_reflectance(
        *_with_axis(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d), np.asarray(wavelengths, dtype=np.float64)
    )
    if space == "rgb":
        return samples
    if space == "xyz":
        return colorimetry.xyz_to_rgb(samples * colorimetry.white_xyz())
    raise ValueError(f"space must be 'rgb' or 'xyz', not {space!r}")


def fourier_rgb(
    eta_1: ArrayLike, eta_2: ArrayLike, eta_3: ArrayLike, kappa_3: ArrayLike, cos_theta_1: ArrayLike, thickness_d: ArrayLike,
    m_max: int = 3, sensitivity: str = "table", sigma_D_inc: ArrayLike | None = None, remainder: bool = True,
) -> np.ndarray:
    """
    The paper's analytic spectral integration (Eq. 10) truncated at ``m_max``, both polarisations.

    Parameters
    ----------
    eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d : array_like
        As in :func:`airy_reflectance`.
    m_max : int
        Highest harmonic kept (the paper uses 1 to 3; 0 gives ``C_0``, the fringe average).
    sensitivity : {'table', 'gaussian', 'exact'}
        See :func:`sensitivity_fourier_transform`.
    sigma_D_inc : array_like, optional
        Standard deviation of ``D_inc`` (nm): Eq. 10 averaged over a Gaussian distribution of thickness
        (Section 5; see :func:`fourier_rgb_prefiltered`).
    remainder : bool
        Add the series' terms beyond ``m_max`` in closed form (:func:`fourier_remainder`); False is the
        paper's plain truncation (``m_max = 0``: the fringe average ``C_0``).

    Returns
    -------
    ndarray, shape ``broadcast shape + (3,)``: linear sRGB, unclamped.

    Notes
    -----
    Where the film is evanescent (``eta_1 sin theta_1 > eta_2``, possible only when ``eta_1 > eta_2``),
    ``R`` has no fringes and Eq. 5 does not apply; there the result is the exact reflectance at
    :data:`NAIVE_WAVELENGTHS`. The indices are constant over the spectrum, so the paper's "Fresnel terms
    constant per band" assumption holds exactly: the only errors are the truncation at ``m_max`` and the
    sensitivity's transform (tabulated, fitted).

    References
    ----------
    Belcour & Barla (2017), Eqs. 5-10 and Section 5 (BRDF evaluation).
    """
    eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d = validate_film(
        eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d
    )
    rgb = 0.0
    propagates = True
    for pol in POLARISATIONS:
        terms = film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, pol)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            rgb = rgb + 0.5 * spectral_integration_fourier(terms, m_max, sensitivity, sigma_D_inc, remainder)
        propagates = propagates & terms.film_propagates
    propagates = np.asarray(propagates)
    if np.all(propagates):
        return rgb
    naive = naive_rgb(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d)
    return np.where(propagates[..., None], rgb, naive)


# --------------------------------------------------------------------------------------------------
# Parametrisation by the optical path difference at normal incidence (Section 5)


def D_inc(eta_2: ArrayLike, thickness_d: ArrayLike) -> np.ndarray:
    """``D_inc = 2 eta_2 d``: the OPD at normal incidence (Section 5); then ``D = D_inc cos theta_2``."""
    return 2.0 * np.asarray(eta_2, dtype=np.float64) * np.asarray(thickness_d, dtype=np.float64)


def film_from_D_inc(D_inc: ArrayLike, eta_1: ArrayLike, eta_2: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """
    The film ``(eta_2', thickness_d)`` an artist's ``D_inc`` stands for (Section 5).

    ``eta_2' = eta_1 + (eta_2 - eta_1) smoothstep(0, D_INC_BLEND, D_inc)`` forces ``eta_2 -> eta_1`` as
    ``D_inc -> 0``, so that a vanishing film leaves the single interface ``eta_1 | eta_3`` (the paper:
    superimposed interfaces with different indices are not physical); ``thickness_d = D_inc / (2 eta_2')``
    keeps ``D = D_inc cos theta_2`` (``D_inc = 0`` gives ``d = 0``).

    Parameters
    ----------
    D_inc : array_like
        OPD at normal incidence, nm (``>= 0``).
    eta_1, eta_2 : array_like
        Exterior and film indices.

    Returns
    -------
    eta_2_effective, thickness_d : ndarray

    Raises
    ------
    ValueError
        On a negative ``D_inc``.

    References
    ----------
    Belcour & Barla (2017), Section 5 (Parametric control); the smoothstep width is the authors' code's.
    """
    D_inc = _real_array("D_inc", D_inc)
    if np.any(D_inc < 0.0):
        raise ValueError(f"D_inc must be >= 0 nm, got {np.min(D_inc):g}")
    eta_1, eta_2 = _real_array("eta_1", eta_1), _real_array("eta_2", eta_2)
    t = np.clip(D_inc / D_INC_BLEND, 0.0, 1.0)
    blend = t * t * (3.0 - 2.0 * t)
    eta_2_effective = eta_1 + (eta_2 - eta_1) * blend
    return eta_2_effective, D_inc / (2.0 * eta_2_effective)


# --------------------------------------------------------------------------------------------------
# Multi-scale rendering: Eq. 10 averaged over a Gaussian distribution of OPD (Section 5)

#: The pre-filtered table's scale axis: standard deviations ``sigma = k PREFILTER_SIGMA_STEP`` nm of the
#: OPD, ``k = 0 .. PREFILTER_LEVELS - 1`` (the last, 793.75 nm, damps every harmonic by 2e-8 or more, at 830 nm).
PREFILTER_SIGMA_STEP = 6.25
PREFILTER_LEVELS = 128


def _sensitivity_fourier_prefiltered() -> np.ndarray:
    """
    The pre-filtered Fourier table (Section 5, "Multi-scale Rendering"): for each level ``sigma_k``, the
    demodulated envelope of ``S^_j`` convolved with a centred Gaussian of standard deviation ``sigma_k``
    in the OPD variable,

        ``E_{j,k}(mu) = sum_lambda s_j(lambda) exp(-2 pi^2 sigma_k^2 / lambda^2) exp(-2 pi i mu (1/lambda - 1/carrier_j))``,

    since ``S^_j`` is a sum of complex exponentials ``exp(-2 pi i mu / lambda)`` and a Gaussian's
    characteristic function multiplies each by ``exp(-2 pi^2 sigma^2 / lambda^2)``. Level 0 is the
    ``sensitivity_fourier`` table. Shape ``(2 PREFILTER_LEVELS, SENSITIVITY_FOURIER_COUNT, 3)``: the real parts
    of every level, then the imaginary parts (the texture ``lib/thinfilm.glsl`` reads), float32.
    Computed by the host on first use (one complex matrix product per channel, under a second).
    """
    sensitivities = sensitivities_rgb()
    mu = np.arange(SENSITIVITY_FOURIER_COUNT, dtype=np.float64) * SENSITIVITY_FOURIER_STEP
    wavelengths = colorimetry.WAVELENGTHS.astype(np.float64)
    sigma = np.arange(PREFILTER_LEVELS, dtype=np.float64) * PREFILTER_SIGMA_STEP
    damping = np.exp(-2.0 * np.pi**2 * (sigma[:, None] / wavelengths[None, :]) ** 2)  # (levels, 471)
    table = np.empty((2, PREFILTER_LEVELS, mu.size, 3), dtype=np.float64)
    for j, carrier in enumerate(SENSITIVITY_FOURIER_CARRIER_NM):
        phase = np.exp(-2j * np.pi * (1.0 / wavelengths - 1.0 / carrier)[:, None] * mu[None, :])  # (471, mu)
        envelope = (damping * sensitivities[None, :, j]).astype(np.complex128) @ phase
        table[0, :, :, j], table[1, :, :, j] = envelope.real, envelope.imag
    return table.reshape(2 * PREFILTER_LEVELS, mu.size, 3).astype(np.float32)


_PREFILTERED: list[np.ndarray] = []


def sensitivity_fourier_prefiltered() -> np.ndarray:
    """:func:`_sensitivity_fourier_prefiltered`, computed once per process."""
    if not _PREFILTERED:
        _PREFILTERED.append(_sensitivity_fourier_prefiltered())
    return _PREFILTERED[0]


def sensitivity_fourier_transform_prefiltered(mu: ArrayLike, sigma: ArrayLike) -> np.ndarray:
    """
    ``S^_j`` averaged over OPDs distributed as a Gaussian of mean ``mu`` and standard deviation ``sigma``
    (nm): the pre-filtered table interpolated bilinearly in ``(mu, sigma)``, as ``lib/thinfilm.glsl``
    does, times the carrier; 0 beyond the last ``mu`` node; ``sigma`` clamped to the last level.

    Returns
    -------
    ndarray of complex, shape ``broadcast(mu, sigma).shape + (3,)``
    """
    table = sensitivity_fourier_prefiltered().astype(np.float64)
    mu, sigma = np.broadcast_arrays(np.asarray(mu, dtype=np.float64), np.asarray(sigma, dtype=np.float64))
    x = mu / SENSITIVITY_FOURIER_STEP
    last = SENSITIVITY_FOURIER_COUNT - 1
    inside = (x >= 0.0) & (x <= last)
    x = np.clip(x, 0.0, last)
    i = np.minimum(np.floor(x).astype(np.int64), last - 1)
    f = (x - i)[..., None]
    y = np.clip(sigma / PREFILTER_SIGMA_STEP, 0.0, PREFILTER_LEVELS - 1)
    k = np.minimum(np.floor(y).astype(np.int64), PREFILTER_LEVELS - 2)
    g = (y - k)[..., None]

    def level(row_offset):
        def at(rows, cols):
            return table[rows + row_offset, cols]

        low = at(k, i) * (1.0 - f) + at(k, i + 1) * f
        high = at(k + 1, i) * (1.0 - f) + at(k + 1, i + 1) * f
        return low * (1.0 - g) + high * g

    envelope = level(0) + 1j * level(PREFILTER_LEVELS)
    carrier = np.exp(-2j * np.pi * mu[..., None] / np.asarray(SENSITIVITY_FOURIER_CARRIER_NM))
    return np.where(inside[..., None], envelope * carrier, 0.0)


def fourier_rgb_prefiltered(
    eta_1: ArrayLike, eta_2: ArrayLike, eta_3: ArrayLike, kappa_3: ArrayLike, cos_theta_1: ArrayLike, thickness_d: ArrayLike,
    sigma_D_inc: ArrayLike, m_max: int = 3,
) -> np.ndarray:
    """
    Eq. 10 integrated against a Gaussian distribution of thickness (Section 5, Multi-scale Rendering):

        ``R̄_j = C_0 + 2 sum_m C_m [cos(m phi_2), sin(m phi_2)] . ∫ [Re, Im] S^_j(m D) P(d) dd``.

    Only ``S^`` depends on ``d``; with ``D = D_inc cos theta_2`` the OPD of harmonic ``m`` has mean
    ``m D̄`` and standard deviation ``m cos theta_2 sigma_D_inc`` (the paper's ``tau = m 2 eta_2 cos theta_2``
    applied to ``d``), so each term is the pre-filtered table at that mean and scale
    (:func:`sensitivity_fourier_transform_prefiltered`). ``thickness_d`` is the mean thickness,
    ``sigma_D_inc`` the standard deviation of ``D_inc`` (nm). Evanescent film: as :func:`fourier_rgb`.
    """
    return fourier_rgb(
        eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, m_max,
        sigma_D_inc=_real_array("sigma_D_inc", sigma_D_inc),
    )
