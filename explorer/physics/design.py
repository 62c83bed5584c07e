"""
Inverse design of Bragg mirrors and thin films: from the colours wanted at a few angles to the structure
that makes them, or the structure that comes closest when none does.

The forward model is the converged spectral colour of the smooth structure at each target angle (what the
tabulated method shows, :func:`explorer.physics.bragg.reference_rgb`,
:func:`explorer.physics.thinfilm.reference_rgb`). The search minimises the sum of the squared CIEDE2000
differences over the targets, in three stages:

1. a space-filling first pass: a scrambled Sobol sequence of shapes over the free parameters' box (``N`` on
   a log scale, continuous), each at every value of the length that scales it (:meth:`_Problem.scale_scan`:
   one spectrum per shape over ``s / lambda``, a correlation with the CMFs gives every scale); without a
   free scale, every candidate evaluated at once by a vectorised coarse model (:func:`bragg_rgb_batch`,
   :func:`thin_film_rgb_batch`: point samples every :data:`COARSE_STEP` nm);
   the best distinct shapes then walk downhill by the same scan, windowed around their period
   (:func:`_scan_descent`: a (1 + lambda) evolution whose moves shrink from 0.08 to 0.01 of the box);
2. local refinement (``scipy.optimize.least_squares``) of the best distinct candidates on the coarse model,
   with Jacobians by finite differences evaluated in one batch;
3. a polish of the best few on the converged model with ``N`` rounded to an integer.

With ``tries`` above 1, a design that leaves a target above :data:`REACHED_DELTA_E` searches again from a
fresh first pass with the best structure so far among its guesses (an iterated search with restarts).

Residuals are the CIELAB differences scaled per target by ``dE2000 / dE76``, so that their squared norm per
target is exactly CIEDE2000 squared while staying differentiable.

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. CGF 43(2): Eqs. 2, 8-10 (Yeh's reflectance), Appendix D (the host), Section 7 (inverse design
named as future work).
Belcour & Barla (2017). A Practical Extension to Microfacet Theory for the Modeling of Varying
Iridescence. ACM TOG 36(4): Eqs. 2-3 (the film's Airy reflectance).
Sharma, Wu, Dalal (2005). The CIEDE2000 colour-difference formula. Color Res. Appl. 30(1).
"""

from __future__ import annotations

import math
import os
import threading
import time
from dataclasses import dataclass, field, replace
from typing import Callable, Mapping, Sequence

import colour
import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import bragg, colorimetry, thinfilm
from explorer.physics.fresnel import cos_theta_transmitted, fresnel_r

#: A target whose CIEDE2000 stays above this is reported as not reachable (about twice a just
#: noticeable difference).
REACHABLE_DELTA_E = 2.0
#: Tries (``design(..., tries=K)``) stop once every target is within this CIEDE2000 (about a just
#: noticeable difference).
REACHED_DELTA_E = 1.0
#: Successive tries' seeds this far apart: each a fresh scrambled Sobol first pass.
TRY_SEED_STRIDE = 1000
#: The coarse model's wavelength step (nm): the spectrum at these nodes, interpolated linearly, against the
#: 1-nm CMFs.
COARSE_STEP = 2.0
#: The first pass's and the scan's wavelength step (nm): screening only, about 4 times cheaper.
SCREEN_STEP = 4.0
#: The screening averages out fringes narrower than about this (nm): their ripples make the landscape
#: rugged where the bands' positions, which it keeps, decide the basin.
SCREEN_SMOOTH = 12.0
#: Candidates of the first pass (a power of two: Sobol's balance).
FIRST_PASS_SAMPLES = 2048
#: The scan: this many scrambled-Sobol shapes, each at every value of the scale parameter (the period, the
#: film's thickness) on a geometric grid. A mirror's spectrum shifts by about lambda dLambda / Lambda when
#: Lambda moves: its colour turns as fast in log Lambda everywhere, by several CIEDE2000 per percent at
#: high orders (Lambda ~ 1 um), whose basins in Lambda are narrow. Half the 1024 of a scan without the
#: descent: its time goes to the descent, which finds more (round trip of 50, median of the medians
#: 0.83 -> 0.24, share within 1: 52 -> 64 %, in one run each).
SCAN_SHAPES = 512
#: The scan's spectra: samples at this relative step in s / lambda (3 nm at 600 nm), also its scales' step.
SCAN_RELATIVE_STEP = 0.005
#: The scan's spectra average out fringes narrower than about this share of the wavelength (two of its steps:
#: point samples would alias; measured: 0.93 -> 0.71 median of the round trip's medians against 0.004).
SCAN_SMOOTH = 0.01
#: The scan's CIEDE2000 is evaluated at this many scales per shape, those nearest in CIELAB.
SCAN_KEPT = 48
#: Shapes per batch of the scan (memory: shapes x angles x ~1800 samples x 3, complex).
SCAN_BATCH = 8
#: ... at spectra this long (samples of the full range of scales).
SCAN_BATCH_SAMPLES = 1000
#: CPU seconds the polish on the converged model may take (a mirror with N ~ 1000 costs ~0.1 s a colour).
#: CPU time, not wall time: a design's result must not depend on how busy the machine is.
POLISH_SECONDS = 1.5
#: The polish stops below this RMS CIEDE2000 per target (a hundredth of a just-noticeable difference).
POLISHED_ENOUGH = 0.01
#: Distinct starts refined on the coarse model, and of those, how many are polished on the converged one.
LOCAL_STARTS = 6
#: Evaluations of each coarse refinement.
REFINE_NFEV = 40
POLISHED = 2
#: Two starts closer than this in the unit box (max norm) are the same basin.
DISTINCT_STARTS = 0.08
#: Two polished candidates closer than this are the same one.
POLISH_DISTINCT = 0.01
#: Finite-difference step in the unit box for the coarse Jacobians (the model is smooth there), and the
#: converged model's (its adaptive refinement moves colours by up to ~2e-4: a larger step).
COARSE_DIFF_STEP = 1e-4
FINE_DIFF_STEP = 1e-3
#: The second scan: counts tried, perturbed shapes, their spread, and the starts refined from them.
SECOND_COUNTS = 48
SECOND_PERTURBED = 48
SECOND_SPREAD = 0.05
SECOND_STARTS = 3
#: Above this median CIEDE2000 the coarse stage has not found the basin: more starts are refined.
GOOD_ENOUGH = 0.05
#: Threads of the scans (:func:`_threaded_scan`): this machine's cores, at most 4.
SCAN_THREADS = max(1, min(4, os.cpu_count() or 1))
#: The scan's descent (:func:`_scan_descent`): starts, moves per step, their spreads in the unit box, and
#: the window of scales around each. Measured against 8 starts (0.35, 62 %), three spreads (0.54, 58 %),
#: six (0.30, 64 %, 15 % slower) and 40 moves (0.44, 58 %).
DESCENT_STARTS = 16
DESCENT_SAMPLES = 48
DESCENT_SIGMAS = (0.08, 0.04, 0.02, 0.01)
DESCENT_SPAN = 0.06
#: Candidates evaluated per batch of the coarse model (memory: rows x angles x wavelengths complex).
BATCH = 32


class DesignError(ValueError):
    """A design request that cannot be met: one line (a bad colour, an impossible fix)."""


class DesignCancelled(Exception):
    """The caller's ``cancelled()`` said stop."""


# --------------------------------------------------------------------------------------------------
# The design parameters


@dataclass(frozen=True)
class DesignParameter:
    """
    One structural parameter: its name in the material file, its box (the file's declared range unless
    the caller narrows it), and whether the search walks it on a log scale or rounds it to an integer.
    """

    name: str
    low: float
    high: float
    log: bool = False
    integer: bool = False

    def from_unit(self, u):
        u = np.clip(np.asarray(u, dtype=np.float64), 0.0, 1.0)
        if self.log:
            return np.exp(math.log(self.low) + u * (math.log(self.high) - math.log(self.low)))
        return self.low + u * (self.high - self.low)

    def whole(self, value):
        """``value`` at the nearest whole number in the box for an integer parameter, as it is otherwise."""
        return np.maximum(np.round(value), self.low) if self.integer else value

    def to_unit(self, value):
        value = np.asarray(value, dtype=np.float64)
        if self.high == self.low:
            return np.zeros_like(value)
        if self.log:
            return (np.log(value) - math.log(self.low)) / (math.log(self.high) - math.log(self.low))
        return (value - self.low) / (self.high - self.low)


@dataclass(frozen=True)
class DesignModel:
    """
    What can be designed of one material model: its structural parameters (the others, such as
    ``method`` or a roughness, do not change the specular colour), the coarse batch model and the
    converged one.
    """

    name: str
    parameters: tuple[str, ...]
    log_parameters: tuple[str, ...]
    integer_parameters: tuple[str, ...]
    #: ``batch(values: dict of (B,) arrays, cos_theta (A,)) -> (B, A, 3)`` linear RGB, coarse.
    batch: Callable
    #: ``converged(values: dict of floats, cos_theta (A,), final: bool) -> (A, 3)`` linear RGB.
    converged: Callable
    #: Parameters whose value below ``host_threshold`` means "no separate host" (a branch, not a slope).
    host_parameter: str | None = None
    host_threshold: float = 1.0
    #: The length that scales the structure (scanned on every value: :meth:`_Problem.scale_scan`).
    scale_parameter: str | None = None
    #: Search a mirror by its optical period and thickness share instead of ``Lambda`` and ``delta``.
    optical: bool = False
    #: ``spectra(values, cos_theta (A,), wavelengths (W,), smooth_relative) -> (B, A, W)`` for the scale scan.
    spectra: Callable | None = None


