"""
Layered Bragg structures: the integrated transmissivity of rough Bragg layers and the single-reflection
BRDF of a stack of 1 to 3 of them over a Lambertian base, under an optional smooth coating
(Fourneau et al. 2024, Sections 4.2.2-4.3).

A stack (:class:`LayeredBragg`) is, from top to bottom: a smooth interface from air to the host medium
of index ``n1`` (the coating, present when ``n1 != 1``), then ``L`` rough Bragg layers
(:class:`RoughBraggLayer`, each a GGX distribution of Bragg mirrors of its own ``n2, Lambda, delta, N,
alpha`` in the host), then a Lambertian base of RGB albedo ``rho_d``. Transmission through a rough
Bragg layer is ballistic (Section 4.2.1) and its transmitted fraction is Yeh's transmissivity filtered
by ``F_alpha`` (Eq. 28); the single-reflection BRDF (Eq. 34) sums the paths that reflect once.

The "LUT version" of Table 2: per layer, the host tabulates Yeh's reflectance ``R_lambda(theta)`` and
the integrated transmissivity ``f_t(theta) cos theta`` (Eq. 28) at 0.25 degrees and every nm from 360
to 830 (:func:`layer_tables`), from the transmission filter of the layer's ``alpha``
(:func:`explorer.physics.microfacet.transmission_filter_table`, cached per ``alpha``). Spectra are multiplied
per wavelength and integrated against the CMFs (:mod:`explorer.physics.colorimetry`) only at the end; the
base's albedo, given in RGB, multiplies the RGB of its spectral transmission factor (the only product
taken in RGB, as ``rho_d`` has no spectrum).

Directions ``i`` and ``o`` are unit vectors in the local frame (``n = +z``), above the surface, pointing
away from it, in air. Numpy only.

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. Computer Graphics Forum 43(2). Sections 4.1-4.3 (Eqs. 17-19, 28-30, 34), Table 2, Appendix C.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import bragg, colorimetry, microfacet
from explorer.physics.dispersion import Dispersion
from explorer.physics.fresnel import fresnel_r_p, fresnel_r_s, fresnel_reflectance

#: At most this many rough Bragg layers in a stack.
MAX_LAYERS = 3


# --------------------------------------------------------------------------------------------------
# Parameters


@dataclass(frozen=True)
class RoughBraggLayer:
    """
    A rough Bragg layer (Section 4.1): Bragg mirrors of ``N`` cells ``(n2, d2), (n1, d1)`` oriented by
    an isotropic GGX distribution of roughness ``alpha``, in the stack's host medium.

    Parameters
    ----------
    n2 : float
        Index of the mirror's high layers.
    Lambda : float
        Period ``d1 + d2`` in nm.
    delta : float
        ``d1 / Lambda`` in [0, 1].
    N : int
        Number of cells (1 is a thin film of ``n2``).
    alpha : float
        GGX roughness in [0, 1] (Eq. 18).
    n1 : float, optional
        The mirror's low index when it differs from the host (the jewel-beetle cuticles of Table 3:
        Yeh's reflectance then follows Appendix D with ``nh`` the host); ``None``, the host's ``n1``.
    k1, k2 : float
        Extinction coefficients of the ``n1`` and ``n2`` layers (>= 0; absorbing layers).
    sigma : float
        Thickness disorder (:class:`explorer.physics.natural.NaturalMirror`): the ensemble's mean.
    medium_n1, medium_n2 : explorer.physics.dispersion.Dispersion, optional
        Dispersive media instead of the numbers ``n1``, ``n2`` (which then only stand for them on a slider).
    With any of the last five the layer is natural (:attr:`natural`): its tables are the exact multilayer's
    (:func:`explorer.physics.natural.spectral_tables`), its facets transmit ``T <= 1 - R``.
    """

    n2: float = 1.5
    Lambda: float = 500.0
    delta: float = 0.5
    N: int = 10
    alpha: float = 0.1
    n1: float | None = None
    k1: float = 0.0
    k2: float = 0.0
    sigma: float = 0.0
    medium_n1: object = None
    medium_n2: object = None

    def __post_init__(self):
        microfacet.check_alpha(self.alpha)
        if self.natural or min(self.k1, self.k2, self.sigma) < 0.0:
            self.natural_mirror(1.0)  # NaturalMirror's own checks (k >= 0, sigma's range)
        if not (float(self.N) >= 1 and float(self.N) == int(self.N)):
            raise ValueError(f"N must be a whole number of cells >= 1, got {self.N}")
        if not (self.Lambda > 0.0):
            raise ValueError(f"Lambda must be positive (nm), got {self.Lambda}")
        if not (0.0 <= self.delta <= 1.0):
            raise ValueError(f"delta must be in [0, 1], got {self.delta}")
        if not (self.n2 > 0.0 and (self.n1 is None or self.n1 > 0.0)):
            raise ValueError(f"refractive indices must be positive, got n2={self.n2}, n1={self.n1}")

    def mirror(self, host_n1: float) -> bragg.BraggMirror:
        """The layer's Bragg mirror in a host of index ``host_n1`` (``nh`` only when it differs from ``n1``)."""
        n1 = host_n1 if self.n1 is None else float(self.n1)
        return bragg.BraggMirror(
            n1=n1,
            n2=float(self.n2),
            Lambda=float(self.Lambda),
            delta=float(self.delta),
            N=int(self.N),
            nh=None if n1 == host_n1 else float(host_n1),
        )

    @property
    def natural(self) -> bool:
        """Whether the layer absorbs, disperses or is disordered (its tables are then the exact multilayer's)."""
        return (self.k1 > 0.0 or self.k2 > 0.0 or self.sigma > 0.0
                or self.medium_n1 is not None or self.medium_n2 is not None)

    def natural_mirror(self, host_n1):
        """
        The layer's :class:`explorer.physics.natural.NaturalMirror` in a lossless host ``host_n1``: a number, or a
        dispersive medium (:class:`explorer.physics.dispersion.Dispersion`; then ``n1`` unset is that medium too).
        """
        from explorer.physics import natural

        host = host_n1 if isinstance(host_n1, Dispersion) else float(host_n1)
        n1 = self.medium_n1 if self.medium_n1 is not None else (host if self.n1 is None else float(self.n1))
        n2 = self.medium_n2 if self.medium_n2 is not None else float(self.n2)
        return natural.NaturalMirror(n1=n1, n2=n2, Lambda=float(self.Lambda), delta=float(self.delta), N=int(self.N),
                                     nh=host, k1=float(self.k1), k2=float(self.k2), sigma=float(self.sigma))


