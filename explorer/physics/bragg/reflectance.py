"""
Yeh's closed-form reflectance of a Bragg mirror (Section 3.1, Eqs. 2, 8-10, Appendix D): the exact complex path and
the real fast path over many angles and wavelengths (:func:`reflectance_spectra`). Numpy only; GLSL twins of the same
names in ``shaders/lib/bragg.glsl``. Yeh (1988), Optical Waves in Layered Media, Chapter 6.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.physics.bragg.mirror import POLARISATIONS, BraggMirror, CellGeometry, cell_geometry

# --------------------------------------------------------------------------------------------------
# Yeh's reflectance (Section 3.1)


def airy_slab_coefficients(omega: ArrayLike, geometry: CellGeometry) -> tuple[np.ndarray, np.ndarray]:
    """
    Reflection and transmission coefficients ``(r1, t1)`` of one slab of ``n2`` in ``n1`` (Eq. 10).

    ``r1 = r12 (1 - e^{2i phi}) / (1 - r12^2 e^{2i phi})`` with ``phi = k_2z d2``, and
    ``t1 = (1 - r12^2) e^{i phi} / (1 - r12^2 e^{2i phi})`` (as ``t12 t21 = 1 - r12^2``).
    """
    return slab_coefficients(geometry.r12, np.exp(1j * omega * geometry.p2))


def slab_coefficients(r12: ArrayLike, phase: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """
    :func:`airy_slab_coefficients` from the interface's ``r12`` and the slab's ``phase = e^{i phi}`` (numpy only: the
    batched model's phases have their decay capped, :mod:`explorer.physics.bragg.batch`).
    """
    phase2 = phase * phase
    r12_2 = r12 * r12
    denominator = 1.0 - r12_2 * phase2
    return r12 * (1.0 - phase2) / denominator, (1.0 - r12_2) * phase / denominator


def cos_K_Lambda(omega: ArrayLike, geometry: CellGeometry) -> np.ndarray:
    """
    The dispersion relation (Eq. 8): ``cos k1z d1 cos k2z d2 - Omega/2 sin k1z d1 sin k2z d2``.

    Real for real indices, also when a layer is evanescent; ``|cos K Lambda| > 1`` in band gaps.
    """
    psi = clamp_decay(omega * geometry.p1)
    phi = clamp_decay(omega * geometry.p2)
    value = np.cos(psi) * np.cos(phi) - 0.5 * geometry.Omega * np.sin(psi) * np.sin(phi)
    return np.real(value)


#: Evanescent phases are clamped here: cosh(40)^2 stays finite in float32, and a layer that damps a
#: wave by e^-40 is already opaque (|cos K Lambda| ~ 1e34 means R = 1 to float precision).
MAX_DECAY = 40.0


def clamp_decay(phase: ArrayLike) -> np.ndarray:
    """A complex phase with its decay (imaginary part) capped at :data:`MAX_DECAY`: evanescent layers stay finite."""
    return np.real(phase) + 1j * np.minimum(np.imag(phase), MAX_DECAY)


def one_minus_exp_minus_2x(x: ArrayLike) -> np.ndarray:
    """``1 - exp(-2x)`` without cancellation near band edges (small ``x``)."""
    return -np.expm1(-2.0 * x)


def chebyshev_U(cos_K_Lambda: ArrayLike, N: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Chebyshev polynomials ``(U_{N-1}, U_{N-2})`` of ``cos K Lambda``, scaled to stay finite.

    ``U_{N-1}(cos K Lambda) = sin(N K Lambda) / sin(K Lambda)``: Yeh's ``[M]^N = U_{N-1} M - U_{N-2} I``
    (Appendix D). In a band gap they grow like ``exp(N Im[K] Lambda)`` and overflow for large ``N``, so
    both are returned divided by ``U_{N-1}`` there, with that scale; elsewhere the scale is 1. Band
    edges (``sin K Lambda -> 0``) take the limits ``U_{N-1} -> N``, ``U_{N-2} -> N - 1`` without 0/0. ``N`` may be
    an array broadcast against ``cos_K_Lambda``, and real: ``sin(N t) / sin t`` continues the polynomials to
    non-integer cell counts (the design's continuous search).

    Returns
    -------
    U_N1, U_N2, scale : ndarray
        ``scale * U_{N-1}(a) == U_N1`` and ``scale * U_{N-2}(a) == U_N2``.
    """
    a = np.asarray(cos_K_Lambda, dtype=np.float64)
    N = np.asarray(N, dtype=np.float64)
    in_band = np.abs(a) < 1.0
    # Pass band: K Lambda = t real in (0, pi).
    t = np.arccos(np.clip(a, -1.0, 1.0))
    sin_t = np.sin(t)
    safe_sin_t = np.where(in_band, sin_t, 1.0)
    U_N1_band = np.sin(N * t) / safe_sin_t
    U_N2_band = np.sin((N - 1.0) * t) / safe_sin_t
    # Band gap (Eq. 9): K Lambda = m pi + i x with x = Im[K] Lambda = acosh|a|; U_n(-b) = (-1)^n U_n(b).
    x = np.maximum(np.arccosh(np.maximum(np.abs(a), 1.0)), 1e-12)
    ratio_N2 = np.exp(-x) * one_minus_exp_minus_2x((N - 1.0) * x) / one_minus_exp_minus_2x(N * x)
    scale_gap = np.exp(-(N - 1.0) * x) * one_minus_exp_minus_2x(x) / one_minus_exp_minus_2x(N * x)
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


def _take(geometry: CellGeometry, rows) -> CellGeometry:
    """The geometry at some of its angles (``rows`` may repeat), with a trailing axis (:func:`_rows`)."""
    fields = {k: (v[rows][:, None] if isinstance(v, np.ndarray) else v) for k, v in vars(geometry).items()}
    return CellGeometry(**fields)


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
    first = geometries[0]
    counts = np.asarray(first.N)  # one count, or one per row (many mirrors' rows: :func:`reference_rgb_many`)
    f32 = np.float32 if np.max(counts) <= FLOAT32_MAX_N and not float64 else np.float64
    omega = omega.astype(f32)
    psi = omega * first.p1.real[rows, None].astype(f32)
    phi = omega * first.p2.real[rows, None].astype(f32)
    cos_psi, sin_psi, cos_phi, sin_phi = np.cos(psi), np.sin(psi), np.cos(phi), np.sin(phi)
    cos_cos, sin_sin, sin2_phi = cos_psi * cos_phi, sin_psi * sin_phi, f32(4.0) * sin_phi * sin_phi
    N = counts[rows, None].astype(f32) if counts.ndim else f32(first.N)
    total = np.zeros_like(psi)
    # Rows where both polarisations' terms agree (normal incidence) take one pass, counted twice.
    terms = [(g.r12.real[rows, None] ** 2, 0.5 * g.Omega.real[rows, None]) for g in geometries]
    twice = np.zeros(np.shape(rows), bool)
    if len(terms) == 2:
        twice = np.ravel(same_polarisations(terms[0][0], terms[1][0], terms[0][1], terms[1][1]))
    for k, geometry in enumerate(geometries):
        if k and twice.all():
            break
        r12_2, half_omega = terms[k]
        r12_2 = r12_2.astype(f32)
        a = cos_cos - half_omega.astype(f32) * sin_sin
        r1_2 = r12_2 * sin2_phi
        t1_2 = (f32(1.0) - r12_2) ** 2
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            a_band = np.clip(a, f32(-1.0), f32(1.0))
            Q = (f32(1.0) - a_band * a_band) / np.sin(N * np.arccos(a_band)) ** 2
            gap = np.abs(a) >= f32(1.0)
            if gap.any():  # Eq. 9's ratio, only in the gaps (a minority of samples)
                abs_a = np.abs(a[gap])
                N_gap = np.broadcast_to(N, a.shape)[gap]
                x = np.maximum(np.log(abs_a + np.sqrt(abs_a * abs_a - f32(1.0))), f32(1e-12))  # acosh|a|
                h = lambda y: -np.expm1(f32(-2.0) * y)  # noqa: E731
                Q[gap] = (np.exp(-(N_gap - f32(1.0)) * x) * h(x) / h(N_gap * x)) ** 2
            R = r1_2 / (r1_2 + t1_2 * Q)
        if k == 0:
            total += R * np.where(twice, f32(2.0), f32(1.0))[:, None].astype(f32)
        else:
            total += np.where(twice[:, None], f32(0.0), R)
    return f32(0.5) * total


def same_polarisations(r12_2_s: np.ndarray, r12_2_p: np.ndarray, half_omega_s: np.ndarray, half_omega_p: np.ndarray) -> np.ndarray:
    """Where both polarisations' ``r12^2`` and ``Omega`` agree (to rounding: normal incidence), elementwise."""
    return (np.abs(r12_2_s - r12_2_p) <= 1e-14 * np.abs(r12_2_p)) & (np.abs(half_omega_s - half_omega_p) <= 1e-14 * np.abs(half_omega_p))


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


def _rows(geometry: CellGeometry) -> CellGeometry:
    """The geometry with a trailing axis, to broadcast angles against wavelengths."""
    fields = {k: (v[:, None] if isinstance(v, np.ndarray) else v) for k, v in vars(geometry).items()}
    return CellGeometry(**fields)
