"""
Belcour's (2018) atomic decomposition of layered materials, as recalled by Bati, Barla & Pacanowski
(2021), Section 4: a stack of rough GGX interfaces between absorbing media, over a dielectric or
conducting base, is rendered as a sum of GGX lobes whose energies ``R_k(theta)`` and variances
``sigma_k(theta)`` follow from adding equations (Eqs. 2, 4-6); the BRDF is Eq. 3.

Notation (the paper's Table 1): medium ``i`` (``i = 0`` the ambient, air) has the index
``eta_i + i kappa_i`` and, between interfaces ``i`` and ``i + 1``, the optical depth at normal incidence
``tau_i`` (RGB); interface ``i`` (``i = 1..n``, from the top) has the GGX roughness ``alpha_i``.
Dielectric indices are achromatic; only the base (medium ``n``) may be a coloured conductor.

What is ours, where the papers leave a choice:

- Energies are carried per polarisation (s and p) through the adding equations and averaged at the
  end, so that smooth stacks equal an incoherent transfer-matrix computation (``tmm.inc_tmm``) at every
  angle; averaging the Fresnel terms first is off by up to 2e-2 at 60-85 degrees. At normal incidence,
  where the inverse method works, both are the same.
- A rough dielectric interface's directional albedo ``FGD`` is the exact Fresnel term plus a tabulated
  correction ``FGD - F`` over (cos theta, alpha, eta) (``luts/lobes_fgd_correction.npy``), exact for
  smooth interfaces whatever the interpolation. A rough conductor's is ``E(theta, alpha) F(cbar_d)``,
  the GGX lobe's albedo times the Fresnel term at its mean half-angle cosine
  (``luts/lobes_ggx_moments.npy``), which Bati et al. (Sec. 5.1.2) observe is nearly Fresnel's at
  normal incidence: a 3D table instead of Belcour's 4D one. Both tables' ``alpha = 0`` rows are the
  closed-form smooth limit (``E = 1``, ``cbar_d = cos theta``, correction 0:
  :func:`explorer.physics.lobes_fgd.smooth_lobe_moments`), so a smooth interface is exact Fresnel at
  every angle, grazing and total internal reflection included.
- Variances are per RGB channel (Bati et al., footnote 1) and each is expressed in the medium where it
  is observed: the Jacobian ``j = eta_{i+1} cos theta_{i+1} / (eta_i cos theta_i)`` of Belcour's
  implementation maps medium ``i + 1`` to medium ``i``; at normal incidence ``j_{0n} = eta_n / eta_0`` as
  in Eqs. 5 and 19.
- The TIR term of Belcour's model is not used (Bati et al., Sec. 5.2: negligible at normal incidence);
  light beyond a critical angle does not reach the media below.

References
----------
Belcour, L. (2018). Efficient rendering of layered materials using an atomic decomposition with
statistical operators. ACM TOG 37(4).
Bati, M., Barla, P., Pacanowski, R. (2021). An inverse method for the exploration of layered material
appearance. ACM TOG 40(4). Sections 4-6, Table 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import microfacet
from explorer.physics.lobes_fgd import (  # the Fresnel terms and table coordinates the model reads
    ETA_TABLE_MAX, FGD_ALPHA_COUNT, FGD_COS_COUNT, FGD_ETA_COUNT, _axis, fgd_cos_coordinate, fresnel_sp,
)

#: Upper bound on dielectric indices (Bati et al. use eta_max = 4 "for illustration").
ETA_MAX = 4.0
#: Interfaces of the material file and its shader.
MAX_INTERFACES = 4

#: Directions are clamped to this cosine in the adding equations (the Jacobian divides by it).
COS_MIN = 1e-4


# --------------------------------------------------------------------------------------------------
# Roughness and variance


#: The variance of alpha = 1 (f diverges there): finite, so that 0 x it stays 0, in float32 too.
VARIANCE_MAX = 1e6


def variance_from_roughness(alpha: ArrayLike) -> np.ndarray:
    """Belcour's roughness-to-variance mapping ``f(alpha) = alpha^1.1 / (1 - alpha^1.1)`` (Bati et al., Sec. 4), at most :data:`VARIANCE_MAX`."""
    a = np.clip(np.asarray(alpha, dtype=np.float64), 0.0, 1.0) ** 1.1
    return np.minimum(a / np.maximum(1.0 - a, 1.0 / VARIANCE_MAX), VARIANCE_MAX)


