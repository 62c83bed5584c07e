"""
The inverse method of Bati, Barla & Pacanowski (2021): from BRDF lobe properties at normal incidence
(energy ``R_k``, RGB, and variance ``sigma_k``) to layer stacks of Belcour's model (:mod:`explorer.physics.lobes`).

- Single lobes (Section 5): 1-layer dielectric (Eq. 7, or the FGD term inverted numerically when
  rough) and conductor (Eqs. 8-10) lobes; 2-layer lobes with absorption and roughness (Algorithm 1,
  Eqs. 11-16), coloured media (Sec. 5.2.3: the channel of largest ``R'_12`` sets ``alpha_2``), conductor
  base (Sec. 5.2.4).
- Multiple lobes (Section 6): top-down stacking, Algorithms 2-5 (Eqs. 17-20).
- Equivalence classes as sampled curves and regions with validity masks (:func:`one_layer_class`,
  :func:`two_layer_class`), and a point of a class to a stack (:func:`invert_lobes` with ``choices``).

Everything is computed with the forward model's own terms (its FGD tables and the statistics of the
stack above, :func:`explorer.physics.lobes.stack_statistics`), so that ``forward(inverse(lobes))`` reproduces
the requested energies exactly and the variances exactly on the channel that sets each roughness.

What is ours: the default point of each class (the upper dielectric root with ``tau = 0`` on the
brightest channel; for a 2-layer lobe, ``eta_{n+1}`` at the middle of ``N_1``; for a conductor, the
middle of ``[eta_min^c, eta_max^c]``, as the paper's Figure 16); rough conductors are inverted through
the forward model's ``E F(cbar_d)`` rather than Eq. 8 (equal for smooth ones).

References
----------
Bati, M., Barla, P., Pacanowski, R. (2021). An inverse method for the exploration of layered material
appearance. ACM TOG 40(4). Sections 5-6, Algorithms 1-5.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import lobes
from explorer.physics.lobes import ETA_MAX, roughness_from_variance, variance_from_roughness

#: Bisection steps of the numerical inversions (relative precision 2^-60).
BISECTION_STEPS = 60
#: The smallest conductor reflectance with kappa >= eta (Sec. 5.1.2: 3 - 2 sqrt 2).
CONDUCTOR_R_MIN = 3.0 - 2.0 * np.sqrt(2.0)
KAPPA_MAX = 100.0


class InverseError(ValueError):
    """Lobes no stack achieves: one line naming the constraint that fails and the achievable range."""


@dataclass
class Lobe:
    """A lobe's properties at normal incidence: ``energy`` (RGB), ``variance``, its ``layers`` (1 or 2) and ``base``."""

    energy: np.ndarray
    variance: float
    layers: int = 1
    base: str = "dielectric"  # "conductor" only for the bottom lobe

    def __post_init__(self):
        self.energy = np.broadcast_to(np.asarray(self.energy, dtype=np.float64), (3,)).copy()
        self.variance = float(self.variance)


def _mean(F) -> np.ndarray:
    return np.asarray(F).mean(axis=0)


def fgd_normal(alpha: ArrayLike, eta_ratio: ArrayLike) -> np.ndarray:
    """The forward model's dielectric FGD at normal incidence (s = p there), for relative index ``eta_ratio``."""
    return _mean(lobes.fgd_dielectric(1.0, alpha, eta_ratio))


def _bisect(function, lo, hi, target):
    """Solve ``function(x) = target`` for increasing ``function`` on [lo, hi] (arrays broadcast)."""
    lo, hi = np.broadcast_arrays(np.asarray(lo, float), np.asarray(hi, float))
    lo, hi = lo.copy(), hi.copy()
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        above = function(mid) > target
        hi, lo = np.where(above, mid, hi), np.where(above, lo, mid)
    return 0.5 * (lo + hi)