@dataclass(frozen=True)
class LayeredBragg:
    """
    A layered Bragg structure (Figure 2(e)): 1 to 3 rough Bragg layers in a host of index ``n1``, over
    a Lambertian base, under a smooth coating when ``n1 != 1``.

    Parameters
    ----------
    layers : sequence of RoughBraggLayer
        From top to bottom; 1 to :data:`MAX_LAYERS`.
    n1 : float
        Index of the host medium (>= 1). Eq. 34's coating is the interface from air to it.
    rho_d : float or (float, float, float)
        Linear-sRGB albedo of the Lambertian base, each in [0, 1] (0: an absorbing base).
    coating : bool
        ``False`` drops the coating's interface (no Fresnel reflection, no refraction, no ``1/n1^2``):
        the stack seen from inside its host. With ``n1 = 1`` both give the same BRDF.
    tau_h : float
        The host's optical depth, at normal incidence, of each gap a path crosses: below the coating,
        between consecutive layers, above the base. Crossing one at ``theta_t`` in the host attenuates by
        ``exp(-tau_h / cos theta_t)`` (Beer-Lambert; Section 6's absorption between the layers). >= 0.
    medium_n1 : explorer.physics.dispersion.Dispersion, optional
        A dispersive host instead of the number ``n1`` (which then stands for it at 550 nm, as a slider does):
        lossless, ``n >= 1`` from 360 to 830 nm. Every wavelength then has its own refraction angle into the
        host, coating Fresnel terms and ``1/n1^2`` (:meth:`host_index`), and the layers' tables are taken with
        the host's index at each wavelength (:func:`layer_tables`).
    """

    layers: tuple = ()
    n1: float = 1.0
    rho_d: tuple = (0.0, 0.0, 0.0)
    coating: bool = True
    tau_h: float = 0.0
    medium_n1: object = None

    def __post_init__(self):
        layers = tuple(self.layers) if not isinstance(self.layers, RoughBraggLayer) else (self.layers,)
        if not 1 <= len(layers) <= MAX_LAYERS:
            raise ValueError(f"a layered Bragg structure has 1 to {MAX_LAYERS} layers, got {len(layers)}")
        for layer in layers:
            if not isinstance(layer, RoughBraggLayer):
                raise ValueError(f"layers must be RoughBraggLayer, got {type(layer).__name__}")
        try:
            rho_d = np.broadcast_to(np.asarray(self.rho_d, dtype=np.float64), (3,))
        except (TypeError, ValueError):
            raise ValueError(f"rho_d must be one number or three (r, g, b), got {self.rho_d!r}") from None
        if not np.all((rho_d >= 0.0) & (rho_d <= 1.0)):
            raise ValueError(f"rho_d must be in [0, 1] per channel, got {tuple(float(x) for x in rho_d)}")
        if not (self.n1 >= 1.0):
            raise ValueError(f"the host index n1 must be >= 1, got {self.n1}")
        object.__setattr__(self, "layers", layers)
        object.__setattr__(self, "rho_d", tuple(float(x) for x in rho_d))
        object.__setattr__(self, "n1", float(self.n1))
        if not (float(self.tau_h) >= 0.0 and np.isfinite(self.tau_h)):
            raise ValueError(f"tau_h must be >= 0, got {self.tau_h}")
        object.__setattr__(self, "tau_h", float(self.tau_h))
        if self.medium_n1 is not None:
            if not isinstance(self.medium_n1, Dispersion):
                raise ValueError(f"the host's medium must be a dispersion, got {type(self.medium_n1).__name__}")
            problem = host_medium_problem(self.medium_n1)
            if problem:
                raise ValueError(problem)

    @property
    def host(self):
        """The host as the layers' tables take it: its medium, or the number ``n1``."""
        return self.medium_n1 if self.medium_n1 is not None else self.n1

    @property
    def dispersive_host(self) -> bool:
        """Whether the host names a dispersive medium (its index differs per wavelength)."""
        return self.medium_n1 is not None

    def host_index(self, wavelength: ArrayLike | None = None) -> np.ndarray:
        """The host's (real) index at ``wavelength`` (nm; the CMFs' 471 by default): ``n1`` everywhere, or its medium's."""
        wavelength = colorimetry.WAVELENGTHS if wavelength is None else np.asarray(wavelength, dtype=np.float64)
        if self.medium_n1 is None:
            return np.full(np.shape(wavelength), self.n1)
        return np.asarray(self.medium_n1.index(wavelength).real, dtype=np.float64)

    def coating_indices(self) -> np.ndarray:
        """
        The host's index along the last (wavelength) axis of the coating's per-direction terms: ``(471,)`` when a
        coated host disperses (every wavelength refracts its own way), else ``(1,)`` (one direction for all).
        """
        if self.coating and self.dispersive_host:
            return self.host_index()
        return np.array([self.n1])