def roughness_from_variance(sigma: ArrayLike) -> np.ndarray:
    """``f^{-1}(sigma) = (sigma / (1 + sigma))^(1 / 1.1)``; 0 for ``sigma <= 0``, 1 from :data:`VARIANCE_MAX` on."""
    s = np.clip(np.asarray(sigma, dtype=np.float64), 0.0, VARIANCE_MAX)
    return np.where(s >= VARIANCE_MAX, 1.0, (s / (1.0 + s)) ** (1.0 / 1.1))


def fgd_dielectric(cos_theta: ArrayLike, alpha: ArrayLike, eta: ArrayLike) -> np.ndarray:
    """
    ``FGD_{s,p}`` of a rough dielectric interface of relative index ``eta`` (achromatic or per channel):
    the exact Fresnel term plus the (unpolarised) tabulated correction, interpolated trilinearly in
    (:func:`fgd_cos_coordinate`, alpha, log eta), split
    between s and p in proportion to their Fresnel reflectances where it lowers FGD below F, to their
    transmittances where it raises it (both stay in [0, 1], their mean is the unpolarised FGD). Leading axis 2.
    """
    from explorer.tables import luts

    table = luts.load("lobes_fgd_correction")
    cos_theta, alpha, eta = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (cos_theta, alpha, eta)))
    ic, fc = _axis(fgd_cos_coordinate(cos_theta, eta), FGD_COS_COUNT, 0.0, 1.0)
    ia, fa = _axis(alpha, FGD_ALPHA_COUNT, 0.0, 1.0)
    log_eta = np.log(np.maximum(eta, 1e-12)) / np.log(ETA_TABLE_MAX)
    ie, fe = _axis(log_eta, FGD_ETA_COUNT, -1.0, 1.0)
    correction = 0.0
    for de, we in ((0, 1.0 - fe), (1, fe)):
        for da, wa in ((0, 1.0 - fa), (1, fa)):
            for dc, wc in ((0, 1.0 - fc), (1, fc)):
                correction = correction + (we * wa * wc) * table[ie + de, ia + da, ic + dc]
    # The unpolarised FGD = F + correction, shared by s and p: where the rough interface reflects less than
    # the smooth one, in proportion to their reflectances F_{s,p} (both stay >= 0 where one alone would go
    # negative, near Brewster's angle); where it reflects more, in proportion to their transmittances
    # 1 - F_{s,p} (both stay <= 1: scaling F_s up overshot 1 just past a critical angle, where F_s ~ 1 and
    # F_p ~ 0, and two such interfaces facing each other made the adding equations' 1 - R R' vanish).
    F = fresnel_sp(cos_theta, eta)
    mean = F.mean(axis=0)
    target = np.clip(mean + correction, 0.0, 1.0)  # the table's interpolation, kept an albedo
    less = target <= mean
    reflected = F * np.where(less & (mean > 0.0), target / np.where(mean > 0.0, mean, 1.0), 1.0)
    transmitted = (1.0 - F) * np.where(~less, (1.0 - target) / np.where(mean < 1.0, 1.0 - mean, 1.0), 1.0)
    return np.clip(np.where(less, reflected, 1.0 - transmitted), 0.0, 1.0)  # rounding only: |r|^2 = 1 + 4e-16 under TIR


