"""
Thin films: the Airy reflectance of a dielectric film over a dielectric or conducting base, and its
analytic spectral integration in Fourier space (Belcour & Barla 2017).

A film of real index ``eta_2`` and thickness ``thickness_d`` (nm) lies on a base of complex index
``eta_3 + i kappa_3`` (``kappa_3 = 0``: a dielectric, ``kappa_3 > 0``: a conductor), under an
exterior medium of real index ``eta_1``. Light arrives from the exterior; ``cos_theta_1`` is the
cosine of its angle of incidence (the paper's ``h . omega_i``), kept at or above
:data:`COS_THETA_MIN` as in :mod:`explorer.physics.bragg`. Wavelengths and optical path differences are in
nm. Every function broadcasts its arguments against each other (angles, wavelengths and the
material's parameters alike).

Conventions are those of :mod:`explorer.physics.fresnel` and of ``tmm``: waves travel as ``exp(+i k_z z)``,
an absorbing index is ``eta + i kappa`` with ``kappa >= 0``, and ``r_p`` has ``tmm``'s sign. They are
also the paper's: its Eq. 3 has ``exp(+i Delta phi)`` and its base ``eta_3 + i kappa_3``, so the
phases on reflection ``phi_ab = arg(r_ab)`` are used exactly as its Eqs. 5-10 write them.

Colours follow the product's convention (:mod:`explorer.physics.colorimetry`) and come out in linear sRGB,
unclamped:

- :func:`reference_rgb`, the spectral reference: the exact Airy reflectance at every nm from 360 to
  830, both polarisations, integrated against the CMFs;
- :func:`fourier_rgb`, the paper's method: Eq. 10 truncated at ``m_max`` (1 to 3), with the Fourier
  transform of this convention's RGB sensitivities tabulated in ``luts/`` (``'table'``), the paper's
  Gaussian fits (``'gaussian'``), or computed exactly (``'exact'``, for validation);
- :func:`naive_rgb`: the Airy reflectance at one wavelength per channel (:data:`NAIVE_WAVELENGTHS`).

The Appendix's closed form of ``R`` cancels catastrophically near grazing incidence; it is evaluated
here in the exactly equivalent form ``R = 1 - T12 T23 / |1 - R_l e^{i Phi}|^2`` (see
:func:`airy_reflectance_from_terms`), and ``C_m`` likewise (:func:`C_m`).

References
----------
Belcour, Barla (2017). A Practical Extension to Microfacet Theory for the Modeling of Varying
Iridescence. ACM Transactions on Graphics 36(4), Article 65. Sections 3-5 and Appendix.
Born and Wolf, Principles of Optics, Sections 1.5-1.6 and 13.2. Yeh (1988), Optical Waves in Layered
Media, Section 4.2 (Airy summation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.tables import luts
from explorer.physics.fresnel import cos_theta_transmitted, fresnel_r


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


#: Cosines are kept away from exact grazing incidence, where every interface reflects totally.
COS_THETA_MIN = 1e-6
POLARISATIONS = ("s", "p")
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
# Input validation


def _real_array(name: str, value) -> np.ndarray:
    array = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return array


def validate_film(
    eta_1: ArrayLike, eta_2: ArrayLike, eta_3: ArrayLike, kappa_3: ArrayLike, cos_theta_1: ArrayLike, thickness_d: ArrayLike,
) -> tuple[np.ndarray, ...]:
    """
    The film's parameters as float arrays, or a ``ValueError`` with a one-line message.

    Indices must be positive, ``kappa_3`` and ``thickness_d`` non-negative, everything finite;
    ``cos_theta_1`` is clipped to ``[COS_THETA_MIN, 1]``.
    """
    eta_1, eta_2, eta_3 = (_real_array(n, v) for n, v in (("eta_1", eta_1), ("eta_2", eta_2), ("eta_3", eta_3)))
    kappa_3 = _real_array("kappa_3", kappa_3)
    cos_theta_1 = _real_array("cos_theta_1", cos_theta_1)
    thickness_d = _real_array("thickness_d", thickness_d)
    for name, value in (("eta_1", eta_1), ("eta_2", eta_2), ("eta_3", eta_3)):
        if np.any(value <= 0.0):
            raise ValueError(f"{name} must be positive, got {np.min(value):g}")
    if np.any(kappa_3 < 0.0):
        raise ValueError(f"kappa_3 must be >= 0 (an absorbing base; gain media are not modelled), got {np.min(kappa_3):g}")
    if np.any(thickness_d < 0.0):
        raise ValueError(f"thickness_d must be >= 0 nm, got {np.min(thickness_d):g}")
    return eta_1, eta_2, eta_3, kappa_3, np.clip(cos_theta_1, COS_THETA_MIN, 1.0), thickness_d


def _validate_wavelength(wavelength) -> np.ndarray:
    wavelength = _real_array("wavelength", wavelength)
    if np.any(wavelength <= 0.0):
        raise ValueError(f"wavelength must be positive (nm), got {np.min(wavelength):g}")
    return wavelength


# --------------------------------------------------------------------------------------------------
# Snell and Fresnel with a conducting base (explorer.physics.fresnel is dielectric-only)


def cos_theta_transmitted_conductor(cos_theta_1: ArrayLike, eta_1: ArrayLike, eta_3: ArrayLike, kappa_3: ArrayLike) -> np.ndarray:
    """
    Cosine of the complex refraction angle into a base of index ``eta_3 + i kappa_3``.

    Snell's law ``eta_1 sin theta_1 = (eta_3 + i kappa_3) sin theta_3`` through the normal wave number
    ``q_3 = n_3 cos theta_3 = sqrt(n_3^2 - eta_1^2 sin^2 theta_1)``, on the branch ``Im q_3 >= 0`` (the
    wave decays into the base; with ``kappa_3 = 0`` this is :func:`explorer.physics.fresnel.cos_theta_transmitted`,
    total internal reflection included).
    """
    cos_theta_1 = np.asarray(cos_theta_1, dtype=np.float64)
    n_3 = np.asarray(eta_3, dtype=np.float64) + 1j * np.asarray(kappa_3, dtype=np.float64)
    q_3 = np.sqrt(n_3 * n_3 - np.asarray(eta_1) ** 2 * (1.0 - cos_theta_1**2))
    q_3 = np.where(q_3.imag < 0.0, -q_3, q_3)
    # Exactly at a critical angle q_3 = 0 and a Fresnel coefficient would be 0/0; stay on the
    # evanescent side by a negligible amount.
    q_3 = np.where(np.abs(q_3) < 1e-12, 1e-12j, q_3)
    return q_3 / n_3


def fresnel_t(polarisation: str, eta_i: ArrayLike, cos_theta_i: ArrayLike, eta_t: ArrayLike, cos_theta_t: ArrayLike) -> np.ndarray:
    """
    Amplitude transmission coefficient (the ``tmm`` convention, as :func:`explorer.physics.fresnel.fresnel_r`):
    ``t_s = 2 a / (a + b)`` with ``a = eta_i cos_i``, ``b = eta_t cos_t``; ``t_p = 2 a / (eta_t cos_i + eta_i cos_t)``.
    """
    a = eta_i * cos_theta_i
    if polarisation == "s":
        return 2.0 * a / (a + eta_t * cos_theta_t)
    if polarisation == "p":
        return 2.0 * a / (eta_t * cos_theta_i + eta_i * cos_theta_t)
    raise ValueError(f"polarisation must be 's' or 'p', not {polarisation!r}")


def _power_factor(polarisation: str, eta_i, cos_theta_i, eta_t, cos_theta_t) -> np.ndarray:
    """``T / |t|^2`` for a wave leaving medium ``i`` into ``t``: the ratio of the normal Poynting fluxes
    (``Re(n_t cos_t) / Re(n_i cos_i)`` for s, with ``conj(cos)`` for p), as ``tmm`` defines it."""
    if polarisation == "s":
        return np.real(eta_t * cos_theta_t) / np.real(eta_i * cos_theta_i)
    return np.real(eta_t * np.conj(cos_theta_t)) / np.real(eta_i * np.conj(cos_theta_i))


# --------------------------------------------------------------------------------------------------
# The film at one angle and polarisation (Section 3, Eq. 6 and Appendix)


@dataclass
class FilmTerms:
    """
    A film's wavelength-independent quantities for one polarisation.

    The amplitudes ``r_ab``, ``t_ab`` are complex Fresnel coefficients from medium ``a`` to ``b``
    (``1`` exterior, ``2`` film, ``3`` base); ``R_ab = |r_ab|^2``; ``phi_2 = phi_21 + phi_23`` the
    phase shifts on reflection inside the film (Eq. 9); ``D = 2 eta_2 d cos theta_2`` the optical
    path difference (Section 3); ``film_propagates`` is False where the film is evanescent
    (``eta_1 sin theta_1 > eta_2``), where only Eq. 3 holds and the Fourier series of Eq. 5 does not.
    """

    cos_theta_1: np.ndarray
    cos_theta_2: np.ndarray
    cos_theta_3: np.ndarray
    eta_1: np.ndarray
    eta_2: np.ndarray
    n_3: np.ndarray
    thickness_d: np.ndarray
    r12: np.ndarray
    r21: np.ndarray
    r23: np.ndarray
    t12: np.ndarray
    t21: np.ndarray
    t23: np.ndarray
    polarisation: str

    @property
    def film_propagates(self) -> np.ndarray:
        return (self.cos_theta_2.imag == 0.0) & (self.cos_theta_2.real > 0.0)

    @property
    def D(self) -> np.ndarray:
        """Optical path difference ``D = 2 eta_2 d cos theta_2`` (Section 3; 0 where evanescent)."""
        return optical_path_difference(self.eta_2, np.where(self.film_propagates, self.cos_theta_2.real, 0.0), self.thickness_d)

    @property
    def R12(self) -> np.ndarray:
        return np.abs(self.r12) ** 2

    @property
    def R21(self) -> np.ndarray:
        return np.abs(self.r21) ** 2

    @property
    def R23(self) -> np.ndarray:
        return np.abs(self.r23) ** 2

    @property
    def sqrt_T12T21(self) -> np.ndarray:
        """``sqrt(T12 T21) = |t12| |t21|`` (Appendix). Where the film propagates, ``t12 t21 = 1 - r12^2``
        is real and this is ``T12 = T21 = 1 - R12``, computed without cancellation at grazing angles."""
        return np.abs(self.t12 * self.t21)

    @property
    def T23(self) -> np.ndarray:
        """The power transmitted into the base at the film's lower interface, ``= 1 - R23`` (0 under total
        internal reflection; for a conductor, the power it absorbs), without cancellation."""
        with np.errstate(invalid="ignore", divide="ignore"):
            factor = _power_factor(self.polarisation, self.eta_2, self.cos_theta_2, self.n_3, self.cos_theta_3)
        return factor * np.abs(self.t23) ** 2

    @property
    def R_l(self) -> np.ndarray:
        """``R_l = sqrt(R23 R21)`` (Appendix): the ratio of successive orders' amplitudes."""
        return np.sqrt(self.R23 * self.R21)

    @property
    def one_minus_R_l2(self) -> np.ndarray:
        """``1 - R23 R21 = T21 + T23 - T21 T23`` where the film propagates (no cancellation as ``R_l -> 1``)."""
        T21, T23 = self.sqrt_T12T21, self.T23
        return T21 + T23 - T21 * T23

    @property
    def R_star(self) -> np.ndarray:
        """``R* = T12 T21 R23 / (1 - R23 R21)`` (Eq. 6): all inter-reflections inside the film."""
        return self.sqrt_T12T21**2 * self.R23 / self.one_minus_R_l2

    @property
    def phi_2(self) -> np.ndarray:
        """``phi_2 = phi_21 + phi_23``, the phases of ``r21`` and ``r23`` (Eq. 9)."""
        return np.angle(self.r21) + np.angle(self.r23)

    @property
    def T12T23(self) -> np.ndarray:
        """``T12 T23 = (eta_3 cos theta_3)/(eta_1 cos theta_1) |t12|^2 |t23|^2`` (Appendix), the
        Poynting-flux ratio generalised to complex angles and bases as ``tmm`` does."""
        factor = _power_factor(self.polarisation, self.eta_1, self.cos_theta_1, self.n_3, self.cos_theta_3)
        return factor * np.abs(self.t12 * self.t23) ** 2