def host_medium_problem(medium: Dispersion) -> str | None:
    """Why ``medium`` cannot be a stack's host (it absorbs, or its ``n`` drops below 1 somewhere), or None."""
    if medium.absorbing:
        return f"the host {medium.name} absorbs (k > 0): a stack's host must be lossless"
    n, at = medium.lowest_real()
    if n < 1.0:
        return f"the host {medium.name} has n = {n:.4g} < 1 at {at:g} nm: a stack's host has n >= 1"
    return None


#: Cosines of the host angles are kept above this in the gaps' attenuation (exp(-tau / cos) is 0 there anyway).
GAP_COS_MIN = 1e-6


def gap_transmittance(tau_h: float, cos_theta_host: ArrayLike) -> np.ndarray:
    """``exp(-tau_h / cos theta)``: one crossing of a host gap at ``theta`` in the host (1 when ``tau_h = 0``)."""
    if tau_h == 0.0:
        return np.ones(np.shape(cos_theta_host))
    return np.exp(-tau_h / np.maximum(np.asarray(cos_theta_host, dtype=np.float64), GAP_COS_MIN))


# --------------------------------------------------------------------------------------------------
# Eqs. 28 and 30


def rough_bragg_brdf(
    i: ArrayLike, o: ArrayLike, mirror: bragg.BraggMirror, alpha: float, wavelength: ArrayLike | None = None,
) -> np.ndarray:
    """
    The BRDF of a rough Bragg layer (Eq. 17): GGX microfacets that are Bragg mirrors, reflecting with
    Yeh's exact unpolarised reflectance ``R_lambda`` at the half-vector angle ``theta_d = acos(i.h)``
    (Eqs. 2, 9, 10; Appendix D when the mirror's host ``nh`` differs from its ``n1``).

    Parameters
    ----------
    i, o : array_like, shape (..., 3)
        Unit directions in the mirror's host medium, ``n = +z``, pointing away from the surface.
    mirror : explorer.physics.bragg.BraggMirror
    alpha : float
        GGX roughness in [0, 1].
    wavelength : array_like, optional
        Wavelengths in nm; :data:`explorer.physics.colorimetry.WAVELENGTHS` by default.

    Returns
    -------
    ndarray, shape (..., n_wavelengths)
        The spectral BRDF (1/sr).

    References
    ----------
    Fourneau et al. (2024), Eq. 17 (with Eqs. 18-19) and Section 3.1.
    """
    wavelength = colorimetry.WAVELENGTHS if wavelength is None else np.asarray(wavelength, dtype=np.float64)
    return microfacet.microfacet_brdf(
        i, o, alpha, lambda cos_theta_d: bragg.bragg_reflectance(np.maximum(cos_theta_d, microfacet.COS_THETA_MIN), wavelength, mirror)
    )


def integrated_transmissivity(transmission_filter: microfacet.TransmissionFilter, transmissivity: ArrayLike) -> np.ndarray:
    """
    The integrated transmissivity of a rough Bragg layer (Eq. 28), per wavelength:
    ``f_t(theta_i) cos theta_i = int_0^{pi/2} T_lambda(theta_d) F_alpha(theta_i, theta_d) d theta_d``.

    Parameters
    ----------
    transmission_filter : explorer.physics.microfacet.TransmissionFilter
        ``F_alpha`` of the layer's roughness; its cell weights are the quadrature weights.
    transmissivity : array_like, shape (361, n_wavelengths)
        ``T_lambda = 1 - R_lambda`` of the layer's mirror at the nodes ``theta_d = k * 0.25 deg``.

    Returns
    -------
    ndarray, shape (361, n_wavelengths)
        The fraction of light at ``theta_i = k * 0.25 deg`` that crosses the layer, ballistically;
        at most ``G1(theta_i)`` (Eq. 30).

    References
    ----------
    Fourneau et al. (2024), Eqs. 22-29.
    """
    return transmission_filter.weights @ np.asarray(transmissivity, dtype=np.float64)


def absorption(cos_theta_i: ArrayLike, alpha: ArrayLike) -> np.ndarray:
    """
    The part of the light a rough Bragg layer absorbs (Eq. 30): ``A(theta_i) = 1 - G1(theta_i)``, the
    paths that would scatter more than once among its microfacets (Eq. 28 with ``T = 1``, Appendix C).
    """
    return 1.0 - microfacet.smith_G1(cos_theta_i, alpha)


def coating_reflectance(cos_theta_i: ArrayLike, n1: ArrayLike) -> np.ndarray:
    """
    The weight of the coating's specular reflection ``f_r,0`` of Eq. 34 (a Dirac in the mirror
    direction): the unpolarised Fresnel reflectance from air into the host ``n1`` (0 for ``n1 = 1``).
    Point lights never meet a Dirac; the directional albedo adds it.
    """
    cos_theta_i = np.clip(np.asarray(cos_theta_i, dtype=np.float64), microfacet.COS_THETA_MIN, 1.0)
    if np.size(n1) > 1:
        # A dispersive host, one index per wavelength (n >= 1: from air, never total reflection): the same
        # amplitudes in real arithmetic, several times quicker over (directions, 471) than the complex path.
        n1 = np.asarray(n1, dtype=np.float64)
        cos_t = np.sqrt(1.0 - (1.0 - cos_theta_i**2) / (n1 * n1))
        r_s, r_p = fresnel_r_s(1.0, cos_theta_i, n1, cos_t), fresnel_r_p(1.0, cos_theta_i, n1, cos_t)
        return 0.5 * (r_s * r_s + r_p * r_p)
    return fresnel_reflectance(cos_theta_i, 1.0, n1)


