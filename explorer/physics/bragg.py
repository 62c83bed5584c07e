"""
Bragg mirrors: Yeh's closed-form reflectance, its spectral landmarks and the piecewise-constant RGB
approximation of Fourneau et al. (2024).

A mirror is ``N`` cells, each a layer of index ``n2`` (thickness ``d2``) followed by a layer of index
``n1`` (thickness ``d1``), between a host medium ``nh`` above and ``n1`` below. With ``nh == n1`` (the
default) this is the paper's mirror (its Figure 2(d)); with ``nh != n1`` the host interface is added
as in its Appendix D, directly above the first ``n2`` layer. ``Lambda = d1 + d2`` and
``delta = d1 / Lambda``.

Angles are given as the cosine of the incidence angle in the host; wavelengths in nanometres;
``omega = 2 pi / lambda`` (rad/nm) is the paper's spectral variable (Section 3.2.1). Waves travel as
``exp(+i k_z z)`` (the ``tmm`` convention; the paper's Eq. 10 is written in the opposite one, which
conjugates amplitudes and leaves reflectances unchanged). Every function here is numpy only and has a
GLSL twin of the same name in ``shaders/lib/bragg.glsl``.

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. Computer Graphics Forum 43(2). Sections 3.1-3.2, Appendices A, B, D.
Yeh (1988). Optical Waves in Layered Media, Chapter 6.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable, Iterator

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.physics.fresnel import cos_theta_transmitted, fresnel_r

#: Bisection steps for each landmark (Airy point, band-gap edges). The GLSL twin uses the same count.
BISECTION_STEPS = 12
#: The visible range of the approximation: the edges of the 1 nm bins of the spectral reference.
WAVELENGTH_LOW = colorimetry.WAVELENGTH_MIN - 0.5
WAVELENGTH_HIGH = colorimetry.WAVELENGTH_MAX + 0.5
#: Cosines are kept away from exact grazing incidence, where every interface reflects totally.
COS_THETA_MIN = 1e-6
POLARISATIONS = ("s", "p")


@dataclass(frozen=True)
class BraggMirror:
    """
    A Bragg mirror: ``N`` cells of ``(n2, d2), (n1, d1)`` in a host of index ``nh``.

    Parameters
    ----------
    n1, n2 : float
        Refractive indices of the two layers of a cell (real: dielectric media).
    Lambda : float
        Period ``d1 + d2`` in nm.
    delta : float
        Relative thickness ``d1 / Lambda`` in [0, 1].
    N : int
        Number of cells (1 gives a thin film of index ``n2`` and thickness ``d2``).
    nh : float, optional
        Index of the host medium above the mirror; defaults to ``n1`` (Appendix D otherwise).
    """

    n1: float = 1.0
    n2: float = 1.5
    Lambda: float = 500.0
    delta: float = 0.5
    N: int = 20
    nh: float | None = None

    @property
    def d1(self) -> float:
        return self.delta * self.Lambda

    @property
    def d2(self) -> float:
        return (1.0 - self.delta) * self.Lambda

    @property
    def eta_h(self) -> float:
        return self.n1 if self.nh is None else self.nh


# --------------------------------------------------------------------------------------------------
# Per-angle quantities


@dataclass
class CellGeometry:
    """
    What a cell looks like at one incidence angle and polarisation; independent of wavelength.

    ``p1 = n1 cos(theta_1) d1`` and ``p2 = n2 cos(theta_2) d2`` are the optical thicknesses along z,
    so that ``k_1z d1 = omega p1`` and ``k_2z d2 = omega p2``; both are complex under total internal
    reflection (then purely imaginary).
    """

    cos_theta_1: np.ndarray
    cos_theta_2: np.ndarray
    p1: np.ndarray
    p2: np.ndarray
    r12: np.ndarray
    Omega: np.ndarray
    r_h1: np.ndarray
    correction: np.ndarray
    N: int
    host_is_n1: bool


def Omega(polarisation: str, n1: ArrayLike, cos_theta_1: ArrayLike, n2: ArrayLike, cos_theta_2: ArrayLike) -> np.ndarray:
    """The polarisation term of the dispersion relation (Eqs. 6-7); ``Omega >= 2`` for real angles."""
    if polarisation == "s":
        x = (n2 * cos_theta_2) / (n1 * cos_theta_1)
    else:
        x = (n1 * cos_theta_2) / (n2 * cos_theta_1)
    x = np.where(np.abs(x) < 1e-10, 1e-10, x)  # exactly at a critical angle
    return x + 1.0 / x


def cell_geometry(cos_theta_h: ArrayLike, mirror: BraggMirror, polarisation: str) -> CellGeometry:
    """Snell's law into both layers, and the cell's angular terms, for one polarisation."""
    cos_theta_h = np.maximum(np.asarray(cos_theta_h, dtype=np.float64), COS_THETA_MIN)
    eta_h, n1, n2 = mirror.eta_h, mirror.n1, mirror.n2
    cos_theta_1 = cos_theta_transmitted(cos_theta_h, eta_h, n1)
    cos_theta_2 = cos_theta_transmitted(cos_theta_h, eta_h, n2)
    return CellGeometry(
        cos_theta_1=cos_theta_1,
        cos_theta_2=cos_theta_2,
        p1=n1 * cos_theta_1 * mirror.d1,
        p2=n2 * cos_theta_2 * mirror.d2,
        r12=fresnel_r(polarisation, n1, cos_theta_1, n2, cos_theta_2),
        Omega=Omega(polarisation, n1, cos_theta_1, n2, cos_theta_2),
        r_h1=fresnel_r(polarisation, eta_h, cos_theta_h.astype(np.complex128), n1, cos_theta_1),
        correction=angular_correction(cos_theta_1, n1, n2),
        N=int(mirror.N),
        host_is_n1=(eta_h == n1),
    )


# --------------------------------------------------------------------------------------------------
# Yeh's reflectance (Section 3.1)


def airy_slab_coefficients(omega: ArrayLike, geometry: CellGeometry) -> tuple[np.ndarray, np.ndarray]:
    """
    Reflection and transmission coefficients ``(r1, t1)`` of one slab of ``n2`` in ``n1`` (Eq. 10).

    ``r1 = r12 (1 - e^{2i phi}) / (1 - r12^2 e^{2i phi})`` with ``phi = k_2z d2``, and
    ``t1 = (1 - r12^2) e^{i phi} / (1 - r12^2 e^{2i phi})`` (as ``t12 t21 = 1 - r12^2``).
    """
    phase = np.exp(1j * omega * geometry.p2)
    phase2 = phase * phase
    r12_2 = geometry.r12 * geometry.r12
    denominator = 1.0 - r12_2 * phase2
    return geometry.r12 * (1.0 - phase2) / denominator, (1.0 - r12_2) * phase / denominator


def cos_K_Lambda(omega: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    The dispersion relation (Eq. 8): ``cos k1z d1 cos k2z d2 - Omega/2 sin k1z d1 sin k2z d2``.

    Real for real indices, also when a layer is evanescent; ``|cos K Lambda| > 1`` in band gaps.
    """
    psi = _clamp_decay(omega * geometry.p1)
    phi = _clamp_decay(omega * geometry.p2)
    value = np.cos(psi) * np.cos(phi) - 0.5 * geometry.Omega * np.sin(psi) * np.sin(phi)
    return np.real(value)


#: Evanescent phases are clamped here: cosh(40)^2 stays finite in float32, and a layer that damps a
#: wave by e^-40 is already opaque (|cos K Lambda| ~ 1e34 means R = 1 to float precision).
MAX_DECAY = 40.0


def _clamp_decay(phase):
    return np.real(phase) + 1j * np.minimum(np.imag(phase), MAX_DECAY)


def _one_minus_exp_minus_2x(x):
    """``1 - exp(-2x)`` without cancellation near band edges (small ``x``)."""
    return -np.expm1(-2.0 * x)


