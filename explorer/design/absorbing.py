"""
The batch model's reflectance with complex indices (a medium's ``n + i k`` per wavelength, or a constant): the
characteristic-matrix form of :func:`explorer.design.forward.bragg_reflectance_batch` (Yeh's
``[M]^N = U_{N-1} M - U_{N-2} I``, Appendix D) holds at each wavelength with complex indices, where ``cos K Lambda``
is complex, and so is ``K Lambda = t``. With ``Im t >= 0`` and ``z = e^{i t}`` (``|z| <= 1``),
``z^{N-1} (1 - z^2) U_{N-1} = 1 - z^{2N}`` and ``z^{N-1} (1 - z^2) U_{N-2} = z (1 - z^{2N-2})``: ``r_N`` is a
ratio of these, finite for any (real) ``N``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import bragg, multilayer

#: Below this ``|1 - z^2|`` the band edge's limits ``U_{N-1} -> N``, ``U_{N-2} -> N - 1`` (times ``z^{N-1}``).
EDGE = 1e-9


@dataclass
class _Geometry:
    """What :func:`explorer.physics.bragg.fringe_average_under_host` reads of a cell."""

    p1: np.ndarray
    r_h1: np.ndarray


def _col(v) -> np.ndarray:
    a = np.asarray(v)
    return a.reshape(-1, 1, 1) if a.ndim <= 1 else a


def absorbing_reflectance_batch(n1, n2, Lambda, delta, N, nh, cos_theta: ArrayLike, wavelengths: ArrayLike,
                                step: float | None = None, smooth: float | None = None) -> np.ndarray:
    """
    :func:`explorer.design.forward.bragg_reflectance_batch` with complex indices ``n1``, ``n2`` (``(B,)`` or
    ``(B, 1, W)``) under a lossless host ``nh`` (``nh < 1``: ``Re n1``, as :class:`explorer.physics.natural.NaturalMirror`).
    At point samples (``step`` None, or fringes wide against it) it is the exact unpolarised reflectance of
    :func:`explorer.physics.natural.mirror_spectrum` (tested to 1e-9). Fringes narrower than a few steps are blended
    into :func:`explorer.physics.bragg.fringe_average_under_host` taken at ``Re cos K Lambda`` (the screening's
    approximation), less so where absorption damps them (visibility ``exp(-2 N Im K Lambda)``).
    """
    n1, n2 = _col(n1).astype(np.complex128), _col(n2).astype(np.complex128)
    Lambda, delta, N = (_col(np.asarray(v, dtype=np.float64)) for v in (Lambda, delta, N))
    nh = np.real(_col(nh)).astype(np.float64)
    eta_h = np.where(nh >= 1.0, nh, np.real(n1))
    cos_h = np.maximum(np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1), bragg.COS_THETA_MIN)
    wavelengths = np.asarray(wavelengths, dtype=np.float64).reshape(1, 1, -1)
    omega = 2.0 * np.pi / wavelengths
    n_sin = eta_h * np.sqrt(1.0 - cos_h * cos_h)
    kz_h = (eta_h * cos_h).astype(np.complex128)
    kz1, kz2 = multilayer.forward_kz(n1, n_sin), multilayer.forward_kz(n2, n_sin)
    p1, p2 = kz1 * delta * Lambda, kz2 * (1.0 - delta) * Lambda
    psi, phi = bragg.clamp_decay(omega * p1), bragg.clamp_decay(omega * p2)
    e_psi, e_phi = np.exp(1j * psi), np.exp(1j * phi)
    cos_psi, sin_psi = (e_psi + 1.0 / e_psi) / 2.0, (e_psi - 1.0 / e_psi) / 2j
    cos_phi, sin_phi = (e_phi + 1.0 / e_phi) / 2.0, (e_phi - 1.0 / e_phi) / 2j
    shape = np.broadcast_shapes(kz1.shape, kz2.shape, wavelengths.shape, N.shape, Lambda.shape)
    if step is None:
        w_point = np.ones(shape)
    else:
        path = np.maximum(np.real(p1) + np.real(p2), 1e-9)
        fringe = wavelengths**2 / (2.0 * N * path)
        w_point = np.broadcast_to(np.clip((fringe / (step if smooth is None else smooth) - 1.0) / 3.0, 0.0, 1.0), shape)
    total = 0.0
    for pol in bragg.POLARISATIONS:
        r12, _ = multilayer.interface(pol, n1, kz1, n2, kz2)
        r_h1, _ = multilayer.interface(pol, eta_h.astype(np.complex128), kz_h, n1, kz1)
        x = kz2 / kz1 if pol == "s" else (n1 * n1 * kz2) / (n2 * n2 * kz1)
        x = np.where(np.abs(x) < 1e-10, 1e-10, x)
        a = cos_psi * cos_phi - 0.5 * (x + 1.0 / x) * sin_psi * sin_phi  # Eq. 8, complex
        phase2 = e_phi * e_phi
        denominator = 1.0 - r12 * r12 * phase2
        r1 = r12 * (1.0 - phase2) / denominator
        t1 = (1.0 - r12 * r12) * e_phi / denominator
        # Below the gap at K Lambda ~ pi, U_n(-b) = (-1)^n U_n(b): the ratio U_{N-2} / U_{N-1} of -a, negated,
        # continues the count N as the real model does (chebyshev_U's gap: no phase e^{2 pi i N} between counts).
        flip = np.real(a) < -1.0
        t = np.arccos(np.where(flip, -a, a).astype(np.complex128))
        t = np.where(np.imag(t) < 0.0, -t, t)  # U_n(cos t) is even in t: the decaying branch
        z = np.exp(1j * t)
        one_z2 = 1.0 - z * z
        edge = np.abs(one_z2) < EDGE
        safe = np.where(edge, 1.0, one_z2)
        W1 = np.where(edge, N, (1.0 - np.exp(2j * N * t)) / safe)
        W2 = np.where(edge, z * (N - 1.0), z * (1.0 - np.exp(2j * (N - 1.0) * t)) / safe)
        W2 = np.where(flip, -W2, W2)
        r_N = r1 * W1 / (W1 - W2 * t1 * e_psi)
        R = np.abs(bragg.reflection_coefficient_host(r_N, r_h1)) ** 2
        if step is not None and np.any(w_point < 1.0):
            average = bragg.fringe_average_under_host(r1, t1, omega, _Geometry(p1, r_h1), np.real(a))
            w = 1.0 - (1.0 - w_point) * np.exp(-2.0 * N * np.imag(t))
            R = w * R + (1.0 - w) * average
        total = total + R
    return np.clip(total / 2.0, 0.0, 1.0)