def coating_rgb(stack: LayeredBragg, cos_theta_i: ArrayLike) -> np.ndarray:
    """
    The coating's Dirac reflection (:func:`coating_reflectance`) in linear sRGB, ``(..., 3)``: flat (white times
    ``F``) in a host of one index, the RGB of the spectrum ``F(theta, n1(lambda))`` in a dispersive one; 0 uncoated.
    """
    cos_theta_i = np.asarray(cos_theta_i, dtype=np.float64)
    if not stack.coating:
        return np.zeros(cos_theta_i.shape + (3,))
    if stack.dispersive_host:
        return colorimetry.spectrum_to_rgb(coating_reflectance(cos_theta_i[..., None], stack.host_index()))
    return np.repeat(coating_reflectance(cos_theta_i, stack.n1)[..., None], 3, axis=-1)


# --------------------------------------------------------------------------------------------------
# Per-layer tables (the "LUT version" of Table 2)


#: The layer tables' finest sampling (samples per nm): their colours converge to 2e-4 up to N ~ 100 and
#: stay within ~1e-3 at N = 1000, where finer samplings would cost tens of seconds per layer. They stop
#: at the first halving that changes the colour by less than 2e-4 (one pass: half the cost of two).
LAYER_MAX_SUBSTEPS = 64


def reflectance_table(mirror: bragg.BraggMirror, cos_theta: ArrayLike) -> np.ndarray:
    """
    Yeh's unpolarised reflectance ``R_lambda`` of ``mirror`` at every angle of ``cos_theta``, averaged
    over each nm of :data:`explorer.physics.colorimetry.WAVELENGTHS` (its hat function), sampled finely enough
    that the colour has converged (:func:`explorer.physics.bragg.converged_reflectance_spectra`, at most
    :data:`LAYER_MAX_SUBSTEPS` samples per nm): shape ``(n_angles, 471)``. Integrated against the
    1-nm CMFs, a row gives the converged reference colour; so does Eq. 28's transmissivity ``1 - R``,
    whose integral is linear in ``R``.
    """
    spectra, _ = bragg.converged_reflectance_spectra(cos_theta, mirror, passes=1, substeps_max=LAYER_MAX_SUBSTEPS)
    return spectra


@functools.lru_cache(maxsize=8)
def _cached_filter(alpha: float) -> microfacet.TransmissionFilter:
    return microfacet.transmission_filter_table(alpha)


def transmission_filter_for(alpha: float) -> microfacet.TransmissionFilter:
    """The transmission filter ``F_alpha`` (Eq. 29), built once per ``alpha`` and cached (8 of them)."""
    return _cached_filter(float(microfacet.check_alpha(alpha)))


@dataclass(frozen=True)
class LayerTables:
    """
    A rough Bragg layer's tables, rebuilt whenever one of its parameters changes (Table 2, LUT version).

    Attributes
    ----------
    layer : RoughBraggLayer
    n1 : float or explorer.physics.dispersion.Dispersion
        The host index (or dispersive medium) they were built in.
    theta : ndarray, shape (361,)
        Rows: ``theta = k * 0.25 deg`` (radians), in the host medium.
    reflectance : ndarray, shape (361, 471), float32
        Yeh's unpolarised ``R_lambda(theta)`` (Eqs. 2, 9, 10; Appendix D): the microfacet reflectance
        of Eq. 17, looked up at the half-vector angle.
    transmissivity : ndarray, shape (361, 471), float32
        The integrated transmissivity ``f_t(theta) cos theta`` (Eq. 28): Eq. 34's ``f_t,k``.
    transmittance : ndarray, shape (361, 471), float32, or None
        A natural layer's exact smooth transmittance ``T_lambda(theta)`` (``< 1 - R`` where it absorbs); None:
        ``1 - R`` (lossless layers).
    seconds : float
        Wall-clock build time of both (the filter excluded: it depends on ``alpha`` only).
    """

    layer: RoughBraggLayer
    n1: object
    theta: np.ndarray = field(repr=False)
    reflectance: np.ndarray = field(repr=False)
    transmissivity: np.ndarray = field(repr=False)
    seconds: float = 0.0
    transmittance: np.ndarray | None = field(default=None, repr=False)


@functools.lru_cache(maxsize=32)
def _reflectance_at_theta_nodes(mirror: bragg.BraggMirror) -> np.ndarray:
    """:func:`reflectance_table` at the 361 angles of :func:`explorer.physics.microfacet.theta_nodes`, cached per mirror."""
    table = reflectance_table(mirror, np.cos(microfacet.theta_nodes())).astype(np.float32)
    table.setflags(write=False)
    return table