def chebyshev_U(cos_K_Lambda: ArrayLike, N: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Chebyshev polynomials ``(U_{N-1}, U_{N-2})`` of ``cos K Lambda``, scaled to stay finite.

    ``U_{N-1}(cos K Lambda) = sin(N K Lambda) / sin(K Lambda)``: Yeh's ``[M]^N = U_{N-1} M - U_{N-2} I``
    (Appendix D). In a band gap they grow like ``exp(N Im[K] Lambda)`` and overflow for large ``N``, so
    both are returned divided by ``U_{N-1}`` there, with that scale; elsewhere the scale is 1. Band
    edges (``sin K Lambda -> 0``) take the limits ``U_{N-1} -> N``, ``U_{N-2} -> N - 1`` without 0/0.

    Returns
    -------
    U_N1, U_N2, scale : ndarray
        ``scale * U_{N-1}(a) == U_N1`` and ``scale * U_{N-2}(a) == U_N2``.
    """
    a = np.asarray(cos_K_Lambda, dtype=np.float64)
    N = float(N)
    in_band = np.abs(a) < 1.0
    # Pass band: K Lambda = t real in (0, pi).
    t = np.arccos(np.clip(a, -1.0, 1.0))
    sin_t = np.sin(t)
    safe_sin_t = np.where(in_band, sin_t, 1.0)
    U_N1_band = np.sin(N * t) / safe_sin_t
    U_N2_band = np.sin((N - 1.0) * t) / safe_sin_t
    # Band gap (Eq. 9): K Lambda = m pi + i x with x = Im[K] Lambda = acosh|a|; U_n(-b) = (-1)^n U_n(b).
    x = np.maximum(np.arccosh(np.maximum(np.abs(a), 1.0)), 1e-12)
    ratio_N2 = np.exp(-x) * _one_minus_exp_minus_2x((N - 1.0) * x) / _one_minus_exp_minus_2x(N * x)
    scale_gap = np.exp(-(N - 1.0) * x) * _one_minus_exp_minus_2x(x) / _one_minus_exp_minus_2x(N * x)
    U_N1 = np.where(in_band, U_N1_band, 1.0)
    U_N2 = np.where(in_band, U_N2_band, np.sign(a) * ratio_N2)
    scale = np.where(in_band, 1.0, scale_gap)
    return U_N1, U_N2, scale


def reflectance_yeh(r1: ArrayLike, t1: ArrayLike, cos_K_Lambda: ArrayLike, N: int) -> np.ndarray:
    """
    Yeh's reflectance of ``N`` cells in ``n1`` (Eqs. 2 and 9): ``|C|^2 / (|C|^2 + (sin K/sin NK)^2)``.

    Written as ``|r1|^2 U^2 / (|r1|^2 U^2 + |t1|^2 s^2)`` with the scaled Chebyshev values of
    :func:`chebyshev_U`: the same ratio, finite at band edges, for any ``N`` and at grazing angles.
    """
    U_N1, _, scale = chebyshev_U(cos_K_Lambda, N)
    numerator = np.abs(r1) ** 2 * U_N1**2
    return numerator / (numerator + np.abs(t1) ** 2 * scale**2)


def reflection_coefficient_bragg(
    r1: ArrayLike, t1: ArrayLike, omega: ArrayLike, geometry: CellGeometry, cos_K_Lambda: ArrayLike,
) -> np.ndarray:
    """
    The mirror's amplitude coefficient ``r_N = U(C) / V(A)`` (Appendix D), seen from ``n1``.

    With the cell's transfer matrix ``A = 1/t_cell``, ``C = r1/t_cell`` and ``t_cell = t1 e^{i k_1z d1}``:
    ``r_N = r1 U_{N-1} / (U_{N-1} - U_{N-2} t_cell)``.
    """
    U_N1, U_N2, _ = chebyshev_U(cos_K_Lambda, geometry.N)
    t_cell = t1 * np.exp(1j * omega * geometry.p1)
    return r1 * U_N1 / (U_N1 - U_N2 * t_cell)


def reflection_coefficient_host(r_N: ArrayLike, r_h1: ArrayLike) -> np.ndarray:
    """``r_hN = (r_N + r_h1) / (1 + r_h1 r_N)``: the mirror under a host medium ``nh`` (Appendix D)."""
    return (r_N + r_h1) / (1.0 + r_h1 * r_N)


def reflectance_polarised(omega: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """Exact reflectance of the mirror for one polarisation (Eqs. 2, 9, 10; Appendix D if nh != n1)."""
    r1, t1 = airy_slab_coefficients(omega, geometry)
    a = cos_K_Lambda(omega, geometry)
    if geometry.host_is_n1:
        return reflectance_yeh(r1, t1, a, geometry.N)
    r_N = reflection_coefficient_bragg(r1, t1, omega, geometry, a)
    return np.abs(reflection_coefficient_host(r_N, geometry.r_h1)) ** 2


def bragg_reflectance(cos_theta: ArrayLike, wavelength: ArrayLike, mirror: BraggMirror, polarisation: str | None = None) -> np.ndarray:
    """
    Spectral reflectance ``R_lambda`` of a Bragg mirror.

    Parameters
    ----------
    cos_theta : array_like
        Cosine of the incidence angle in the host medium.
    wavelength : array_like
        Wavelength in nm (broadcast against ``cos_theta``).
    mirror : BraggMirror
    polarisation : {'s', 'p', None}
        ``None`` averages both (unpolarised light).

    Returns
    -------
    ndarray
        Reflectance in [0, 1].
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    omega = 2.0 * np.pi / np.asarray(wavelength, dtype=np.float64)
    polarisations = POLARISATIONS if polarisation is None else (polarisation,)
    total = 0.0
    for pol in polarisations:
        total = total + reflectance_polarised(omega, cell_geometry(cos_theta, mirror, pol))
    return total / len(polarisations)


def _spectra(cos_theta, mirror: BraggMirror, wavelengths, fast: bool) -> np.ndarray:
    return reflectance_spectra(cos_theta, mirror, wavelengths, float64=not fast)


def substeps_for(mirror: BraggMirror, cos_theta: ArrayLike) -> int:
    """
    The coarsest sampling (samples per nm) that resolves the mirror's fringes: ``N`` fringes per band,
    bands ``pi / n_+`` apart in ``omega``, so fringes as if from an optical path ``2 N n_+``
    (:func:`explorer.physics.colorimetry.substeps_for_fringes`), ``n_+`` the largest over the angles.
    """
    n_plus = optical_thickness(cell_geometry(np.asarray(cos_theta, dtype=np.float64), mirror, "s"))
    return colorimetry.substeps_for_fringes(2.0 * mirror.N * float(np.max(n_plus, initial=0.0)))


def converged_reflectance_spectra(
    cos_theta: ArrayLike, mirror: BraggMirror, tolerance: float = colorimetry.CONVERGENCE_TOLERANCE,
    passes: int = colorimetry.CONVERGENCE_PASSES, fast: bool = True, substeps_max: int = colorimetry.MAX_SUBSTEPS,
) -> tuple[np.ndarray, np.ndarray]:
    """
    The unpolarised ``R_lambda`` averaged over each nm's hat function (:func:`explorer.physics.colorimetry.hat_average`),
    sampled finely enough that the colour has converged (:func:`explorer.physics.colorimetry.converged_spectra`).

    Near band edges the pass band's transmission resonances (Eq. 2's zeros of ``sin N K Lambda``) are
    narrower than a nanometre and narrow further as ``N`` grows: point samples at every nm hit or miss
    them, hat averages integrate them. ``spectra @ colour_matching_functions()`` is the integral of
    ``R_lambda`` against the CMFs interpolated linearly between their 1-nm nodes.

    ``fast``: the tables' real float32 path where it applies (:func:`reflectance_spectra`, ~1e-5);
    otherwise float64 throughout (to ~1e-12 of Yeh's complex :func:`bragg_reflectance`), as
    :func:`reference_rgb` uses.
    ``substeps_max`` caps the refinement (samples per nm).

    Returns
    -------
    spectra : ndarray, shape ``(cos_theta.size, 471)``
    substeps : ndarray of int, shape ``(cos_theta.size,)``
        Samples per nm each angle needed.
    """
    # Each distinct angle once (a view's pixels share a few: the slice view's rows, a sphere's symmetry),
    # up to 1e-12 in cos theta (pixels compute the same angle with different roundings; the colour moves
    # by ~1e-11 over such a step).
    cos_theta, inverse = np.unique(np.round(np.asarray(cos_theta, dtype=np.float64).ravel(), 12), return_inverse=True)
    spectra, substeps = colorimetry.converged_spectra(
        _spectrum_function(cos_theta, mirror, float64=not fast),
        cos_theta.size,
        substeps_min=min(substeps_for(mirror, cos_theta), substeps_max),
        tolerance=tolerance,
        passes=passes,
        substeps_max=substeps_max,
    )
    return spectra[inverse.ravel()], substeps[inverse.ravel()]


def _take(geometry: CellGeometry, rows) -> CellGeometry:
    """The geometry at some of its angles (``rows`` may repeat), with a trailing axis (:func:`_rows`)."""
    fields = {k: (v[rows][:, None] if isinstance(v, np.ndarray) else v) for k, v in vars(geometry).items()}
    return CellGeometry(**fields)


def _spectrum_function(cos_theta, mirror: BraggMirror, float64: bool):
    """
    ``spectrum(wavelengths, rows)`` for :func:`explorer.physics.colorimetry.converged_spectra`: the values of
    :func:`reflectance_spectra` at the angles ``cos_theta[rows]`` (rows may repeat; ``wavelengths`` 1D,
    shared, or 2D, one set per row), with the angles' geometry computed once.
    """
    return _row_spectrum_function(
        cos_theta, mirror,
        lambda omega, geometries, rows: _reflectance_real(omega, geometries, rows, float64),
        reflectance_polarised,
    )


def _row_spectrum_function(cos_theta, mirror: BraggMirror, real_path, complex_path):
    """
    The row-blocked ``spectrum(wavelengths, rows)`` shared by the reference and the windowed table: the
    angles' geometry once, rows with real angles through ``real_path(omega, geometries, rows)``, the others
    (a host, evanescent layers) through ``complex_path(omega, geometry)`` averaged over the polarisations.
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64).ravel()
    geometries = tuple(cell_geometry(cos_theta, mirror, pol) for pol in POLARISATIONS)
    first = geometries[0]
    real = (first.cos_theta_1.imag == 0) & (first.cos_theta_2.imag == 0) & first.host_is_n1

    def spectrum(wavelengths, rows):
        omega = 2.0 * np.pi / np.asarray(wavelengths, dtype=np.float64)
        rows = np.asarray(rows)
        per_row = omega.ndim == 2
        out = np.empty((rows.size, omega.shape[-1]))
        is_real = real[rows]
        block = max(1, ROW_BLOCK * 471 // max(omega.shape[-1], 1))
        for mask, fast_path in ((is_real, True), (~is_real, False)):
            # Slices where every row takes one path (the usual case), to spare the gathers.
            where = np.arange(rows.size) if mask.all() else np.flatnonzero(mask)
            for start in range(0, where.size, block):
                at = slice(start, start + block) if mask.all() else where[start : start + block]
                om = omega[at] if per_row else omega
                if fast_path:
                    out[at] = real_path(om, geometries, rows[at])
                else:
                    out[at] = sum(complex_path(om, _take(g, rows[at])) for g in geometries) / len(geometries)
        return out

    return spectrum


def reference_rgb(cos_theta: ArrayLike, mirror: BraggMirror, step: float | None = None) -> np.ndarray:
    """
    The spectral reference: exact ``R_lambda`` (both polarisations averaged) integrated against the CMFs
    (Section 3.2.2), in linear sRGB.

    Parameters
    ----------
    cos_theta : array_like
    mirror : BraggMirror
    step : float, optional
        ``None``: the converged integral (:func:`converged_reflectance_spectra`), the reference every
        accuracy figure is measured against. A number: samples every ``1 / round(1 / step)`` nm against
        the linearly interpolated CMFs; ``step = 1`` is the paper's sum over every nm from 360 to 830,
        which is not converged for ``N`` of a few tens and more.

    Returns
    -------
    ndarray, shape ``cos_theta.shape + (3,)``
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    if step is None:
        spectra, _ = converged_reflectance_spectra(cos_theta, mirror, fast=False)
    else:
        flat = cos_theta.ravel()
        spectra = colorimetry.fixed_step_spectra(
            lambda wavelengths, rows: _spectra(flat[rows], mirror, wavelengths, fast=False), flat.size, step
        )
    return colorimetry.spectrum_to_rgb(spectra).reshape(cos_theta.shape + (3,))


# --------------------------------------------------------------------------------------------------
# The envelope and the spectral landmarks (Section 3.2.1, Appendix A)


def host_reflectance(geometry: CellGeometry) -> np.ndarray:
    """``R_h1 = |r_h1|^2``, the host interface's reflectance (0 when the host is ``n1``), at most 1."""
    if geometry.host_is_n1:
        return np.zeros(np.shape(geometry.p1))
    return np.minimum(np.abs(geometry.r_h1) ** 2, 1.0)


def under_host(R_mirror: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    A mirror reflectance seen through the host interface ``nh -> n1``, added incoherently (our
    extension for the approximations when ``nh != n1``): ``R_h1 + (1 - R_h1)^2 R / (1 - R_h1 R)``,
    written as ``1 - (1 - R_h1)(1 - R) / (1 - R_h1 R)``, which stays 1 when both reflect totally.
    """
    if geometry.host_is_n1:
        return R_mirror
    R_h1 = np.minimum(np.abs(geometry.r_h1) ** 2, 1.0)
    return 1.0 - (1.0 - R_h1) * (1.0 - R_mirror) / np.maximum(1.0 - R_h1 * R_mirror, 1e-300)


def reflectance_envelope(omega: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    The envelope ``R^e = |C|^2 / (|C|^2 + sin^2 K Lambda)`` (Eq. 11); 1 inside band gaps.

    Under a host ``nh != n1`` the host interface is added incoherently, which keeps band gaps at 1
    (our extension; the paper's approximation assumes ``nh == n1``).
    """
    r1, t1 = airy_slab_coefficients(omega, geometry)
    a = cos_K_Lambda(omega, geometry)
    r1_2 = np.abs(r1) ** 2
    denominator = r1_2 + np.abs(t1) ** 2 * np.maximum(1.0 - a * a, 0.0)
    # A cell that reflects nothing (delta = 1) has no gap either: 0, not 0/0.
    return under_host(np.divide(r1_2, denominator, out=np.zeros_like(r1_2), where=denominator > 0.0), geometry)


def reflectance_fringe_average(omega: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    Yeh's reflectance averaged over its fringes: ``1 - |sin K Lambda| / sqrt(|C|^2 + sin^2 K Lambda)``.

    Outside band gaps ``R = |C|^2 / (|C|^2 + sin^2 K Lambda / sin^2 N K Lambda)`` oscillates ``N - 1``
    times between gaps; averaging over the fast phase ``N K Lambda`` at fixed ``K Lambda`` gives this
    closed form. It equals 1 at band edges and ``~ R^e / 2`` for weak contrast (what the paper's
    empirical ``w~0 ~ 0.53`` of Appendix B approximates). Our improvement, not in the paper.

    Under a host ``nh != n1`` (Appendix D): the coherent average of :func:`fringe_average_under_host`.
    """
    r1, t1 = airy_slab_coefficients(omega, geometry)
    a = cos_K_Lambda(omega, geometry)
    if not geometry.host_is_n1:
        return fringe_average_under_host(r1, t1, omega, geometry, a)
    t1_2_sin2 = np.abs(t1) ** 2 * np.maximum(1.0 - a * a, 0.0)
    denominator = np.abs(r1) ** 2 + t1_2_sin2
    ratio = np.divide(t1_2_sin2, denominator, out=np.ones_like(denominator), where=denominator > 0.0)
    return 1.0 - np.sqrt(ratio)


#: Below this |B|^2 the fringes' weight vanishes and the average is its limit |P / S|^2.
FRINGE_B_MIN = 1e-12
#: A pole of r_hN on the real x axis (never for real indices) is moved off it by this much.
FRINGE_Q_MIN = 1e-6


def fringe_average_under_host(r1: ArrayLike, t1: ArrayLike, omega: ArrayLike, geometry: CellGeometry, a: ArrayLike) -> np.ndarray:
    """
    ``|r_hN|^2`` (Appendix D) averaged over the fringes, coherently: the host's interface reflects in
    phase with the mirror, and the incoherent :func:`under_host` misses a slow modulation of up to
    ~0.07 in R (n1 = 1.33, n2 = 1.8, nh = 1).

    With ``u = N K Lambda``, ``U_{N-1} = sin u / sin t`` and ``U_{N-2} = (sin u cos t - cos u sin t) / sin t``
    (``t = K Lambda`` held fixed over a fringe), Appendix D's ``r_N = r1 / (A + B x)`` where ``x = cot u``,
    ``A = 1 - cos t t_cell`` and ``B = sin t t_cell``; then ``r_hN = (P + Q x) / (S + T x)`` with
    ``P = r1 + r_h1 A``, ``Q = r_h1 B``, ``S = A + r_h1 r1``, ``T = B``, i.e. ``alpha + beta / (x - z)``
    with ``alpha = Q / T``, ``beta = (P T - Q S) / T^2``, ``z = -S / T = p + i q``. As ``u`` sweeps a fringe,
    ``x`` sweeps the real line with the Cauchy density ``1 / (pi (1 + x^2))``, whose averages are
    ``<1 / (x - z)> = 1 / (-i sign(q) - z)`` and ``<1 / |x - z|^2> = (1 + |q|) / (|q| ((1 + |q|)^2 + p^2))``
    (two Cauchy densities convolved): so ``<|r_hN|^2> = |alpha|^2 + 2 Re(alpha* beta <1 / (x - z)>) +
    |beta|^2 <1 / |x - z|^2>``. For a lossless cell ``z`` lies on the imaginary axis, ``|z| >= 1``: no
    term is singular, also where the cell barely reflects.
    """
    t_cell = t1 * np.exp(1j * omega * geometry.p1)
    sin_t = np.sqrt(np.maximum(1.0 - a * a, 0.0))
    A = 1.0 - a * t_cell
    B = sin_t * t_cell
    r_h1 = geometry.r_h1
    P, Q, S, T = r1 + r_h1 * A, r_h1 * B, A + r_h1 * r1, B
    fringes = np.abs(B) ** 2 > FRINGE_B_MIN
    T = np.where(fringes, T, 1.0)
    alpha, beta, z = Q / T, (P * T - Q * S) / T**2, -S / T
    p, q = np.real(z), np.abs(np.imag(z))
    q = np.maximum(q, FRINGE_Q_MIN)
    mean_pole = 1.0 / (1j * np.where(np.imag(z) > 0.0, -1.0, 1.0) - z)
    mean_pole_2 = (1.0 + q) / (q * ((1.0 + q) ** 2 + p * p))
    average = np.abs(alpha) ** 2 + 2.0 * np.real(np.conj(alpha) * beta * mean_pole) + np.abs(beta) ** 2 * mean_pole_2
    # At a band edge (sin t -> 0) the fringes' weight vanishes: the limit |P / S|^2.
    limit = np.abs(P) ** 2 / np.maximum(np.abs(S) ** 2, 1e-300)
    return np.clip(np.where(fringes, average, limit), 0.0, 1.0)


def paper_weight(omega: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    The paper's box weight ``w = w~(theta) R^e`` (Section 3.2.2, Appendix B). Under a host ``nh != n1`` the
    host interface's own reflection is no fringe: the correction ``w~`` (a fringe average) applies to the
    mirror's envelope only, and the host interface is added after it, ``under_host(w~ R^e)`` (Appendix D;
    applying ``w~`` to the host's Fresnel reflection halved it).
    """
    if geometry.host_is_n1:
        return geometry.correction * reflectance_envelope(omega, geometry)
    r1, t1 = airy_slab_coefficients(omega, geometry)
    a = cos_K_Lambda(omega, geometry)
    r1_2 = np.abs(r1) ** 2
    denominator = r1_2 + np.abs(t1) ** 2 * np.maximum(1.0 - a * a, 0.0)
    envelope = np.divide(r1_2, denominator, out=np.zeros_like(r1_2), where=denominator > 0.0)
    return under_host(geometry.correction * envelope, geometry)


def angular_correction(cos_theta_1: ArrayLike, n1: ArrayLike, n2: ArrayLike) -> np.ndarray:
    """
    The angular correction ``w~(theta_1) = w~0 + (1 - w~0)(1 - cos theta_1)^5`` (Appendix B), with
    ``w~0 = 0.735 R12 + 0.532`` and ``R12`` the normal-incidence reflectance between ``n1`` and ``n2``.
    """
    R12 = ((n1 - n2) / (n1 + n2)) ** 2
    w0 = 0.735 * R12 + 0.532
    cos_theta_1 = np.clip(np.real(cos_theta_1), 0.0, 1.0)
    return w0 + (1.0 - w0) * (1.0 - cos_theta_1) ** 5


def optical_thickness(geometry: CellGeometry) -> np.ndarray:
    """``n_+ = n1 cos(theta_1) d1 + n2 cos(theta_2) d2`` (Appendix A), the real parts under TIR."""
    return np.maximum(np.real(geometry.p1) + np.real(geometry.p2), 1e-9)


def mode_frequency(m: ArrayLike, n_plus: ArrayLike) -> np.ndarray:
    """Spectral modes ``omega_m = m pi / n_+`` (Eq. 13): inside a band gap for every ``m >= 1``."""
    return m * np.pi / n_plus


def _bisect(f, lo, hi, positive_at_lo):
    """Fixed-step bisection, as the shader does, for the sign change of ``f`` on ``[lo, hi]``."""
    positive_at_lo = np.broadcast_to(positive_at_lo, np.shape(lo))
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        same_side = (f(mid) >= 0.0) == positive_at_lo
        lo = np.where(same_side, mid, lo)
        hi = np.where(same_side, hi, mid)
    return 0.5 * (lo + hi)


def airy_point(geometry: CellGeometry, omega_m: ArrayLike, omega_next: ArrayLike, m: ArrayLike) -> np.ndarray:
    """The zero of ``cos K Lambda`` between modes ``m`` and ``m + 1``, where ``R^e = |r1|^2``.

    ``cos K Lambda`` has the sign ``(-1)^m`` at ``omega_m`` (Appendix A)."""
    return _bisect(lambda w: cos_K_Lambda(w, geometry), omega_m, omega_next, (m % 2) == 0)


def band_edge(geometry: CellGeometry, lo: ArrayLike, hi: ArrayLike, gap_at_lo: bool) -> np.ndarray:
    """The band-gap edge ``|cos K Lambda| = 1`` between a mode and an Airy point, in either order."""
    return _bisect(lambda w: np.abs(cos_K_Lambda(w, geometry)) - 1.0, lo, hi, gap_at_lo)


def zero_point_after(geometry: CellGeometry, omega: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """
    The first zero point ``omega_z = z pi / (n2 cos theta_2 d2)`` (Eq. 12) above ``omega``.

    Returns the frequency and whether it exists (no zero points while ``n2`` is evanescent).
    """
    p2 = np.real(geometry.p2)
    exists = (np.abs(np.imag(geometry.p2)) == 0.0) & (p2 > 0.0)
    p2 = np.where(exists, p2, 1.0)
    z = np.floor(omega * p2 / np.pi) + 1.0
    return z * np.pi / p2, exists


# --------------------------------------------------------------------------------------------------
# The piecewise-constant approximation (Section 3.2.2)

def wavelength_of(omega: ArrayLike) -> np.ndarray:
    """``lambda = 2 pi / omega`` in nm; ``omega = 0`` (mode 0) maps past the visible range."""
    return 2.0 * np.pi / np.maximum(omega, 1e-9)


OMEGA_LOW = 2.0 * np.pi / WAVELENGTH_HIGH
OMEGA_HIGH = 2.0 * np.pi / WAVELENGTH_LOW


def mode_range(n_plus: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """First and last intervals ``[omega_m, omega_{m+1}]`` that overlap the visible range."""
    m_first = np.floor(OMEGA_LOW * n_plus / np.pi)
    m_last = np.floor(OMEGA_HIGH * n_plus / np.pi)
    return m_first, m_last


def subdivisions(m: ArrayLike, m_first: ArrayLike, s: int, mode_numbering: str = "relative") -> np.ndarray:
    """
    Sub-boxes per box outside band gaps: ``max(1, s - m)`` (Section 3.2.2); ``s = 0`` is the basic
    approximation (one box). The paper leaves open how ``m`` is counted: ``'relative'`` counts from
    the first interval between modes that overlaps the visible range (the reading of its Table 1,
    where ``s = 3`` costs more than the basic method at Lambda = 988 nm), ``'absolute'`` from mode 0.
    """
    if s <= 0:
        return np.ones_like(m)
    index = m if mode_numbering == "absolute" else m - m_first
    return np.maximum(1.0, s - index)


def subdivisions_by_mass(omega_low: ArrayLike, omega_high: ArrayLike, s: int) -> np.ndarray:
    """
    Sub-boxes of the improved variant (ours): ``ceil(4 s mu)``, with ``mu`` the box's share of the
    visible CMF mass (X + Y + Z), i.e. ``s`` sub-boxes per quarter of it. Boxes where the eye is most
    sensitive get the subdivisions, wherever their mode number. On the grid of Figure 4 this spends
    as many boxes as the paper's ``max(1, s - m)``; the mass comes from the box ends' lookups, which
    the method makes anyway (Eq. 15).
    """
    if s <= 0:
        return np.ones_like(omega_low)
    mass = (colorimetry.cmf_cumulative_at(wavelength_of(omega_low)) - colorimetry.cmf_cumulative_at(wavelength_of(omega_high))).sum(axis=-1)
    total = colorimetry.cmf_cumulative_at(WAVELENGTH_HIGH).sum()
    return np.maximum(1.0, np.ceil(4.0 * s * mass / total))


#: The improved variant resolves a pass band's fringes where, in its visible part, a fringe feature is
#: wider than ``FRINGE_RESOLVE_NM / s`` nm (8 nm at s = 3), times ``(N / N_RESOLVE)^GROW_EXPONENT`` beyond
#: ``N_RESOLVE`` cells (:func:`fringes_resolved`): its sub-boxes then sample the exact reflectance;
#: elsewhere the fringes are averaged in closed form (docs/accuracy.md).
FRINGE_RESOLVE_NM = 24.0
#: Sub-boxes per resolved fringe (each rises from a zero of R to a peak and back; 2 alias).
SAMPLES_PER_FRINGE = 3.0
#: Fringes are resolved only while ``SAMPLES_PER_FRINGE N`` is at most this (N <= 21).
RESOLVE_BUDGET = 64.0
#: Beyond this many cells the width a fringe must have to be resolved grows like ``N^GROW_EXPONENT``:
#: Figure 4's N = 20 mirrors (fringes of 10-25 nm) keep their fringe average and their cost, while the
#: weak-contrast mirrors of up to ~20 cells (a fringe of ~40 nm) are resolved.
N_RESOLVE = 10.0
GROW_EXPONENT = 2.0
#: At most this many sub-boxes per box (sharp dips at grazing angles ask for more).
MAX_RESOLVED_PIECES = 48.0


def fringe_count(omega_low: ArrayLike, omega_high: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    How many fringes of Eq. 2 lie in a pass-band box: ``N |Delta K Lambda| / pi``. Between zeros of
    ``sin N K Lambda`` the Bloch phase ``K Lambda`` advances by ``pi / N``, and it is monotone across a
    pass band (Eq. 8 with ``|cos K Lambda| <= 1``).
    """
    t_low = np.arccos(np.clip(cos_K_Lambda(omega_low, geometry), -1.0, 1.0))
    t_high = np.arccos(np.clip(cos_K_Lambda(omega_high, geometry), -1.0, 1.0))
    return geometry.N * np.abs(t_high - t_low) / np.pi


def fringes_resolved(edge_low: ArrayLike, edge_high: ArrayLike, s: int, geometry: CellGeometry) -> np.ndarray:
    """
    Whether the improved variant (ours) resolves the fringes of the pass band ``[edge_low, edge_high]``.

    Eq. 2 has ``N`` fringes per pass band; the fringe average (:func:`reflectance_fringe_average`)
    replaces them by their mean, right when they are narrower than the CMFs vary: large ``N``. For a few
    cells (the jewel beetles of Table 3, ``N = 6-8``; Figure 12, ``N = 3``) a fringe spans tens of nm and
    where it lies is the colour. They are resolved where, in the pass band's visible part, a fringe's
    feature (:func:`fringe_sharpness`) is wider than ``FRINGE_RESOLVE_NM / s`` nm, a width that grows like
    ``(N / N_RESOLVE)^GROW_EXPONENT`` beyond :data:`N_RESOLVE` cells, and ``SAMPLES_PER_FRINGE N <= RESOLVE_BUDGET``.
    """
    if s <= 0:
        return np.zeros(np.shape(edge_low), dtype=bool)
    # The pass band's visible part: its fringes there, and their mean width in nm.
    low, high = np.maximum(edge_low, OMEGA_LOW), np.minimum(edge_high, OMEGA_HIGH)
    visible = high > low
    high = np.where(visible, high, low)
    fringes = np.maximum(fringe_count(low, high, geometry), 1e-9)
    width_nm = wavelength_of(low) - wavelength_of(high)
    # The width (nm) to resolve grows beyond N_RESOLVE cells, as the cost of resolving them does.
    grow = max(1.0, geometry.N / N_RESOLVE) ** GROW_EXPONENT
    wide = width_nm * fringe_sharpness(geometry) * s > FRINGE_RESOLVE_NM * grow * fringes
    return visible & wide & (SAMPLES_PER_FRINGE * geometry.N <= RESOLVE_BUDGET)


def subdivisions_resolving_fringes(
    omega_low: ArrayLike, omega_high: ArrayLike, s: int, geometry: CellGeometry, resolved: ArrayLike,
) -> np.ndarray:
    """
    Sub-boxes of the improved variant (ours) in a pass-band box: :func:`subdivisions_by_mass`, and where
    the fringes are resolved (:func:`fringes_resolved`) at least :data:`SAMPLES_PER_FRINGE` per fringe
    feature (:func:`fringe_count`, :func:`fringe_sharpness`), at most :data:`MAX_RESOLVED_PIECES`.
    """
    by_mass = subdivisions_by_mass(omega_low, omega_high, s)
    if not np.any(resolved):
        return by_mass
    pieces = np.ceil(SAMPLES_PER_FRINGE * fringe_count(omega_low, omega_high, geometry) / fringe_sharpness(geometry))
    pieces = np.minimum(pieces, MAX_RESOLVED_PIECES)
    return np.where(resolved, np.maximum(pieces, by_mass), by_mass)


def fringe_sharpness(geometry: CellGeometry) -> np.ndarray:
    """
    The share of a fringe its feature (a dip of Eq. 2) fills at most: ``min(1, 2 / (pi sqrt(k)))``, Eq. 2
    written ``R = k sin^2 u / (1 + k sin^2 u)`` with ``u = N K Lambda`` and ``k = |r1|^2 / (|t1|^2 sin^2 K Lambda)
    >= 4 r12^2 / (1 - r12^2)^2`` (Eq. 10 at ``sin phi = 1``). Where ``k >> 1`` (strong contrast, grazing
    angles) ``R ~ 1`` but for dips of width ``~ 2 / sqrt(k)`` in ``u``, which samples must resolve. Under a
    host ``nh != n1`` its interface sharpens them alike: ``k >= R_h1 / (1 - R_h1)``.
    """
    r12_2 = np.minimum(np.abs(geometry.r12) ** 2, 1.0 - 1e-12)
    k = 4.0 * r12_2 / (1.0 - r12_2) ** 2
    R_h1 = np.minimum(host_reflectance(geometry), 1.0 - 1e-12)
    k = np.maximum(k, R_h1 / (1.0 - R_h1))
    return np.minimum(1.0, 2.0 / (np.pi * np.sqrt(np.maximum(k, 1e-300))))


def pass_band_weight(omega: ArrayLike, geometry: CellGeometry, resolved: ArrayLike) -> np.ndarray:
    """The improved variant's weight in a pass band: the exact reflectance (Eqs. 2, 9, 10; Appendix D)
    where the fringes are resolved, their closed-form average otherwise."""
    average = reflectance_fringe_average(omega, geometry)
    if not np.any(resolved):
        return average
    return np.where(resolved, np.clip(reflectance_polarised(omega, geometry), 0.0, 1.0), average)


def gap_weight(omega_low: ArrayLike, omega_high: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    The improved variant's weight of a half band gap: the exact reflectance at its middle. The paper
    gives gaps ``w = 1``, the limit of Eq. 9 for large ``N``: ``R = 1 - O(e^{-2 N Im[K] Lambda})``. A mirror
    of a few cells or weak contrast (Table 3: ``n2 - n1 = 0.08``, ``N = 8``) reflects far less in its gaps,
    and under a host (Appendix D) the host interface adds to it in phase; without fringes in a gap, one
    sample suffices.
    """
    return np.clip(reflectance_polarised(0.5 * (omega_low + omega_high), geometry), 0.0, 1.0)


def _sub_box(lo, hi, j, pieces, edge):
    """
    Sub-box ``j`` of ``pieces`` in ``[lo, hi]`` and the point where its weight is sampled.

    ``edge = 0``: equal sub-boxes sampled at their centres (the paper). ``edge = -1`` (band edge at
    ``lo``) or ``+1`` (at ``hi``): sub-boxes graded quadratically toward the band edge, ``x = u^2``
    with ``u`` uniform, because the fringe average varies like ``sqrt(x)`` there; each is sampled at
    its centroid ``u = 2 (u0^2 + u0 u1 + u1^2) / (3 (u0 + u1))``, where ``1 - c u`` equals its mean.
    """
    u0, u1 = j / pieces, (j + 1.0) / pieces
    width = hi - lo
    if edge == 0:
        return lo + width * u0, lo + width * 0.5 * (u0 + u1), lo + width * u1
    uc = 2.0 * (u0 * u0 + u0 * u1 + u1 * u1) / (3.0 * (u0 + u1))
    if edge < 0:
        return lo + width * u0 * u0, lo + width * uc * uc, lo + width * u1 * u1
    return hi - width * u1 * u1, hi - width * uc * uc, hi - width * u0 * u0


def piecewise_constant_boxes(
    geometry: CellGeometry, s: int = 0, mode_numbering: str = "relative", variant: str = "paper"
) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """
    The boxes ``B_j`` of the approximation (Eq. 14) and their weights ``w_j`` (Section 3.2.2).

    Walks the intervals between consecutive modes that overlap the visible range; in each, finds the
    Airy point and both band-gap edges by bisection (Section 3.2.1), inserts a zero point where one
    falls outside the gaps, gives the gap halves ``w = 1`` and the boxes outside the gaps
    :func:`subdivisions` sub-boxes each.

    ``variant='paper'``: equal sub-boxes, ``w = w~(theta) R^e(centre)`` (Section 3.2.2, Appendix B).
    ``variant='improved'`` (ours): ``w =`` :func:`reflectance_fringe_average` at the sub-box's
    centroid, sub-boxes graded toward band edges (:func:`_sub_box`), their number set by the box's
    share of the CMF mass (:func:`subdivisions_by_mass`; ``mode_numbering`` is then unused). Same
    landmarks, same lookups per box. Where a pass band's fringes are wide (:func:`fringes_resolved`) they
    are resolved instead: sub-boxes per fringe weighted by the exact reflectance
    (:func:`pass_band_weight`), and the pass band's half-gaps by theirs (:func:`gap_weight`); the
    paper's weights under a host are :func:`paper_weight`.

    Yields
    ------
    omega_low, omega_high, weight, active : ndarray
        One box per element of the angle arrays (``active`` is False where that element has no box
        left). Intervals are cut at the top of the visible range: landmarks beyond it add nothing,
        and far beyond it evanescent layers overflow.
    """
    improved = variant == "improved"
    n_plus = optical_thickness(geometry)
    m_first, m_last = mode_range(n_plus)
    count = int(np.max(m_last - m_first)) + 1 if n_plus.size else 0
    ones = np.ones_like(n_plus)
    for k in range(count):
        active = m_first + k <= m_last
        m = np.minimum(m_first + k, m_last)  # finished elements redo their last interval, masked out
        omega_m = mode_frequency(m, n_plus)
        omega_next = np.minimum(mode_frequency(m + 1.0, n_plus), OMEGA_HIGH)
        omega_a = airy_point(geometry, omega_m, omega_next, m)
        edge_low = band_edge(geometry, omega_m, omega_a, True)
        edge_high = band_edge(geometry, omega_a, omega_next, False)
        omega_z, has_zero = zero_point_after(geometry, edge_low)
        has_zero = has_zero & (omega_z < edge_high)
        # Pass-band boundaries edge_low <= x1 <= x2 <= edge_high: the zero point, if any, on either
        # side of the Airy point; without one, x1 == x2 leaves an empty box.
        z = np.where(has_zero, omega_z, omega_a)
        x1 = np.minimum(z, omega_a)
        x2 = np.maximum(z, omega_a)
        boxes = ((edge_low, x1, -1), (x1, x2, 0), (x2, edge_high, 1))
        if improved:
            resolved = fringes_resolved(edge_low, edge_high, s, geometry)
            # Resolved fringes: the gaps take their finite-N reflectance too (the fringe average and
            # w = 1 are both the large-N limit, consistent only together).
            gap_low = np.where(resolved, gap_weight(omega_m, edge_low, geometry), 1.0)
            gap_high = np.where(resolved, gap_weight(edge_high, omega_next, geometry), 1.0)
        yield omega_m, edge_low, gap_low if improved else ones, active
        for lo, hi, edge in boxes:
            if improved:
                pieces = subdivisions_resolving_fringes(lo, hi, s, geometry, resolved)
            else:
                pieces = subdivisions(m, m_first, s, mode_numbering)
            for j in range(int(np.max(np.where(active, pieces, 1.0)))):
                sub_lo, centre, sub_hi = _sub_box(lo, hi, j, pieces, edge if improved else 0)
                if improved:
                    weight = pass_band_weight(centre, geometry, resolved)
                else:
                    weight = paper_weight(centre, geometry)
                yield sub_lo, sub_hi, weight, active & (j < pieces)
        yield edge_high, omega_next, gap_high if improved else ones, active


def approximate_xyz_polarised(
    geometry: CellGeometry, s: int = 0, mode_numbering: str = "relative", variant: str = "paper"
) -> np.ndarray:
    """
    XYZ of the piecewise-constant spectrum for one polarisation (Eq. 15): each box adds
    ``w_j (C(omega_{j+1}) - C(omega_j))`` from the cumulative CMF table (Eq. 16).
    """
    xyz = np.zeros(np.shape(geometry.p1) + (3,))
    # Finished elements' extra boxes (masked by active) may lie at negative omega, where the exact
    # reflectance of the improved variant overflows: their warnings are noise.
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        for omega_low, omega_high, weight, active in piecewise_constant_boxes(geometry, s, mode_numbering, variant):
            # omega -> lambda reverses the order: the box covers [2 pi / omega_high, 2 pi / omega_low].
            span = colorimetry.cmf_cumulative_at(wavelength_of(omega_low)) - colorimetry.cmf_cumulative_at(wavelength_of(omega_high))
            xyz += np.where(active, weight, 0.0)[..., None] * span
    return xyz


def approximate_rgb(
    cos_theta: ArrayLike, mirror: BraggMirror, s: int = 0, mode_numbering: str = "relative", variant: str = "paper"
) -> np.ndarray:
    """
    The RGB approximation of Section 3.2: ``s = 0`` the basic one, ``s >= 1`` the subdivided one
    (``variant='improved'`` for ours); one XYZ per polarisation, averaged, then linear sRGB.

    Returns
    -------
    ndarray, shape ``cos_theta.shape + (3,)``
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    xyz = sum(
        approximate_xyz_polarised(cell_geometry(cos_theta, mirror, pol), s, mode_numbering, variant)
        for pol in POLARISATIONS
    )
    return colorimetry.xyz_to_rgb(0.5 * xyz)


# --------------------------------------------------------------------------------------------------
# The tabulated method (ours): a homogeneous mirror's colour depends on cos(theta) alone.

#: Entries of the table over cos(theta) in [0, 1].
TABLE_SIZE = 256


#: Up to this many cells the table's fast path runs in float32 (node error ~1e-5); above it the phase
#: N K Lambda amplifies float32's rounding N times, and float64 keeps the table exact (~2.4x slower).
FLOAT32_MAX_N = 100


def _reflectance_real(omega, geometries: tuple[CellGeometry, CellGeometry], rows, float64: bool = False) -> np.ndarray:
    """
    Unpolarised Eqs. 2, 8, 9, 10 in real (float32) arithmetic, for angles where every wave propagates
    and ``nh == n1``: the values of :func:`reflectance_polarised` to ~1e-5, several times faster (the
    table is rebuilt on every parameter change). Both polarisations share the phases ``psi, phi`` and
    their sines and cosines. With Eq. 2's own term ``Q = (sin K Lambda / sin N K Lambda)^2`` (Eq. 9's
    sinh ratio in band gaps), ``R = |r1|^2 / (|r1|^2 + |t1|^2 Q)``, where
    ``|r1|^2 : |t1|^2 = 4 r12^2 sin^2 phi : (1 - r12^2)^2`` (their common denominator cancels).
    float64 above :data:`FLOAT32_MAX_N` cells, or when ``float64`` (the reference: then equal to the
    complex path to ~1e-12, several times faster).
    """
    f32 = np.float32 if geometries[0].N <= FLOAT32_MAX_N and not float64 else np.float64
    omega = omega.astype(f32)
    first = geometries[0]
    psi = omega * first.p1.real[rows, None].astype(f32)
    phi = omega * first.p2.real[rows, None].astype(f32)
    cos_psi, sin_psi, cos_phi, sin_phi = np.cos(psi), np.sin(psi), np.cos(phi), np.sin(phi)
    cos_cos, sin_sin, sin2_phi = cos_psi * cos_phi, sin_psi * sin_phi, f32(4.0) * sin_phi * sin_phi
    N = f32(first.N)
    total = np.zeros_like(psi)
    for geometry in geometries:
        r12_2 = (geometry.r12.real[rows, None] ** 2).astype(f32)
        a = cos_cos - (0.5 * geometry.Omega.real[rows, None]).astype(f32) * sin_sin
        r1_2 = r12_2 * sin2_phi
        t1_2 = (f32(1.0) - r12_2) ** 2
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            a_band = np.clip(a, f32(-1.0), f32(1.0))
            Q_band = (f32(1.0) - a_band * a_band) / np.sin(N * np.arccos(a_band)) ** 2
            abs_a = np.maximum(np.abs(a), f32(1.0))
            x = np.maximum(np.log(abs_a + np.sqrt(abs_a * abs_a - f32(1.0))), f32(1e-12))  # acosh|a|
            h = lambda y: -np.expm1(f32(-2.0) * y)
            Q_gap = (np.exp(-(N - f32(1.0)) * x) * h(x) / h(N * x)) ** 2
            Q = np.where(np.abs(a) < f32(1.0), Q_band, Q_gap)
            total += r1_2 / (r1_2 + t1_2 * Q)
    return f32(0.5) * total


#: Rows of angles per block of the fast path: 32 x 471 float32 temporaries stay in cache.
ROW_BLOCK = 32


def reflectance_spectra(
    cos_theta: ArrayLike, mirror: BraggMirror, wavelengths: ArrayLike = colorimetry.WAVELENGTHS, float64: bool = False,
) -> np.ndarray:
    """
    Unpolarised ``R_lambda`` at every angle of ``cos_theta`` and every wavelength (nm; by default every nm
    of :data:`explorer.physics.colorimetry.WAVELENGTHS`): shape ``(n_angles, n_wavelengths)``. A 2D
    ``wavelengths`` of shape ``(n_angles, M)`` gives each angle its own wavelengths.

    Angles where every wave propagates and ``nh == n1`` take the real fast path
    (:func:`_reflectance_real`), by blocks of rows; the others (total internal reflection, a host
    ``nh != n1``) the exact complex one.
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64).ravel()
    omega = 2.0 * np.pi / np.asarray(wavelengths, dtype=np.float64)
    geometries = tuple(cell_geometry(cos_theta, mirror, pol) for pol in POLARISATIONS)
    first = geometries[0]
    # Classified by the cosines, not the optical thicknesses (a zero-thickness evanescent layer has p = 0).
    real = (first.cos_theta_1.imag == 0) & (first.cos_theta_2.imag == 0) & first.host_is_n1
    per_row = omega.ndim == 2
    spectra = np.empty((cos_theta.size, omega.shape[-1]))
    real_rows, other_rows = np.flatnonzero(real), np.flatnonzero(~real)
    block = max(1, ROW_BLOCK * 471 // max(omega.shape[-1], 1))
    for start in range(0, real_rows.size, block):
        rows = real_rows[start : start + block]
        spectra[rows] = _reflectance_real(omega[rows] if per_row else omega, geometries, rows, float64)
    for start in range(0, other_rows.size, block):
        rows = other_rows[start : start + block]
        spectra[rows] = sum(
            reflectance_polarised(omega[rows] if per_row else omega, _rows(cell_geometry(cos_theta[rows], mirror, pol)))
            for pol in POLARISATIONS
        ) / len(POLARISATIONS)
    return spectra


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


def _converged_rgb(cos_theta, mirror: BraggMirror) -> np.ndarray:
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
    table = _converged_rgb(cos_theta, mirror)
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
                values[computed] = _converged_rgb(midpoints[computed], mirror)
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


def _rows(geometry: CellGeometry) -> CellGeometry:
    """The geometry with a trailing axis, to broadcast angles against wavelengths."""
    fields = {k: (v[:, None] if isinstance(v, np.ndarray) else v) for k, v in vars(geometry).items()}
    return CellGeometry(**fields)


def tabulated_rgb(table: np.ndarray, cos_theta: ArrayLike) -> np.ndarray:
    """Linear interpolation in the table, as a linearly filtered texture fetch does."""
    size = table.shape[0]
    x = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0) * (size - 1)
    i = np.minimum(np.floor(x).astype(np.int64), size - 2)
    f = (x - i)[..., None]
    return table[i].astype(np.float64) * (1.0 - f) + table[i + 1].astype(np.float64) * f

# --------------------------------------------------------------------------------------------------
# The converged table's integrand (ours): the fringe average plus the fringes near band edges
#
# The converged colour of a Bragg mirror at a cost independent of ``N``: Yeh's reflectance split into its
# fringe average and the fringes themselves, which matter only near band edges.
#
# In a pass band, with ``u = K Lambda`` in (0, pi) and ``psi = N u``, Yeh's reflectance (Eq. 2) is
# ``R = F sin^2 psi / (1 + F sin^2 psi)`` with ``F = |C|^2 / sin^2 u``, and
#
#     1 - R = (1 / sqrt(1 + F)) (1 + 2 sum_k rho^k cos 2 k psi),   rho = (sqrt(1 + F) - 1) / (sqrt(1 + F) + 1),
#
# so ``R = Rbar + D``: the fringe average ``Rbar = 1 - 1 / sqrt(1 + F)``
# (:func:`explorer.physics.bragg.reflectance_fringe_average`; under a host, its coherent twin
# :func:`explorer.physics.bragg.fringe_average_under_host`), which does not depend on ``N``, plus harmonics of
# the fast phase ``psi``. Against a weight that varies slowly over a fringe (the CMFs: linear over each nm;
# ``F`` and ``d psi / d lambda``: over tens of nm, except near band edges), each harmonic integrates to
# ``O((N u')^-2)``: integrating by parts in ``psi``, the boundary terms vanish at band edges (``sin 2 k psi = 0``
# there, and ``1 / sqrt(1 + F) -> 0``) and cancel between neighbouring cells. What is left is a band edge's
# first fringes, where ``F`` changes by a factor ~``(m + 1)^2 / m^2`` from fringe ``m`` to the next (``F ~ 1 / u^2``)
# and the expansion does not hold; their width in ``lambda`` shrinks like ``(m / N)^2``.
#
# So the spectrum integrated here is ``Rbar + W D``, with a window ``W`` that is 1 within
# :data:`EDGE_FRINGES` fringes of a band edge (counted by ``s = N min(u, pi - u) / pi`` in a pass band and
# ``s = N Im[K] Lambda / pi`` in a gap, where ``D`` decays like ``exp(-2 N Im[K] Lambda)``) and tapers to 0 over
# as many more. Near edges it is Yeh's exact ``R`` (``Rbar``'s square-root singularity at the edge cancels);
# elsewhere it is smooth on the scale of tens of nm, whatever ``N``. The adaptive rule of
# :func:`explorer.physics.colorimetry.converged_spectra` then needs ~2 samples per nm in the bands' interior and
# refines only the cells beside band edges. With ``N <= 4`` :data:`EDGE_FRINGES` the window covers every pass
# band and the integrand is Yeh's ``R`` itself.
#
# References: Section 3.1 (Eqs. 2, 8-10), Appendix D; Yeh (1988), Chapter 6.

#: Fringes from a band edge within which the integrand is Yeh's exact R (then a taper over as many more).
EDGE_FRINGES = 8.0
#: The sampling (samples per nm) the refinement starts from: the integrand's fringes are ``N``-independent.
WINDOW_SUBSTEPS_MIN = 4
#: At or below this fringe floor (:func:`substeps_for`: fringes at least 2 nm wide at 360 nm, ~11 nm at 830 nm) the
#: integrand is Yeh's R itself: the fringe average's error grows with the fringes' width against the CMFs'.
WINDOW_EXACT_SUBSTEPS = 2


def edge_window(a: np.ndarray, N: int, fringes: float = EDGE_FRINGES) -> np.ndarray:
    """
    The window ``W`` of the fringe part: 1 within ``fringes`` fringes of a band edge, a cos^2 taper to 0
    over as many more, from ``a = cos K Lambda`` (Eq. 8): ``s = N min(u, pi - u) / pi`` with ``u = acos a``
    in a pass band, ``s = N acosh|a| / pi`` in a gap.
    """
    abs_a = np.abs(a)
    with np.errstate(invalid="ignore"):
        distance = np.where(abs_a < 1.0, np.arccos(np.minimum(abs_a, 1.0)), np.arccosh(np.maximum(abs_a, 1.0)))
    s = (N / np.pi) * distance / fringes  # 1 at the window's inner end, 2 at its outer end
    taper = np.cos(0.5 * np.pi * np.clip(s - 1.0, 0.0, 1.0)) ** 2
    return taper.astype(a.dtype, copy=False)


def window_threshold(N: int, fringes: float = EDGE_FRINGES) -> float:
    """The ``|cos K Lambda|`` below which :func:`edge_window` is 0 (-1 where it covers whole pass bands)."""
    outer = 2.0 * fringes * np.pi / N
    return float(np.cos(outer)) if outer < 0.5 * np.pi else -1.0


def _windowed_real(omega, geometries, rows, float64: bool) -> np.ndarray:
    """
    ``Rbar + W (R - Rbar)`` unpolarised, for angles where every wave propagates and ``nh == n1``: the real
    arithmetic of :func:`explorer.physics._reflectance_real` (``|r1|^2 : |t1|^2 = 4 r12^2 sin^2 phi :
    (1 - r12^2)^2``), float32 up to :data:`explorer.physics.FLOAT32_MAX_N` cells. ``Rbar = 1 -
    sqrt(|t1|^2 sin^2 u / (|r1|^2 + |t1|^2 sin^2 u))`` (the fringe average of Eq. 2). Yeh's exact ``R``
    is computed only where the window is not 0.
    """
    first = geometries[0]
    N = first.N
    f = np.float32 if N <= FLOAT32_MAX_N and not float64 else np.float64
    omega = omega.astype(f)
    psi = omega * first.p1.real[rows, None].astype(f)
    phi = omega * first.p2.real[rows, None].astype(f)
    cos_psi, sin_psi, cos_phi, sin_phi = np.cos(psi), np.sin(psi), np.cos(phi), np.sin(phi)
    cos_cos, sin_sin, sin2_phi = cos_psi * cos_phi, sin_psi * sin_phi, f(4.0) * sin_phi * sin_phi
    threshold = window_threshold(N)
    total = np.zeros_like(psi)
    for geometry in geometries:
        r12_2 = (geometry.r12.real[rows, None] ** 2).astype(f)
        a = cos_cos - (0.5 * geometry.Omega.real[rows, None]).astype(f) * sin_sin
        r1_2 = r12_2 * sin2_phi
        t1_2 = np.broadcast_to((f(1.0) - r12_2) ** 2, a.shape)
        sin2_u = np.maximum(f(1.0) - a * a, f(0.0))
        t_sin = t1_2 * sin2_u
        denominator = r1_2 + t_sin
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = f(1.0) - np.sqrt(np.where(denominator > 0.0, t_sin / denominator, f(1.0)))
        near = np.flatnonzero(np.abs(a) > threshold)
        if near.size:
            a_n, r1_n, t1_n = a.ravel()[near], r1_2.ravel()[near], t1_2.ravel()[near]
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                a_band = np.clip(a_n, f(-1.0), f(1.0))
                Q_band = (f(1.0) - a_band * a_band) / np.sin(f(N) * np.arccos(a_band)) ** 2
                abs_a = np.maximum(np.abs(a_n), f(1.0))
                x = np.maximum(np.log(abs_a + np.sqrt(abs_a * abs_a - f(1.0))), f(1e-12))  # acosh|a|
                h = lambda y: -np.expm1(f(-2.0) * y)
                Q_gap = (np.exp(-(f(N) - f(1.0)) * x) * h(x) / h(f(N) * x)) ** 2
                Q = np.where(np.abs(a_n) < f(1.0), Q_band, Q_gap)
                exact = r1_n / (r1_n + t1_n * Q)
            mean_n = mean.ravel()[near]
            exact = np.where(np.isfinite(exact), exact, mean_n)
            mean.ravel()[near] = mean_n + edge_window(a_n, N) * (exact - mean_n)
        total += mean
    return f(0.5) * total


def _windowed_complex(omega, geometry: CellGeometry) -> np.ndarray:
    """
    ``Rbar + W (R - Rbar)`` for one polarisation in complex float64 (total internal reflection, a host
    ``nh != n1``): Yeh's ``R`` (Eqs. 2, 9, 10; Appendix D's ``r_hN``) only where the window is not 0.
    """
    r1, t1 = airy_slab_coefficients(omega, geometry)
    a = cos_K_Lambda(omega, geometry)
    if geometry.host_is_n1:
        t1_2_sin2 = np.abs(t1) ** 2 * np.maximum(1.0 - a * a, 0.0)
        denominator = np.abs(r1) ** 2 + t1_2_sin2
        ratio = np.divide(t1_2_sin2, denominator, out=np.ones_like(denominator), where=denominator > 0.0)
        mean = 1.0 - np.sqrt(ratio)
    else:
        mean = fringe_average_under_host(r1, t1, omega, geometry, a)
    near = np.flatnonzero(np.abs(a) > window_threshold(geometry.N))
    if near.size:
        shape = a.shape
        a_n, r1_n, t1_n = a.ravel()[near], r1.ravel()[near], t1.ravel()[near]
        if geometry.host_is_n1:
            exact = reflectance_yeh(r1_n, t1_n, a_n, geometry.N)
        else:
            omega_n = np.broadcast_to(omega, shape).ravel()[near]
            p1_n = np.broadcast_to(geometry.p1, shape).ravel()[near]
            r_h1_n = np.broadcast_to(geometry.r_h1, shape).ravel()[near]
            U_N1, U_N2, _ = chebyshev_U(a_n, geometry.N)
            t_cell = t1_n * np.exp(1j * omega_n * p1_n)
            r_N = r1_n * U_N1 / (U_N1 - U_N2 * t_cell)  # Appendix D, as reflection_coefficient_bragg
            exact = np.abs(reflection_coefficient_host(r_N, r_h1_n)) ** 2
        mean_n = mean.ravel()[near]
        mean = mean.copy()
        mean.ravel()[near] = mean_n + edge_window(a_n, geometry.N) * (exact - mean_n)
    return mean


def windowed_spectrum_function(
    cos_theta: ArrayLike, mirror: BraggMirror, float64: bool = False,
) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """
    ``spectrum(wavelengths, rows)`` for :func:`explorer.physics.colorimetry.converged_spectra`: the unpolarised
    ``Rbar + W (R - Rbar)`` (the section's comment above) at the angles ``cos_theta[rows]``, as
    :func:`explorer.physics._spectrum_function` gives ``R``.
    """
    return _row_spectrum_function(
        cos_theta, mirror,
        lambda omega, geometries, rows: _windowed_real(omega, geometries, rows, float64),
        _windowed_complex,
    )


def windowed_converged_spectra(
    cos_theta: ArrayLike, mirror: BraggMirror, tolerance: float = colorimetry.CONVERGENCE_TOLERANCE,
    passes: int = colorimetry.CONVERGENCE_PASSES, float64: bool = False, substeps_max: int = colorimetry.MAX_SUBSTEPS,
) -> tuple[np.ndarray, np.ndarray]:
    """
    Hat-averaged spectra whose colours equal those of
    :func:`explorer.physics.converged_reflectance_spectra`, from ``Rbar + W (R - Rbar)`` (module
    docstring): the same adaptive rule, started at :data:`WINDOW_SUBSTEPS_MIN` samples per nm whatever ``N``.
    The spectra themselves differ from Yeh's hat averages only by the fringes away from band edges,
    whose integral against any weight that is smooth over a fringe vanishes.

    Returns
    -------
    spectra : ndarray, shape ``(cos_theta.size, 471)``
    substeps : ndarray of int, shape ``(cos_theta.size,)``
    """
    cos_theta, inverse = np.unique(np.round(np.asarray(cos_theta, dtype=np.float64).ravel(), 12), return_inverse=True)
    if window_threshold(mirror.N) <= -1.0 or substeps_for(mirror, cos_theta) <= WINDOW_EXACT_SUBSTEPS:
        # The window covers whole pass bands, or the fringes are so wide (the reference's fringe floor below this
        # rule's start) that the fringe average misses their colour (Lambda = 50 nm, N = 64-300: 2e-2 to 5e-4) while
        # Yeh's R costs no more: the integrand is Yeh's R itself.
        function = _spectrum_function(cos_theta, mirror, float64=float64)
    else:
        function = windowed_spectrum_function(cos_theta, mirror, float64=float64)
    spectra, substeps = colorimetry.converged_spectra(
        function,
        cos_theta.size,
        # Fringes only near band edges: the fringe floor of the mirror (substeps_for) where it is lower.
        substeps_min=min(WINDOW_SUBSTEPS_MIN, substeps_for(mirror, cos_theta), substeps_max),
        tolerance=tolerance,
        passes=passes,
        substeps_max=substeps_max,
    )
    return spectra[inverse.ravel()], substeps[inverse.ravel()]


def windowed_converged_rgb(cos_theta: ArrayLike, mirror: BraggMirror, **kwargs: float) -> np.ndarray:
    """Linear sRGB of :func:`windowed_converged_spectra`, shape ``cos_theta.shape + (3,)``."""
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    spectra, _ = windowed_converged_spectra(cos_theta, mirror, **kwargs)
    return colorimetry.spectrum_to_rgb(spectra).reshape(cos_theta.shape + (3,))


# --------------------------------------------------------------------------------------------------
# The converged colour by Gauss quadrature over band pieces (ours)
#
# The integral of Yeh's R against the CMFs interpolated linearly (what the converged reference computes,
# :func:`explorer.physics.colorimetry.converged_spectra`), with a few hundred reflectances per angle
# whatever N. With x = omega n_+ and Delta = p1 - p2, Eq. 8 is a trigonometric polynomial,
#
#     cos K Lambda = a(omega) = (1/2 + Omega/4) cos(omega n_+) + (1/2 - Omega/4) cos(omega Delta),
#
# whose gaps hold the modes omega_m = m pi / n_+ (Eq. 13) and whose Airy points (a = 0) lie between
# them (Appendix A). Each interval [omega_m, omega_{m+1}] is cut at its band edges e+_m, e-_{m+1}
# (|a| = 1) and its Airy point into four pieces, each anchored at its band edge with the map
# omega = e + S t^2 (t in [0, 1]): Yeh's R is analytic in omega, the fringe average's square root
# 1 - a^2 ~ (omega - e) becomes linear in t, and fringes near the edge (u = K Lambda ~ t) are evenly
# spaced in t. On each piece:
#
# - a pass band's first BAND_EDGE_FRINGES fringes from its edge (u < M pi / N): Yeh's exact R. The cut lies
#   on a transmission dip (sin N u = 0), where the fringes' integration-by-parts boundary terms vanish (see
#   the windowed section above). Panels end at every half fringe (u = h pi / 2N, found by Newton's method);
#   around each dip 1 - R = 1 / (1 + F sin^2 N u), F = |C|^2 / sin^2 u, is integrated on nodes squeezed by
#   psi = arctan(tan(chi) / k), k = sqrt(1 + F), under which (1 - R) d psi = d chi / k: a dip of any
#   sharpness (F ~ (N |C|)^2 near edges) costs FRINGE_NODES nodes a side;
# - the rest of the pass band: the fringe average Rbar (its harmonics integrate to O((N u')^-2)),
#   smooth in t, on panels graded geometrically from the cut. Where fringes are wider than FRINGE_MEAN_NM
#   anywhere in a piece, or N < PIECES_EXACT_N, Yeh's R throughout instead;
# - a gap: Yeh's R while N Im[K] Lambda < GAP_DECAY (its deficit 1 - R decays like exp(-2 N Im[K] Lambda)),
#   then R = 1, integrated against the CMFs in closed form.
#
# Every panel is also cut to at most PANEL_NM nm for the CMFs. The pieces tile the visible range exactly
# (tests/test_fast_tables.py).
#
# Under a host nh != n1 (Appendix D) the same pieces hold |r_hN|^2: its transmission peaks are the mirror's dips moved
# by psi0 in N K Lambda and sharpened to k (_host_dip), so the fringe boundaries move there, and the fringe average is
# the coherent one (fringe_average_under_host, in closed form). References: Section 3.1 (Eqs. 2, 8-10), Appendices A
# and D; Yeh (1988), Chapter 6.

#: Fringes from a band edge integrated exactly (Yeh's R); beyond them, the fringe average. 8, not 4: with
#: fringes up to FRINGE_MEAN_NM wide the average's error at N = 64-100 halved (2e-4 -> 1e-4 of a 1e-5 reference).
BAND_EDGE_FRINGES = 8
#: Gauss-Legendre nodes per panel (one panel per fringe near band edges).
GAUSS_NODES = 8
#: Nodes per fringe near band edges (clustered at the fringe's ends, where its transmission dip is).
FRINGE_NODES = 6
#: A pass piece whose fringes are wider than this (nm) at its Airy point is Yeh's R throughout. 3 nm, not 1:
#: N = 64-300 pieces then take the fringe average beyond their edge fringes (half the nodes), within 1e-4.
FRINGE_MEAN_NM = 3.0
#: ... times N / PIECES_EXACT_N, up to this factor: the average's error at a given fringe width falls with N (measured:
#: 6-nm fringes 2.8e-4 at N = 64, 1.1e-4 at N = 100, against a 1e-5 reference).
FRINGE_MEAN_GROWTH = 2.0
#: ... under a host: a strongly reflecting host interface (grazing) and the mirror form a cavity whose fringes are
#: not the mirror's shape (nh = 1 over n1 = 1.5, N = 20, cos 0.02: 2.9e-4 with 6 nodes, 1.3e-4 with 8).
HOST_FRINGE_NODES = 8
#: ... under a host: its interface and the mirror interfere to first order in the mirror's r1 (the mirror alone: second),
#: so wide fringes' harmonics weigh more against R: no growth (weak contrast 1.05/1.10 under nh = 1, N = 300: 4.4e-4 with
#: 6-nm fringes averaged, 1e-7 with 3 nm).
HOST_FRINGE_MEAN_GROWTH = 1.0
#: Dips with k = sqrt(1 + F) above this are integrated as 1 - (1 - R), the dip on squeezed nodes.
DIP_SHARP = 2.0
#: Panels of a gap's exact part.
GAP_PANELS = 4
#: Widest panel in wavelength (nm), for the CMFs' own structure.
PANEL_NM = 16.0
#: N Im[K] Lambda beyond which a gap reflects 1 (to exp(-2 GAP_DECAY)).
GAP_DECAY = 12.0
#: Newton steps (bisection-safeguarded) for the Airy points, band edges and the cuts.
ROOT_STEPS = 8
#: Fringe boundaries: u on this many points of t per piece for first guesses, then Newton steps.
ROOT_GRID = 17
ROOT_POLISH = 2
#: Under a host: Newton steps moving the fringe boundaries to the host's peaks (_host_dip).
HOST_SHIFT_STEPS = 1


@functools.lru_cache(maxsize=None)
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


@functools.lru_cache(maxsize=None)
def _cmf_nodes() -> tuple[np.ndarray, np.ndarray]:
    """The CMFs at the 473 nodes 359..831 nm (zero at both ends) and their exact cumulative integral there."""
    c = np.vstack([np.zeros(3), colorimetry.colour_matching_functions(), np.zeros(3)])
    cumulative = np.vstack([np.zeros(3), np.cumsum(0.5 * (c[:-1] + c[1:]), axis=0)])
    return c, cumulative


def _cmf_linear(wavelength: np.ndarray) -> np.ndarray:
    """The CMFs interpolated linearly between their 1-nm nodes (zero outside 359-831 nm), ``(n, 3)``."""
    c, _ = _cmf_nodes()
    nodes = colorimetry.HAT_LOW + np.arange(c.shape[0], dtype=np.float64)
    return np.stack([np.interp(wavelength, nodes, c[:, channel], left=0.0, right=0.0) for channel in range(3)], axis=-1)


def _cmf_integral_to(wavelength: np.ndarray) -> np.ndarray:
    """``int_359^lambda`` of :func:`_cmf_linear` in closed form (piecewise quadratic), ``(n, 3)``."""
    c, cumulative = _cmf_nodes()
    x = np.clip(wavelength - colorimetry.HAT_LOW, 0.0, c.shape[0] - 1.0)
    i = np.minimum(x.astype(np.int64), c.shape[0] - 2)
    f = (x - i)[:, None]
    return cumulative[i] + c[i] * f + (c[i + 1] - c[i]) * (0.5 * f * f)


#: Below this many values :func:`_cos_sin` calls numpy's ``cos`` and ``sin``: per-call overhead dominates there.
COS_SIN_MIN_SIZE = 2048


def _cos_sin(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    ``(cos x, sin x)`` from ``tau = tan(r / 2)``, ``r`` = ``x`` reduced to [-pi, pi]: ``((1 - tau^2), 2 tau) / (1 + tau^2)``.
    numpy's float64 ``tan`` is vectorised where its ``cos`` and ``sin`` are not (1.5 against ~20 ns a value on this
    machine): 2.5x faster for both, to ~1e-14 for ``|x| <= 100`` (the band pieces' phases stay below ~70).
    """
    if np.size(x) < COS_SIN_MIN_SIZE:  # small arrays (root finding): two calls cost less than the ten below
        return np.cos(x), np.sin(x)
    tau = np.tan(0.5 * (x - (2.0 * np.pi) * np.rint(x * (0.5 / np.pi))))
    tau2 = tau * tau
    inverse = 1.0 / (1.0 + tau2)
    return (1.0 - tau2) * inverse, 2.0 * tau * inverse


@dataclass
class _Lines:
    """Per (angle, polarisation) line: Eq. 8's trigonometric form and Eq. 10's slab terms (real angles)."""

    n_plus: np.ndarray
    delta_p: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray
    p2: np.ndarray
    r12_2: np.ndarray
    N: int
    #: Under a host nh != n1 (Appendix D): the signed r12 and the host interface's real r_h1 per line; None otherwise.
    r12: np.ndarray | None = None
    r_h1: np.ndarray | None = None

    def a(self, omega, line):
        """``cos K Lambda`` (Eq. 8) and its derivative in omega."""
        n_plus, delta_p = self.n_plus[line], self.delta_p[line]
        (cos_x, sin_x), (cos_y, sin_y) = _cos_sin(omega * n_plus), _cos_sin(omega * delta_p)
        alpha, beta = self.alpha[line], self.beta[line]
        return alpha * cos_x + beta * cos_y, -(alpha * n_plus * sin_x + beta * delta_p * sin_y)


def _safeguarded_newton(g, lo, hi, guess, positive_at_lo, steps=ROOT_STEPS):
    """The root of ``g`` (returning value and slope) in ``[lo, hi]``, where it changes sign once."""
    x = np.clip(guess, np.minimum(lo, hi), np.maximum(lo, hi))
    for _ in range(steps):
        value, slope = g(x)
        same = (value >= 0.0) == positive_at_lo
        lo, hi = np.where(same, x, lo), np.where(same, hi, x)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = x - value / slope
        # A converged x sits on its bracket's end: its Newton step (x itself) is kept, not bisected away.
        inside = np.isfinite(step) & ((step - lo) * (step - hi) <= 0.0)
        x = np.where(inside, step, 0.5 * (lo + hi))
    return x


def _panels(piece, lo, hi, count):
    """``count`` equal panels of ``[lo, hi]`` per entry (flattened): their piece, lower end and width."""
    count = np.asarray(count, dtype=np.int64)
    panel_piece = np.repeat(piece, count)
    j = np.arange(panel_piece.size) - np.repeat(np.cumsum(count) - count, count)
    width = np.repeat((hi - lo) / np.maximum(count, 1), count)
    return panel_piece, np.repeat(lo, count) + j * width, width


def _pieces_xyz(lines: _Lines, exact_everywhere: bool, scale: int = 1) -> np.ndarray:
    """XYZ (the CMFs' integral of R) of every line, ``(n_lines, 3)``; ``scale`` multiplies every node count."""
    N = lines.N
    n_lines = lines.n_plus.size
    omega_lo, omega_hi = 2.0 * np.pi / colorimetry.HAT_HIGH, 2.0 * np.pi / colorimetry.HAT_LOW
    m_first = np.floor(omega_lo * lines.n_plus / np.pi)
    m_last = np.floor(omega_hi * lines.n_plus / np.pi)
    count = int((m_last - m_first).max()) + 1
    line, k = np.divmod(np.arange(n_lines * count), count)
    m = m_first[line] + k
    valid = m <= m_last[line]
    line, m = line[valid], m[valid]
    n_plus = lines.n_plus[line]
    omega_m, omega_next = m * np.pi / n_plus, (m + 1.0) * np.pi / n_plus
    sign_m = np.where(m % 2 == 0, 1.0, -1.0)  # the sign of a at omega_m (Appendix A)

    def shifted_a(sign, shift):
        def g(w):
            value, slope = lines.a(w, line)
            return sign * value - shift, sign * slope
        return g

    airy = _safeguarded_newton(shifted_a(sign_m, 0.0), omega_m, omega_next, 0.5 * (omega_m + omega_next), True)
    # Both band edges in one solve (a is +-1 there): elementwise the same as two, half the numpy calls.
    both_line, both_sign = np.concatenate([line, line]), np.concatenate([sign_m, -sign_m])

    def edge_g(w):
        value, slope = lines.a(w, both_line)
        return both_sign * value - 1.0, both_sign * slope

    edges = _safeguarded_newton(edge_g, np.concatenate([omega_m, airy]), np.concatenate([airy, omega_next]),
                                np.concatenate([0.5 * (omega_m + airy), 0.5 * (airy + omega_next)]),
                                np.repeat([True, False], line.size))
    edge_up, edge_down = np.where(m == 0, 0.0, edges[: line.size]), edges[line.size :]
    # Four pieces per interval, each anchored at a band edge e with omega = e + S t^2: two halves of the pass band
    # (towards the Airy point), two halves of gaps (towards the modes).
    anchor = np.concatenate([edge_up, edge_down, edge_up, edge_down])
    span = np.concatenate([airy - edge_up, airy - edge_down, omega_m - edge_up, omega_next - edge_down])
    piece_line = np.tile(line, 4)
    is_gap = np.repeat([False, False, True, True], line.size)
    with np.errstate(divide="ignore", invalid="ignore"):
        q_lo, q_hi = (omega_lo - anchor) / span, (omega_hi - anchor) / span
    t0 = np.sqrt(np.clip(np.nan_to_num(np.minimum(q_lo, q_hi), nan=1.0), 0.0, 1.0))
    t1 = np.sqrt(np.clip(np.nan_to_num(np.maximum(q_lo, q_hi), nan=0.0), 0.0, 1.0))
    keep = t1 > t0
    anchor, span, piece_line, is_gap, t0, t1 = (v[keep] for v in (anchor, span, piece_line, is_gap, t0, t1))

    def omega_at(t, pieces):
        return anchor[pieces] + span[pieces] * t * t

    def a_at_t(t, pieces):
        value, slope = lines.a(omega_at(t, pieces), piece_line[pieces])
        return value, slope * 2.0 * span[pieces] * t

    def nm_between(t_a, t_b, pieces):
        return np.abs(2.0 * np.pi / omega_at(t_a, pieces) - 2.0 * np.pi / omega_at(t_b, pieces))

    # u (or Im[K] Lambda in a gap) ~ sqrt(2 |a'(e)| |S|) t near the edge: the roots' first guesses.
    _, slope_e = lines.a(anchor, piece_line)
    u_slope = np.sqrt(np.maximum(2.0 * np.abs(slope_e * span), 1e-300))
    # Panels: (piece, t_a, t_span, k, kind): t = t_a + t_span (2 / pi) arctan(tan(chi) / k), chi in [0, pi / 2].
    panels = []

    def add(piece, t_a, t_span, k, kind, nodes):
        chi_hi = np.full(piece.size, 0.5 * np.pi)
        panels.append((piece, t_a, t_span, k, kind, nodes, chi_hi))

    band = np.flatnonzero(~is_gap)
    # Each pass piece is exact up to u_cut: M fringes from its edge, or the whole piece where fringes
    # (lambda^2 / (2 N du/domega) wide) are wider than FRINGE_MEAN_NM at its Airy point or at either end of its
    # visible part, as the fringe average's far harmonics then do not cancel against the CMFs.
    def fringe_nm_at(t):
        value, slope = lines.a(omega_at(t, band), piece_line[band])
        du_domega = np.abs(slope) / np.maximum(np.sqrt(np.maximum(1.0 - value * value, 0.0)), 1e-300)
        lam = 2.0 * np.pi / omega_at(t, band)
        return lam * lam / (2.0 * N * np.maximum(du_domega, 1e-300))

    fringe_nm = np.maximum(np.maximum(fringe_nm_at(t0[band]), fringe_nm_at(t1[band])), fringe_nm_at(np.ones(band.size)))
    growth = FRINGE_MEAN_GROWTH if lines.r_h1 is None else HOST_FRINGE_MEAN_GROWTH
    mean_nm = FRINGE_MEAN_NM * min(max(N / PIECES_EXACT_N, 1.0), growth)
    whole = exact_everywhere | (fringe_nm > mean_nm) | (BAND_EDGE_FRINGES * np.pi / N >= 0.5 * np.pi)
    u_cut = np.where(whole, 0.5 * np.pi, BAND_EDGE_FRINGES * np.pi / N)
    def fringe_panels(band, u_cut):
        """The exact part of the pass pieces ``band`` (up to ``u_cut``), as panels; returns the cut in t."""
        # Fringe boundaries: u = h pi / (2 N), h = 1..H (clamped to each piece's cut); the transmission dips at even h.
        H = int(np.ceil(2.0 * u_cut.max() * N / np.pi - 1e-9))
        halves = np.arange(1, H + 1)
        targets = np.minimum(halves[None, :] * 0.5 * np.pi / N, u_cut[:, None])  # (band, H)
        bp = np.repeat(band, H)
        target = targets.ravel()

        def g(t):
            value, slope = a_at_t(t, bp)
            u = np.arccos(np.clip(np.abs(value), 0.0, 1.0))
            return u - target, -np.sign(value) * slope / np.maximum(np.sin(u), 1e-300)

        # First guesses: u on a grid of t per piece, inverted linearly; then Newton within the grid's bracket.
        grid = np.linspace(0.0, 1.0, ROOT_GRID)
        u_grid = np.arccos(np.clip(np.abs(a_at_t(np.tile(grid, band.size), np.repeat(band, ROOT_GRID))[0]), 0.0, 1.0))
        u_grid = np.maximum.accumulate(u_grid.reshape(band.size, ROOT_GRID), axis=1)
        j = np.clip((u_grid[:, :, None] < targets[:, None, :]).sum(axis=1), 1, ROOT_GRID - 1)  # (band, H)
        u_a = np.take_along_axis(u_grid, j - 1, axis=1)
        u_b = np.take_along_axis(u_grid, j, axis=1)
        f = np.clip((targets - u_a) / np.maximum(u_b - u_a, 1e-300), 0.0, 1.0)
        guess = (grid[j - 1] + f * (grid[1] - grid[0])).ravel()
        bounds = _safeguarded_newton(g, grid[j - 1].ravel(), grid[j].ravel(), guess, False, steps=ROOT_POLISH)
        if lines.r_h1 is not None:
            # Under a host the transmission peaks sit at N K Lambda = j pi + psi0 (_host_dip), not at the mirror's
            # dips: the boundaries move there (Newton steps on N u - psi0 = h pi / 2: psi0 varies slowly), so that the
            # squeezed nodes are centred on the peaks and the cut to the fringe average lies where the fringes' boundary
            # terms vanish (cut at the mirror's dip instead: 1.3e-3 at nh = 2.4, N = 100; 3e-5 once moved).
            shifted = bounds
            for _ in range(HOST_SHIFT_STEPS):
                value, slope = a_at_t(shifted, bp)
                u = np.arccos(np.clip(np.abs(value), 0.0, 1.0))
                du_dt = np.abs(slope) / np.maximum(np.sin(u), 1e-300)
                psi0, _ = _host_dip(lines, omega_at(shifted, bp), piece_line[bp])
                # psi0 is defined mod pi: made continuous along each piece from its edge (where psi0 -> 0), so that every
                # even boundary stays on a peak, also where a host that reflects strongly (grazing) and a weak mirror
                # form a cavity whose sharp peaks sit near the mirror's half fringes (psi0 ~ pi / 2).
                psi0 = np.unwrap(psi0.reshape(band.size, H), period=np.pi, axis=1)
                # u is K Lambda from the piece's edge: N K Lambda = N u where a > 0, N pi - N u where a < 0.
                shift = np.sign(value).reshape(band.size, H) * psi0
                # A peak left between the edge and the first boundary (psi0 not -> 0 at the edge: nearly closed gaps,
                # delta ~ 0, where the edge's fringes are not sharp) would get plain nodes: the boundaries go a fringe back.
                shift = (shift - np.pi * (shift[:, :1] > 0.25 * np.pi)).ravel()
                goal = target + shift / N
                shifted = np.clip(shifted + (goal - u) / np.maximum(du_dt, 1e-300), 0.0, 1.0)
            bounds = np.maximum.accumulate(np.where(target < 0.5 * np.pi - 1e-12, shifted, bounds)
                                           .reshape(band.size, H), axis=1).ravel()
        bounds = np.where(target >= 0.5 * np.pi - 1e-12, 1.0, bounds).reshape(band.size, H)
        cut_t = bounds[:, -1]
        bounds = np.concatenate([np.zeros((band.size, 1)), bounds], axis=1)  # columns: h = 0..H
        # From the edge to the first half fringe: no dip (R -> kappa^2 / (1 + kappa^2) at the edge), Yeh's R.
        add(band, bounds[:, 0], bounds[:, 1] - bounds[:, 0], np.ones(band.size), 0, GAUSS_NODES)
        # Beyond it, two half panels around each dip u = j pi / N. Sharp dips (k = sqrt(1 + F) > DIP_SHARP): R = 1 - (1 - R),
        # the 1 on plain nodes, the dip 1 - R = 1 / (1 + F sin^2 N u) on nodes squeezed by psi = arctan(tan(chi) / k),
        # under which (1 - R) d psi = d chi / k for a fixed F: the dip, however narrow, is spread over the panel.
        dips = np.arange(2, H + 1, 2)
        if dips.size:
            t_dip = bounds[:, dips]
            dip_piece = np.repeat(band, dips.size)
            omega_dip = omega_at(t_dip.ravel(), dip_piece)
            line_dip = piece_line[dip_piece]
            sin_phi = np.sin(omega_dip * lines.p2[line_dip])
            r12_2 = lines.r12_2[line_dip]
            C2 = 4.0 * r12_2 * sin_phi * sin_phi / (1.0 - r12_2) ** 2  # |C|^2 (Eq. 2) = |r1|^2 / |t1|^2
            F = C2 / np.maximum(np.sin(np.tile(dips * 0.5 * np.pi / N, band.size)) ** 2, 1e-300)
            k_dip = np.sqrt(1.0 + F) if lines.r_h1 is None else _host_dip(lines, omega_dip, line_dip)[1]
            k = k_dip
            left = bounds[:, dips - 1].ravel() - t_dip.ravel()
            right = bounds[:, np.minimum(dips + 1, H)].ravel() - t_dip.ravel()
            sharp = k > DIP_SHARP
            # The map takes psi linear in t over the half panel; the dip's width in t is set by dpsi/dt at the dip.
            value, slope = a_at_t(t_dip.ravel(), dip_piece)
            dpsi_dt = N * np.abs(slope) / np.maximum(np.sqrt(np.maximum(1.0 - value * value, 0.0)), 1e-300)
            fringe_nodes = FRINGE_NODES if lines.r_h1 is None else HOST_FRINGE_NODES
            for side in (left, right):
                k = k_dip * np.clip(dpsi_dt * np.abs(side) / (0.5 * np.pi), 0.25, 4.0)
                # Soft dips: Yeh's R on plain nodes (1 and R - 1 would cancel to R's small values).
                add(dip_piece[~sharp], t_dip.ravel()[~sharp], side[~sharp], np.ones(int((~sharp).sum())), 0, fringe_nodes)
                add(dip_piece[sharp], t_dip.ravel()[sharp], side[sharp], np.ones(int(sharp.sum())), 2, fringe_nodes)
                add(dip_piece[sharp], t_dip.ravel()[sharp], side[sharp], k[sharp], 3, fringe_nodes)
        return cut_t

    cut_band = np.ones(band.size)
    for group in (whole, ~whole):
        if group.any():
            cut_band[group] = fringe_panels(band[group], u_cut[group])
    # The rest of the pass band: the fringe average, panels graded geometrically from the cut.
    s0 = cut_band
    rest = s0 < 1.0
    smooth, s0 = band[rest], s0[rest]
    doublings = np.ceil(np.log2(1.0 / np.maximum(s0, 1e-12))).clip(1, 40).astype(np.int64)
    geo_piece = np.repeat(smooth, doublings)
    jj = np.arange(geo_piece.size) - np.repeat(np.cumsum(doublings) - doublings, doublings)
    ratio = (1.0 / np.repeat(np.maximum(s0, 1e-12), doublings)) ** (1.0 / np.repeat(doublings, doublings))
    geo_lo = np.where(jj == 0, np.repeat(s0, doublings), np.repeat(np.maximum(s0, 1e-12), doublings) * ratio**jj)
    geo_hi = np.minimum(np.repeat(np.maximum(s0, 1e-12), doublings) * ratio ** (jj + 1), 1.0)
    add(geo_piece, geo_lo, geo_hi - geo_lo, np.ones(geo_piece.size), 1, GAUSS_NODES)
    # Gaps: Yeh's R up to N Im[K] Lambda = GAP_DECAY, then 1.
    gap = np.flatnonzero(is_gap)
    cut = np.ones(gap.size)
    if not exact_everywhere:
        x_cut = GAP_DECAY / N

        def h(t):
            value, slope = a_at_t(t, gap)
            abs_a = np.maximum(np.abs(value), 1.0)
            return np.arccosh(abs_a) - x_cut, np.sign(value) * slope / np.maximum(np.sqrt(abs_a * abs_a - 1.0), 1e-300)

        end_value, _ = a_at_t(np.ones(gap.size), gap)
        deep = np.arccosh(np.maximum(np.abs(end_value), 1.0)) > x_cut
        solved = _safeguarded_newton(h, np.zeros(gap.size), np.ones(gap.size), np.clip(x_cut / u_slope[gap], 0.0, 1.0), False)
        cut = np.where(deep, solved, 1.0)
    gap_piece, gap_lo, gap_width = _panels(gap, np.zeros(gap.size), cut, np.full(gap.size, GAP_PANELS))
    add(gap_piece, gap_lo, gap_width, np.ones(gap_piece.size), 0, GAUSS_NODES)
    # Nodes: each panel clipped to its piece's visible part (in chi), split for the CMFs (PANEL_NM), Gauss-Legendre.
    # Panels where R = 1 (kind 2, and the gaps beyond their exact part) integrate the CMFs in closed form instead.
    nodes_t, nodes_w, nodes_piece, nodes_kind = [], [], [], []
    ones_piece, ones_lo, ones_hi = [], [], []
    for piece, t_a, t_span, k, kind, n, _ in panels:
        with np.errstate(divide="ignore", invalid="ignore"):
            rel_lo = np.clip((t0[piece] - t_a) / t_span, 0.0, 1.0)
            rel_hi = np.clip((t1[piece] - t_a) / t_span, 0.0, 1.0)
        rel_lo, rel_hi = np.nan_to_num(np.minimum(rel_lo, rel_hi)), np.nan_to_num(np.maximum(rel_lo, rel_hi))
        if kind == 2:
            inside = (rel_hi > rel_lo) & (t_span != 0.0)
            ones_piece.append(piece[inside])
            ones_lo.append((t_a + t_span * rel_lo)[inside])
            ones_hi.append((t_a + t_span * rel_hi)[inside])
            continue
        chi_lo, chi_hi = np.arctan(k * np.tan(0.5 * np.pi * rel_lo)), np.arctan(k * np.tan(0.5 * np.pi * np.minimum(rel_hi, 1.0 - 1e-16)))
        chi_hi = np.where(rel_hi >= 1.0, 0.5 * np.pi, chi_hi)
        inside = (chi_hi > chi_lo) & (t_span != 0.0)
        piece, t_a, t_span, k, chi_lo, chi_hi = (v[inside] for v in (piece, t_a, t_span, k, chi_lo, chi_hi))
        if kind == 3:
            ends_lo = t_a + t_span * (2.0 / np.pi) * np.arctan(np.tan(chi_lo) / k)
            ends_hi = t_a + t_span * (2.0 / np.pi) * np.arctan(np.tan(np.minimum(chi_hi, 0.5 * np.pi - 1e-16)) / k)
        else:  # k = 1
            ends_lo, ends_hi = t_a + t_span * (2.0 / np.pi) * chi_lo, t_a + t_span * (2.0 / np.pi) * chi_hi
        split = np.ceil(nm_between(ends_lo, ends_hi, piece) / PANEL_NM).clip(1, None)
        if (split == 1).all():
            sub, sub_lo, sub_width = np.arange(piece.size), chi_lo, chi_hi - chi_lo
        else:
            sub, sub_lo, sub_width = _panels(np.arange(piece.size), chi_lo, chi_hi, split)
        x, w = _gauss_legendre(n * scale)
        chi = sub_lo[:, None] + sub_width[:, None] * x
        if kind == 3:
            kk = k[sub][:, None]
            cos_chi, sin_chi = _cos_sin(chi)
            psi = np.arctan2(sin_chi, kk * cos_chi)  # arctan(tan(chi) / k) in [0, pi / 2]
            jacobian = np.abs(t_span[sub][:, None]) * (2.0 / np.pi) * kk / (kk * kk * cos_chi * cos_chi + sin_chi * sin_chi)
        else:  # k = 1: psi = chi
            psi, jacobian = chi, np.abs(t_span[sub][:, None]) * (2.0 / np.pi)
        nodes_t.append((t_a[sub][:, None] + t_span[sub][:, None] * (2.0 / np.pi) * psi).ravel())
        nodes_w.append((sub_width[:, None] * w * jacobian).ravel())
        nodes_piece.append(np.repeat(piece[sub], x.size))
        nodes_kind.append(np.full(chi.size, kind, dtype=np.int8))
    t = np.concatenate(nodes_t)
    node_piece = np.concatenate(nodes_piece)
    omega = omega_at(t, node_piece)
    wavelength = 2.0 * np.pi / omega
    weight = np.concatenate(nodes_w) * np.abs(2.0 * span[node_piece] * t) * wavelength / omega
    node_line = piece_line[node_piece]
    value = _line_reflectance(lines, omega, node_line, np.concatenate(nodes_kind))
    xyz = _cmf_weighted_sums(wavelength, value * weight, node_line, n_lines)
    # Gaps beyond their exact part and the sharp dips' "1" reflect 1: the CMFs' integral in closed form.
    ones = cut < 1.0
    ones_piece.append(gap[ones])
    ones_lo.append(np.clip(cut[ones], t0[gap[ones]], t1[gap[ones]]))
    ones_hi.append(t1[gap[ones]])
    pieces, t_a, t_b = np.concatenate(ones_piece), np.concatenate(ones_lo), np.concatenate(ones_hi)
    if pieces.size:
        total = np.abs(_cmf_integral_to(2.0 * np.pi / omega_at(t_a, pieces)) - _cmf_integral_to(2.0 * np.pi / omega_at(t_b, pieces)))
        xyz += np.stack([np.bincount(piece_line[pieces], total[:, c], minlength=n_lines) for c in range(3)], axis=-1)
    return xyz


def _cmf_weighted_sums(wavelength: np.ndarray, value: np.ndarray, line: np.ndarray, n_lines: int) -> np.ndarray:
    """
    ``sum value * CMF(wavelength)`` per line, ``(n_lines, 3)``, with the CMFs interpolated linearly between their
    1-nm nodes (:func:`_cmf_linear`): each value split between its two nodes (two bincounts), then one product
    with the nodes' CMFs, instead of three interpolations and three bincounts.
    """
    c, _ = _cmf_nodes()
    x = np.clip(wavelength - colorimetry.HAT_LOW, 0.0, c.shape[0] - 1.0)
    i = np.minimum(x.astype(np.int64), c.shape[0] - 2)
    f = x - i
    index = line * c.shape[0] + i
    size = n_lines * c.shape[0]
    bins = np.bincount(index, value * (1.0 - f), minlength=size) + np.bincount(index + 1, value * f, minlength=size)
    return bins.reshape(n_lines, c.shape[0]) @ c


#: Nodes per block of :func:`_line_reflectance`: its ~20 temporaries stay in cache (2.5x faster than whole arrays
#: of ~1e5 nodes, measured).
NODE_BLOCK = 16384


def _line_reflectance(lines: _Lines, omega, line, kind) -> np.ndarray:
    """At each node by ``kind`` (:func:`_line_reflectance_block`), by blocks of :data:`NODE_BLOCK` nodes."""
    if omega.size <= NODE_BLOCK:
        return _line_reflectance_block(lines, omega, line, kind)
    out = np.empty(omega.shape)
    for start in range(0, omega.size, NODE_BLOCK):
        at = slice(start, start + NODE_BLOCK)
        out[at] = _line_reflectance_block(lines, omega[at], line[at], kind[at])
    return out


def _line_reflectance_block(lines: _Lines, omega, line, kind) -> np.ndarray:
    """
    At each node by ``kind``: 0, Yeh's R; 1, its fringe average; 2, 1; 3, R - 1. Real arithmetic (Eqs. 2, 8-10;
    ``|r1|^2 : |t1|^2 = 4 r12^2 sin^2 phi : (1 - r12^2)^2``, as :func:`_reflectance_real`). In a pass band Eq. 2 is
    written ``R = |r1|^2 sin^2 N u / (|r1|^2 sin^2 N u + |t1|^2 sin^2 u)``, finite at its transmission dips; in a gap
    with Eq. 9's scaled sinh ratio (:func:`chebyshev_U`).
    """
    out = np.ones(omega.shape)
    rows = np.flatnonzero(kind != 2)
    omega, line, kind = omega[rows], line[rows], kind[rows]
    # Eq. 8 from the layers' own phases (psi = omega p1, phi = omega p2; alpha - beta = Omega / 2): two sines and
    # cosines per node, sin phi among them.
    p2 = lines.p2[line]
    cos_psi, sin_psi = _cos_sin(omega * (lines.n_plus[line] - p2))
    cos_phi, sin_phi = _cos_sin(omega * p2)
    a = cos_psi * cos_phi - (lines.alpha[line] - lines.beta[line]) * (sin_psi * sin_phi)
    r12_2 = lines.r12_2[line]
    r1_2 = (4.0 * r12_2) * (sin_phi * sin_phi)
    t1_2 = (1.0 - r12_2) ** 2
    sin2_u = np.maximum(1.0 - a * a, 0.0)
    value = np.empty(omega.shape)
    N = float(lines.N)
    exact = kind != 1
    band = np.flatnonzero(exact & (np.abs(a) < 1.0))
    gap = np.flatnonzero(exact & (np.abs(a) >= 1.0))
    mean = np.flatnonzero(~exact)
    if lines.r_h1 is not None:
        out[rows] = _host_line_reflectance(lines, line, kind, a, sin2_u, cos_psi, sin_psi, cos_phi, sin_phi)
        return out
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        # Pass band: the deficit 1 - R = |t1|^2 sin^2 u / (|r1|^2 sin^2 N u + |t1|^2 sin^2 u).
        sin_Nu = _cos_sin(N * np.arccos(a[band]))[1]
        t_sin = t1_2[band] * sin2_u[band]
        deficit_band = t_sin / (r1_2[band] * sin_Nu * sin_Nu + t_sin)
        # Gap: Q = (sinh Im[K] Lambda / sinh N Im[K] Lambda)^2, scaled as chebyshev_U.
        xg = np.maximum(np.arccosh(np.abs(a[gap])), 1e-12)
        Q = (np.exp(-(N - 1.0) * xg) * _one_minus_exp_minus_2x(xg) / _one_minus_exp_minus_2x(N * xg)) ** 2
        deficit_gap = t1_2[gap] * Q / (r1_2[gap] + t1_2[gap] * Q)
        for where, deficit in ((band, deficit_band), (gap, deficit_gap)):
            value[where] = np.where(kind[where] == 3, -deficit, 1.0 - deficit)
        t_sin = t1_2[mean] * sin2_u[mean]
        denominator = r1_2[mean] + t_sin
        value[mean] = 1.0 - np.sqrt(np.where(denominator > 0.0, t_sin / denominator, 1.0))
    out[rows] = value
    return out


def _host_slab(lines: _Lines, line, cos_psi, sin_psi, cos_phi, sin_phi) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 10's ``r1 = r12 (1 - e^{2i phi}) / (1 - r12^2 e^{2i phi})`` and ``t_cell = t1 e^{i psi}`` (Appendix D)."""
    r12 = lines.r12[line]
    r12_2 = r12 * r12
    e_phi = cos_phi + 1j * sin_phi
    e_2phi = e_phi * e_phi
    inverse = 1.0 / (1.0 - r12_2 * e_2phi)
    return r12 * (1.0 - e_2phi) * inverse, (1.0 - r12_2) * e_phi * inverse * (cos_psi + 1j * sin_psi)


def _host_dip(lines: _Lines, omega, line) -> tuple[np.ndarray, np.ndarray]:
    """
    Where the transmission peaks of a mirror under a host lie and how sharp they are, in a pass band: with
    ``z = -S / B = p + i q`` (:func:`_host_line_reflectance`), ``1 - |r_hN|^2 = (1 - R_h1) / D(psi)``,
    ``D = (cos psi - p sin psi)^2 + q^2 sin^2 psi``, ``psi = N K Lambda``: a quadratic form in ``(cos psi, sin psi)``,
    smallest at ``psi0 = atan2(2p, p^2 + q^2 - 1) / 2`` (mod pi), with eigenvalues ``l1 l2 = q^2``,
    ``l1 + l2 = 1 + p^2 + q^2``. So ``D = l1 (1 + (k^2 - 1) sin^2(psi - psi0))`` with ``k = l2 / q``: the mirror's
    dip shape (``psi0 = 0``, ``k = sqrt(1 + F)`` without a host), shifted by ``psi0``.

    Returns
    -------
    psi0, k : ndarray
    """
    p2 = lines.p2[line]
    cos_psi, sin_psi = _cos_sin(omega * (lines.n_plus[line] - p2))
    cos_phi, sin_phi = _cos_sin(omega * p2)
    a = cos_psi * cos_phi - (lines.alpha[line] - lines.beta[line]) * (sin_psi * sin_phi)
    r1, t_cell = _host_slab(lines, line, cos_psi, sin_psi, cos_phi, sin_phi)
    B = np.sqrt(np.maximum(1.0 - a * a, 0.0)) * t_cell
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        z = -(1.0 - a * t_cell + lines.r_h1[line] * r1) / B
        p, q = np.real(z), np.abs(np.imag(z))
        s = 1.0 + p * p + q * q
        k = 0.5 * (s + np.sqrt(np.maximum(s * s - 4.0 * q * q, 0.0))) / q
        psi0 = 0.5 * np.arctan2(2.0 * p, p * p + q * q - 1.0)
    # At a band edge (B = 0) the peaks are the edge's own: no shift, and sharp.
    finite = np.isfinite(psi0) & np.isfinite(k)
    return np.where(finite, psi0, 0.0), np.where(finite, k, 1e300)


def _host_line_reflectance(lines: _Lines, line, kind, a, sin2_u, cos_psi, sin_psi, cos_phi, sin_phi) -> np.ndarray:
    """
    :func:`_line_reflectance_block`'s values under a host ``nh != n1`` (every wave propagating, so ``r12`` and ``r_h1``
    real): ``|r_hN|^2`` (Appendix D), the same ``r_hN = (r_N + r_h1) / (1 + r_h1 r_N)`` as :func:`reference_rgb`'s.
    With ``r_N = num / den``: in a pass band ``num = r1 sin N u``, ``den = A sin N u + B cos N u`` (``A = 1 - a t_cell``,
    ``B = sin u t_cell``, ``t_cell = t1 e^{i psi}``: Appendix D's ``r1 U_{N-1} / (U_{N-1} - U_{N-2} t_cell)`` times
    ``sin u``, finite at dips and edges); in a gap Eq. 9's scaled Chebyshev values (:func:`chebyshev_U`). The fringe
    average (kind 1) is :func:`fringe_average_under_host`'s for a lossless cell: with ``r_hN = (P + Q x) / (S + T x)``,
    ``x = cot N u``, ``1 - |r_hN|^2 = (1 - R_h1)(1 + x^2) / |x - z|^2``, ``z = -S / T``, whose Cauchy average over
    a fringe is ``(1 - R_h1) / |Im z|``: ``Rbar = 1 - (1 - R_h1) |B|^2 / |Im(S B*)|``, ``S = A + r_h1 r1``.
    A gap that reflects 1 still does under the (lossless) host interface: kind 2 stays 1, kind 3 is ``R - 1``.
    """
    r_h1 = lines.r_h1[line]
    r1, t_cell = _host_slab(lines, line, cos_psi, sin_psi, cos_phi, sin_phi)
    N = float(lines.N)
    A, B = 1.0 - a * t_cell, np.sqrt(sin2_u) * t_cell
    value = np.empty(a.shape)
    exact = kind != 1
    band = np.flatnonzero(exact & (np.abs(a) < 1.0))
    gap = np.flatnonzero(exact & (np.abs(a) >= 1.0))
    mean = np.flatnonzero(~exact)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        cos_Nu, sin_Nu = _cos_sin(N * np.arccos(a[band]))
        _, U_N2, _ = chebyshev_U(a[gap], N)  # U_{N-2} / U_{N-1}, scaled in the gap
        for where, num, den in ((band, r1[band] * sin_Nu, A[band] * sin_Nu + B[band] * cos_Nu),
                                (gap, r1[gap], 1.0 - U_N2 * t_cell[gap])):
            value[where] = np.abs(num + r_h1[where] * den) ** 2 / np.abs(den + r_h1[where] * num) ** 2
        B_m, r_h1_m = B[mean], r_h1[mean]
        im = np.abs(np.imag((A[mean] + r_h1_m * r1[mean]) * np.conj(B_m)))
        value[mean] = 1.0 - (1.0 - r_h1_m * r_h1_m) * np.abs(B_m) ** 2 / np.maximum(im, 1e-300)
    return np.where(kind == 3, value - 1.0, value)


#: Below this many cells the pieces integrate Yeh's R throughout (the fringe average's far harmonics still count).
PIECES_EXACT_N = 64
#: From this many cells the table's colours come from the band pieces. Below it the windowed rule costs less (its
#: integrand is Yeh's R itself up to N = 4 EDGE_FRINGES, and where fringes are wide: WINDOW_EXACT_SUBSTEPS); from
#: N ~ 64 the pieces do (default mirror, 65 angles: 19 against 30 ms at N = 100), whose cost stops growing.
PIECES_MIN_N = 64
#: ... under a host nh != n1, where the windowed rule's complex arithmetic costs 2-3.5x more than the pieces already at
#: N = 1-20 (n1 = 1.33, n2 = 1.8, nh = 1: 49 against 14 ms CPU at N = 1, 82 against 39 at N = 20; docs/performance.md).
PIECES_MIN_N_HOST = 1


def band_pieces_rgb(cos_theta: ArrayLike, mirror: BraggMirror, scale: int = 1) -> np.ndarray:
    """
    Linear sRGB of the converged spectral reference (:func:`reference_rgb` without a step) by Gauss quadrature
    over band pieces (the section's comment), for angles where every wave propagates (under a host ``nh != n1`` too:
    Appendix D's ``|r_hN|^2`` at the nodes, :func:`_host_line_reflectance`).

    Parameters
    ----------
    cos_theta : array_like
    mirror : BraggMirror
    scale : int
        Multiplies every panel's node count (convergence studies).

    Returns
    -------
    ndarray, shape ``(cos_theta.size, 3)``

    References
    ----------
    Fourneau et al. (2024), Section 3.1 (Eqs. 2, 8-10), Appendix A; Yeh (1988), Chapter 6.
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64).ravel()
    geometries = [cell_geometry(cos_theta, mirror, pol) for pol in POLARISATIONS]
    first = geometries[0]
    if not ((first.cos_theta_1.imag == 0).all() and (first.cos_theta_2.imag == 0).all()):
        raise ValueError("band_pieces_rgb: real angles only (no evanescent layer, no total reflection at the host)")
    p1 = np.concatenate([g.p1.real for g in geometries])
    p2 = np.concatenate([g.p2.real for g in geometries])
    Omega_ = np.concatenate([g.Omega.real for g in geometries])
    r12 = np.concatenate([g.r12.real for g in geometries])
    # Under a host (Appendix D) the nodes take |r_hN|^2; r_h1 is real where the wave in n1 propagates.
    r_h1 = None if first.host_is_n1 else np.concatenate([np.broadcast_to(g.r_h1.real, g.p1.shape) for g in geometries])
    lines = _Lines(p1 + p2, p1 - p2, 0.5 + 0.25 * Omega_, 0.5 - 0.25 * Omega_, p2, r12 * r12, int(mirror.N),
                   r12=r12, r_h1=r_h1)
    exact_everywhere = mirror.N < PIECES_EXACT_N or BAND_EDGE_FRINGES * np.pi / mirror.N >= 0.5 * np.pi
    xyz = _pieces_xyz(lines, exact_everywhere, scale)
    xyz = 0.5 * (xyz[: cos_theta.size] + xyz[cos_theta.size :])
    return colorimetry.xyz_to_rgb(xyz)


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
    """The converged colours (:func:`_converged_rgb`) of the mirror at texture value ``T``, at ``cos_theta``."""
    m = textured_mirror(mirror, T, mapping)
    return _converged_rgb(cos_theta, BraggMirror(mirror.n1, mirror.n2, float(m.Lambda), float(m.delta), mirror.N, mirror.nh))


@functools.lru_cache(maxsize=8)
def textured_rgb_table(mirror: BraggMirror, mapping: str, rows: int = TEXTURE_TABLE_ROWS,
                       columns: int = TEXTURE_TABLE_COLUMNS, max_rows: int = TEXTURE_TABLE_MAX_ROWS,
                       budget: int = TEXTURE_TABLE_BUDGET) -> np.ndarray:
    """
    The tabulated method's table of a textured mirror, ``(R, columns, 3)`` float32: the converged reference
    (:func:`_converged_rgb`, as :func:`tabulated_rgb_table`) at ``T = k / (R - 1)`` and ``cos theta = i /
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
        table = np.broadcast_to(_converged_rgb(cos_theta, mirror)[None], (2, columns, 3))
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