def optical_path_difference(eta_2: ArrayLike, cos_theta_2: ArrayLike, thickness_d: ArrayLike) -> np.ndarray:
    """``D = 2 eta_2 d cos theta_2`` (Section 3), in nm; the order-``k`` path difference is ``k D``."""
    return 2.0 * np.asarray(eta_2) * np.asarray(cos_theta_2) * np.asarray(thickness_d)


def phase_shift(D: ArrayLike, wavelength: ArrayLike) -> np.ndarray:
    """``Delta phi = 2 pi nu D`` with ``nu = 1 / lambda`` (Section 3): the OPD's phase."""
    return 2.0 * np.pi * np.asarray(D) / np.asarray(wavelength)


def film_terms(
    eta_1: ArrayLike, eta_2: ArrayLike, eta_3: ArrayLike, kappa_3: ArrayLike, cos_theta_1: ArrayLike, thickness_d: ArrayLike,
    polarisation: str,
) -> FilmTerms:
    """
    Snell's law into the film and the base, and the Fresnel coefficients of both interfaces.

    Parameters
    ----------
    eta_1, eta_2 : array_like
        Real indices of the exterior and of the film.
    eta_3, kappa_3 : array_like
        Complex index ``eta_3 + i kappa_3`` of the base (``kappa_3 >= 0``).
    cos_theta_1 : array_like
        Cosine of the incidence angle in the exterior.
    thickness_d : array_like
        Film thickness in nm (``>= 0``).
    polarisation : {'s', 'p'}

    Returns
    -------
    FilmTerms

    Raises
    ------
    ValueError
        On a negative thickness, ``kappa_3 < 0``, a non-positive index or a non-finite value.
    """
    if polarisation not in POLARISATIONS:
        raise ValueError(f"polarisation must be 's' or 'p', not {polarisation!r}")
    eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d = validate_film(
        eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d
    )
    cos_1 = cos_theta_1.astype(np.complex128)
    cos_2 = cos_theta_transmitted(cos_theta_1, eta_1, eta_2)
    cos_2 = np.where(np.abs(cos_2) < 1e-12, 1e-12j, cos_2)  # exactly at the film's critical angle
    cos_3 = cos_theta_transmitted_conductor(cos_theta_1, eta_1, eta_3, kappa_3)
    n_3 = eta_3 + 1j * kappa_3
    return FilmTerms(
        cos_theta_1=cos_theta_1,
        cos_theta_2=cos_2,
        cos_theta_3=cos_3,
        eta_1=eta_1,
        eta_2=eta_2,
        n_3=n_3,
        thickness_d=thickness_d,
        r12=fresnel_r(polarisation, eta_1, cos_1, eta_2, cos_2),
        r21=fresnel_r(polarisation, eta_2, cos_2, eta_1, cos_1),
        r23=fresnel_r(polarisation, eta_2, cos_2, n_3, cos_3),
        t12=fresnel_t(polarisation, eta_1, cos_1, eta_2, cos_2),
        t21=fresnel_t(polarisation, eta_2, cos_2, eta_1, cos_1),
        t23=fresnel_t(polarisation, eta_2, cos_2, n_3, cos_3),
        polarisation=polarisation,
    )