def dielectric_roots(R: ArrayLike, alpha: ArrayLike, eta_0: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """
    The indices ``eta_1`` (lower, upper) with ``FGD(0, alpha, eta_1 / eta_0) = R`` (Eq. 7 when smooth; the
    FGD term inverted numerically when rough, Sec. 5.1.1); NaN where a root leaves the table's range.
    """
    R = np.asarray(R, dtype=np.float64)
    top = fgd_normal(alpha, lobes.ETA_TABLE_MAX)
    bottom = fgd_normal(alpha, 1.0 / lobes.ETA_TABLE_MAX)
    upper = _bisect(lambda x: fgd_normal(alpha, x), 1.0, lobes.ETA_TABLE_MAX, R)
    lower = _bisect(lambda x: -fgd_normal(alpha, x), 1.0 / lobes.ETA_TABLE_MAX, 1.0, -R)
    return np.where(R <= bottom, eta_0 * lower, np.nan), np.where(R <= top, eta_0 * upper, np.nan)


def conductor_fgd_normal(alpha: ArrayLike, eta: ArrayLike, kappa: ArrayLike) -> np.ndarray:
    return _mean(lobes.fgd_conductor(1.0, alpha, eta, kappa))


def conductor_bounds(R: ArrayLike, eta_0: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 9-10: ``(eta_min^c, eta_max^c)`` of a conductor of normal reflectance ``R`` under ``eta_0`` (NaN max below 3 - 2 sqrt 2)."""
    R = np.asarray(R, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        eta_max = eta_0 * (1 + R + np.sqrt(6 * R - 1 - R * R)) / (2 * (1 - R))
    return eta_0 * (1 - R) / (1 + R), eta_max


def conductor_kappa(R: ArrayLike, alpha: ArrayLike, eta: ArrayLike, eta_0: float = 1.0) -> np.ndarray:
    """
    ``kappa`` with the forward model's conductor FGD at normal incidence equal to ``R`` (Eq. 8 when
    smooth), for ``eta`` under ``eta_0``; NaN where no ``kappa`` reaches it.
    """
    R, eta = np.broadcast_arrays(np.asarray(R, float), np.asarray(eta, float))
    ratio = eta / eta_0
    kappa = _bisect(lambda k: conductor_fgd_normal(alpha, ratio, k), 0.0, KAPPA_MAX, R) * eta_0
    reached = np.abs(conductor_fgd_normal(alpha, ratio, kappa / eta_0) - R) < 1e-9
    return np.where(reached, kappa, np.nan)


# --------------------------------------------------------------------------------------------------
# Equivalence classes (the app panel's curves and regions)


@dataclass
class OneLayerClass:
    """
    A 1-layer lobe's class under ``eta_0`` (Fig. 4). Dielectric: the roots ``eta_1`` (per channel of
    ``R e^{2 tau_0}``, i.e. on the brightest channel) and their validity. Conductor: per channel the curve
    ``kappa(eta)`` over ``eta`` samples, valid between Eqs. 10 and 9 (kappa >= eta).
    """

    kind: str
    alpha: float
    eta: np.ndarray
    kappa: np.ndarray | None
    valid: np.ndarray
    bounds: tuple


def one_layer_class(
    energy: ArrayLike, variance: ArrayLike, eta_0: float = 1.0, base: str = "dielectric", samples: int = 64, eta_max: float = ETA_MAX,
) -> OneLayerClass:
    energy = np.broadcast_to(np.asarray(energy, float), (3,))
    alpha = float(roughness_from_variance(variance))
    if base == "dielectric":
        lower, upper = dielectric_roots(energy.max(), alpha, eta_0)
        eta = np.array([lower, upper])
        valid = np.isfinite(eta) & (eta >= 1.0) & (eta <= eta_max)
        return OneLayerClass("dielectric", alpha, eta, None, valid, (1.0, eta_max))
    eta_min, eta_top = conductor_bounds(energy, eta_0)
    eta = np.linspace(0.0, 1.0, samples)[:, None] * np.nan_to_num(eta_top, nan=eta_min) * 1.2 + 1e-3
    kappa = conductor_kappa(energy[None, :], alpha, eta, eta_0)
    valid = np.isfinite(kappa) & (eta >= eta_min) & (kappa >= eta)
    return OneLayerClass("conductor", alpha, eta, kappa, valid, (eta_min, eta_top))


@dataclass
class TwoLayerClass:
    """
    A 2-layer lobe's constrained class (Algorithm 1, Figs. 7, 9, 11, 12) on an ``(eta_1, eta_2)`` grid:
    ``tau_1`` (RGB, Eq. 13), ``alpha_1`` and ``alpha_2`` (Eq. 15, ``alpha_2`` per ``eta_1``; NaN where
    ``sigma_12 < 0``), and the masks: ``valid_channel`` (per channel: ``tau_1 >= 0``, ``sigma_12 >= 0``),
    ``valid`` (all channels: the intersection of Sec. 5.2.3). ``N_1``: the ``eta_1`` with a valid point.
    """

    eta_0: float
    alpha_1: float
    eta_1: np.ndarray
    eta_2: np.ndarray
    alpha_2: np.ndarray
    tau_1: np.ndarray
    valid_channel: np.ndarray
    valid: np.ndarray

    @property
    def N_1(self) -> np.ndarray:
        return self.eta_1[self.valid.any(axis=1)]

    def N_2(self, i: int) -> np.ndarray:
        return self.eta_2[self.valid[i]]


def two_layer_energy_bounds(variance: ArrayLike, eta_0: float = 1.0, samples: int = 48, eta_max: float = ETA_MAX) -> tuple[float, float]:
    """
    ``[R_min, R_max]``: the achromatic energies a 2-layer lobe of ``variance`` reaches under ``eta_0``
    with ``eta_1, eta_2`` in ``[1, eta_max]`` and no absorption (Sec. 5.2.1: the adding equation on the
    bounds of N_1), scanned on a grid; 0.53 at most in air for ``eta_max = 4`` (smooth).
    """
    alpha = float(roughness_from_variance(variance))
    eta_1, eta_2 = np.meshgrid(*(np.linspace(1.0, eta_max, samples),) * 2, indexing="ij")
    R_01 = fgd_normal(alpha, eta_1 / eta_0)
    # The forward model at normal incidence, both interfaces of roughness alpha (Eqs. 2 and 6).
    sigma_T_01 = variance_from_roughness(0.5 * np.abs(1.0 - eta_0 / eta_1) * alpha)
    R_12 = fgd_normal(roughness_from_variance(sigma_T_01 + variance_from_roughness(alpha)), eta_2 / eta_1)
    R_02 = R_01 + (1.0 - R_01) ** 2 * R_12 / (1.0 - R_12 * R_01)
    return float(R_02.min()), float(R_02.max())


def tau_0_range(energy: ArrayLike, variance: ArrayLike, eta_0: float = 1.0, eta_max: float = ETA_MAX) -> tuple[float, float]:
    """
    Eq. 16: ``T_0 = 1/2 log([R_min, R_max] / R_02)`` intersected with ``tau_0 >= 0``: the optical depths of
    the medium above a 2-layer lobe (a lobe under others) that leave its energy achievable. Coloured
    energies: the brightest channel. Empty (NaN, NaN) when ``R_02 > R_max``.
    """
    R = float(np.max(energy))
    R_min, R_max = two_layer_energy_bounds(variance, eta_0, eta_max=eta_max)
    if R > R_max:
        return (np.nan, np.nan)
    low = 0.5 * np.log(R_min / R) if R_min > 0.0 else -np.inf
    return (max(0.0, low), 0.5 * np.log(R_max / R))


def two_layer_point_stack(cls: TwoLayerClass, i: int, j: int) -> lobes.Stack:
    """The stack at grid point ``(eta_1[i], eta_2[j])`` of a 2-layer class (raises where it is not valid)."""
    if not cls.valid[i, j]:
        raise InverseError(f"(eta_1, eta_2) = ({cls.eta_1[i]:.4g}, {cls.eta_2[j]:.4g}) is outside the constrained class (tau_1 >= 0, sigma_12 >= 0)")
    return lobes.make_stack([cls.eta_1[i], cls.eta_2[j]], [cls.alpha_1, cls.alpha_2[i]], tau=[cls.tau_1[i, j]], eta_0=cls.eta_0)


def _lobe_terms(statistics, energy, variance, eta_0, eta_n):
    """Eqs. 18-19: ``R'_{n,n+l}`` (RGB) and ``sigma^R_{n,n+l}`` (RGB) under the statistics of the stack above."""
    s = statistics
    with np.errstate(divide="ignore", invalid="ignore"):
        R_prime = 1.0 / (s.T_0n * s.T_n0 / energy + s.R_n0)  # Eq. 18
    R_prime = np.where(energy > 0.0, R_prime, 0.0)
    sigma_R = (1.0 - s.R_n0 * R_prime) * (eta_0 / eta_n * (variance - s.sigma_T_n0) - s.sigma_T_0n) \
        - s.R_n0 * R_prime * s.sigma_R_n0  # Eq. 19
    return R_prime, sigma_R


