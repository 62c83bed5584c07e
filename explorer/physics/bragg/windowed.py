"""
The converged table's integrand (ours): the fringe average plus the fringes near band edges, at a cost that does not
grow with ``N`` (:func:`windowed_converged_spectra`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.physics.bragg.approximation import fringe_average_under_host
from explorer.physics.bragg.mirror import BraggMirror, CellGeometry
from explorer.physics.bragg.reference import _row_spectrum_function, _spectrum_function, substeps_for
from explorer.physics.bragg.reflectance import (
    FLOAT32_MAX_N,
    airy_slab_coefficients,
    chebyshev_U,
    cos_K_Lambda,
    reflectance_yeh,
    reflection_coefficient_host,
)

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