def _polarisations(polarisation: str | None) -> tuple[str, ...]:
    if polarisation is None:
        return POLARISATIONS
    if polarisation not in POLARISATIONS:
        raise ValueError(f"polarisation must be 's', 'p' or None, not {polarisation!r}")
    return (polarisation,)


# --------------------------------------------------------------------------------------------------
# Airy reflectance and transmittance (Eqs. 2-3, Appendix)


def _complex_phase(terms: FilmTerms, wavelength) -> np.ndarray:
    """``exp(i Delta phi)`` with the complex ``Delta phi = 2 pi nu 2 eta_2 d cos theta_2``: decays
    (``|.| <= 1``) where the film is evanescent."""
    return np.exp(2j * np.pi * 2.0 * terms.eta_2 * terms.thickness_d * terms.cos_theta_2 / wavelength)


def airy_reflection_coefficient_from_terms(terms: FilmTerms, wavelength: ArrayLike) -> np.ndarray:
    """Airy summation (Eq. 3): ``r = r12 + t12 r23 t21 e^{i Dphi} / (1 - r21 r23 e^{i Dphi})``."""
    e = _complex_phase(terms, wavelength)
    return terms.r12 + terms.t12 * terms.r23 * terms.t21 * e / (1.0 - terms.r21 * terms.r23 * e)