def fgd_conductor(cos_theta: ArrayLike, alpha: ArrayLike, eta: ArrayLike, kappa: ArrayLike) -> np.ndarray:
    """
    ``FGD_{s,p} ~ E(theta, alpha) F_{s,p}(cbar_d)`` of a rough conductor ``eta + i kappa`` (relative indices),
    bilinear in (cos theta, alpha); exactly ``F_{s,p}(cos theta)`` at ``alpha = 0`` (the table's smooth row,
    linear in cos theta, is reproduced by the interpolation).
    """
    from explorer.tables import luts

    table = luts.load("lobes_ggx_moments")
    cos_theta, alpha, eta, kappa = np.broadcast_arrays(
        *(np.asarray(v, dtype=np.float64) for v in (cos_theta, alpha, eta, kappa)))
    ic, fc = _axis(cos_theta, FGD_COS_COUNT, 0.0, 1.0)
    ia, fa = _axis(alpha, FGD_ALPHA_COUNT, 0.0, 1.0)
    moments = 0.0
    for da, wa in ((0, 1.0 - fa), (1, fa)):
        for dc, wc in ((0, 1.0 - fc), (1, fc)):
            moments = moments + (wa * wc) * table[:, ia + da, ic + dc]
    return np.clip(moments[0] * fresnel_sp(moments[1], eta, kappa), 0.0, 1.0)


# --------------------------------------------------------------------------------------------------
# Stacks


class StackError(ValueError):
    """A stack's parameters break a physical constraint (one line: which, and the achievable range)."""


@dataclass(frozen=True)
class Stack:
    """
    A layered material, indexed as in Bati et al.'s Table 1 (arrays over media ``i = 0..n``).

    eta, kappa : ``(n + 1, 3)``
        Index of medium ``i`` (``eta_0 + i kappa_0`` the ambient); ``kappa_i = 0`` except for a
        conducting base ``i = n``.
    alpha : ``(n + 1,)``
        ``alpha_i``, roughness of interface ``i`` (the top of medium ``i``); ``alpha_0`` is unused.
    tau : ``(n + 1, 3)``
        ``tau_i``, optical depth at normal incidence of medium ``i``; ``tau_0`` (the ambient) and
        ``tau_n`` (below the base) are unused.
    tir : bool
        Our TIR term: light going up through a rough interface is reflected by the FGD of its own (denser
        or not) side, ``FGD(cos theta_i, alpha, eta_{i-1} / eta_i)``, which holds the part of the lobe beyond
        the critical angle; off, Belcour's symmetric ``R_21 = R_12`` (Bati et al. do not use a TIR term).
        Smooth interfaces are the same either way (Stokes).
    """

    eta: np.ndarray
    kappa: np.ndarray
    alpha: np.ndarray
    tau: np.ndarray
    tir: bool = False

    @property
    def count(self) -> int:
        """The number of interfaces ``n``."""
        return self.alpha.shape[0] - 1

    @property
    def conductor(self) -> bool:
        return bool(np.any(self.kappa[-1] > 0.0))

    def as_dict(self) -> dict:
        """JSON-ready: one entry per interface, top first, with the medium below it."""
        layers = []
        for i in range(1, self.count + 1):
            layer = {"alpha": float(self.alpha[i])}
            if i == self.count and self.conductor:
                layer["eta"] = [float(v) for v in self.eta[i]]
                layer["kappa"] = [float(v) for v in self.kappa[i]]
            else:
                layer["eta"] = float(self.eta[i].mean()) if np.ptp(self.eta[i]) == 0 else [float(v) for v in self.eta[i]]
            if i < self.count:
                layer["tau"] = [float(v) for v in self.tau[i]]
            layers.append(layer)
        return {"eta_0": float(self.eta[0].mean()), "tir": self.tir, "interfaces": layers}


def _rgb(value) -> np.ndarray:
    return np.broadcast_to(np.asarray(value, dtype=np.float64), (3,)).copy()


def make_stack(
    eta: ArrayLike, alpha: ArrayLike, tau: ArrayLike | None = None, base_kappa: ArrayLike | None = None, eta_0: float = 1.0,
    tir: bool = False,
) -> Stack:
    """
    A stack from its interfaces, top first: ``eta[i - 1]`` (a number, or RGB for a conducting base),
    ``alpha[i - 1]``, ``tau[i - 1]`` the optical depth below interface ``i`` (RGB; ``n - 1`` entries, or
    ``n`` with the last ignored), ``base_kappa`` (RGB) for a conducting base, ``tir`` (:class:`Stack`).
    Checks the constraints.
    """
    count = len(eta)
    if count < 1 or len(alpha) != count:
        raise StackError(f"a stack needs as many roughnesses as interfaces (got {len(eta)} and {len(alpha)})")
    etas = np.stack([_rgb(eta_0)] + [_rgb(e) for e in eta])
    kappas = np.zeros_like(etas)
    if base_kappa is not None:
        kappas[-1] = _rgb(base_kappa)
    alphas = np.concatenate([[0.0], np.asarray(alpha, dtype=np.float64)])
    taus = np.zeros_like(etas)
    for i, t in enumerate(tau or ()):
        if i + 1 < count:
            taus[i + 1] = _rgb(t)
    stack = Stack(etas, kappas, alphas, taus, bool(tir))
    check_stack(stack)
    return stack


