"""
Fresnel equations for smooth dielectric interfaces, with Snell's law and total internal reflection.

Conventions (those of the transfer-matrix literature and of the ``tmm`` package): a wave travels as
``exp(+i k_z z)``, so the cosine of a refraction angle is the complex square root with a
non-negative imaginary part; beyond the critical angle it is purely imaginary and the wave decays
(total internal reflection). Every function is vectorised over its arguments by numpy broadcasting.

References
----------
Born and Wolf, Principles of Optics, Section 1.5. Yeh (1988), Optical Waves in Layered Media, Ch. 3.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def cos_theta_transmitted(cos_theta_i: ArrayLike, eta_i: ArrayLike, eta_t: ArrayLike) -> np.ndarray:
    """
    Cosine of the refraction angle by Snell's law, ``eta_i sin(theta_i) = eta_t sin(theta_t)``.

    Returns a complex array: real below the critical angle, purely imaginary (with a positive
    imaginary part) under total internal reflection.
    """
    cos_theta_i = np.asarray(cos_theta_i, dtype=np.float64)
    sin2_theta_t = (np.asarray(eta_i) / np.asarray(eta_t)) ** 2 * (1.0 - cos_theta_i**2)
    cos2_theta_t = (1.0 - sin2_theta_t).astype(np.complex128)
    cos_t = np.sqrt(cos2_theta_t)
    # numpy's principal root already has Im >= 0 for a negative real argument; keep the sign explicit.
    return np.where(cos_t.imag < 0, -cos_t, cos_t)


def is_total_internal_reflection(cos_theta_i: ArrayLike, eta_i: ArrayLike, eta_t: ArrayLike) -> np.ndarray:
    """True where a wave from ``eta_i`` is totally reflected at an interface with ``eta_t``."""
    cos_theta_i = np.asarray(cos_theta_i, dtype=np.float64)
    return (np.asarray(eta_i) / np.asarray(eta_t)) ** 2 * (1.0 - cos_theta_i**2) > 1.0


def fresnel_r_s(eta_i: ArrayLike, cos_theta_i: ArrayLike, eta_t: ArrayLike, cos_theta_t: ArrayLike) -> np.ndarray:
    """Amplitude reflection coefficient for 's' (TE) polarisation."""
    a, b = eta_i * cos_theta_i, eta_t * cos_theta_t
    return (a - b) / (a + b)


def fresnel_r_p(eta_i: ArrayLike, cos_theta_i: ArrayLike, eta_t: ArrayLike, cos_theta_t: ArrayLike) -> np.ndarray:
    """Amplitude reflection coefficient for 'p' (TM) polarisation (the ``tmm`` sign convention)."""
    a, b = eta_t * cos_theta_i, eta_i * cos_theta_t
    return (a - b) / (a + b)


def fresnel_r(polarisation: str, eta_i: ArrayLike, cos_theta_i: ArrayLike, eta_t: ArrayLike, cos_theta_t: ArrayLike) -> np.ndarray:
    """Amplitude reflection coefficient, ``polarisation`` in ``{'s', 'p'}``."""
    if polarisation == "s":
        return fresnel_r_s(eta_i, cos_theta_i, eta_t, cos_theta_t)
    if polarisation == "p":
        return fresnel_r_p(eta_i, cos_theta_i, eta_t, cos_theta_t)
    raise ValueError(f"polarisation must be 's' or 'p', not {polarisation!r}")


def fresnel_reflectance(cos_theta_i: ArrayLike, eta_i: ArrayLike, eta_t: ArrayLike) -> np.ndarray:
    """Unpolarised Fresnel reflectance of a smooth dielectric interface (the average of s and p)."""
    cos_theta_t = cos_theta_transmitted(cos_theta_i, eta_i, eta_t)
    r_s = fresnel_r_s(eta_i, cos_theta_i, eta_t, cos_theta_t)
    r_p = fresnel_r_p(eta_i, cos_theta_i, eta_t, cos_theta_t)
    return 0.5 * (np.abs(r_s) ** 2 + np.abs(r_p) ** 2)


def fresnel_schlick(cos_theta_i: ArrayLike, F0: ArrayLike) -> np.ndarray:
    """Schlick's approximation ``F0 + (1 - F0)(1 - cos)^5``; the cheapest reflectance a shader has."""
    return F0 + (1.0 - F0) * (1.0 - np.asarray(cos_theta_i)) ** 5