def airy_transmission_coefficient_from_terms(terms: FilmTerms, wavelength: ArrayLike) -> np.ndarray:
    """Airy summation for transmission (Appendix): ``t = t12 t23 e^{i Dphi/2} / (1 - r21 r23 e^{i Dphi})``
    (``e^{i Dphi / 2}`` is the one crossing, the Appendix's ``delta phi``)."""
    e = _complex_phase(terms, wavelength)
    return terms.t12 * terms.t23 * np.sqrt(e) / (1.0 - terms.r21 * terms.r23 * e)


def _Phi(terms: FilmTerms, wavelength) -> np.ndarray:
    """``Phi = Delta phi + phi_23 + phi_21`` (Section 4)."""
    return phase_shift(terms.D, wavelength) + terms.phi_2


def _airy_series_factor(R_l, Phi) -> np.ndarray:
    """``2 (R_l cos Phi - R_l^2) / (1 - 2 R_l cos Phi + R_l^2)`` = ``2 sum_m R_l^m cos(m Phi)`` (Appendix)."""
    cos_Phi = np.cos(Phi)
    return 2.0 * (R_l * cos_Phi - R_l**2) / (1.0 - 2.0 * R_l * cos_Phi + R_l**2)


def _airy_denominator(terms: FilmTerms, Phi) -> np.ndarray:
    """``|1 - R_l e^{i Phi}|^2 = 1 - 2 R_l cos Phi + R_l^2``, as ``(1 - R_l)^2 + 4 R_l sin^2(Phi/2)`` with
    ``1 - R_l = (1 - R_l^2) / (1 + R_l)``: accurate where both ``R_l -> 1`` and ``Phi -> 0`` (grazing)."""
    R_l = terms.R_l
    one_minus_R_l = terms.one_minus_R_l2 / (1.0 + R_l)
    return one_minus_R_l**2 + 4.0 * R_l * np.sin(0.5 * Phi) ** 2