def two_layer_class(
    energy: ArrayLike, variance: ArrayLike, eta_0: float = 1.0, samples: int = 48, eta_max: float = ETA_MAX,
) -> TwoLayerClass:
    """Algorithm 1 (``tau_0 = 0``) on a ``samples x samples`` grid of ``[1, eta_max]^2``."""
    energy = np.broadcast_to(np.asarray(energy, float), (3,))
    alpha_1 = float(roughness_from_variance(variance))
    eta_1 = np.linspace(1.0, eta_max, samples)
    eta_2 = np.linspace(1.0, eta_max, samples)
    alpha_2 = np.full(samples, np.nan)
    tau_1 = np.full((samples, samples, 3), np.nan)
    for i, e1 in enumerate(eta_1):
        stack = lobes.make_stack([e1], [alpha_1], eta_0=eta_0)
        statistics = lobes.stack_statistics(stack, 1)
        R_prime, sigma_R = _lobe_terms(statistics, energy - statistics.R_0n, variance, eta_0, e1)  # Eq. 11, 15
        c = int(np.argmax(R_prime))  # Sec. 5.2.3: the brightest channel sets alpha_2
        if not (sigma_R[c] >= 0.0 and np.all(R_prime >= 0.0) and np.all(R_prime <= 1.0)):
            continue
        alpha_2[i] = roughness_from_variance(sigma_R[c])
        alpha_eff = roughness_from_variance(sigma_R[c] + statistics.sigma_T_0n[c])  # alpha'_2
        R_12 = fgd_normal(alpha_eff, eta_2 / e1)
        with np.errstate(divide="ignore", invalid="ignore"):
            tau_1[i] = 0.5 * np.log(R_12[:, None] / R_prime[None, :])  # Eq. 13
    valid_channel = np.isfinite(tau_1) & (tau_1 >= 0.0)
    return TwoLayerClass(eta_0, alpha_1, eta_1, eta_2, alpha_2, tau_1, valid_channel, valid_channel.all(axis=-1))