def layer_tables(
    layer: RoughBraggLayer, n1: float = 1.0, transmission_filter: microfacet.TransmissionFilter | None = None, cached: bool = True,
    draft: bool = False,
) -> LayerTables:
    """
    Build a layer's tables: ``R_lambda`` over angle and the integrated transmissivity (Eq. 28).

    Parameters
    ----------
    layer : RoughBraggLayer
    n1 : float or explorer.physics.dispersion.Dispersion
        Index of the host medium, or its dispersive medium (the exact multilayer's tables, per wavelength).
    transmission_filter : explorer.physics.microfacet.TransmissionFilter, optional
        ``F_alpha`` for the layer's ``alpha``; the cached one by default.
    cached : bool
        Reuse ``R_lambda`` of a mirror seen before (it depends on the mirror only, not on ``alpha``);
        ``False`` computes it afresh (timings).
    draft : bool
        ``R_lambda`` sampled at every nm (the paper's 1-nm sum, :func:`explorer.physics.bragg.reflectance_spectra`)
        instead of converged hat averages: several times quicker, for an interactive host to show while a
        slider moves; not converged near band edges (never a reference).

    Returns
    -------
    LayerTables

    References
    ----------
    Fourneau et al. (2024), Eq. 28, Section 4.2.2 (per-layer tables), Table 2 (LUT version).
    """
    F = transmission_filter if transmission_filter is not None else transmission_filter_for(layer.alpha)
    if abs(F.alpha - float(microfacet.check_alpha(layer.alpha))) > 1e-12:
        raise ValueError(f"the transmission filter is for alpha={F.alpha:g}, the layer has alpha={layer.alpha:g}")
    start = time.perf_counter()
    theta = F.theta
    host = n1 if isinstance(n1, Dispersion) else float(n1)
    if layer.natural or isinstance(host, Dispersion):
        # Absorbing, dispersive or disordered, or in a dispersive host (each column then in the host's index at
        # its wavelength, the rows at angles in the host): the exact multilayer (no draft), Eq. 28 over its T.
        from explorer.physics import natural

        R, T = (np.asarray(a, dtype=np.float32) for a in natural.spectral_tables(layer.natural_mirror(host), theta))
        transmissivity = F.weights.astype(np.float32) @ T
        for a in (R, T, transmissivity):
            a.setflags(write=False)
        return LayerTables(layer, host, theta, R, transmissivity, time.perf_counter() - start, transmittance=T)
    mirror = layer.mirror(float(n1))
    if draft:
        reflectance = bragg.reflectance_spectra(np.cos(theta), mirror).astype(np.float32)
    elif cached and np.array_equal(theta, microfacet.theta_nodes()):
        reflectance = _reflectance_at_theta_nodes(mirror)
    else:
        reflectance = reflectance_table(mirror, np.cos(theta)).astype(np.float32)
    # Eq. 28 with T = 1 - R, in float32 (the tables' precision; twice as fast as float64).
    transmissivity = F.weights.astype(np.float32) @ (np.float32(1.0) - reflectance)
    seconds = time.perf_counter() - start
    transmissivity.setflags(write=False)
    reflectance.setflags(write=False)
    return LayerTables(layer, float(n1), theta, reflectance, transmissivity, seconds)


def stack_tables(stack: LayeredBragg) -> tuple[LayerTables, ...]:
    """The tables of every layer of ``stack``, top to bottom."""
    return tuple(layer_tables(layer, stack.host) for layer in stack.layers)


def lookup(table: np.ndarray, theta: ArrayLike) -> np.ndarray:
    """
    Linear interpolation of a per-angle table (rows at ``k * 0.25 deg``) at ``theta`` (radians), as a
    linearly filtered texture fetch does: shape ``theta.shape + table.shape[1:]``, in the table's precision
    (a float32 table is blended in float32, as the texture unit does: several times faster than promoting
    its rows to float64, and the hot spot of every spectral BRDF evaluation).
    """
    x = np.clip(np.asarray(theta, dtype=np.float64), 0.0, 0.5 * np.pi) / microfacet.THETA_STEP
    k = np.minimum(np.floor(x).astype(np.intp), table.shape[0] - 2)
    f = (x - k).astype(table.dtype, copy=False)[..., None]
    low = table[k]
    out = table[k + 1]  # a fresh copy (fancy indexing): blended in place, low + (high - low) f
    out -= low
    out *= f
    out += low
    return out


def lookup_columns(table: np.ndarray, theta: ArrayLike) -> np.ndarray:
    """
    :func:`lookup` with one angle per wavelength: ``theta`` ``(..., W)`` in radians, column ``j`` of ``table`` read at
    ``theta[..., j]`` (a dispersive host refracts each wavelength its own way), interpolated as :func:`lookup` does.
    A last axis of 1 is one angle for every column (:func:`lookup` itself). Shape ``(..., W)``.
    """
    theta = np.asarray(theta, dtype=np.float64)
    if theta.shape[-1] == 1:
        return lookup(table, theta[..., 0])
    x = np.clip(theta, 0.0, 0.5 * np.pi) / microfacet.THETA_STEP
    k = np.minimum(np.floor(x).astype(np.intp), table.shape[0] - 2)
    f = (x - k).astype(table.dtype, copy=False)
    width = table.shape[1]
    flat = np.ascontiguousarray(table).reshape(-1)
    index = k * width + np.arange(width)  # a 1D gather: several times quicker than table[k, columns]
    low = flat[index]
    out = flat[index + width]
    out -= low
    out *= f
    out += low
    return out


# --------------------------------------------------------------------------------------------------
# The single-reflection BRDF (Eq. 34)


def refract_into_host(direction: ArrayLike, n1: ArrayLike) -> np.ndarray:
    """
    Snell's law through the smooth coating, from air into the host ``n1 >= 1``: the direction keeps its
    azimuth, ``sin theta' = sin theta / n1`` (Eq. 34's refracted ``i`` and ``o``), and stays above. ``n1``
    broadcasts against ``direction[..., 0]`` (one index per path, or per wavelength of a dispersive host).
    """
    d = np.asarray(direction, dtype=np.float64)
    tangent = d[..., :2] / np.asarray(n1, dtype=np.float64)[..., None]
    cos_t = np.sqrt(np.maximum(1.0 - np.sum(tangent * tangent, axis=-1), 0.0))
    return np.concatenate([tangent, cos_t[..., None]], axis=-1)


