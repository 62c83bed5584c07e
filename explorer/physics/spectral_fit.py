"""
The structure of a natural Bragg mirror from a measured reflectance spectrum: least squares in R(lambda).

A global pass evaluates a scrambled Sobol sample of the free continuous parameters for each candidate
cell count ``N`` on a coarse subset of the measured wavelengths (vectorised over the sample), then the
best few are refined by ``scipy.optimize.least_squares`` (bounded, trust-region reflective) on every
measured wavelength, ``N`` held and then moved by one while it improves. The model is the exact
unpolarised reflectance of :func:`explorer.physics.natural.mirror_spectrum`. A disordered mirror (``sigma``
fixed above 0, or free) is searched so on the ordered mirror, then its best :data:`DISORDERED_REFINED` ends are
refined on the ensemble mean over :data:`FIT_REALISATIONS` seeded realisations at the coarse wavelengths (a
smooth function of the structure: the realisations' noise is fixed by their seed), ``sigma`` with them when free.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import multilayer
from explorer.physics.dispersion import Dispersion, complex_index
from explorer.physics.natural import NaturalMirror, mirror_spectrum

#: The free parameters' ranges (N apart).
RANGES = {"Lambda": (80.0, 1000.0), "delta": (0.05, 0.95), "n1": (1.0, 2.0), "n2": (1.2, 2.5), "k1": (0.0, 0.3), "k2": (0.0, 0.3)}
#: The cell counts the global pass tries when N is free.
N_CANDIDATES = tuple(range(1, 31))
N_MAX = 60
#: Sobol samples of the continuous parameters per cell count, and the wavelengths the global pass uses.
GLOBAL_SAMPLES = 1024
COARSE_WAVELENGTHS = 48
#: The disorder's box when free, and the realisations and starts of the disordered refinement.
SIGMA_RANGE = (0.0, 0.3)
FIT_REALISATIONS = 256
DISORDERED_REFINED = 2
#: Starts kept per cell count, and refined by least squares (the best over every count).
PER_COUNT = 2
REFINED = 12


@dataclass
class SpectrumFit:
    """The fitted mirror, its values (``--set`` names), the RMS of ``R_fit - R_measured`` and the fitted spectrum."""

    mirror: NaturalMirror
    values: dict
    rms: float
    wavelength_nm: np.ndarray
    measured: np.ndarray
    fitted: np.ndarray
    seconds: float


def _reflectance_batch(n_host, n1, n2, d1, d2, N: int, wavelength_nm, sin_theta) -> np.ndarray:
    """Unpolarised R of mirrors broadcast over ``(samples, wavelengths)`` (all arrays broadcastable), ``N`` cells each."""
    shape = np.broadcast_shapes(np.shape(n1), np.shape(n2), np.shape(d1), np.shape(d2), np.shape(wavelength_nm), np.shape(n_host))
    k0 = 2.0 * np.pi / wavelength_nm
    n_sin = n_host * sin_theta
    kh, k1, k2 = (multilayer.forward_kz(n, n_sin) for n in (n_host, n1, n2))
    total = np.zeros(shape)
    for pol in ("s", "p"):
        r12, _ = multilayer.interface(pol, n1, k1, n2, k2)  # from n1 above into n2 below
        r21, _ = multilayer.interface(pol, n2, k2, n1, k1)  # from n2 above into n1 below
        rh2, _ = multilayer.interface(pol, n_host, kh, n2, k2)
        e1, e2 = np.exp(2j * k0 * k1 * d1), np.exp(2j * k0 * k2 * d2)
        r = np.zeros(shape, dtype=np.complex128)  # below the last n1 layer: the n1 base
        for cell in range(N):
            r = (r21 + r * e1) / (1.0 + r21 * r * e1)  # through n1 (d1), entered from the n2 above
            top = rh2 if cell == N - 1 else r12
            r = (top + r * e2) / (1.0 + top * r * e2)  # through n2 (d2), from n1 or the host
        total += np.abs(r) ** 2
    return 0.5 * total


def _model(free: list[str], fixed: dict, vector: np.ndarray, wavelength_nm: np.ndarray):
    """Indices and thicknesses of samples ``vector`` (``(samples, len(free))``) at ``wavelength_nm``, broadcast."""
    value = {name: vector[:, i:i + 1] for i, name in enumerate(free)}
    get = lambda name, default=0.0: value[name] if name in value else fixed.get(name, default)  # noqa: E731
    n1 = complex_index(fixed["n1"], 0.0, wavelength_nm) if isinstance(fixed.get("n1"), Dispersion) else get("n1") + 0j
    n2 = complex_index(fixed["n2"], 0.0, wavelength_nm) if isinstance(fixed.get("n2"), Dispersion) else get("n2") + 0j
    n1 = n1 + 1j * get("k1")
    n2 = n2 + 1j * get("k2")
    nh = fixed.get("nh")
    host = n1.real + 0j if nh is None else complex_index(nh, 0.0, wavelength_nm)
    Lambda, delta = get("Lambda"), get("delta")
    return host, n1, n2, delta * Lambda, (1.0 - delta) * Lambda


def mirror_of(free: list[str], fixed: dict, vector: ArrayLike, N: int) -> NaturalMirror:
    values = {**{k: v for k, v in fixed.items() if k in ("n1", "n2", "nh", "k1", "k2", "Lambda", "delta", "sigma")},
              **{name: float(x) for name, x in zip(free, vector)}}
    return NaturalMirror(N=int(N), **values)


def fit_spectrum(wavelength_nm: ArrayLike, measured: ArrayLike, theta_deg: float, fixed: dict, seed: int = 0,
                 free_sigma: bool = False) -> SpectrumFit:
    """
    The mirror whose unpolarised reflectance at ``theta_deg`` best matches ``measured`` at ``wavelength_nm``.

    ``fixed`` holds values not fitted (``n1``/``n2``/``nh`` may be media; ``N`` an integer; ``nh`` absent:
    the host is ``n1``; ``sigma`` absent: 0 unless ``free_sigma``); the others in :data:`RANGES` and ``N`` are free.
    """
    from scipy.optimize import least_squares
    from scipy.stats import qmc

    start = time.perf_counter()
    wavelength_nm = np.asarray(wavelength_nm, dtype=np.float64)
    measured = np.asarray(measured, dtype=np.float64)
    fixed = dict(fixed)
    free = [name for name in RANGES if name not in fixed]
    low = np.array([RANGES[n][0] for n in free])
    high = np.array([RANGES[n][1] for n in free])
    sin_theta = float(np.sin(np.radians(theta_deg)))
    coarse = np.unique(np.linspace(0, wavelength_nm.size - 1, min(COARSE_WAVELENGTHS, wavelength_nm.size)).round().astype(int))
    w_coarse = wavelength_nm[coarse][np.newaxis, :]
    counts = (int(fixed["N"]),) if "N" in fixed else N_CANDIDATES
    sample = low + (high - low) * qmc.Sobol(d=len(free), scramble=True, seed=seed).random(GLOBAL_SAMPLES) if free else np.zeros((1, 0))
    candidates = []
    for N in counts:
        host, n1, n2, d1, d2 = _model(free, fixed, sample, w_coarse)
        R = _reflectance_batch(host, n1, n2, d1, d2, N, w_coarse, sin_theta)
        cost = np.sqrt(np.mean((R - measured[coarse]) ** 2, axis=1))
        for i in np.argsort(cost)[:PER_COUNT]:  # the best few of each N: starts from different basins
            candidates.append((float(cost[i]), N, sample[i]))
    candidates.sort(key=lambda c: c[0])

    def residual(vector, N):
        host, n1, n2, d1, d2 = _model(free, fixed, vector[np.newaxis, :], wavelength_nm[np.newaxis, :])
        return _reflectance_batch(host, n1, n2, d1, d2, N, wavelength_nm[np.newaxis, :], sin_theta)[0] - measured

    def refine(vector, N):
        if not free:
            return vector, float(np.sqrt(np.mean(residual(vector, N) ** 2)))
        solution = least_squares(residual, np.clip(vector, low, high), bounds=(low, high), args=(N,), x_scale=high - low,
                                 max_nfev=200 * len(free))
        return solution.x, float(np.sqrt(np.mean(solution.fun ** 2)))

    best, ends = (np.inf, None, None), []
    for _, N, vector in candidates[:REFINED]:
        vector, rms = refine(vector, N)
        if "N" not in fixed:  # move N by one while it improves (the band's width and fringes follow N)
            for step in (-1, 1):
                M = N + step
                while 1 <= M <= N_MAX:
                    trial, trial_rms = refine(vector, M)
                    if trial_rms >= rms - 1e-6:
                        break
                    vector, rms, N = trial, trial_rms, M
                    M += step
        ends.append((rms, N, vector))
        if rms < best[0]:
            best = (rms, N, vector)
    rms, N, vector = best
    mirror = mirror_of(free, fixed, vector, N)
    values = {name: float(x) for name, x in zip(free, vector)}
    if free_sigma or fixed.get("sigma", 0.0) > 0.0:
        ends = [best] + [(r, M, v) for r, M, v in ends if v is not vector]
        mirror, values = _refine_disordered(ends[:DISORDERED_REFINED], free, fixed, free_sigma, wavelength_nm[coarse],
                                            measured[coarse], theta_deg)
    fitted = mirror_spectrum(mirror, wavelength_nm, [theta_deg])["R"][0]
    if "N" not in fixed:
        values["N"] = int(mirror.N)
    return SpectrumFit(mirror, values, float(np.sqrt(np.mean((fitted - measured) ** 2))), wavelength_nm, measured, fitted,
                       time.perf_counter() - start)


def _refine_disordered(ends, free: list[str], fixed: dict, free_sigma: bool, wavelength_nm: np.ndarray,
                       measured: np.ndarray, theta_deg: float) -> tuple[NaturalMirror, dict]:
    """
    The ordered fit's best ``ends`` ``(rms, N, vector)`` refined on the disordered mirror's ensemble mean (``N``
    held; ``sigma`` free from 0.05 when ``free_sigma``): the best mirror and its fitted values.
    """
    from scipy.optimize import least_squares

    from explorer.physics.natural import _unpolarised

    names = free + (["sigma"] if free_sigma else [])
    low = np.array([SIGMA_RANGE[0] if n == "sigma" else RANGES[n][0] for n in names])
    high = np.array([SIGMA_RANGE[1] if n == "sigma" else RANGES[n][1] for n in names])
    cos_theta = np.array([[np.cos(np.radians(theta_deg))]])
    base = {k: v for k, v in fixed.items() if k != "N"}

    def mirror(vector, N):
        return mirror_of(names, base, vector, N)

    def residual(vector, N):
        m = mirror(vector, N)
        thicknesses = np.array([m.d2, m.d1] * int(m.N))
        realised = multilayer.disordered_thicknesses(thicknesses, m.sigma, FIT_REALISATIONS)
        return _unpolarised(m, wavelength_nm[np.newaxis, :], cos_theta, realised)[0] - measured

    best = (np.inf, None, None)
    for _, N, vector in ends:
        start = np.concatenate([vector, [0.05]]) if free_sigma else np.asarray(vector)
        if start.size:
            solution = least_squares(residual, np.clip(start, low, high), bounds=(low, high), args=(N,),
                                     x_scale=np.maximum(high - low, 1e-9), max_nfev=30 * len(names))
            x, cost = solution.x, float(np.mean(solution.fun ** 2))
        else:
            x, cost = start, float(np.mean(residual(start, N) ** 2))
        if cost < best[0]:
            best = (cost, N, x)
    _, N, x = best
    values = {name: float(v) for name, v in zip(names, x)}
    return mirror(x, N), values