def airy_reflectance_appendix_from_terms(terms: FilmTerms, wavelength: ArrayLike) -> np.ndarray:
    """
    The Appendix's closed form, literally:
    ``R = R12 + R* + 2 (R_l cos Phi - R_l^2) / (1 - 2 R_l cos Phi + R_l^2) (R* - sqrt(T12 T21))``.

    Valid where the film propagates. Its last product cancels catastrophically near grazing incidence
    (``R_l -> 1`` and ``R* - sqrt(T12 T21) -> 0``: errors ~1e-5 at ``cos theta_1 = 1e-6``);
    :func:`airy_reflectance_from_terms` evaluates the same quantity without cancellation.
    """
    return terms.R12 + terms.R_star + _airy_series_factor(terms.R_l, _Phi(terms, wavelength)) * (
        terms.R_star - terms.sqrt_T12T21
    )


def airy_reflectance_from_terms(terms: FilmTerms, wavelength: ArrayLike) -> np.ndarray:
    """
    The spectral Airy reflectance for one polarisation: the Appendix's closed form, rearranged.

    Where the film propagates, ``sqrt(T12 T21) = T12 = 1 - R12`` and ``1 - R_l^2 = 1 - R21 R23``, so
    ``(1 - R_l^2)(R* - sqrt(T12 T21)) = -T12 (1 - R23)`` and the Appendix's
    ``R = R12 + R* + 2 (R_l cos Phi - R_l^2) / (1 - 2 R_l cos Phi + R_l^2) (R* - sqrt(T12 T21))``
    is exactly ``R = 1 - T12 T23 / |1 - R_l e^{i Phi}|^2`` (``T23 = 1 - R23``), which has no
    cancellation at grazing angles (:func:`airy_reflectance_appendix_from_terms` is the literal form).
    Where the film is evanescent, ``|r|^2`` of Eq. 3 (the closed form assumes a propagating film).
    """
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        closed = 1.0 - terms.sqrt_T12T21 * terms.T23 / _airy_denominator(terms, _Phi(terms, wavelength))
    propagates = terms.film_propagates
    if np.all(propagates):
        return closed
    evanescent = np.abs(airy_reflection_coefficient_from_terms(terms, wavelength)) ** 2
    return np.where(propagates, closed, evanescent)