# --------------------------------------------------------------------------------------------------
# Multiple lobes, top-down (Section 6)


@dataclass
class _Partial:
    """A stack under construction: interfaces top first (eta, alpha), media below them (tau)."""

    eta: list = field(default_factory=list)
    alpha: list = field(default_factory=list)
    tau: list = field(default_factory=list)
    base_kappa: np.ndarray | None = None
    tir: bool = False

    def stack(self) -> lobes.Stack:
        taus = self.tau + [0.0] * max(0, len(self.eta) - 1 - len(self.tau))
        return lobes.make_stack(self.eta, self.alpha, tau=taus[: max(0, len(self.eta) - 1)], base_kappa=self.base_kappa, tir=self.tir)

    def eta_below(self) -> float:
        return float(np.mean(self.eta[-1])) if self.eta else 1.0


def _fmt(values) -> str:
    values = np.atleast_1d(values)
    return f"{values[0]:.4g}" if np.ptp(values) == 0 else "[" + ", ".join(f"{v:.4g}" for v in values) + "]"


def _base_statistics(partial: _Partial):
    if not partial.eta:
        return lobes.stack_statistics(lobes.make_stack([1.0], [0.0]), 0)  # nothing above: T = 1, R = 0
    return lobes.stack_statistics(partial.stack(), len(partial.eta))


def _achievable_energy(statistics, R_max) -> np.ndarray:
    """The largest lobe energy (Eq. 17) with ``R'`` at most ``R_max``."""
    return statistics.T_0n * R_max * statistics.T_n0 / (1.0 - R_max * statistics.R_n0)


def _least_variance(statistics, R_prime, c: int, eta_n: float) -> float:
    """The smallest lobe variance the layers above allow on channel ``c``: Eq. 19 with ``sigma^R = 0``."""
    s = statistics
    x = s.R_n0[c] * R_prime[c]
    return float(s.sigma_T_n0[c] + eta_n * (s.sigma_T_0n[c] + x * s.sigma_R_n0[c] / (1.0 - x)))


def conductor_albedo(alpha: ArrayLike) -> float:
    """``E(0, alpha)``: the forward model's rough conductor FGD at normal incidence is ``E F(cbar_d)``."""
    return float(_mean(lobes.fgd_conductor(1.0, alpha, 1.0, 1e9)))