def check_stack(stack: Stack) -> Stack:
    """Raise :class:`StackError` (one line) where a parameter is outside its physical range."""
    if np.any(stack.kappa[-1] < 0.0):
        raise StackError(f"kappa_{stack.count} = {stack.kappa[-1].tolist()} must be >= 0")
    for i in range(1, stack.count + 1):
        a = stack.alpha[i]
        if not (np.isfinite(a) and 0.0 <= a <= 1.0):
            raise StackError(f"alpha_{i} = {a:g} is outside [0, 1]")
        if i < stack.count and np.any(stack.kappa[i] != 0.0):
            raise StackError(f"kappa_{i} must be 0: only the base (interface {stack.count}) may be a conductor")
        if not np.all(np.isfinite(stack.eta[i])) or np.any(stack.eta[i] <= 0.0):
            raise StackError(f"eta_{i} = {stack.eta[i].tolist()} must be positive")
        if (i < stack.count or not stack.conductor) and np.ptp(stack.eta[i]) > 0.0:
            raise StackError(f"eta_{i} = {stack.eta[i].tolist()} must be achromatic for a dielectric (a coloured index needs kappa > 0: a conductor base)")
        if i < stack.count and (np.any(stack.tau[i] < 0.0) or not np.all(np.isfinite(stack.tau[i]))):
            raise StackError(f"tau_{i} = {stack.tau[i].tolist()} must be >= 0")
    if np.any(stack.kappa[-1] < 0.0):
        raise StackError(f"kappa_{stack.count} = {stack.kappa[-1].tolist()} must be >= 0")
    return stack


@dataclass
class StackStatistics:
    """
    Belcour's statistics of the top ``n`` interfaces at one incidence (Bati et al., Fig. 13 right),
    polarisation-averaged, per RGB channel (arrays ``(..., 3)``): energies ``R_0n`` (reflected, seen from
    above), ``R_n0`` (seen from below, in medium ``n``), ``T_0n``, ``T_n0``; normalised variances
    ``sigma_R_0n`` (in medium 0), ``sigma_R_n0`` (in medium n), ``sigma_T_0n`` (downward, in medium n),
    ``sigma_T_n0`` (upward, in medium 0); ``j_0n`` maps a variance in medium n to medium 0;
    ``cos_n`` the direction's cosine in medium ``n``.
    """

    R_0n: np.ndarray
    R_n0: np.ndarray
    T_0n: np.ndarray
    T_n0: np.ndarray
    sigma_R_0n: np.ndarray
    sigma_R_n0: np.ndarray
    sigma_T_0n: np.ndarray
    sigma_T_n0: np.ndarray
    j_0n: np.ndarray
    cos_n: np.ndarray


def _safe_divide(a, b):
    return np.where(b > 0.0, a / np.where(b > 0.0, b, 1.0), 0.0)


def interface_fgd(stack: Stack, i: int, cos_theta: ArrayLike, alpha: ArrayLike) -> np.ndarray:
    """``FGD_{s,p}`` of interface ``i`` seen from medium ``i - 1`` (conductor or dielectric), ``(2, ..., 3)``."""
    ratio = stack.eta[i] / stack.eta[i - 1].mean()
    if i == stack.count and stack.conductor:
        return fgd_conductor(cos_theta, alpha, ratio, stack.kappa[i] / stack.eta[i - 1].mean())
    return fgd_dielectric(cos_theta, alpha, ratio)