# --------------------------------------------------------------------------------------------------
# Forward models


def _interpolation_weights(step: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Nodes every ``step`` nm over the CMFs' range and the XYZ weights that integrate the spectrum's linear
    interpolant between them against the 1-nm CMFs: ``XYZ = R(nodes) @ weights``.
    """
    lo, hi = colorimetry.WAVELENGTH_MIN, colorimetry.WAVELENGTH_MAX
    return _interpolation_weights_at(np.linspace(lo, hi, int(math.ceil((hi - lo) / step)) + 1))


def _interpolation_weights_at(nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    :func:`_interpolation_weights` at ascending ``nodes`` (nm) that span the CMFs' range: the interpolant
    sampled every ``1 / K`` nm and integrated against the CMFs' hats as the converged colours are
    (:func:`explorer.physics.colorimetry.hat_average`), ``K`` the power of two that puts a sample in every
    node interval (``K = 1``, the 1-nm sum, for nodes 1 nm apart or more).
    """
    count = nodes.size
    K = 2 ** max(0, math.ceil(math.log2(1.0 / float(np.min(np.diff(nodes))))))
    fine = colorimetry.fine_wavelengths(K)
    position = np.interp(fine, nodes, np.arange(count))
    left = np.minimum(np.floor(position).astype(int), count - 2)
    frac = position - left
    interpolation = np.zeros((fine.size, count))
    interpolation[np.arange(fine.size), left] = 1.0 - frac
    interpolation[np.arange(fine.size), left + 1] += frac
    # Fortran order: at K = 1 the same product, bit for bit, as the 1-nm sum of the interpolant.
    return nodes, np.asfortranarray(colorimetry.hat_average(interpolation.T, K)) @ colorimetry.colour_matching_functions()


_WEIGHTS: dict[float, tuple[np.ndarray, np.ndarray]] = {}


def coarse_nodes(step: float = COARSE_STEP) -> tuple[np.ndarray, np.ndarray]:
    """Cached :func:`_interpolation_weights`."""
    if step not in _WEIGHTS:
        _WEIGHTS[step] = _interpolation_weights(step)
    return _WEIGHTS[step]


_LOG_WEIGHTS: dict[float, tuple[np.ndarray, np.ndarray]] = {}


def log_nodes(ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Wavelengths ``lambda_max r^-j`` (ascending) down to below ``lambda_min``, and the XYZ weights that
    integrate the spectrum's linear interpolant between them against the 1-nm CMFs (the scale scan's).
    """
    if ratio not in _LOG_WEIGHTS:
        lo, hi = colorimetry.WAVELENGTH_MIN, colorimetry.WAVELENGTH_MAX
        count = int(np.ceil(np.log(hi / lo) / np.log(ratio))) + 1
        _LOG_WEIGHTS[ratio] = _interpolation_weights_at(hi / ratio ** np.arange(count)[::-1])
    return _LOG_WEIGHTS[ratio]


def chebyshev_U_real_N(a: ArrayLike, N: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    :func:`explorer.physics.bragg.chebyshev_U` for a real (array) ``N``: ``sin(N t) / sin t`` continues the
    polynomials to non-integer cell counts, which lets the coarse search treat ``N`` as continuous.
    """
    in_band = np.abs(a) < 1.0
    t = np.arccos(np.clip(a, -1.0, 1.0))
    safe_sin_t = np.where(in_band, np.sin(t), 1.0)
    U_N1_band = np.sin(N * t) / safe_sin_t
    U_N2_band = np.sin((N - 1.0) * t) / safe_sin_t
    x = np.maximum(np.arccosh(np.maximum(np.abs(a), 1.0)), 1e-12)
    h = lambda y: -np.expm1(-2.0 * y)  # 1 - exp(-2y), as bragg._one_minus_exp_minus_2x
    ratio_N2 = np.exp(-x) * h((N - 1.0) * x) / h(N * x)
    scale_gap = np.exp(-(N - 1.0) * x) * h(x) / h(N * x)
    # Band edges: the limits N and N - 1 (sin t -> 0) without 0/0.
    edge = in_band & (np.abs(np.sin(t)) < 1e-9)
    U_N1 = np.where(in_band, np.where(edge, N, U_N1_band), 1.0)
    U_N2 = np.where(in_band, np.where(edge, N - 1.0, U_N2_band), np.sign(a) * ratio_N2)
    return U_N1, U_N2, np.where(in_band, 1.0, scale_gap)


def bragg_reflectance_batch(
    n1: ArrayLike, n2: ArrayLike, Lambda: ArrayLike, delta: ArrayLike, N: ArrayLike, nh: ArrayLike, cos_theta: ArrayLike,
    wavelengths: ArrayLike, step: float | None = None, smooth: float | None = None,
) -> np.ndarray:
    """
    Unpolarised ``R_lambda`` of many mirrors at once: parameters of shape ``(B,)`` (``nh < 1``: the host is
    ``n1``; ``N`` may be fractional), ``cos_theta`` ``(A,)`` in the host, ``wavelengths`` ``(W,)`` nm;
    returns ``(B, A, W)``. Appendix D's coefficient ``r_hN = (r_N + r_h1) / (1 + r_h1 r_N)`` with
    ``r_N = r1 U_{N-1} / (U_{N-1} - U_{N-2} t1 e^{i k_1z d1})`` and the slab's ``r1, t1`` (Eq. 10);
    ``|r_N|^2`` is Yeh's Eq. 2 when the host is ``n1`` (``r_h1 = 0``). Equals
    :func:`explorer.physics.bragg.bragg_reflectance` at integer ``N`` (tested) when ``step`` is None.

    ``step`` (nm): the spectrum is to be sampled that coarsely, so where the fringes are narrower than a
    few steps it is blended into its average over the fringes
    (:func:`explorer.physics.bragg.reflectance_fringe_average`, :func:`explorer.physics.bragg.fringe_average_under_host`),
    which is what the converged colour of such a mirror integrates; point samples would alias.
    ``smooth`` (nm, default ``step``) averages out fringes narrower than a few times it: the screening's
    smoother landscape (the envelope's band gaps without the fringes' ripples).
    """
    col = lambda v: np.asarray(v, dtype=np.float64).reshape(-1, 1, 1)
    n1, n2, Lambda, delta, N, nh = (col(v) for v in (n1, n2, Lambda, delta, N, nh))
    host = nh >= 1.0
    eta_h = np.where(host, nh, n1)
    cos_h = np.maximum(np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1), bragg.COS_THETA_MIN)
    wavelengths = np.asarray(wavelengths, dtype=np.float64).reshape(1, 1, -1)
    omega = 2.0 * np.pi / wavelengths
    cos_1 = cos_theta_transmitted(cos_h, eta_h, n1)
    cos_2 = cos_theta_transmitted(cos_h, eta_h, n2)
    p1 = n1 * cos_1 * delta * Lambda
    p2 = n2 * cos_2 * (1.0 - delta) * Lambda
    psi = bragg._clamp_decay(omega * p1)
    phi = bragg._clamp_decay(omega * p2)
    e_psi, e_phi = np.exp(1j * psi), np.exp(1j * phi)
    cos_psi, sin_psi = (e_psi + 1.0 / e_psi) / 2.0, (e_psi - 1.0 / e_psi) / 2j
    cos_phi, sin_phi = (e_phi + 1.0 / e_phi) / 2.0, (e_phi - 1.0 / e_phi) / 2j
    shape = np.broadcast_shapes(cos_1.shape, wavelengths.shape, n1.shape)
    if step is None:
        w_point = np.ones(shape)
    else:
        # Fringes lambda^2 / (2 N path) apart (path: the cell's optical thickness along z); a point sample
        # per step resolves them from ~4 per fringe, and averages them out below 1 per fringe.
        path = np.maximum(np.real(p1) + np.real(p2), 1e-9)
        fringe = wavelengths**2 / (2.0 * N * path)
        w_point = np.broadcast_to(np.clip((fringe / (step if smooth is None else smooth) - 1.0) / 3.0, 0.0, 1.0), shape)
    # Each sample computes only the reflectances its weight needs: a scan's spectrum runs from point
    # samples (thin, short cells) to averages (thick stacks), blending both over a factor ~4 in between.
    point, averaged = w_point > 0.0, w_point < 1.0
    total = 0.0
    for pol in bragg.POLARISATIONS:
        r12 = fresnel_r(pol, n1, cos_1, n2, cos_2)
        Omega = bragg.Omega(pol, n1, cos_1, n2, cos_2)
        a = np.real(cos_psi * cos_phi - 0.5 * Omega * sin_psi * sin_phi)  # Eq. 8
        phase2 = e_phi * e_phi
        r12_2 = r12 * r12
        denominator = 1.0 - r12_2 * phase2
        r1 = r12 * (1.0 - phase2) / denominator
        t1 = (1.0 - r12_2) * e_phi / denominator
        r_h1 = np.where(host, fresnel_r(pol, eta_h, cos_h.astype(np.complex128), n1, cos_1), 0.0)
        R = _where_needed(point, _point_reflectance, a, N, r1, t1, e_psi, r_h1)
        if averaged.any():
            average = _where_needed(averaged, _averaged_reflectance, r1, t1, omega, p1, r_h1, a)
            R = w_point * R + (1.0 - w_point) * average
        total = total + R
    return np.clip(total / 2.0, 0.0, 1.0)