def _one_layer(partial: _Partial, k: int, R_prime, sigma_R, statistics, base: str, choice: dict, probe: bool = False):
    """Algorithm 4: the interface below medium m = len(partial.eta), from ``R'_{m,m+1}`` and ``sigma^R_{m,m+1}``."""
    m = len(partial.eta)
    eta_m = partial.eta_below()
    c = int(np.argmax(R_prime))  # Sec. 5.2.3: the brightest channel sets the roughness
    sigma = float(sigma_R[c])
    if sigma < -1e-12:
        raise InverseError(f"lobe {k}: variance is below what the layers above give (constraint sigma^R >= 0, Eq. 19): "
                           f"achievable sigma >= {_least_variance(statistics, R_prime, c, eta_m):.4g}")
    sigma = max(sigma, 0.0)
    alpha = float(roughness_from_variance(sigma))
    alpha_eff = float(roughness_from_variance(sigma + statistics.sigma_T_0n[c]))  # Algorithm 4's FGD roughness
    if base == "conductor":
        tau_m = np.asarray(choice.get("tau", 0.0), dtype=np.float64) * np.ones(3) if m > 0 else np.zeros(3)
        R_target = R_prime * np.exp(2.0 * tau_m)  # Eq. 13 the other way
        E = conductor_albedo(alpha_eff)
        eta_min, eta_top = conductor_bounds(np.minimum(R_target / E, 1.0 - 1e-12), eta_m)  # Eqs. 9-10
        if np.any(~np.isfinite(eta_top)) or np.any(R_target >= E):
            raise InverseError(
                f"lobe {k}: its energy needs a conductor reflectance {_fmt(R_target)}{' below the layers above' if m else ''}; "
                f"conductors with kappa >= eta reach [{CONDUCTOR_R_MIN * E:.4f}, {E:.4f}) at this roughness (Sec. 5.1.2)")
        if probe:
            return  # some eta in [eta_min^c, eta_max^c] reaches it
        if "eta" in choice:
            eta = np.broadcast_to(np.asarray(choice["eta"], float), (3,)).copy()
        else:
            eta = eta_min + float(choice.get("t", 0.5)) * (eta_top - eta_min)
        kappa = conductor_kappa(R_target, alpha_eff, eta, eta_m)
        if np.any(~np.isfinite(kappa)):
            raise InverseError(f"lobe {k}: no conductor of index eta = {_fmt(eta)} reaches reflectance {_fmt(R_target)}")
        partial.eta.append(eta)
        partial.alpha.append(alpha)
        partial.base_kappa = kappa
        if m > 0:
            partial.tau.append(tau_m)
        return
    # Dielectric: eta_{m+1} chosen (default: the root with tau_m = 0 on the brightest channel), tau_m by Eq. 13.
    if m == 0 and np.ptp(R_prime) > 1e-9:
        raise InverseError(f"lobe {k}: a 1-layer dielectric lobe in air is achromatic (no absorbing medium above it): energy {_fmt(R_prime)} is coloured")
    R_max = max(float(fgd_normal(alpha_eff, ETA_MAX / eta_m)), float(fgd_normal(alpha_eff, 1.0 / eta_m)))
    if R_prime[c] > R_max + 1e-12:
        reach = R_max if m == 0 else float(_achievable_energy(statistics, R_max)[c])
        energy = R_prime[c] if m == 0 else float(_achievable_energy(statistics, R_prime)[c])
        raise InverseError(
            f"lobe {k}: energy {energy:.4g} is not achievable by a 1-layer dielectric lobe (eta in [1, {ETA_MAX:g}]): "
            f"achievable energy in [0, {reach:.4g}]")
    if probe:
        return  # R'_c <= R_max: a root in [1, eta_max] exists (FGD is continuous), tau >= 0 on the other channels
    if "eta" in choice and m == 0:
        roots = [r for r in dielectric_roots(R_prime[c], alpha_eff, eta_m) if np.isfinite(r) and 1.0 <= r <= ETA_MAX]
        if not any(abs(float(choice["eta"]) - r) < 1e-6 for r in roots):
            raise InverseError(f"lobe {k}: in air the energy fixes eta (Eq. 7, no absorbing medium above): eta in {{{', '.join(f'{r:.6g}' for r in roots)}}}, not {float(choice['eta']):.6g}")
    if "eta" in choice:
        eta = float(choice["eta"])
    else:
        roots = [r for r in dielectric_roots(R_prime[c], alpha_eff, eta_m)[::-1] if np.isfinite(r) and 1.0 <= r <= ETA_MAX]
        if not roots:
            raise InverseError(f"lobe {k}: no index in [1, {ETA_MAX:g}] reflects {R_prime[c]:.4g} under eta = {eta_m:.4g}")
        eta = float(roots[0])  # the upper root when valid (Eq. 7)
    if not 1.0 <= eta <= ETA_MAX:
        raise InverseError(f"lobe {k}: eta = {eta:.4g} is outside [1, {ETA_MAX:g}]")
    R = float(fgd_normal(alpha_eff, eta / eta_m))
    with np.errstate(divide="ignore"):
        tau = 0.5 * np.log(R / R_prime)  # Eq. 13 / Algorithm 4
    if m > 0 and np.any(tau < -1e-9):
        raise InverseError(f"lobe {k}: eta = {eta:.4g} reflects {R:.4g}, less than {_fmt(R_prime)} needed below the layers (constraint tau >= 0): choose another eta")
    partial.eta.append(eta)
    partial.alpha.append(alpha)
    if m > 0:
        partial.tau.append(np.maximum(tau, 0.0))