@dataclass(frozen=True)
class SingleReflectionSpectra:
    """
    Eq. 34 split by what multiplies the base's RGB albedo, per wavelength (last axis, 471).

    Attributes
    ----------
    layers : ndarray
        ``(1/n1^2) sum_l f_r,l(i', o') prod_{k<l} f_t,k(i) f_t,k(o)`` over the Bragg layers (1/sr).
    base : ndarray
        The same product through every layer, times ``1/(pi n1^2)``: the base's term per unit albedo.
    """

    layers: np.ndarray
    base: np.ndarray

    def total(self, rho_d=1.0) -> np.ndarray:
        """The spectral BRDF for a spectrally flat base albedo ``rho_d`` (a scalar or a spectrum)."""
        return self.layers + np.asarray(rho_d) * self.base


def single_reflection_spectra(
    stack: LayeredBragg, i: ArrayLike, o: ArrayLike, tables: Sequence[LayerTables] | None = None, exact_reflectance: bool = False,
) -> SingleReflectionSpectra:
    """
    The single-reflection BRDF of a layered Bragg structure (Eq. 34), spectrally:
    ``f_r(i, o) = f_r,0(i, o) + (1/n1^2) sum_{l=1}^{L+1} f_r,l(i', o') prod_{k=0}^{l-1} f_t,k(i) f_t,k(o)``,
    where layer ``L + 1`` is the Lambertian base (``rho_d / pi``), ``f_r,l`` is Eq. 17 for Bragg layer
    ``l`` at the refracted directions ``i', o'``, ``f_t,k`` its integrated transmissivity (Eq. 28) at
    their angles, and ``f_t,0 = 1 - F`` the coating's Fresnel transmittance at the angles in air. The
    coating's own reflection ``f_r,0`` is a Dirac (:func:`coating_reflectance`), left out here.

    Parameters
    ----------
    stack : LayeredBragg
    i, o : array_like, shape (..., 3)
        Unit directions in air, ``n = +z``; 0 where either is at or below the horizon.
    tables : sequence of LayerTables, optional
        One per layer (:func:`stack_tables`); built (and their filters cached) when omitted.
    exact_reflectance : bool
        ``True`` evaluates Yeh's ``R_lambda`` at the exact half-vector angle (Table 2's "Model"),
        ``False`` interpolates the layer's table (Table 2's "Model-LUT").

    Returns
    -------
    SingleReflectionSpectra
        Shapes ``(..., 471)``.

    References
    ----------
    Fourneau et al. (2024), Eq. 34 (Section 4.3.1), Eqs. 17-19, 28, Table 2.
    """
    tables = stack_tables(stack) if tables is None else tuple(tables)
    if len(tables) != len(stack.layers):
        raise ValueError(f"{len(tables)} layer tables for {len(stack.layers)} layers")
    i = np.asarray(i, dtype=np.float64)
    o = np.asarray(o, dtype=np.float64)
    above = (i[..., 2] > 0.0) & (o[..., 2] > 0.0)
    # A last axis for the wavelengths the directions depend on: 1 (one refraction for all), or 471 when a
    # coated host disperses (each wavelength's own Snell angle, Fresnel terms and 1/n1^2).
    cos_i, cos_o = i[..., 2, None], o[..., 2, None]
    # The directions' tangential parts: Snell keeps their azimuth and divides them by n1 (refract_into_host);
    # kept as squared lengths, so that a wavelength's directions in the host cost a few scalars each.
    tangent_i = np.sum(i[..., :2] ** 2, axis=-1)[..., None]
    tangent_o = np.sum(o[..., :2] ** 2, axis=-1)[..., None]
    tangent_sum = np.sum((i[..., :2] + o[..., :2]) ** 2, axis=-1)[..., None]
    tangent_difference = np.sum((i[..., :2] - o[..., :2]) ** 2, axis=-1)[..., None]
    if stack.coating:
        n1 = stack.coating_indices()
        # f_t,0 = 1 - F at the angles in air; i, o refracted into the host; radiance scaled by 1/n1^2.
        path = (1.0 - coating_reflectance(cos_i, n1)) * (1.0 - coating_reflectance(cos_o, n1)) / (n1 * n1)
        scale = 1.0 / (n1 * n1)
        tangent_i, tangent_o = tangent_i * scale, tangent_o * scale
        tangent_sum, tangent_difference = tangent_sum * scale, tangent_difference * scale
        cos_i = np.sqrt(np.maximum(1.0 - tangent_i, 0.0))
        cos_o = np.sqrt(np.maximum(1.0 - tangent_o, 0.0))
    else:
        path = np.ones(np.broadcast_shapes(cos_i.shape, cos_o.shape))
    path = np.where(above[..., None], path, 0.0)
    # Angles for the table lookups by atan2 (precise near 0, unlike acos; what the GLSL twin does):
    # theta = atan2(|v_xy|, v_z), and theta_d = angle(i, h) = atan2(|i - o|, |i + o|), with h = (i + o) / |i + o|.
    theta_i = np.arctan2(np.sqrt(tangent_i), np.maximum(cos_i, 0.0))
    theta_o = np.arctan2(np.sqrt(tangent_o), np.maximum(cos_o, 0.0))
    length_sum = np.sqrt(tangent_sum + (cos_i + cos_o) ** 2)
    length_difference = np.sqrt(tangent_difference + (cos_i - cos_o) ** 2)
    h_z = np.where(length_sum > 1e-12, (cos_i + cos_o) / np.maximum(length_sum, 1e-300), 1.0)  # microfacet.half_vector's
    cos_theta_d = np.clip(0.5 * length_sum, 0.0, 1.0)  # microfacet.half_vector_cosine's |i + o| / 2
    theta_d = np.arctan2(length_difference, length_sum)
    cos_i_host = np.maximum(cos_i, 0.0)
    cos_o_host = np.maximum(cos_o, 0.0)
    # The host's absorption: each gap above a layer (and above the base) crossed down along i' and up along o'.
    gap = gap_transmittance(stack.tau_h, cos_i_host) * gap_transmittance(stack.tau_h, cos_o_host)
    layers = 0.0
    for l, (layer, table) in enumerate(zip(stack.layers, tables)):
        path = path * gap
        # Eq. 17: D(h) G1(i) G1(o) R(i.h) / (4 cos_i cos_o), G1/cos finite at grazing angles.
        lobe = (
            0.25
            * microfacet.ggx_D(h_z, layer.alpha)
            * microfacet.smith_G1_over_cos(cos_i_host, layer.alpha)
            * microfacet.smith_G1_over_cos(cos_o_host, layer.alpha)
        )
        if exact_reflectance and not layer.natural and not stack.dispersive_host:
            R = bragg.bragg_reflectance(
                np.maximum(cos_theta_d, microfacet.COS_THETA_MIN), colorimetry.WAVELENGTHS, layer.mirror(stack.n1)
            )
        else:
            R = lookup_columns(table.reflectance, theta_d)
        # The per-direction factors first (cheap), then one product per wavelength.
        layers = layers + (lobe * path) * R
        path = path * (lookup_columns(table.transmissivity, theta_i) * lookup_columns(table.transmissivity, theta_o))
    path = path * gap
    return SingleReflectionSpectra(layers=np.broadcast_to(layers, path.shape) * 1.0, base=path / np.pi)