def lobes_and_statistics(stack: Stack, cos_theta: ArrayLike, count: int | None = None) -> tuple[np.ndarray, np.ndarray, StackStatistics]:
    """
    The adding equations (Bati et al., Eqs. 2, 4-6; Belcour 2018) down to interface ``count``
    (default: all): the lobes' energies ``R_k`` and variances ``sigma_k``, ``(..., count, 3)`` each, and
    the :class:`StackStatistics` of the top ``count`` interfaces (seen from medium ``count``, below them,
    when ``count`` is not the base).

    Lobe ``k`` gathers the paths that reach interface ``k`` and no deeper (Eq. 3):
    ``R_k = T_0n R'_{n,n+1} T_n0 / (1 - R'_{n,n+1} R_n0)`` (Eq. 17, n = k - 1, ``R'`` attenuated by
    ``exp(-2 tau_n / cos theta_n)``), its variance
    ``sigma_T_n0 + j_0n (sigma_T_0n + sigma_R + m (sigma_R + sigma_R_n0))``, ``m = R' R_n0 / (1 - R' R_n0)``
    (Eq. 5, generalised as Eq. 19 inverts it).
    """
    check_stack(stack)
    count = stack.count if count is None else count
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), COS_MIN, 1.0)[..., None] * np.ones(3)
    shape = c.shape
    R_0n, R_n0 = np.zeros((2,) + shape), np.zeros((2,) + shape)
    T_0n, T_n0 = np.ones((2,) + shape), np.ones((2,) + shape)
    s_r0n, s_rn0, s_t0n, s_tn0 = (np.zeros(shape) for _ in range(4))
    j_0n = np.ones(shape)
    energies, variances = [], []
    for i in range(1, count + 1):
        conductor = i == stack.count and stack.conductor
        n12 = stack.eta[i].mean() / stack.eta[i - 1].mean()
        sin_t = np.sqrt(np.maximum(1.0 - c * c, 0.0)) / n12
        transmits = (sin_t < 1.0) & (not conductor)
        c_t = np.where(transmits, np.sqrt(np.maximum(1.0 - sin_t * sin_t, 0.0)), c)
        c_t = np.maximum(c_t, COS_MIN)
        attenuation = np.exp(-stack.tau[i - 1] / c) if i > 1 else np.ones(shape)  # medium i - 1, one way
        a2 = attenuation * attenuation
        alpha = stack.alpha[i]
        s_r12 = variance_from_roughness(alpha)
        s_t12 = variance_from_roughness(0.5 * abs(1.0 - 1.0 / n12) * alpha)  # Eq. 6
        s_t21 = variance_from_roughness(0.5 * abs(1.0 - n12) * alpha)
        alpha_eff = roughness_from_variance(s_t0n + s_r12)  # the light arrives blurred (Belcour; Alg. 1's alpha'_2)
        R12 = interface_fgd(stack, i, c, alpha_eff)
        T12 = np.zeros_like(R12) if conductor else 1.0 - R12
        if stack.tir and not conductor:
            R21 = np.where(transmits, fgd_dielectric(c_t, alpha_eff, 1.0 / n12), R12)  # seen from below
            T21 = 1.0 - R21
        else:
            R21, T21 = R12, T12  # Belcour's symmetric interface; exact for smooth ones
        j12 = np.where(transmits, c_t * n12 / c, 1.0)
        x = a2 * R12 * R_n0
        D = 1.0 - x
        E = T_0n * a2 * R12 * T_n0 / D  # Eqs. 2 and 17
        m_rr = (x / D).mean(axis=0)
        E_mean = E.mean(axis=0)
        sigma = s_tn0 + j_0n * (s_t0n + s_r12 + m_rr * (s_r12 + s_rn0))  # Eqs. 4-5
        energies.append(E_mean)
        variances.append(sigma)
        R_new = R_0n + E
        s_r0n = _safe_divide(R_0n.mean(axis=0) * s_r0n + E_mean * sigma, R_new.mean(axis=0))
        R_0n = R_new
        if conductor:
            break
        # Below interface i (the next iteration's medium i): only transmitted light goes on.
        m_ri0 = T21 * a2 * R_n0 * T12 / D
        R_n0_new = R21 + m_ri0
        s_t0n_new = (s_t0n + m_rr * (s_r12 + s_rn0)) / j12 + s_t12
        s_tn0 = s_tn0 + j_0n * (s_t21 + m_rr * (s_r12 + s_rn0))
        s_rn0 = _safe_divide(
            R21.mean(axis=0) * s_r12 + m_ri0.mean(axis=0) * (s_t12 + (s_t21 + s_rn0 + m_rr * (s_r12 + s_rn0)) / j12),
            R_n0_new.mean(axis=0),
        )
        s_t0n = s_t0n_new
        T_0n = np.where(transmits, T_0n * attenuation * T12 / D, 0.0)
        T_n0 = np.where(transmits, T21 * attenuation * T_n0 / D, 0.0)
        R_n0 = R_n0_new
        j_0n = j_0n * j12
        c = np.where(transmits, c_t, c)
        if i == count:
            break
    statistics = StackStatistics(
        R_0n.mean(axis=0), R_n0.mean(axis=0), T_0n.mean(axis=0), T_n0.mean(axis=0),
        s_r0n, s_rn0, s_t0n, s_tn0, j_0n, c,
    )
    return np.stack(energies, axis=-2), np.stack(variances, axis=-2), statistics