def airy_transmittance_from_terms(terms: FilmTerms, wavelength: ArrayLike) -> np.ndarray:
    """
    The spectral Airy transmittance for one polarisation (Appendix):
    ``T = T* (1 + 2 (R_l cos Phi - R_l^2) / (1 - 2 R_l cos Phi + R_l^2))`` with
    ``T* = T12 T23 / (1 - R23 R21)``, i.e. ``T = T12 T23 / |1 - R_l e^{i Phi}|^2``; where the film is
    evanescent, ``|t|^2`` of the Airy sum times the flux ratio. For a conducting base, the power
    entering (absorbed by) the base.
    """
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        closed = terms.T12T23 / _airy_denominator(terms, _Phi(terms, wavelength))
    propagates = terms.film_propagates
    if np.all(propagates):
        return closed
    factor = _power_factor(terms.polarisation, terms.eta_1, terms.cos_theta_1, terms.n_3, terms.cos_theta_3)
    evanescent = factor * np.abs(airy_transmission_coefficient_from_terms(terms, wavelength)) ** 2
    return np.where(propagates, closed, evanescent)


def airy_reflection_coefficient(
    eta_1: ArrayLike, eta_2: ArrayLike, eta_3: ArrayLike, kappa_3: ArrayLike, cos_theta_1: ArrayLike, thickness_d: ArrayLike,
    wavelength: ArrayLike, polarisation: str,
) -> np.ndarray:
    """
    The film's complex amplitude reflection coefficient ``r`` by Airy summation (Eqs. 2-3).

    Parameters
    ----------
    eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d : array_like
        As in :func:`film_terms`.
    wavelength : array_like
        Vacuum wavelength in nm.
    polarisation : {'s', 'p'}

    Returns
    -------
    ndarray of complex
        ``r`` in the ``tmm`` convention (equal to ``coh_tmm(...)['r']``).
    """
    wavelength = _validate_wavelength(wavelength)
    terms = film_terms(eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d, polarisation)
    return airy_reflection_coefficient_from_terms(terms, wavelength)


def _polarisation_average(of_terms, film, wavelength, polarisation: str | None) -> np.ndarray:
    """``of_terms(film_terms(*film, pol), wavelength)`` for one polarisation, or averaged over both."""
    wavelength = _validate_wavelength(wavelength)
    pols = _polarisations(polarisation)
    return sum(of_terms(film_terms(*film, pol), wavelength) for pol in pols) / len(pols)