def _point_reflectance(a, N, r1, t1, e_psi, r_h1) -> np.ndarray:
    """``|r_hN|^2`` of :func:`bragg_reflectance_batch` at its samples (Appendix D, ``N`` real)."""
    U_N1, U_N2, _ = chebyshev_U_real_N(a, N)
    r_N = r1 * U_N1 / (U_N1 - U_N2 * t1 * e_psi)
    return np.abs((r_N + r_h1) / (1.0 + r_h1 * r_N)) ** 2


def _averaged_reflectance(r1, t1, omega, p1, r_h1, a) -> np.ndarray:
    """``|r_hN|^2`` of :func:`bragg_reflectance_batch` averaged over its fringes (Appendix D)."""
    return bragg.fringe_average_under_host(r1, t1, omega, _Geometry(p1, r_h1), a)


def _where_needed(mask: np.ndarray, function: Callable[..., np.ndarray], *arrays) -> np.ndarray:
    """``function(*arrays)`` where ``mask`` (the arrays broadcast to its shape), 0 elsewhere."""
    if mask.all():
        return np.broadcast_to(function(*arrays), mask.shape)
    out = np.zeros(mask.shape)
    if mask.any():
        out[mask] = function(*(np.broadcast_to(v, mask.shape)[mask] for v in arrays))
    return out


@dataclass
class _Geometry:
    """What :func:`explorer.physics.bragg.fringe_average_under_host` reads of a cell (``r_h1 = 0``: no host)."""

    p1: np.ndarray
    r_h1: np.ndarray


def bragg_rgb_batch(values: Mapping[str, np.ndarray], cos_theta: ArrayLike, step: float = COARSE_STEP,
                    smooth: float | None = None) -> np.ndarray:
    """The coarse colours ``(B, A, 3)`` of mirrors ``values`` (arrays ``(B,)``) at ``cos_theta`` ``(A,)``."""
    nodes, weights = coarse_nodes(step)
    R = bragg_reflectance_batch(values["n1"], values["n2"], values["Lambda"], values["delta"], values["N"],
                                values["nh"], cos_theta, nodes, step=step, smooth=smooth)
    return colorimetry.xyz_to_rgb(R @ weights)


def thin_film_rgb_batch(values: Mapping[str, np.ndarray], cos_theta: ArrayLike, step: float = COARSE_STEP,
                        smooth: float | None = None) -> np.ndarray:
    """
    The coarse colours ``(B, A, 3)`` of films ``values`` (``d``, ``eta1``, ``eta2``, ``eta3``, ``kappa3``); a
    film's few fringes are its colour, so ``smooth`` is not used.
    """
    nodes, weights = coarse_nodes(step)
    col = lambda name: np.asarray(values[name], dtype=np.float64).reshape(-1, 1, 1)
    cos = np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1)
    R = thinfilm.airy_reflectance(col("eta1"), col("eta2"), col("eta3"), col("kappa3"), cos, col("d"), nodes)
    return colorimetry.xyz_to_rgb(R @ weights)


def bragg_spectra_batch(
    values: Mapping[str, np.ndarray], cos_theta: ArrayLike, wavelengths: ArrayLike, smooth_relative: float,
) -> np.ndarray:
    """Screening spectra ``(B, A, W)``: fringes narrower than ~``smooth_relative`` lambda averaged out."""
    wavelengths = np.asarray(wavelengths, dtype=np.float64)
    return bragg_reflectance_batch(values["n1"], values["n2"], values["Lambda"], values["delta"], values["N"], values["nh"],
                                   cos_theta, wavelengths, step=1.0, smooth=smooth_relative * wavelengths)


def thin_film_spectra_batch(
    values: Mapping[str, np.ndarray], cos_theta: ArrayLike, wavelengths: ArrayLike, smooth_relative: float,
) -> np.ndarray:
    """The films' spectra ``(B, A, W)`` (not smoothed: a film's fringes are its colour)."""
    col = lambda name: np.asarray(values[name], dtype=np.float64).reshape(-1, 1, 1)
    cos = np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1)
    return thinfilm.airy_reflectance(col("eta1"), col("eta2"), col("eta3"), col("kappa3"), cos, col("d"), np.asarray(wavelengths, float))


def mirror_of(values: Mapping[str, float]) -> bragg.BraggMirror:
    """The :class:`explorer.physics.bragg.BraggMirror` of design values (``nh < 1``: the host is ``n1``)."""
    nh = float(values["nh"])
    return bragg.BraggMirror(n1=float(values["n1"]), n2=float(values["n2"]), Lambda=float(values["Lambda"]),
                             delta=float(values["delta"]), N=max(1, int(round(float(values["N"])))),
                             nh=nh if nh >= 1.0 else None)


def bragg_converged_rgb(values: Mapping[str, float], cos_theta: ArrayLike, final: bool = True) -> np.ndarray:
    """
    The converged colours of a mirror (``N`` rounded): :func:`explorer.physics.bragg.reference_rgb` when
    ``final``, otherwise the tabulated method's own nodes (float32 where it applies, substeps capped),
    which the polish calls many times.
    """
    mirror = mirror_of(values)
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    if final:
        return bragg.reference_rgb(cos_theta, mirror)
    return bragg._converged_rgb(cos_theta, mirror)


def thin_film_converged_rgb(values: Mapping[str, float], cos_theta: ArrayLike, final: bool = True) -> np.ndarray:
    """The film's converged colours (:func:`explorer.physics.thinfilm.reference_rgb`)."""
    return thinfilm.reference_rgb(float(values["eta1"]), float(values["eta2"]), float(values["eta3"]),
                                  float(values["kappa3"]), np.asarray(cos_theta, dtype=np.float64), float(values["d"]))


_BRAGG = dict(parameters=("n1", "n2", "Lambda", "delta", "N", "nh"), log_parameters=("N", "Lambda"),
              integer_parameters=("N",), batch=bragg_rgb_batch, converged=bragg_converged_rgb, host_parameter="nh",
              scale_parameter="Lambda", optical=True, spectra=bragg_spectra_batch)
#: Every designable material model; its specular colour is what is designed (``bragg_layer``: the smooth
#: mirror's colour, which its gradient view shows).
DESIGN_MODELS: dict[str, DesignModel] = {model.name: model for model in (
    DesignModel("bragg_mirror", **_BRAGG),
    DesignModel("bragg_layer", **_BRAGG),
    DesignModel("thin_film", ("d", "eta1", "eta2", "eta3", "kappa3"), (), (), thin_film_rgb_batch, thin_film_converged_rgb,
                scale_parameter="d", spectra=thin_film_spectra_batch),
)}
DESIGNABLE = tuple(DESIGN_MODELS)


def design_model(name: str | None) -> DesignModel:
    """The :class:`DesignModel` of a material model name, or a :class:`DesignError`."""
    if name not in DESIGN_MODELS:
        raise DesignError(f"model {name or '(none)'} cannot be designed (designable: {', '.join(DESIGNABLE)})")
    return DESIGN_MODELS[name]


# --------------------------------------------------------------------------------------------------
# Colours


def _white_xy() -> np.ndarray:
    return colour.XYZ_to_xy(colorimetry.white_xyz())


def rgb_to_lab(rgb: ArrayLike) -> np.ndarray:
    """CIELAB of linear RGB colours of this convention, relative to the flat reflectance of 1 (as ΔE2000)."""
    return colour.XYZ_to_Lab(colorimetry.rgb_to_xyz(np.asarray(rgb, dtype=np.float64)), _white_xy())


def delta_E_2000_lab(lab_a: ArrayLike, lab_b: ArrayLike) -> np.ndarray:
    """CIEDE2000 between CIELAB colours (colour-science)."""
    return np.asarray(colour.delta_E(lab_a, lab_b, method="CIE 2000"))


def check_target_rgb(rgb: ArrayLike, what: str = "colour") -> np.ndarray:
    """
    A target colour as linear RGB, or a :class:`DesignError`: non-finite values, or a luminance no passive
    reflector has (``Y > 1``: brighter than the flat reflectance of 1; ``Y < 0``). Channels outside [0, 1]
    are kept (vivid Bragg colours lie outside sRGB).
    """
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.shape != (3,) or not np.all(np.isfinite(rgb)):
        raise DesignError(f"{what}: expected three finite numbers")
    Y = float(colorimetry.rgb_to_xyz(rgb)[1])
    if Y > 1.0 + 1e-6:
        raise DesignError(f"{what}: luminance Y = {Y:.4g} > 1, brighter than a perfect mirror: no passive reflector has it")
    if Y < -1e-6:
        raise DesignError(f"{what}: luminance Y = {Y:.4g} < 0: no colour has it")
    return rgb