def single_reflection_brdf(
    stack: LayeredBragg, i: ArrayLike, o: ArrayLike, tables: Sequence[LayerTables] | None = None, exact_reflectance: bool = False,
) -> np.ndarray:
    """
    The single-reflection BRDF of a layered Bragg structure (Eq. 34) in linear sRGB (1/sr): the Bragg
    layers' spectral term integrated against the CMFs, plus the base's spectral transmission factor
    integrated likewise and multiplied by its RGB albedo ``rho_d``. The coating's Dirac reflection is
    left out (:func:`coating_reflectance`).

    Parameters
    ----------
    stack : LayeredBragg
    i, o : array_like, shape (..., 3)
        Unit directions in air, ``n = +z``.
    tables, exact_reflectance
        As in :func:`single_reflection_spectra`.

    Returns
    -------
    ndarray, shape (..., 3)
        Unclamped linear sRGB (vivid colours have negative channels).

    References
    ----------
    Fourneau et al. (2024), Eq. 34; the colour convention of :mod:`explorer.physics.colorimetry`.
    """
    spectra = single_reflection_spectra(stack, i, o, tables, exact_reflectance)
    return colorimetry.spectrum_to_rgb(spectra.layers) + np.asarray(stack.rho_d) * colorimetry.spectrum_to_rgb(spectra.base)


def _host_angle(cos_theta, n1: float, coating: bool) -> tuple[np.ndarray, np.ndarray]:
    """(theta', coating Fresnel F): the angle in the host of incidence ``cos_theta`` in air, by atan2."""
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    if not coating:
        return np.arctan2(s, c), np.zeros_like(c)
    F = coating_reflectance(c, n1)
    s = s / n1
    return np.arctan2(s, np.sqrt(np.maximum(1.0 - s * s, 0.0))), F


def stack_specular_rgb(stack: LayeredBragg, cos_theta: ArrayLike, tables: Sequence[LayerTables] | None = None) -> np.ndarray:
    """
    The smooth limit's specular colour of a stack at incidence ``cos_theta`` (in air), in linear sRGB: the
    weight of the mirror reflection, ``F + (1 - F)^2 sum_l R_l(theta') prod_{k<l} (1 - R_k(theta'))^2``,
    with ``F`` the coating's Fresnel reflectance, ``theta'`` the refracted angle and ``R_l`` Yeh's
    reflectance. What the ``sphere`` and ``gradient`` views show for ``shaders/bragg_stack.brd``; not part
    of Eq. 34 (which has no Dirac term for rough layers).

    In the smooth limit (``alpha -> 0``) each layer is one Bragg mirror, which transmits ``1 - R_l`` (Yeh's
    ``R + T = 1`` for lossless layers) and ``F_alpha`` of Eq. 28 tends to the identity. The integrated
    transmissivity of the rough layer must not be used here: it averages ``T`` over the half-vector
    angles of the layer's roughness, so beside a band edge or the host's total internal reflection it
    exceeds ``1 - R_l(theta')``, and the sum reflected up to 1.15 times the incident light. With smooth
    transmissions every wavelength's sum is at most 1 (by induction over the layers, each term at most
    what the layers above let through), so the luminance of the colour is too.
    """
    tables = stack_tables(stack) if tables is None else tuple(tables)
    # Per wavelength where a coated host disperses (theta', F of shape (..., 471)), else one angle (..., 1).
    theta, F = _host_angle(np.asarray(cos_theta, dtype=np.float64)[..., None], stack.coating_indices(), stack.coating)
    through = (1.0 - F) ** 2
    gap = gap_transmittance(stack.tau_h, np.cos(theta)) ** 2  # a gap down and up at theta'
    spectrum = 0.0
    for table in tables:
        through = through * gap
        R = lookup_columns(table.reflectance, theta)
        spectrum = spectrum + through * R
        T = 1.0 - R if table.transmittance is None else lookup_columns(table.transmittance, theta)  # absorbing: T < 1 - R
        through = through * T ** 2
    if F.shape[-1] > 1:  # a dispersive coating's Fresnel reflectance is a spectrum
        return colorimetry.spectrum_to_rgb(spectrum + F)
    return colorimetry.spectrum_to_rgb(spectrum) + F  # F is flat: white is (1, 1, 1)


