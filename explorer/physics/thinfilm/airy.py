"""
A thin film at one angle and polarisation (Belcour & Barla 2017, Section 3, Eq. 6 and Appendix): input validation,
Snell and Fresnel with a conducting base, the Airy reflectance and transmittance (Eqs. 2-3) and the Fourier series of
R (Eqs. 5-6). Numpy only; GLSL twins of the same names in ``shaders/lib/thinfilm.glsl``. See
:mod:`explorer.physics.thinfilm` for the conventions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics.fresnel import cos_theta_transmitted, fresnel_r

#: Cosines are kept away from exact grazing incidence, where every interface reflects totally.
COS_THETA_MIN = 1e-6
POLARISATIONS = ("s", "p")


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