def targets_from_strip(image: np.ndarray, theta_a: float, theta_b: float, count: int = 5,
                       clipped: np.ndarray | None = None) -> list["Target"]:
    """
    ``count`` targets from a strip of linear RGB ``(H, W, 3)`` whose column ``i`` shows
    ``theta_a + (theta_b - theta_a)(i + 0.5) / W`` degrees (as the gradient view draws 0 to 90): evenly
    spaced columns, each the mean of its rows; columns at 90 degrees and beyond are skipped. ``clipped``
    ``(H, W, 3)``: -1 where an integer image holds its lowest code, +1 its highest, 0 elsewhere; a channel
    clipped in every row of its column becomes a bound (:class:`Target`), not a value.
    """
    if not (np.isfinite(theta_a) and np.isfinite(theta_b) and 0.0 <= min(theta_a, theta_b)
            and max(theta_a, theta_b) <= 90.0 and theta_a != theta_b):
        raise DesignError(f"theta range {theta_a:g},{theta_b:g}: the two angles must differ, within [0, 90]")
    width = image.shape[1]
    columns = np.unique(np.clip(np.round((np.arange(count) + 0.5) / count * width - 0.5).astype(int), 0, width - 1))
    targets = []
    for i in columns:
        theta = theta_a + (theta_b - theta_a) * (i + 0.5) / width
        if theta >= 90.0:
            continue
        rgb = check_target_rgb(np.asarray(image)[:, i, :3].mean(axis=0), f"strip column {i}")
        bounds = (0, 0, 0)
        if clipped is not None:
            column = np.asarray(clipped)[:, i, :3]
            bounds = tuple(int(column[0, c]) if np.all(column[:, c] == column[0, c]) else 0 for c in range(3))
        targets.append(Target(float(theta), tuple(float(c) for c in rgb), bounds))
    if not targets:
        raise DesignError("the strip has no column below 90 degrees")
    return targets


# --------------------------------------------------------------------------------------------------
# The search


@dataclass(frozen=True)
class Target:
    """
    A wanted colour (linear RGB of this convention) at an angle (degrees, in the outer medium). ``bounds``
    per channel: 0 the value itself; -1 at most it, +1 at least it (a channel an 8-bit image clipped at 0 or
    255: the true colour lies beyond). A bounded channel costs nothing on its side of the bound.
    """

    theta_deg: float
    rgb: tuple[float, float, float]
    bounds: tuple[int, int, int] = (0, 0, 0)

    @property
    def bounded(self) -> bool:
        return any(self.bounds)


@dataclass
class DesignResult:
    """
    The best structure found: every design value (``values``, free and fixed, ``N`` an integer), the
    converged colour at each target and its CIEDE2000, the time taken (wall and this process's CPU: on
    a shared machine the wall time measures the load as much as the search) and how many candidates
    were evaluated.
    """

    model: str
    values: dict[str, float]
    targets: list[Target]
    achieved_rgb: np.ndarray
    delta_e2000: np.ndarray
    seconds: float
    cpu_seconds: float = 0.0
    evaluations: int = 0
    #: Searches run (:func:`design`'s ``tries``: fewer when every target was reached early).
    tries: int = 1
    stages: dict[str, float] = field(default_factory=dict)

    @property
    def median_delta_e2000(self) -> float:
        return float(np.median(self.delta_e2000))

    @property
    def reachable(self) -> np.ndarray:
        """Per target: whether the design reaches it (CIEDE2000 at most :data:`REACHABLE_DELTA_E`)."""
        return self.delta_e2000 <= REACHABLE_DELTA_E

    def as_json(self, material: str) -> dict:
        """The ``design --json`` object; colours are linear RGB."""
        return {
            "material": material,
            "set": dict(self.values),
            "targets": [
                {"theta_deg": t.theta_deg, "target_rgb": [float(c) for c in t.rgb],
                 **({"target_bounds": ["at most" if b < 0 else "at least" if b > 0 else "equal" for b in t.bounds]}
                    if t.bounded else {}),
                 "achieved_rgb": [float(c) for c in a], "delta_e2000": float(d)}
                for t, a, d in zip(self.targets, self.achieved_rgb, self.delta_e2000)
            ],
            "median_delta_e2000": self.median_delta_e2000,
            "seconds": self.seconds,
        }


def parameter_box(model: DesignModel, ranges: Mapping[str, tuple[float, float]]) -> list[DesignParameter]:
    """The design parameters of ``model`` over ``ranges`` (name -> (low, high), the material's declared ranges)."""
    box = []
    for name in model.parameters:
        if name not in ranges:
            raise DesignError(f"the material declares no range for {name}")
        low, high = (float(v) for v in ranges[name])
        if name in model.log_parameters:
            low = max(low, 1.0)
        box.append(DesignParameter(name, low, high, log=name in model.log_parameters, integer=name in model.integer_parameters))
    return box


