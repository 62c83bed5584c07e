"""
Exact spectra of planar multilayers with complex, dispersive indices and random layer thicknesses.

The reference of the natural structures (absorbing and dispersive layers, thickness disorder): the
coherent reflection and transmission of any stack of layers between a lossless incidence medium and a
semi-infinite base, by Airy's recursion from the base up (Yeh 1988, Eqs. 5.1-5 to 5.1-7; Born & Wolf
Section 1.6). The recursion is the transfer-matrix method written with the layers' reflection
coefficients: each step multiplies by ``exp(2 i k_z d)``, of modulus at most 1, so it stays finite for
any absorption and any number of layers (the 2x2 products overflow past a few hundred absorbing
layers). Conventions are those of :mod:`explorer.physics.fresnel` and of ``tmm``: waves go as
``exp(+i k_z z)``, a complex index is ``n + i k`` with ``k >= 0``, and ``n cos theta`` in a layer takes
the root with a positive imaginary part (the forward-decaying wave), or a positive real part when it
is real.

Thickness disorder (:func:`disordered_thicknesses`): layer ``i`` has thickness ``d_i (1 + sigma eps_i)``,
``eps_i`` independent standard normal truncated to ``|eps| <= 3``. The ensemble-mean reflectance is
estimated from :data:`REALISATIONS` realisations drawn by a scrambled Sobol sequence with a fixed seed
(randomised quasi-Monte Carlo): deterministic, and in the ``bench``-measured cases more accurate than as
many independent draws (``explorer.dev.natural_studies``).

References
----------
Yeh (1988), Optical Waves in Layered Media, Chapter 5. Born and Wolf, Principles of Optics, Section 1.6.
Byrnes (2016), Multilayer optical calculations, arXiv:1603.02720 (the ``tmm`` package's conventions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

#: Realisations of a disordered stack's thicknesses (a power of two: a Sobol sequence's balanced size).
REALISATIONS = 2048
#: The seed of the scrambled Sobol sequence: the same structure gives the same spectrum.
DISORDER_SEED = 20111123
#: The truncation of the thickness noise, in standard deviations.
TRUNCATION = 3.0
#: Realisations evaluated together (memory: realisations x wavelengths complex values per array).
REALISATION_BLOCK = 256


def forward_kz(n: ArrayLike, n_sin: ArrayLike) -> np.ndarray:
    """``n cos theta = sqrt(n^2 - (n0 sin theta0)^2)`` on the forward branch (``tmm``'s ``is_forward_angle``)."""
    n = np.asarray(n, dtype=np.complex128)
    kz = np.sqrt(n * n - np.asarray(n_sin, dtype=np.complex128) ** 2)
    # Decaying (Im > 0) when it decays at all, else travelling down (Re > 0).
    flip = np.where(np.abs(kz.imag) > 100 * np.finfo(float).eps, kz.imag < 0.0, kz.real < 0.0)
    return np.where(flip, -kz, kz)


def interface(polarisation: str, n_i: ArrayLike, kz_i: ArrayLike, n_t: ArrayLike, kz_t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Amplitude ``(r, t)`` of an interface from ``n_i`` to ``n_t`` (``kz = n cos theta``; ``tmm``'s signs)."""
    if polarisation == "s":
        denominator = kz_i + kz_t
        return (kz_i - kz_t) / denominator, 2.0 * kz_i / denominator
    # p: (n_t cos_i - n_i cos_t) / (n_t cos_i + n_i cos_t), multiplied through by n_i n_t.
    a, b = n_t * n_t * kz_i, n_i * n_i * kz_t
    return (a - b) / (a + b), 2.0 * n_i * n_t * kz_i / (a + b)


@dataclass
class StackOptics:
    """``r``, ``t`` (amplitudes) and ``R``, ``T`` (powers) of a stack, broadcast over its inputs."""

    r: np.ndarray
    t: np.ndarray
    R: np.ndarray
    T: np.ndarray


def stack_optics(polarisation: str, n0: ArrayLike, indices: list, thicknesses: ArrayLike, n_base: ArrayLike,
                 wavelength_nm: ArrayLike, sin_theta0: ArrayLike) -> StackOptics:
    """
    Coherent ``r, t, R, T`` of layers ``indices[j]`` (complex, each broadcast against ``wavelength_nm``)
    of thicknesses ``thicknesses[..., j]`` (nm), top first, between a lossless ``n0`` above and ``n_base``
    below, lit from ``n0`` at ``sin theta0`` (a number, or an array broadcast against ``wavelength_nm``).

    ``thicknesses`` may have leading axes (realisations): the results then have shape
    ``thicknesses.shape[:-1] + wavelength_nm.shape``. ``T`` is the power entering the base (``tmm``'s
    definition, also for an absorbing base); ``1 - R - T`` is absorbed in the layers.
    """
    wavelength_nm = np.asarray(wavelength_nm, dtype=np.float64)
    thicknesses = np.asarray(thicknesses, dtype=np.float64)
    lead = thicknesses.shape[:-1]
    n0 = np.asarray(n0, dtype=np.complex128) * np.ones(wavelength_nm.shape)
    if np.any(np.abs(n0.imag) > 0.0):
        raise ValueError("the incidence medium must be lossless (a real index)")
    n_sin = n0 * sin_theta0  # conserved along the stack (Snell)
    k0 = 2.0 * np.pi / wavelength_nm
    media = [n0] + [np.asarray(n, dtype=np.complex128) * np.ones(wavelength_nm.shape) for n in indices] + \
            [np.asarray(n_base, dtype=np.complex128) * np.ones(wavelength_nm.shape)]
    kz = [forward_kz(n, n_sin) for n in media]
    # Start at the base: the last interface alone.
    r, t = interface(polarisation, media[-2], kz[-2], media[-1], kz[-1])
    r = np.broadcast_to(r, lead + wavelength_nm.shape)
    t = np.broadcast_to(t, lead + wavelength_nm.shape)
    for j in range(len(indices), 0, -1):  # layer j (1-based) between media j-1 and j+1
        d = thicknesses[..., j - 1].reshape(lead + (1,) * wavelength_nm.ndim)
        phase = np.exp(1j * k0 * kz[j] * d)
        r_top, t_top = interface(polarisation, media[j - 1], kz[j - 1], media[j], kz[j])
        denominator = 1.0 + r_top * r * phase * phase
        r, t = (r_top + r * phase * phase) / denominator, t_top * t * phase / denominator
    R = np.abs(r) ** 2
    n_b = media[-1]
    cos_0 = kz[0] / media[0]
    cos_b = kz[-1] / n_b
    incident = (media[0] * (cos_0 if polarisation == "s" else np.conj(cos_0))).real
    with np.errstate(divide="ignore", invalid="ignore"):
        if polarisation == "s":
            T = np.abs(t) ** 2 * (n_b * cos_b).real / incident
        else:
            T = np.abs(t) ** 2 * (n_b * np.conj(cos_b)).real / incident
    T = np.where(incident > 0.0, T, 0.0)  # exact grazing: nothing enters
    return StackOptics(r=r, t=t, R=R, T=T)


def truncated_normal(u: ArrayLike, truncation: float = TRUNCATION) -> np.ndarray:
    """Standard normal variables truncated to ``|eps| <= truncation``, from uniform ``u`` in (0, 1) (inverse CDF)."""
    from scipy.special import ndtr, ndtri

    low = ndtr(-truncation)
    return ndtri(low + np.asarray(u, dtype=np.float64) * (1.0 - 2.0 * low))


def disorder_noise(layers: int, realisations: int = REALISATIONS, seed: int = DISORDER_SEED) -> np.ndarray:
    """``(realisations, layers)`` truncated-normal ``eps``: a scrambled Sobol sequence's points, seeded."""
    from scipy.stats import qmc

    u = qmc.Sobol(d=layers, scramble=True, seed=seed).random(realisations)
    return truncated_normal(np.clip(u, 1e-12, 1.0 - 1e-12))


def disordered_thicknesses(thicknesses: ArrayLike, sigma: float, realisations: int = REALISATIONS,
                           seed: int = DISORDER_SEED) -> np.ndarray:
    """``(realisations, layers)`` thicknesses ``d_i (1 + sigma eps_i)`` (one row, unchanged, for ``sigma = 0``)."""
    thicknesses = np.asarray(thicknesses, dtype=np.float64)
    if sigma == 0.0:
        return thicknesses[np.newaxis, :]
    return thicknesses * (1.0 + sigma * disorder_noise(thicknesses.size, realisations, seed))


def mean_optics(polarisation: str, n0: ArrayLike, indices: list, thicknesses: np.ndarray, n_base: ArrayLike, wavelength_nm: np.ndarray,
                sin_theta0: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The mean ``R`` and ``T`` over the rows of ``thicknesses`` (realisations), in blocks of :data:`REALISATION_BLOCK`."""
    R = np.zeros(np.shape(wavelength_nm))
    T = np.zeros(np.shape(wavelength_nm))
    rows = thicknesses.shape[0]
    for start in range(0, rows, REALISATION_BLOCK):
        optics = stack_optics(polarisation, n0, indices, thicknesses[start:start + REALISATION_BLOCK], n_base,
                              wavelength_nm, sin_theta0)
        R += optics.R.sum(axis=0)
        T += optics.T.sum(axis=0)
    return R / rows, T / rows


# --------------------------------------------------------------------------------------------------
# Periodic stacks: N identical cells by repeated squaring (Redheffer's star product)


def _star(a: tuple, b: tuple) -> tuple:
    """Two-port ``(r_top, t_down, r_bottom, t_up)`` of ``a`` above ``b`` (Redheffer's star product), same medium between."""
    ra, ta, rb_a, tu_a = a
    rb, tb, rbb, tu_b = b
    D = 1.0 / (1.0 - rb_a * rb)
    return (ra + ta * rb * tu_a * D, ta * tb * D, rbb + tu_b * rb_a * tb * D, tu_b * tu_a * D)


def periodic_optics(polarisation: str, n0, n1, n2, d1: float, d2: float, N: int, wavelength_nm, sin_theta0) -> StackOptics:
    """
    ``r, t, R, T`` of ``N`` cells of ``n2`` (``d2``) over ``n1`` (``d1``) between a lossless ``n0`` and an ``n1``
    base, as :func:`stack_optics` of ``[n2, n1] * N`` (to rounding), in ``O(log N)`` star products: a cell is the
    Airy slab of ``n2`` in ``n1`` followed by ``d1`` of ``n1``; its two-port is squared, and the host interface
    added on top. Broadcast over ``wavelength_nm`` and ``sin_theta0``.
    """
    wavelength_nm = np.asarray(wavelength_nm, dtype=np.float64)
    shape = np.broadcast_shapes(wavelength_nm.shape, np.shape(sin_theta0), np.shape(n0), np.shape(n1), np.shape(n2))
    n0, n1, n2 = (np.broadcast_to(np.asarray(n, dtype=np.complex128), shape) for n in (n0, n1, n2))
    n_sin = n0 * sin_theta0
    k0 = 2.0 * np.pi / wavelength_nm
    kz0, kz1, kz2 = forward_kz(n0, n_sin), forward_kz(n1, n_sin), forward_kz(n2, n_sin)
    r12, t12 = interface(polarisation, n1, kz1, n2, kz2)
    r21, t21 = interface(polarisation, n2, kz2, n1, kz1)
    e2 = np.exp(1j * k0 * kz2 * d2)
    denominator = 1.0 - r21 * r21 * e2 * e2
    slab_r = r12 + t12 * t21 * r21 * e2 * e2 / denominator  # the slab seen from n1, either side (symmetric)
    slab_t = t12 * t21 * e2 / denominator
    e1 = np.exp(1j * k0 * kz1 * d1)
    cell = (slab_r, slab_t * e1, slab_r * e1 * e1, slab_t * e1)
    result, power, count = None, cell, int(N)
    while count:
        if count & 1:
            result = power if result is None else _star(result, power)
        count >>= 1
        if count:
            power = _star(power, power)
    rN, tN = result[0], result[1]
    r01, t01 = interface(polarisation, n0, kz0, n1, kz1)
    r10, t10 = interface(polarisation, n1, kz1, n0, kz0)
    denominator = 1.0 - r10 * rN
    r = r01 + t01 * rN * t10 / denominator
    t = t01 * tN / denominator
    cos_0, cos_b = kz0 / n0, kz1 / n1
    incident = (n0 * (cos_0 if polarisation == "s" else np.conj(cos_0))).real
    with np.errstate(divide="ignore", invalid="ignore"):
        if polarisation == "s":
            T = np.abs(t) ** 2 * (n1 * cos_b).real / incident
        else:
            T = np.abs(t) ** 2 * (n1 * np.conj(cos_b)).real / incident
    return StackOptics(r=r, t=t, R=np.abs(r) ** 2, T=np.where(incident > 0.0, T, 0.0))