def airy_reflectance(
    eta_1: ArrayLike, eta_2: ArrayLike, eta_3: ArrayLike, kappa_3: ArrayLike, cos_theta_1: ArrayLike, thickness_d: ArrayLike,
    wavelength: ArrayLike, polarisation: str | None = None,
) -> np.ndarray:
    """
    The spectral Airy reflectance ``R`` of a thin film (Eqs. 2-3; the Appendix's closed form).

    Multiple reflections inside the film, polarisation and the phase shifts on reflection (dielectric
    or conducting base, total internal reflection) are all accounted for. Vectorised: every argument
    broadcasts against the others (e.g. ``cos_theta_1[:, None]`` against a row of wavelengths).

    Parameters
    ----------
    eta_1 : array_like
        Real index of the exterior medium.
    eta_2 : array_like
        Real index of the film.
    eta_3, kappa_3 : array_like
        Complex index ``eta_3 + i kappa_3`` of the base (``kappa_3 = 0``: dielectric).
    cos_theta_1 : array_like
        Cosine of the incidence angle (clipped to ``[COS_THETA_MIN, 1]``).
    thickness_d : array_like
        Film thickness ``d`` in nm.
    wavelength : array_like
        Vacuum wavelength in nm.
    polarisation : {'s', 'p', None}
        ``None`` averages both, ``R = (|r_s|^2 + |r_p|^2) / 2`` (Section 3).

    Returns
    -------
    ndarray
        Reflectance in [0, 1].

    Raises
    ------
    ValueError
        On ``thickness_d < 0``, ``kappa_3 < 0``, a non-positive index or wavelength, a non-finite value.

    References
    ----------
    Belcour & Barla (2017), Eqs. 2-3 and the Appendix ("Derivation of Cm and R in closed form").
    """
    return _polarisation_average(
        airy_reflectance_from_terms, (eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d), wavelength, polarisation
    )


def airy_transmittance(
    eta_1: ArrayLike, eta_2: ArrayLike, eta_3: ArrayLike, kappa_3: ArrayLike, cos_theta_1: ArrayLike, thickness_d: ArrayLike,
    wavelength: ArrayLike, polarisation: str | None = None,
) -> np.ndarray:
    """
    The spectral Airy transmittance ``T`` into the base (Appendix, "The case of transmission").

    For a dielectric base ``R + T = 1`` (the film is lossless); for a conducting base ``T`` is the power
    entering (and absorbed by) the base, as ``tmm`` defines it. Arguments as in :func:`airy_reflectance`.

    Returns
    -------
    ndarray
        Transmittance in [0, 1] (0 under total internal reflection at the base).

    References
    ----------
    Belcour & Barla (2017), Appendix: ``T = T* (1 + 2 (R_l cos Phi - R_l^2) / (1 - 2 R_l cos Phi + R_l^2))``.
    """
    return _polarisation_average(
        airy_transmittance_from_terms, (eta_1, eta_2, eta_3, kappa_3, cos_theta_1, thickness_d), wavelength, polarisation
    )


# --------------------------------------------------------------------------------------------------
# The Fourier series of R (Eqs. 5-6)


def C_0(terms: FilmTerms) -> np.ndarray:
    """``C_0 = R12 + R*`` (Eq. 6): the DC term, the film's reflectance averaged over its fringes."""
    return terms.R12 + terms.R_star


def C_m(terms: FilmTerms, m: int) -> np.ndarray:
    """
    ``C_m = (sqrt(R23 R21))^m (R* - sqrt(T12 T21))`` (Eq. 6; Appendix), ``m >= 1``.

    Evaluated as ``-R_l^m T12 T23 / (1 - R_l^2)``, the same quantity where the film propagates (see
    :func:`airy_reflectance_from_terms`) without the cancellation of ``R* - sqrt(T12 T21)`` at grazing
    angles. Never positive; all vanish at grazing incidence (Fig. 22).
    """
    return -(terms.R_l**m) * terms.sqrt_T12T21 * terms.T23 / terms.one_minus_R_l2


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