class _Problem:
    """The free parameters, the fixed values and the targets, with the residuals of both models."""

    def __init__(self, model: DesignModel, box: list[DesignParameter], fixed: Mapping[str, float],
                 targets: Sequence[Target], cancelled: Callable[[], bool] | None):
        self.model = model
        self.box = {p.name: p for p in box}
        self.fixed = {k: float(v) for k, v in fixed.items()}
        self.free = [p for p in box if p.name not in self.fixed]
        # A mirror whose period and thickness ratio are both free is searched by its optical period and
        # the first layer's share of it (see :meth:`values`): the band positions then depend on one
        # coordinate, and the indices move the angular shift and the contrast without moving the bands.
        names = [p.name for p in self.free]
        self.optical = model.optical and "Lambda" in names and "delta" in names
        if self.optical:
            indices = [self.box[n] if n not in self.fixed else DesignParameter(n, self.fixed[n], self.fixed[n]) for n in ("n1", "n2")]
            n_low, n_high = min(p.low for p in indices), max(p.high for p in indices)
            Lambda = self.box["Lambda"]
            self.free[names.index("Lambda")] = DesignParameter("optical_period", Lambda.low * n_low, Lambda.high * n_high, log=True)
            self.free[names.index("delta")] = DesignParameter("optical_fraction", 0.0, 1.0)
        self.scale_parameter = "optical_period" if self.optical else model.scale_parameter
        # Every angle of every layer depends on index ratios only (Snell's invariant nh sin theta over each
        # index), and every phase on optical thicknesses (Eq. 8), so multiplying n1, n2 and the host by one
        # factor k, at a fixed optical period, changes no colour (Lambda = P (f / n1 + (1 - f) / n2) moves
        # as 1 / k). With all three free, each scale of the scan picks its k inside the boxes
        # (:meth:`index_scale_bounds`, :meth:`at_scale`): a shape reaches every period some k allows.
        host = model.host_parameter
        self.index_scale = self.optical and {"n1", "n2"} <= set(names) and (
            host is None or host in names or self.fixed.get(host, 0.0) < model.host_threshold)
        self.targets = list(targets)
        self.cos_theta = np.cos(np.radians([t.theta_deg for t in self.targets]))
        self.target_rgb = np.array([t.rgb for t in self.targets], dtype=np.float64)
        self.target_lab = rgb_to_lab(self.target_rgb)
        self.bounds = np.array([t.bounds for t in self.targets], dtype=np.int8)
        self.cancelled = cancelled
        self.evaluations = 0
        self._lock = threading.Lock()  # the scans run in threads (:func:`_threaded_scan`)

    def values(self, U: np.ndarray, scale_value: float | np.ndarray | None = None, whole: bool = False) -> dict[str, np.ndarray]:
        """
        Unit-box rows ``(B, P)`` -> every design value as ``(B,)`` arrays. ``scale_value``: the scale
        coordinate at this value (one, or one per row) instead, unclipped (the scale scan's structures).
        ``whole``: integer parameters (``N``) at their nearest whole values; the search otherwise walks them
        continuously (a relaxation: a fractional count has colours no stack has).
        """
        U = np.atleast_2d(U)
        out = {name: np.full(U.shape[0], value) for name, value in self.fixed.items()}
        for k, p in enumerate(self.free):
            out[p.name] = p.whole(p.from_unit(U[:, k])) if whole else p.from_unit(U[:, k])
        if scale_value is not None:
            out[self.scale_parameter] = np.broadcast_to(np.asarray(scale_value, dtype=np.float64), (U.shape[0],)).copy()
        if self.optical:
            # Optical thicknesses n1 d1 = f P and n2 d2 = (1 - f) P at normal incidence (Eq. 8's phases):
            # Lambda = P (f / n1 + (1 - f) / n2), delta = (f / n1) / (f / n1 + (1 - f) / n2).
            f, P = out.pop("optical_fraction"), out.pop("optical_period")
            per_period = f / out["n1"] + (1.0 - f) / out["n2"]
            Lambda = self.box["Lambda"]
            out["Lambda"] = P * per_period if scale_value is not None else np.clip(P * per_period, Lambda.low, Lambda.high)
            out["delta"] = np.clip((f / out["n1"]) / per_period, 0.0, 1.0)
        return out

    def unit_row(self, structure: Mapping[str, float]) -> np.ndarray:
        """
        The unit row of a structure (design values by name): the inverse of :meth:`values`, the optical
        period ``P = Lambda (delta n1 + (1 - delta) n2)`` and share ``f = delta n1 Lambda / P`` where the
        search walks those.
        """
        named = dict(structure)
        if self.optical:
            n1, n2, Lambda, delta = (float(named[k]) for k in ("n1", "n2", "Lambda", "delta"))
            named["optical_period"] = Lambda * (delta * n1 + (1.0 - delta) * n2)
            named["optical_fraction"] = delta * n1 * Lambda / named["optical_period"]
        return np.array([float(p.to_unit(named[p.name])) for p in self.free])

    def index_scale_bounds(self, values: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """
        The factors ``k`` (per row, an interval) that keep ``k n1``, ``k n2`` and a host's ``k nh`` inside
        their boxes (a host stays a host: ``k nh`` at least the threshold); ``(1, 1)`` without
        :attr:`index_scale`.
        """
        rows = np.asarray(next(iter(values.values()))).shape[0]
        k_low, k_high = np.ones(rows), np.ones(rows)
        if not self.index_scale:
            return k_low, k_high
        k_low, k_high = np.zeros(rows), np.full(rows, np.inf)
        host = self.model.host_parameter
        for name in ("n1", "n2", host):
            if name is None or name not in self.box or name in self.fixed:
                continue
            v, p = np.asarray(values[name], dtype=np.float64), self.box[name]
            low = p.low
            if name == host:
                low = max(low, self.model.host_threshold)
                present = v >= self.model.host_threshold
                k_low = np.where(present, np.maximum(k_low, low / np.where(present, v, 1.0)), k_low)
                k_high = np.where(present, np.minimum(k_high, p.high / np.where(present, v, 1.0)), k_high)
            else:
                k_low, k_high = np.maximum(k_low, low / v), np.minimum(k_high, p.high / v)
        return k_low, k_high

    def at_scale(self, U: np.ndarray, scale_value: np.ndarray) -> np.ndarray:
        """
        Unit rows ``U`` with their scale coordinate at ``scale_value`` (one per row, physical); with
        :attr:`index_scale`, the indices multiplied by the ``k`` (geometric middle of those allowed) that
        puts ``Lambda`` inside its box at that optical period: the same colours, a structure in the box.
        """
        U = np.atleast_2d(U).copy()
        scale_value = np.broadcast_to(np.asarray(scale_value, dtype=np.float64), (U.shape[0],))
        if self.index_scale:
            values = self.values(U, scale_value=scale_value)
            k_low, k_high = self.index_scale_bounds(values)
            Lambda = self.box["Lambda"]
            # Lambda / k must lie in [low, high]: k in [Lambda / high, Lambda / low].
            k_low, k_high = np.maximum(k_low, values["Lambda"] / Lambda.high), np.minimum(k_high, values["Lambda"] / Lambda.low)
            k = np.sqrt(k_low * np.maximum(k_high, k_low))
            host = self.model.host_parameter
            for j, p in enumerate(self.free):
                if p.name in ("n1", "n2") or (p.name == host and host is not None):
                    scaled = values[p.name] * k
                    if p.name == host:
                        scaled = np.where(values[p.name] >= self.model.host_threshold, scaled, values[p.name])
                    U[:, j] = np.clip(p.to_unit(scaled), 0.0, 1.0)
        U[:, self.scale_index] = np.clip(self.free[self.scale_index].to_unit(scale_value), 0.0, 1.0)
        return U

    def _check(self):
        if self.cancelled is not None and self.cancelled():
            raise DesignCancelled()

    def coarse_rgb(self, U, step: float = COARSE_STEP, smooth: float | None = None, whole: bool = False) -> np.ndarray:
        U = np.atleast_2d(U)
        self.evaluations += U.shape[0]
        out = np.empty((U.shape[0], self.cos_theta.size, 3))
        for start in range(0, U.shape[0], BATCH):
            self._check()
            out[start : start + BATCH] = self.model.batch(self.values(U[start : start + BATCH], whole=whole), self.cos_theta, step, smooth)
        return out

    @property
    def scale_index(self) -> int | None:
        """The free coordinate that scales every length of the structure (None when it is fixed)."""
        return next((k for k, p in enumerate(self.free) if p.name == self.scale_parameter), None)

    def scale_scan(self, shapes: np.ndarray, relative_step: float | None = None,
                   smooth_relative: float | None = None, around: np.ndarray | None = None,
                   span: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """
        Screening scores ``(B, G)`` of ``shapes`` (unit rows; their scale coordinate ignored) at the scales
        ``s_bm = s_b r^m`` (``r = 1 + relative_step``, default :data:`SCAN_RELATIVE_STEP`; fringes averaged
        below ``smooth_relative`` lambda, default :data:`SCAN_SMOOTH`) that keep each shape's ``Lambda`` in its box (else
        the scale's whole range, or what index scaling allows: :attr:`index_scale`), and those scales
        ``(B, G)`` (physical: :meth:`at_scale` makes unit rows of them). ``around`` (per row) and ``span``:
        only the scales within a factor ``1 + span`` of ``around`` (a local search's window).

        Without dispersion a structure's spectrum depends on ``x = s / lambda`` only (every phase is
        ``2 pi n d cos theta / lambda``, Eq. 8, and ``d`` scales with ``s``): one spectrum per shape on the
        log grid ``x_k = (s_b / lambda_max) r^k``, against CMF weights on the log-spaced wavelengths
        ``lambda_j = lambda_max r^-j``, gives ``XYZ(s_bm) = sum_j W_j R(x_{m+j})``, a correlation (FFT) that
        yields every scale on the grid's own step. Scales that put ``Lambda`` outside its box score infinity.
        """
        from scipy import fft

        p = self.free[self.scale_index]
        ratio = 1.0 + (SCAN_RELATIVE_STEP if relative_step is None else relative_step)
        smooth_relative = SCAN_SMOOTH if smooth_relative is None else smooth_relative
        low, high = (self.box["Lambda"].low, self.box["Lambda"].high) if self.optical else (max(p.low, 1.0), p.high)
        # With index scaling, a shape's periods reach k_high / k_low further (at most n1's box ratio).
        widest = self.box["n1"].high / self.box["n1"].low if self.index_scale else 1.0
        G = int(np.ceil(np.log((high / low * widest) if around is None else (1.0 + span) ** 2) / np.log(ratio))) + 1
        nodes, weights = log_nodes(ratio)  # ascending: node J - j is lambda_j
        J = nodes.size - 1
        # Row b's structure at scale s_b seen at lambda_max r^-k is its spectrum at x_k = (s_b / lambda_max) r^k.
        wavelengths = nodes[-1] / ratio ** np.arange(G + J)
        size = fft.next_fast_len(G + 2 * J)
        kernel = fft.rfft(weights, n=size, axis=0)  # (F, 3): the correlation as a convolution with W reversed
        scores = np.empty((shapes.shape[0], G))
        scales = np.empty((shapes.shape[0], G))
        # Rows per batch: SCAN_BATCH at the full range's length, more for a window's shorter spectra.
        batch = max(SCAN_BATCH, int(SCAN_BATCH * SCAN_BATCH_SAMPLES / (G + J)))
        for start in range(0, shapes.shape[0], batch):
            self._check()
            rows = slice(start, start + batch)
            U = shapes[rows]
            # The first scale: Lambda at its low end (optical period P = Lambda / per_period), or the range's.
            unit_values = self.values(U, scale_value=1.0)
            k_low, k_high = self.index_scale_bounds(unit_values)
            per_period = unit_values["Lambda"] if self.optical else np.ones(len(U))
            s_first = k_low * low / per_period if around is None else np.asarray(around, dtype=np.float64)[rows] / (1.0 + span)
            values = self.values(U, scale_value=s_first)
            R = self.model.spectra(values, self.cos_theta, wavelengths, smooth_relative)  # (B, A, X)
            with self._lock:
                self.evaluations += U.shape[0] * G
            spectrum = fft.rfft(R, n=size, axis=-1)  # (B, A, F)
            xyz = fft.irfft(spectrum[..., None] * kernel[None, None], n=size, axis=-2)[:, :, J : J + G]  # (B, A, G, 3)
            rgb = colorimetry.xyz_to_rgb(xyz).transpose(0, 2, 1, 3)  # (B, G, A, 3)
            s_rows = s_first[:, None] * ratio ** np.arange(G)[None, :]
            # CIEDE2000 at the scales whose CIELAB distance (cheap) is among the SCAN_KEPT smallest.
            proxy = np.sum((rgb_to_lab(np.maximum(rgb, -1.0)) - self.target_lab_for(rgb)) ** 2, axis=(-1, -2))
            # Lambda at k = 1 (or the scale) against the box's top, which k_high stretches.
            top = s_rows * per_period[:, None]
            inside = (top <= k_high[:, None] * high * (1.0 + 1e-9)) & (top >= k_low[:, None] * low * (1.0 - 1e-9))
            proxy = np.where(inside, proxy, np.inf)
            kept = np.argpartition(proxy, min(SCAN_KEPT, G) - 1, axis=1)[:, :SCAN_KEPT]
            chosen = np.take_along_axis(rgb, kept[:, :, None, None], axis=1)
            score = np.full(proxy.shape, np.inf)
            finite = np.isfinite(np.take_along_axis(proxy, kept, axis=1))
            np.put_along_axis(score, kept, np.where(finite, np.sum(self.residuals_of(chosen) ** 2, axis=-1), np.inf), axis=1)
            scores[rows] = score
            scales[rows] = s_rows
        return scores, scales

    def screen(self, U) -> np.ndarray:
        """Sum of squared CIEDE2000 of unit-box rows on the screening model."""
        return np.sum(self.residuals_of(self.coarse_rgb(U, SCREEN_STEP, SCREEN_SMOOTH)) ** 2, axis=-1)

    def residuals_of(self, rgb: np.ndarray) -> np.ndarray:
        """``(..., A, 3)`` colours -> ``(..., 3 A)`` residuals whose squared norm per target is CIEDE2000^2."""
        lab = rgb_to_lab(np.maximum(rgb, -1.0))
        target_lab = np.broadcast_to(self.target_lab_for(rgb), lab.shape)
        difference = lab - target_lab
        e76 = np.linalg.norm(difference, axis=-1)
        e00 = delta_E_2000_lab(lab, target_lab)
        scale = np.where(e76 > 1e-9, e00 / np.maximum(e76, 1e-300), 1.0)
        return (difference * scale[..., None]).reshape(rgb.shape[:-2] + (-1,))

    def target_lab_for(self, rgb: np.ndarray) -> np.ndarray:
        """
        The targets in CIELAB as seen from colours ``rgb`` ``(..., A, 3)``: a bounded channel (``Target.bounds``)
        takes the colour's own value where it lies beyond the bound, so that only the exact channels and the
        wrong side of a bound cost (one-sided).
        """
        if not self.bounds.any():
            return self.target_lab
        rgb = np.asarray(rgb, dtype=np.float64)
        target = np.where(self.bounds < 0, np.minimum(rgb, self.target_rgb),
                          np.where(self.bounds > 0, np.maximum(rgb, self.target_rgb), self.target_rgb))
        return rgb_to_lab(np.maximum(target, -1.0))

    def delta_e(self, rgb) -> np.ndarray:
        lab = rgb_to_lab(rgb)
        return delta_E_2000_lab(lab, np.broadcast_to(self.target_lab_for(rgb), lab.shape))

    def fine_values(self, u: np.ndarray) -> dict[str, float]:
        """The structure of one unit row, integer parameters whole (fixed ones are: :func:`design` checks)."""
        return {k: float(v[0]) for k, v in self.values(u, whole=True).items()}

    def fine_rgb(self, values: Mapping[str, float], final: bool = False) -> np.ndarray:
        self._check()
        self.evaluations += 1
        return self.model.converged(values, self.cos_theta, final=final)

    def fine_residuals(self, u: np.ndarray) -> tuple[dict[str, float], np.ndarray]:
        """One unit row's structure (integer parameters whole) and its residuals on the converged model."""
        values = self.fine_values(u[None])
        return values, self.residuals_of(self.fine_rgb(values)[None])[0]

    def fine_cost(self, u: np.ndarray) -> float:
        """Sum of squared CIEDE2000 of one unit row on the converged model (:meth:`fine_residuals`)."""
        return float(np.sum(self.fine_residuals(u)[1] ** 2))

    @property
    def polished_cost(self) -> float:
        """The cost below which the polish stops: :data:`POLISHED_ENOUGH` per target."""
        return POLISHED_ENOUGH**2 * len(self.targets)


def _least_squares(fun, jac, x0, lower, upper, max_nfev):
    from scipy.optimize import least_squares

    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    x0 = np.clip(x0, lower + 1e-9, upper - 1e-9)
    return least_squares(fun, x0, jac=jac, bounds=(lower, upper), max_nfev=max_nfev, x_scale=1.0, method="dogbox",
                         xtol=1e-10, ftol=1e-10, gtol=1e-10)


def _host_bounds(problem: _Problem, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    The unit box of a local refinement: a host parameter stays on the start's side of its threshold
    (below it the host is ``n1``, a branch, not a slope: there it is held).
    """
    lower, upper = np.zeros(u.size), np.ones(u.size)
    name = problem.model.host_parameter
    for k, p in enumerate(problem.free):
        if p.name == name:
            threshold = float(np.clip(p.to_unit(problem.model.host_threshold), 0.0, 1.0))
            if p.from_unit(u[k]) < problem.model.host_threshold:
                lower[k], upper[k] = max(u[k] - 1e-6, 0.0), min(u[k] + 1e-6, 1.0)
            else:
                lower[k] = threshold
    return lower, upper


def _refine_coarse(problem: _Problem, u0: np.ndarray, max_nfev: int) -> tuple[np.ndarray, float]:
    """The screening model's refinement, then the coarse model's (a continuation: smooth landscape first)."""
    # Without the screening model's level, its moves to basins far from the start were lost (measured with
    # 384 scan shapes: the CI subset's median 0.43 -> 0.85).
    u, _ = _refine_level(problem, u0, max_nfev, SCREEN_STEP, SCREEN_SMOOTH)
    return _refine_level(problem, u, max_nfev, COARSE_STEP, None)


def _refine_level(problem: _Problem, u0: np.ndarray, max_nfev: int, step: float, smooth) -> tuple[np.ndarray, float]:
    """Trust-region refinement (dogbox) on one batch model; Jacobian columns in one batch."""
    lower, upper = _host_bounds(problem, u0)
    P = u0.size
    cache: dict[bytes, np.ndarray] = {}

    def batch_residuals(U):
        return problem.residuals_of(problem.coarse_rgb(U, step, smooth))

    def fun(u):
        key = u.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = batch_residuals(u[None])[0]
        return cache[key]

    def jac(u):
        h = np.where(u + COARSE_DIFF_STEP <= upper, COARSE_DIFF_STEP, -COARSE_DIFF_STEP)
        U = np.repeat(u[None], P, axis=0) + np.diag(h)
        columns = batch_residuals(U)
        return ((columns - fun(u)[None]) / h[:, None]).T

    result = _least_squares(fun, jac, u0, lower, upper, max_nfev)
    return result.x, float(2.0 * result.cost)


def _polish(problem: _Problem, u0: np.ndarray, max_nfev: int, deadline: float) -> tuple[dict[str, float], float]:
    """
    The converged model, with integer parameters held at the better of their two neighbouring integers:
    damped Gauss-Newton steps on the converged model's residuals, its Jacobian by forward differences of
    :data:`FINE_DIFF_STEP` (far above its adaptive refinement's ~1e-4 steps in colour), until no step
    lowers the converged cost, after ``max_nfev`` steps, or at ``deadline`` (``time.process_time()``).
    The batch models' Jacobians pointed elsewhere for thick stacks, whose narrow bands and fringes they
    sample too coarsely: from 0.003 of the box around the truths of 8 thick misses, the 1-nm batch model's
    steps ended below 0.05 per target in 2 of 32 starts, these in 30 (docs/design.md, design_polish.py).
    """
    integer_free = [k for k, p in enumerate(problem.free) if p.integer]
    u0 = u0.copy()
    choices = [u0.copy()]
    for k in integer_free:
        p = problem.free[k]
        value = float(p.from_unit(u0[k]))
        options = sorted({max(p.low, min(p.high, float(math.floor(value)))), max(p.low, min(p.high, float(math.ceil(value))))})
        choices = [np.concatenate([c[:k], [p.to_unit(o)], c[k + 1:]]) for c in choices for o in options]

    def fine(u):
        values, residuals = problem.fine_residuals(u)
        return values, residuals, float(np.sum(residuals**2))

    best = min((fine(np.clip(c, 0.0, 1.0)) + (np.clip(c, 0.0, 1.0),) for c in choices), key=lambda item: item[2])
    values, residuals, cost, u = best
    keep = np.array([k for k in range(u.size) if k not in integer_free])
    if keep.size == 0:
        return values, cost
    lower, upper = _host_bounds(problem, u)
    damping = 1e-3
    for _ in range(max_nfev):
        if time.process_time() > deadline or cost < problem.polished_cost:
            break
        h = np.where(u[keep] + FINE_DIFF_STEP <= upper[keep], FINE_DIFF_STEP, -FINE_DIFF_STEP)
        U = np.repeat(u[None], keep.size, axis=0)
        U[np.arange(keep.size), keep] += h
        columns = np.array([fine(row)[1] for row in U])
        J = ((columns - residuals) / h[:, None]).T
        JTJ, JTr = J.T @ J, J.T @ residuals
        improved = False
        while damping < 1e6:
            step = -np.linalg.solve(JTJ + damping * np.diag(np.diag(JTJ) + 1e-12), JTr)
            trial = u.copy()
            trial[keep] = np.clip(u[keep] + step, lower[keep], upper[keep])
            t_values, t_residuals, t_cost = fine(trial)
            if t_cost < cost:
                u, values, residuals, cost = trial, t_values, t_residuals, t_cost
                damping = max(damping / 3.0, 1e-7)
                improved = True
                break
            damping *= 4.0
            if time.process_time() > deadline:
                break
        if not improved:
            break
    return values, cost


def _variants(problem: _Problem, u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """
    Shapes near ``u``: each integer parameter on :data:`SECOND_COUNTS` log-spaced values, and
    :data:`SECOND_PERTURBED` copies moved by a normal step of :data:`SECOND_SPREAD` in the unit box.
    """
    rows = []
    for k, p in enumerate(problem.free):
        if p.integer:
            for value in np.unique(np.round(np.geomspace(p.low, p.high, SECOND_COUNTS))):
                row = u.copy()
                row[k] = p.to_unit(value)
                rows.append(row)
    rows += list(np.clip(u + rng.normal(0.0, SECOND_SPREAD, (SECOND_PERTURBED, u.size)), 0.0, 1.0))
    return np.array(rows)


def _distinct_indices(U: np.ndarray, scores: np.ndarray, count: int, spacing: float = DISTINCT_STARTS) -> list[int]:
    """The best-scoring rows of ``U``, each farther than ``spacing`` (max norm) from those before it."""
    chosen: list[int] = []
    for index in np.argsort(scores):
        if all(np.max(np.abs(U[index] - U[c])) > spacing for c in chosen):
            chosen.append(int(index))
        if len(chosen) == count:
            break
    return chosen


def _distinct(U: np.ndarray, scores: np.ndarray, count: int, spacing: float = DISTINCT_STARTS) -> list[np.ndarray]:
    """The rows of :func:`_distinct_indices`."""
    return [U[k] for k in _distinct_indices(U, scores, count, spacing)]


def _threaded_scan(problem: _Problem, shapes: np.ndarray, around: np.ndarray | None = None,
                   span: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """
    :meth:`_Problem.scale_scan` with its rows split over :data:`SCAN_THREADS` threads (numpy's array
    operations and the FFT release the GIL): the scan's wall time on a multi-core machine.
    """
    threads = min(SCAN_THREADS, len(shapes) // SCAN_BATCH)
    if threads <= 1:
        return problem.scale_scan(shapes, around=around, span=span)
    from concurrent.futures import ThreadPoolExecutor

    parts = np.array_split(np.arange(len(shapes)), threads)
    with ThreadPoolExecutor(threads) as pool:
        results = list(pool.map(lambda rows: problem.scale_scan(
            shapes[rows], around=None if around is None else np.asarray(around)[rows], span=span), parts))
    return np.concatenate([r[0] for r in results]), np.concatenate([r[1] for r in results])


def _scan_best(problem: _Problem, shapes: np.ndarray, progress: Callable[[float], None] | None = None,
               chunk: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Each shape at its best scale of :meth:`_Problem.scale_scan`, and that score."""
    shapes = shapes.copy()
    scores = np.empty(len(shapes))
    for start in range(0, len(shapes), chunk):
        block, grid = _threaded_scan(problem, shapes[start : start + chunk])
        best = np.argmin(block, axis=1)
        shapes[start : start + chunk] = problem.at_scale(shapes[start : start + chunk], grid[np.arange(len(block)), best])
        scores[start : start + chunk] = block[np.arange(len(block)), best]
        if progress is not None:
            progress(min(1.0, (start + chunk) / len(shapes)))
    return shapes, scores


def _scan_descent(problem: _Problem, U: np.ndarray, scores: np.ndarray, rng: np.random.Generator,
                  progress: Callable[[float], None] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """
    A (1 + lambda) evolution of each row of ``U`` (unit rows at their best scale, ``scores`` theirs): per
    step of :data:`DESCENT_SIGMAS`, :data:`DESCENT_SAMPLES` normal moves of its shape, each at its best scale
    within :data:`DESCENT_SPAN` of the row's (:meth:`_Problem.scale_scan`'s window); the best move replaces
    the row when it scores lower. The scan takes the period out of the landscape, whose remaining basins
    are some 0.01 of the box wide in the thickness share and a few times that in the indices and count:
    wider than a local refinement reaches, narrower than the first pass samples.
    """
    U, scores = U.copy(), scores.copy()
    scale = problem.scale_index
    p = problem.free[scale]
    rows = len(U)
    for step, sigma in enumerate(DESCENT_SIGMAS):
        moves = np.clip(np.repeat(U, DESCENT_SAMPLES, axis=0) + rng.normal(0.0, sigma, (rows * DESCENT_SAMPLES, U.shape[1])), 0.0, 1.0)
        around = np.repeat(p.from_unit(U[:, scale]), DESCENT_SAMPLES)
        block, grid = _threaded_scan(problem, moves, around=around, span=DESCENT_SPAN)
        best = np.argmin(block, axis=1)
        move_scores = block[np.arange(len(block)), best].reshape(rows, DESCENT_SAMPLES)
        winners = np.argmin(move_scores, axis=1)
        better = move_scores[np.arange(rows), winners] < scores
        j = (np.arange(rows) * DESCENT_SAMPLES + winners)[better]
        U[better] = problem.at_scale(moves[j], grid[j, best[j]])
        scores[better] = block[j, best[j]]
        if progress is not None:
            progress((step + 1) / len(DESCENT_SIGMAS))
    return U, scores


def design(
    model_name: str,
    targets: Sequence[Target],
    ranges: Mapping[str, tuple[float, float]],
    fixed: Mapping[str, float] | None = None,
    seed: int = 0,
    samples: int = FIRST_PASS_SAMPLES,
    starts: int = LOCAL_STARTS,
    progress: Callable[[float, str], None] | None = None,
    cancelled: Callable[[], bool] | None = None,
    guesses: Sequence[Mapping[str, float]] = (),
    tries: int = 1,
) -> DesignResult:
    """
    The structure whose converged colours come closest (least squares of CIEDE2000) to ``targets``.

    Parameters
    ----------
    model_name : str
        A key of :data:`DESIGN_MODELS` (the material's ``# model:``).
    targets : sequence of Target
        Colours at angles in [0, 90) degrees.
    ranges : mapping
        Each design parameter's box (the material's declared ``min``, ``max``).
    fixed : mapping, optional
        Parameters held at a value inside their range; the others are searched.
    seed : int
        The first pass's Sobol scrambling: the same seed gives the same design.
    samples, starts : int
        Candidates of the first pass; distinct starts refined on the coarse model.
    progress : callable, optional
        ``progress(fraction, stage)``, for a UI.
    cancelled : callable, optional
        Polled between batches; ``True`` raises :class:`DesignCancelled`.
    guesses : sequence of mapping, optional
        Structures (every design parameter by name; fixed ones take their fixed values; clipped to the
        box) that join the first pass's shapes, each at its best scale like them: a structure known to be
        close, such as the material's current one.
    tries : int
        Searches at most: after one that leaves a target above :data:`REACHED_DELTA_E`, another from a
        fresh first pass (seed + :data:`TRY_SEED_STRIDE` k) with the best structure so far among its
        guesses, so that each try also walks on from the last (an iterated search with restarts); the best
        result is returned, its times and evaluations summed over the tries.

    Returns
    -------
    DesignResult
        Achieved colours from :func:`explorer.physics.bragg.reference_rgb` (or the film's), whatever the
        search used.
    """
    if not (isinstance(tries, int) and tries >= 1):
        raise DesignError(f"tries = {tries!r}: give a whole number of searches, at least 1")
    start_time, start_cpu = time.perf_counter(), time.process_time()
    best: DesignResult | None = None
    evaluations = 0
    for k in range(tries):
        def report(fraction, stage, k=k):
            if progress is not None:
                progress((k + fraction) / tries, stage if tries == 1 else f"try {k + 1} of {tries}: {stage}")

        carried = [] if best is None else [best.values]
        result = _design_once(model_name, targets, ranges, fixed, seed + TRY_SEED_STRIDE * k, samples, starts, report,
                              cancelled, [*guesses, *carried])
        evaluations += result.evaluations
        if best is None or np.sum(result.delta_e2000 ** 2) < np.sum(best.delta_e2000 ** 2):
            best = result
        if np.all(best.delta_e2000 <= REACHED_DELTA_E):
            break
    if progress is not None:
        progress(1.0, "done")
    return replace(best, seconds=time.perf_counter() - start_time, cpu_seconds=time.process_time() - start_cpu,
                   evaluations=evaluations, tries=k + 1)


def _design_once(model_name, targets, ranges, fixed, seed, samples, starts, progress, cancelled, guesses) -> DesignResult:
    """One search of :func:`design` (its parameters), from the first pass on."""
    start_time, start_cpu = time.perf_counter(), time.process_time()
    model = design_model(model_name)
    fixed = dict(fixed or {})
    if not targets:
        raise DesignError("give at least one target colour")
    for t in targets:
        if not (np.isfinite(t.theta_deg) and 0.0 <= t.theta_deg < 90.0):
            raise DesignError(f"target angle {t.theta_deg:g}: must be in [0, 90) degrees")
        check_target_rgb(t.rgb, f"target at {t.theta_deg:g} degrees")
    box = parameter_box(model, ranges)
    names = {p.name for p in box}
    for name, value in fixed.items():
        if name not in names:
            raise DesignError(f"cannot fix {name}: not a design parameter of {model.name} ({', '.join(model.parameters)})")
        p = next(p for p in box if p.name == name)
        low = float(ranges[name][0])
        if not (np.isfinite(value) and low <= value <= p.high):
            raise DesignError(f"cannot fix {name} = {value:g}: outside its range [{low:g}, {p.high:g}]")
        if p.integer and value != round(value):
            raise DesignError(f"cannot fix {name} = {value:g}: {name} is a whole number")
    problem = _Problem(model, box, fixed, targets, cancelled)
    guessed = np.array([np.clip(problem.unit_row(_guess_values(model, g, fixed)), 0.0, 1.0) for g in guesses]).reshape(len(guesses), len(problem.free))
    report = progress or (lambda fraction, stage: None)
    stages: dict[str, float] = {}
    P = len(problem.free)

    if P == 0:
        values = problem.fine_values(np.zeros((1, 0)))
    else:
        from scipy.stats import qmc

        report(0.0, "first pass")
        scale = problem.scale_index
        chunk = 256
        if scale is not None:
            # 1-2. Space-filling shapes (Sobol), each at every value of its scale (the scale scan).
            # The first SCAN_SHAPES points of the next power of two (its balance, without scipy's warning).
            U = qmc.Sobol(P, scramble=True, seed=seed).random_base2(math.ceil(math.log2(SCAN_SHAPES)))[:SCAN_SHAPES]
            U = np.concatenate([guessed, U])
            U, scores = _scan_best(problem, U, lambda f: report(0.5 * f, "scale scan"))
            stages["scan"] = time.perf_counter() - start_time
            # 2b. The best distinct shapes walked downhill by the windowed scan.
            tops = _distinct_indices(U, scores, DESCENT_STARTS)
            U[tops], scores[tops] = _scan_descent(problem, U[tops], scores[tops], np.random.default_rng(seed),
                                                  lambda f: report(0.5 + 0.1 * f, "descent"))
            stages["descent"] = time.perf_counter() - start_time
        else:
            # 1. Space-filling first pass (Sobol) on the screening model.
            U = np.concatenate([guessed, qmc.Sobol(P, scramble=True, seed=seed).random(samples)])
            scores = np.empty(len(U))
            for start in range(0, len(U), chunk):
                scores[start : start + chunk] = problem.screen(U[start : start + chunk])
                report(0.6 * min(1.0, (start + chunk) / len(U)), "first pass")
            stages["first pass"] = time.perf_counter() - start_time
        # 3. Distinct starts, refined on the coarse model.
        chosen = _distinct(U, scores, starts)
        refined = []
        for k, u0 in enumerate(chosen):
            report(0.6 + 0.2 * k / len(chosen), "local refinement")
            u, cost = _refine_coarse(problem, u0, max_nfev=REFINE_NFEV)
            refined.append((cost, k, u))
            # A start that already matches every target to a small fraction of a unit needs no others.
            if k >= 1 and math.sqrt(cost / len(targets)) < GOOD_ENOUGH:
                break
        refined.sort(key=lambda item: item[0])
        if scale is not None and math.sqrt(refined[0][0] / len(targets)) >= GOOD_ENOUGH:
            # 3b. A second scan around the best: its integer count on a grid and perturbed shapes, each at
            # its best scale. Fringes make the count's basins narrow: a neighbouring count rarely wins by
            # refinement alone.
            report(0.75, "second scan")
            variants = _variants(problem, refined[0][2], np.random.default_rng(seed))
            variants, variant_scores = _scan_best(problem, variants)
            for k, u0 in enumerate(_distinct(variants, variant_scores, SECOND_STARTS, spacing=0.005)):
                u, cost = _refine_coarse(problem, u0, max_nfev=REFINE_NFEV)
                refined.append((cost, len(refined), u))
            refined.sort(key=lambda item: item[0])
        stages["coarse refinement"] = time.perf_counter() - start_time
        # 4. Polish the best on the converged model, within a time budget: the best as that model ranks
        # them, the coarse refinements' ends and the descent's shapes. The coarse model misjudges thick
        # stacks (their narrow bands fall between its samples): a shape the scan placed in the right basin
        # was refined out of it (the truth among the scan's shapes, docs/design_ceiling.py: 84 % of round
        # trips within 1 without this ranking, 90 % with it).
        best = None
        deadline = time.process_time() + POLISH_SECONDS
        pool = np.array([u for _, _, u in refined] + (list(U[tops]) if scale is not None else []))
        # Distinct ones: the second scan's refinements often end in the first's basin.
        polished = _distinct(pool, np.array([problem.fine_cost(u) for u in pool]), POLISHED, spacing=POLISH_DISTINCT)
        for k, u in enumerate(polished):
            report(0.8 + 0.2 * k / POLISHED, "polish")
            values, cost = _polish(problem, u, max_nfev=20, deadline=deadline)
            if best is None or cost < best[1]:
                best = (values, cost)
            if time.process_time() > deadline or best[1] < problem.polished_cost:
                break
        values = best[0]
        stages["polish"] = time.perf_counter() - start_time
    achieved = problem.fine_rgb(values, final=True)
    report(1.0, "done")
    return DesignResult(
        model=model.name,
        values=_reported_values(problem, values),
        targets=list(targets),
        achieved_rgb=achieved,
        delta_e2000=problem.delta_e(achieved),
        seconds=time.perf_counter() - start_time,
        cpu_seconds=time.process_time() - start_cpu,
        evaluations=problem.evaluations,
        stages=stages,
    )


def _reported_values(problem: _Problem, values: Mapping[str, float]) -> dict[str, float]:
    """
    The design values as reported: integers whole, and a free host found below its threshold (any value
    there means "the host is n1", the same colours) at its range's lower end, the file's canonical "no
    host", rather than an arbitrary number that reads like an index.
    """
    model = problem.model
    out = {k: (int(round(values[k])) if problem.box[k].integer else float(values[k])) for k in model.parameters}
    host = model.host_parameter
    if host is not None and host not in problem.fixed and out[host] < model.host_threshold:
        out[host] = float(min(problem.box[host].low, out[host]))
    return out


def _guess_values(model: DesignModel, guess: Mapping[str, float], fixed: Mapping[str, float]) -> dict[str, float]:
    """A guessed structure's design values (fixed ones override), checked: every parameter, finite."""
    missing = [name for name in model.parameters if name not in guess and name not in fixed]
    if missing:
        raise DesignError(f"a guessed structure lacks {', '.join(missing)}")
    values = {name: float(guess[name]) for name in model.parameters if name in guess}
    bad = [name for name, value in values.items() if not np.isfinite(value)]
    if bad:
        raise DesignError(f"a guessed structure's {bad[0]} is not a finite number")
    return {**values, **fixed}


def forward_rgb(model_name: str, values: Mapping[str, float], theta_deg: ArrayLike) -> np.ndarray:
    """The converged colours of a structure at angles (degrees): what :func:`design` reports as achieved."""
    model = design_model(model_name)
    return model.converged(values, np.cos(np.radians(np.asarray(theta_deg, dtype=np.float64))), final=True)


def _reachable(model_name: str, theta_deg: float, ranges: Mapping[str, tuple[float, float]],
               fixed: Mapping[str, float] | None, samples: int, seed: int) -> tuple[_Problem, np.ndarray]:
    """The problem at one angle and its ``samples`` scrambled-Sobol unit rows (:func:`reachable_structures`)."""
    from scipy.stats import qmc

    model = design_model(model_name)
    problem = _Problem(model, parameter_box(model, ranges), dict(fixed or {}), [Target(float(theta_deg), (0.5, 0.5, 0.5))], None)
    return problem, qmc.Sobol(max(len(problem.free), 1), scramble=True, seed=seed).random(samples)[:, : len(problem.free)]


def reachable_structures(model_name: str, ranges: Mapping[str, tuple[float, float]], fixed: Mapping[str, float] | None = None,
                         samples: int = 4096, seed: int = 0) -> dict[str, np.ndarray]:
    """
    ``samples`` structures spread over the box (scrambled Sobol over the free parameters, the search's unit
    box), as arrays of design values; integer parameters (``N``) whole, since a fractional count has
    colours no stack has.
    """
    problem, U = _reachable(model_name, 0.0, ranges, fixed, samples, seed)
    return problem.values(U, whole=True)


def reachable_chromaticities(model_name: str, theta_deg: float, ranges: Mapping[str, tuple[float, float]],
                             fixed: Mapping[str, float] | None = None, samples: int = 4096, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """
    The chromaticities ``(x, y)`` and luminances ``Y`` of structures spread over the box
    (:func:`reachable_structures`, coarse model) at one angle: the colours a Bragg mirror (or film) can
    make there.

    Returns
    -------
    xy : ndarray (M, 2)
    Y : ndarray (M,)
    """
    problem, U = _reachable(model_name, theta_deg, ranges, fixed, samples, seed)
    rgb = problem.coarse_rgb(U, whole=True)[:, 0]
    xyz = colorimetry.rgb_to_xyz(rgb)
    total = np.maximum(xyz.sum(axis=-1), 1e-12)
    return np.stack([xyz[:, 0] / total, xyz[:, 1] / total], axis=-1), xyz[:, 1]


#: The round trip's target angles (degrees).
ROUND_TRIP_ANGLES = (0.0, 15.0, 30.0, 45.0, 60.0)


def random_structure(model_name: str, ranges: Mapping[str, tuple[float, float]], rng: np.random.Generator) -> dict[str, float]:
    """
    A structure drawn from the declared ranges: uniform in each, except the parameters the search walks on
    a log scale (``N``: log-uniform, so that thin stacks are drawn as often as thick ones) and integers
    rounded.
    """
    model = design_model(model_name)
    values = {}
    for p in parameter_box(model, ranges):
        value = float(p.from_unit(rng.uniform())) if p.name in model.integer_parameters else float(rng.uniform(*ranges[p.name]))
        values[p.name] = float(p.whole(value))
    return values


def round_trip(model_name: str, ranges: Mapping[str, tuple[float, float]], count: int, seed: int = 0,
               angles: Sequence[float] = ROUND_TRIP_ANGLES, report: Callable[[int, dict, DesignResult], None] | None = None,
               draw_ranges: Mapping[str, tuple[float, float]] | None = None, tries: int = 1) -> list[DesignResult]:
    """
    Designs for ``count`` reachable targets: random structures (:func:`random_structure`, seeded, from
    ``draw_ranges``, default ``ranges``), their converged colours at ``angles`` as targets, each designed
    back from its colours alone over ``ranges`` (in at most ``tries`` searches, :func:`design`).
    """
    rng = np.random.default_rng(seed)
    results = []
    for k in range(count):
        truth = random_structure(model_name, {**ranges, **(draw_ranges or {})}, rng)
        colours = forward_rgb(model_name, truth, angles)
        targets = [Target(float(a), tuple(float(c) for c in rgb)) for a, rgb in zip(angles, colours)]
        result = design(model_name, targets, ranges, seed=seed + k, tries=tries)
        results.append(result)
        if report is not None:
            report(k, truth, result)
    return results