def transmission_probability(mean_transmissivity: ArrayLike, cos_theta: ArrayLike, alpha: ArrayLike) -> np.ndarray:
    """
    The probability of transmission through a rough Bragg layer (Eq. 31), with the numerator averaged
    over wavelengths (the "multiplexed" form of Section 4.2.3): ``2 <f_t cos theta>_lambda / (1 + G1)``.
    """
    p = 2.0 * np.asarray(mean_transmissivity) / (1.0 + microfacet.smith_G1(cos_theta, alpha))
    return np.clip(p, 0.0, 1.0)


def layer_choice_probabilities(
    stack: LayeredBragg, cos_theta: ArrayLike, tables: Sequence[LayerTables] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """
    The probability that a path entering at ``cos_theta`` (in air) reflects on Bragg layer ``l`` (Eq. 35),
    ``p_refl,l = (1 - p_trans,l) prod_{k<l} p_trans,k`` with ``p_trans,0 = 1 - F`` through the coating,
    and the probability of reaching the base. Importance sampling's layer choice (Section 4.3.2).

    Returns
    -------
    p_refl : ndarray, shape (..., number of layers)
    p_base : ndarray, shape (...)
    """
    tables = stack_tables(stack) if tables is None else tuple(tables)
    # A dispersive host: its index at 550 nm (n1), one set of probabilities for every wavelength (an estimate's).
    theta, F = _host_angle(cos_theta, stack.n1, stack.coating)
    reach = 1.0 - F
    p_refl = []
    for layer, table in zip(stack.layers, tables):
        mean_t = lookup(table.transmissivity.mean(axis=1, dtype=np.float64)[:, None], theta)[..., 0]
        p_trans = transmission_probability(mean_t, np.cos(theta), layer.alpha)
        p_refl.append((1.0 - p_trans) * reach)
        reach = reach * p_trans
    return np.stack(p_refl, axis=-1), reach


# --------------------------------------------------------------------------------------------------
# Timings (the goals: F_alpha for a new alpha within 100 ms, a layer's tables within 10 ms)


def figure7_layers() -> dict[str, tuple[RoughBraggLayer, float]]:
    """Figure 7's layers A, B and A' as ``{name: (layer, host n1)}``."""
    return {
        "A (n1=1, d1=d2=250 nm, N=10, alpha=0.1)": (RoughBraggLayer(1.5, 500.0, 0.5, 10, 0.1), 1.0),
        "B (n1=1, d1=d2=494 nm, N=10, alpha=0.05)": (RoughBraggLayer(1.5, 988.0, 0.5, 10, 0.05), 1.0),
        "A' (n1=1.35, d1=d2=250 nm, N=10, alpha=0.1)": (RoughBraggLayer(1.5, 500.0, 0.5, 10, 0.1), 1.35),
    }


def measure_timings(
    alphas: Sequence[float] = (0.025, 0.1, 0.4), layers: Mapping[str, tuple[RoughBraggLayer, float]] | None = None, repeats: int = 5,
) -> dict:
    """
    Median wall-clock times (ms) of building ``F_alpha`` for each of ``alphas`` and each layer's tables
    (``layers``: the Figure 7 configurations A, B and A' by default), over ``repeats`` interleaved
    rounds (every case once per round) after one warm-up round.

    Every ``F_alpha`` is built from scratch (:func:`explorer.physics.microfacet.transmission_filter_table`,
    never the cache of :func:`transmission_filter_for`): a new ``alpha`` each time. A layer's tables
    are timed without its filter (which depends on ``alpha`` only, as in :func:`layer_tables`).
    """
    layers = figure7_layers() if layers is None else layers
    filters = {layer.alpha: microfacet.transmission_filter_table(layer.alpha) for layer, _ in layers.values()}
    cases = [(f"alpha={alpha:g}", functools.partial(microfacet.transmission_filter_table, alpha)) for alpha in alphas]
    cases += [(name, functools.partial(layer_tables, layer, n1, filters[layer.alpha], cached=False)) for name, (layer, n1) in layers.items()]
    times: dict[str, list[float]] = {name: [] for name, _ in cases}
    for round_ in range(repeats + 1):
        for name, build in cases:
            start = time.perf_counter()
            build()
            if round_:  # round 0 warms up
                times[name].append(time.perf_counter() - start)
    medians = {name: 1e3 * float(np.median(t)) for name, t in times.items()}
    return {
        "transmission_filter_ms": {f"alpha={alpha:g}": medians[f"alpha={alpha:g}"] for alpha in alphas},
        "layer_tables_ms": {name: medians[name] for name in layers},
        "repeats": repeats,
    }


if __name__ == "__main__":  # python -m explorer.physics.layered: print the timings
    timings = measure_timings()
    for alpha, ms in timings["transmission_filter_ms"].items():
        print(f"F_alpha, {alpha}: {ms:.1f} ms (goal 100 ms; the paper: 600 ms)")
    for name, ms in timings["layer_tables_ms"].items():
        print(f"layer tables, {name}: {ms:.1f} ms (goal 10 ms; the paper: 40 ms)")