def _default_eta_top(partial: _Partial, k, energy_target, variance, statistics_above, choice):
    """The middle of N_1 (Eq. 12) for a 2-layer lobe's top interface, scanned on a grid."""
    valid = []
    for eta in np.linspace(1.0, ETA_MAX, 49):
        trial = _Partial(list(partial.eta), list(partial.alpha), list(partial.tau), None, partial.tir)
        try:
            _two_layer(trial, k, energy_target, variance, statistics_above, {**choice, "eta_top": eta}, probe=True)
            valid.append(eta)
        except InverseError:
            pass
    if not valid:
        raise InverseError(f"lobe {k}: no 2-layer configuration (eta in [1, {ETA_MAX:g}]) reaches energy {_fmt(energy_target)} with variance {variance:.4g} (N_1 is empty)")
    return float(valid[len(valid) // 2])


def _two_layer(partial: _Partial, k, lobe_energy, variance, statistics_above, choice, probe=False):
    """Algorithm 5: a 2-layer lobe under the ``partial`` stack (``lobe_energy`` = R_k, the lobe's own energy)."""
    n = len(partial.eta)
    eta_n = partial.eta_below()
    R_prime, sigma_R = _lobe_terms(statistics_above, lobe_energy, variance, 1.0, eta_n)
    c = int(np.argmax(R_prime))
    if sigma_R[c] < -1e-12:
        raise InverseError(f"lobe {k}: variance {variance:.4g} is below what the layers above give (constraint sigma^R >= 0, Eq. 19): "
                           f"achievable sigma >= {_least_variance(statistics_above, R_prime, c, eta_n):.4g}")
    eta_top = choice.get("eta_top")
    if eta_top is None:
        eta_top = _default_eta_top(partial, k, lobe_energy, variance, statistics_above, choice)
    tau_n = np.asarray(choice.get("tau_top", 0.0), float) * np.ones(3) if n > 0 else np.zeros(3)
    partial.eta.append(float(eta_top))
    partial.alpha.append(float(roughness_from_variance(max(sigma_R[c], 0.0))))
    if n > 0:
        partial.tau.append(tau_n)
    statistics = _base_statistics(partial)  # n + 1 interfaces
    R_bar = statistics_above.R_0n + lobe_energy - statistics.R_0n  # Eq. 20
    if np.any(R_bar <= 0.0):
        raise InverseError(f"lobe {k}: the top interface eta = {eta_top:.4g} alone reflects more than the lobe's energy {_fmt(lobe_energy)}")
    R_prime_2, sigma_R_2 = _lobe_terms(statistics, R_bar, variance, 1.0, float(eta_top))
    if np.any(R_prime_2 > 1.0):
        raise InverseError(f"lobe {k}: energy {_fmt(lobe_energy)} needs R' > 1 below eta = {eta_top:.4g}")
    base = choice.get("base", "dielectric")
    _one_layer(partial, k, R_prime_2, sigma_R_2, statistics, base, {} if probe else {key: v for key, v in choice.items() if key in ("eta", "t", "tau")}, probe)


def invert_lobes(lobe_list: Sequence[Lobe], choices: Sequence[Mapping[str, float]] | None = None, tir: bool = False) -> lobes.Stack:
    """
    Algorithm 2: the stack whose lobes at normal incidence are ``lobe_list`` (top first; :class:`Lobe`),
    each 1- or 2-layer, the last one possibly on a conductor base.

    ``choices[k]`` (optional, per lobe) picks a point of its equivalence class: ``eta`` (the index below
    a 1-layer lobe or below a 2-layer lobe's bottom interface), ``tau`` (that interface's medium above,
    for lobes under others), ``eta_top`` and ``tau_top`` (a 2-layer lobe's top interface and the medium
    above it), ``t`` in [0, 1] (a conductor's place between Eqs. 10 and 9). Unset, the defaults above.

    ``tir``: the stack's TIR term (:class:`explorer.physics.lobes.Stack`); the statistics of the layers above
    then come with it, so the lobes are still reproduced exactly.

    Raises :class:`InverseError` (one line) naming the constraint that fails and the achievable range.
    """
    choices = list(choices or [{}] * len(lobe_list))
    partial = _Partial(tir=tir)
    total = np.zeros(3)
    for k, (lobe, choice) in enumerate(zip(lobe_list, choices), start=1):
        if not 0.0 <= lobe.variance < lobes.VARIANCE_MAX:  # beyond, f(alpha) would clamp it (alpha = 1)
            raise InverseError(f"lobe {k}: variance sigma = {lobe.variance:.4g} must lie in [0, {lobes.VARIANCE_MAX:g})")
        if np.any(lobe.energy <= 0.0) or np.any(lobe.energy >= 1.0):
            raise InverseError(f"lobe {k}: energy {_fmt(lobe.energy)} must lie in (0, 1)")
        if lobe.layers not in (1, 2):
            raise InverseError(f"lobe {k}: layers must be 1 or 2, got {lobe.layers}")
        if lobe.base == "conductor" and k != len(lobe_list):
            raise InverseError(f"lobe {k}: only the bottom lobe may have a conductor base")
        if total.max() + lobe.energy.max() >= 1.0:
            raise InverseError(f"lobe {k}: energies sum to {_fmt(total + lobe.energy)}: the lobes' energies must sum below 1")
        if len(partial.eta) + lobe.layers > lobes.MAX_INTERFACES:
            raise InverseError(f"lobe {k}: more than {lobes.MAX_INTERFACES} interfaces")
        statistics = _base_statistics(partial)
        eta_n = partial.eta_below()
        if lobe.layers == 1:
            R_prime, sigma_R = _lobe_terms(statistics, lobe.energy, lobe.variance, 1.0, eta_n)  # Algorithm 3
            if np.any(R_prime > 1.0) or np.any(R_prime < 0.0):
                best = _achievable_energy(statistics, 1.0)
                raise InverseError(f"lobe {k}: energy {_fmt(lobe.energy)} exceeds what reaches it through the layers above: achievable < {_fmt(best)}")
            _one_layer(partial, k, R_prime, sigma_R, statistics, lobe.base, dict(choice))
        else:
            _two_layer(partial, k, lobe.energy, lobe.variance, statistics, {**choice, "base": lobe.base})
        total = total + lobe.energy
    return partial.stack()


def forward_lobes(stack: lobes.Stack, layers: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    """The stack's lobes at normal incidence merged as ``layers`` (1 or 2 interfaces each): energies ``(K, 3)``, variances ``(K, 3)``."""
    energies, variances = lobes.lobes(stack, 1.0)
    out_e, out_v, i = [], [], 0
    for l in layers:
        out_e.append(energies[i:i + l].sum(axis=0))
        out_v.append((energies[i:i + l] * variances[i:i + l]).sum(axis=0) / np.maximum(energies[i:i + l].sum(axis=0), 1e-300))
        i += l
    return np.array(out_e), np.array(out_v)


@dataclass
class LobeClass:
    """
    Lobe ``k``'s equivalence class under the stack the lobes above it give (Sec. 6; the app panel's view
    of a stacked lobe), sampled with validity masks:

    - ``"dielectric"`` (1-layer): over ``eta`` (the index below the lobe's interface), ``tau`` ``(B, 3)``
      the optical depth above it (Algorithm 4's ``tau_m``; in air only the roots of Eq. 7 are valid).
    - ``"conductor"`` (1-layer): over ``eta`` ``(B, 3)``, ``kappa`` ``(B, 3)``, valid between Eqs. 10 and 9.
    - ``"two_layer"``: over ``(eta_top, eta)``, ``tau`` ``(A, B, 3)`` between the two interfaces (Eq. 13),
      ``alpha`` ``(A,)`` the bottom roughness (Eq. 19); ``eta_top``'s valid rows are N_1, a row's valid
      ``eta`` N_2 (Eqs. 12, 14).
    - ``"two_layer_conductor"``: ``valid`` ``(A,)`` over ``eta_top`` (N_1); the conductor's own class then
      follows Sec. 5.2.4.

    A valid point is a stack through :func:`invert_lobes` with the choices ``{"eta": ...}`` (1-layer) or
    ``{"eta_top": ..., "eta": ...}`` (2-layer) for lobe ``k``.
    """

    kind: str
    eta_top: np.ndarray | None
    eta: np.ndarray
    kappa: np.ndarray | None
    tau: np.ndarray | None
    alpha: np.ndarray
    valid: np.ndarray


def lobe_class(
    lobe_list: Sequence[Lobe], k: int, choices: Sequence[Mapping[str, float]] | None = None, samples: int = 48, tir: bool = False,
) -> LobeClass:
    """The class of lobe ``k`` (1-based) of ``lobe_list`` once lobes ``1..k-1`` are set (by ``choices``)."""
    choices = list(choices or [{}] * len(lobe_list))
    above = invert_lobes(lobe_list[: k - 1], choices[: k - 1], tir=tir) if k > 1 else None
    partial = _Partial(tir=tir)
    if above is not None:
        for i in range(1, above.count + 1):
            partial.eta.append(float(above.eta[i].mean()))
            partial.alpha.append(float(above.alpha[i]))
            if i < above.count:
                partial.tau.append(above.tau[i])
        partial.tau.append(np.asarray(choices[k - 1].get("tau_top", 0.0), float) * np.ones(3))  # the medium above lobe k
    lobe = lobe_list[k - 1]
    statistics = _base_statistics(partial)
    eta_n = partial.eta_below()
    grid = np.linspace(1.0, ETA_MAX, samples)
    R_prime, sigma_R = _lobe_terms(statistics, lobe.energy, lobe.variance, 1.0, eta_n)
    c = int(np.argmax(R_prime))
    sigma = max(float(sigma_R[c]), 0.0)
    if lobe.layers == 1:
        alpha_eff = float(roughness_from_variance(sigma + statistics.sigma_T_0n[c]))
        alpha = np.array(roughness_from_variance(sigma))
        if lobe.base == "conductor":
            E = conductor_albedo(alpha_eff)
            R_target = R_prime
            eta_min, eta_top = conductor_bounds(np.minimum(R_target / E, 1.0 - 1e-12), eta_n)
            eta = np.linspace(0.0, 1.0, samples)[:, None] * np.nan_to_num(eta_top, nan=eta_min) * 1.2 + 1e-3
            kappa = conductor_kappa(R_target[None, :], alpha_eff, eta, eta_n)
            valid = np.isfinite(kappa) & (eta >= eta_min) & (kappa >= eta) & (sigma_R[c] >= 0.0)
            return LobeClass("conductor", None, eta, kappa, None, alpha, valid)
        with np.errstate(divide="ignore", invalid="ignore"):
            tau = 0.5 * np.log(fgd_normal(alpha_eff, grid / eta_n)[:, None] / R_prime[None, :])
        if not partial.eta:  # in air, no medium above: tau must vanish (Eq. 7's roots)
            roots = [r for r in dielectric_roots(R_prime[c], alpha_eff, 1.0) if np.isfinite(r) and 1.0 <= r <= ETA_MAX]
            return LobeClass("dielectric", None, np.array(roots), None, np.zeros((len(roots), 3)), alpha,
                             np.full(len(roots), np.ptp(R_prime) < 1e-9 and sigma_R[c] >= 0.0))
        valid = np.all(tau >= 0.0, axis=-1) & (sigma_R[c] >= 0.0)
        return LobeClass("dielectric", None, grid, None, tau, alpha, valid)
    alpha_bottom = np.full(samples, np.nan)
    tau = np.full((samples, samples, 3), np.nan)
    valid_rows = np.zeros(samples, bool)
    for i, eta_top in enumerate(grid):
        trial = _Partial(list(partial.eta), list(partial.alpha), list(partial.tau), None, tir)
        trial.eta.append(float(eta_top))
        trial.alpha.append(float(roughness_from_variance(sigma)))
        try:
            statistics_2 = _base_statistics(trial)
        except lobes.StackError:
            continue
        R_bar = statistics.R_0n + lobe.energy - statistics_2.R_0n  # Eq. 20
        if np.any(R_bar <= 0.0) or sigma_R[c] < 0.0:
            continue
        R_prime_2, sigma_R_2 = _lobe_terms(statistics_2, R_bar, lobe.variance, 1.0, float(eta_top))
        c2 = int(np.argmax(R_prime_2))
        if sigma_R_2[c2] < 0.0 or np.any(R_prime_2 > 1.0):
            continue
        alpha_bottom[i] = roughness_from_variance(sigma_R_2[c2])
        alpha_eff = float(roughness_from_variance(sigma_R_2[c2] + statistics_2.sigma_T_0n[c2]))
        if lobe.base == "conductor":
            E = conductor_albedo(alpha_eff)
            valid_rows[i] = bool(np.all(R_prime_2 < E) and np.all(np.isfinite(conductor_bounds(np.minimum(R_prime_2 / E, 1 - 1e-12), eta_top)[1])))
            continue
        with np.errstate(divide="ignore", invalid="ignore"):
            tau[i] = 0.5 * np.log(fgd_normal(alpha_eff, grid / eta_top)[:, None] / R_prime_2[None, :])
    if lobe.base == "conductor":
        return LobeClass("two_layer_conductor", grid, grid, None, None, alpha_bottom, valid_rows)
    valid = np.isfinite(tau).all(axis=-1) & np.all(np.nan_to_num(tau, nan=-1.0) >= 0.0, axis=-1)
    return LobeClass("two_layer", grid, grid, None, tau, alpha_bottom, valid)