def lobes(stack: Stack, cos_theta: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(R_k, sigma_k)`` of every lobe at incidence ``cos_theta``: arrays ``(..., n, 3)``."""
    energies, variances, _ = lobes_and_statistics(stack, cos_theta)
    return energies, variances


def stack_statistics(stack: Stack, count: int, cos_theta: float = 1.0) -> StackStatistics:
    """The statistics of the top ``count`` interfaces (Algorithm 3's input, normal incidence by default)."""
    if count == 0:
        shape = np.shape(cos_theta) + (3,)
        zero, one = np.zeros(shape), np.ones(shape)
        return StackStatistics(zero, zero, one, one, zero, zero, zero, zero, one, np.broadcast_to(np.asarray(cos_theta, float)[..., None], shape))
    return lobes_and_statistics(stack, cos_theta, count)[2]


def reflectance(stack: Stack, cos_theta: ArrayLike) -> np.ndarray:
    """The stack's total reflected energy ``sum_k R_k`` at incidence ``cos_theta``, ``(..., 3)``."""
    return lobes(stack, cos_theta)[0].sum(axis=-2)


def brdf(stack: Stack, L: ArrayLike, V: ArrayLike, N: ArrayLike) -> np.ndarray:
    """
    Eq. 3: ``sum_k R_k(theta_0) D(h; alpha_k) G1(L; alpha_k) G1(V; alpha_k) / (4 cos theta_L cos theta_V)``,
    ``alpha_k = f^{-1}(sigma_k(theta_0))`` per channel and ``theta_0`` the light's angle (unit vectors
    ``(..., 3)``; 0 where L or V is at or below the surface).
    """
    L, V, N = (np.asarray(v, dtype=np.float64) for v in (L, V, N))
    cos_i = np.sum(L * N, axis=-1)
    cos_o = np.sum(V * N, axis=-1)
    shape = np.broadcast_shapes(cos_i.shape, cos_o.shape)
    cos_i, cos_o = np.broadcast_to(cos_i, shape), np.broadcast_to(cos_o, shape)
    H = L + V
    H = H / np.maximum(np.linalg.norm(H, axis=-1, keepdims=True), 1e-300)
    cos_h = np.broadcast_to(np.sum(H * N, axis=-1), shape)
    above = (cos_i > 0.0) & (cos_o > 0.0)
    result = np.zeros(shape + (3,))
    if not above.any():
        return result
    energies, variances = lobes(stack, cos_i[above])
    alphas = roughness_from_variance(variances)
    ci, co, ch = (v[above][:, None, None] for v in (cos_i, cos_o, cos_h))
    lobe = 0.25 * microfacet.ggx_D(ch, alphas) * microfacet.smith_G1_over_cos(ci, alphas) * microfacet.smith_G1_over_cos(co, alphas)
    result[above] = (energies * lobe).sum(axis=-2)
    return result
