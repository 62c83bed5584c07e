"""
The position-free Monte Carlo reference for layered Bragg structures (Fourneau et al. 2024, Section 4.2,
after Guo, Hašan & Zhao 2018): a spectral, unbiased random walk through the structure of
:class:`explorer.physics.layered.LayeredBragg`, with every number of bounces between its layers.

The structure, top to bottom: a smooth coating (the interface from air to the host ``n1``, Fresnel and
Snell; none when ``coating`` is off, or index-matched when ``n1 = 1``), rough Bragg layers in the host,
and a Lambertian base of RGB albedo ``rho_d``. A path is traced from the light's direction ``i`` and
carries a few wavelengths of the 471 of :mod:`explorer.physics.colorimetry` (hero wavelength sampling,
Wilkie et al. 2014: Section 4.2.3's "multiplexed" walk with spectral MIS) and an RGB factor for the base's
albedo, which has no spectrum (as :func:`explorer.physics.layered.single_reflection_brdf` multiplies the
base's term in RGB).

At each event:

- **coating** (from inside, going up): the part ``1 - F`` escapes (the albedo's tally), the part ``F``
  (total internal reflection included) is reflected: a deterministic split, no random choice. Entering
  from air, ``F(theta_i)`` is the coating's Dirac reflection (Eq. 34's ``f_r,0``), tallied exactly.
- **rough Bragg layer** (from either side, its normal flipped from below, Section 4.2.2): a microfacet
  normal ``m`` is drawn from GGX's visible normals (Heitz 2018); the facet, a Bragg mirror, reflects the
  path about ``m`` with Yeh's probability ``R_lambda(i.m)`` (weight Smith's ``G1(o)``: the estimator of
  Eq. 17's ``f_r cos``) or lets it through, ballistically and in the same direction (Section 4.2.1), with
  probability ``T = 1 - R`` (weight ``G1(i)``: the estimator of Eq. 22's ``f_t cos``, whose expectation
  is Eq. 28: marginally, the path crosses with probability ``f_t cos theta / G1``, Eqs. 28 and 30). What neither keeps, ``A`` (Eq. 30: paths reflected into the layer, ``G1 < 1``), is the light
  single scattering among microfacets loses: absorbed. A path's first events take both branches at once
  (splitting), transmission then with Eq. 28's tabulated expectation.
- **base**: Lambertian, cosine-sampled; the path goes on with probability ``max(rho_d)``, its RGB factor
  multiplied by ``rho_d / max(rho_d)``.
- Russian roulette ends paths of low throughput (unbiased: survivors are divided by their probability).

A dispersive host (:attr:`explorer.physics.layered.LayeredBragg.medium_n1`) under the coating refracts each
wavelength its own way: a path then carries its hero wavelength alone and refracts, reflects at the coating and
leaves it with the host's index at that wavelength.

The BRDF ``f(i, o)`` comes by next-event estimation toward ``o``: at every reflection on a layer from
above and at every base bounce, the vertex's BRDF toward the refracted ``o'``, times the ballistic
transmissivity of the layers above along ``o'``, the coating's ``1 - F(theta_o)`` and the radiance's
``1 / n1^2`` (Eq. 34's factors, here for paths of any order). The directional albedo is the escaping
flux (plus the coating's Dirac ``F``). Both report a standard error, the spread of independent replicates.

References
----------
Fourneau, Pacanowski, Barla (2024). Interactive Exploration of Vivid Material Iridescence using Bragg
Mirrors. Computer Graphics Forum 43(2). Section 4.2 (Eqs. 17-19, 22, 28-33), Eq. 34, Appendix C.
Guo, Hašan, Zhao (2018). Position-free Monte Carlo simulation for arbitrary layered BSDFs. ACM TOG 37(6).
Heitz (2018). Sampling the GGX distribution of visible normals. JCGT 7(4).
Wilkie, Nawaz, Droske, Weidlich, Hanika (2014). Hero wavelength spectral sampling. Computer Graphics Forum 33(4).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry, layered, microfacet, microsurface
from explorer.physics.fresnel import fresnel_reflectance

#: How a rough layer's microsurface scatters: ``single``, Eq. 17's one reflection and Eq. 28's ballistic
#: transmission (what single scattering loses, Eq. 30's ``A``, is absorbed); ``walk``, every bounce among
#: its facets (the random walk of Heitz et al. 2016, :mod:`explorer.physics.microsurface`; albedo only).
MICROSURFACES = ("single", "walk")
#: Paths traced together (a few hundred bytes each).
BATCH_PATHS = 1 << 17
#: Russian roulette starts after this many events, for paths whose weight fell below the threshold.
ROULETTE_DEPTH = 4
ROULETTE_THRESHOLD = 0.1
#: A hard stop on path length; with roulette no path of measurable weight gets there.
MAX_EVENTS = 512
#: A path's first layer events take both branches, reflection and transmission (splitting: the first
#: choices carry most of the variance); later events choose one.
SPLIT_EVENTS = 3
#: Wavelengths per path (hero wavelength sampling, Wilkie et al. 2014): the first decides, all are tallied.
HERO_WAVELENGTHS = 4
#: Independent replicates per query: the standard error is their spread (the wavelengths are stratified
#: within a replicate, which makes its paths negatively correlated).
REPLICATES = 32


def _rgb_matrix() -> np.ndarray:
    """The (471, 3) matrix taking a spectrum (reflectance at the 1-nm nodes) to linear sRGB."""
    return colorimetry.colour_matching_functions() @ colorimetry.xyz_to_rgb_matrix().T


def wavelength_pdf() -> np.ndarray:
    """
    The probability of each of the 471 wavelengths of a path: proportional to ``sum_c |M_c(lambda)|``, with
    ``M`` the spectrum-to-RGB matrix, so that a path's RGB weight ``M(lambda) / p(lambda)`` is bounded.
    """
    w = np.abs(_rgb_matrix()).sum(axis=1)
    return w / w.sum()


@dataclass(frozen=True)
class PositionFreeResult:
    """
    A Monte Carlo estimate: ``value`` and its standard error per query, linear sRGB.

    Attributes
    ----------
    value : ndarray, shape (n, 3)
        The estimates (directional albedo, or ``f(i, o)`` in 1/sr).
    stderr : ndarray, shape (n, 3)
        Their standard errors (the spread of independent replicates over the square root of their number).
    paths : int
        Paths per query.
    seconds : float
        Wall-clock time.
    """

    value: np.ndarray
    stderr: np.ndarray
    paths: int
    seconds: float


class PositionFree:
    """
    The random walk through one layered Bragg structure (see the module docstring).

    Each path carries :data:`HERO_WAVELENGTHS` wavelengths of the 471-nm grid (:meth:`sample_wavelengths`:
    drawn with :func:`wavelength_pdf`, stratified over the paths of a replicate); the first decides every
    choice with its own probabilities, and each adds ``f_k M(lambda_k) / (K p(lambda_k))`` divided by
    the mean of the wavelengths' path probabilities (:meth:`trace`): an unbiased estimate of the
    spectrum's colour (:func:`explorer.physics.colorimetry.spectrum_to_rgb`).

    Parameters
    ----------
    stack : explorer.physics.layered.LayeredBragg
    tables : sequence of explorer.physics.layered.LayerTables, optional
        One per layer (:func:`explorer.physics.layered.stack_tables`); built when omitted.

    References
    ----------
    Fourneau et al. (2024), Section 4.2; Guo et al. (2018).
    """

    def __init__(self, stack: layered.LayeredBragg, tables=None, microsurface: str = "single"):
        if microsurface not in MICROSURFACES:
            raise ValueError(f"microsurface must be one of {', '.join(MICROSURFACES)}, got {microsurface!r}")
        self.walk = microsurface == "walk"
        self.stack = stack
        tables = layered.stack_tables(stack) if tables is None else tuple(tables)
        if len(tables) != len(stack.layers):
            raise ValueError(f"{len(tables)} layer tables for {len(stack.layers)} layers")
        self.tables = tables
        self.alphas = [float(microfacet.check_alpha(layer.alpha)) for layer in stack.layers]
        # The layers' tables, float32 (the shader's textures): R_lambda(theta) and f_t cos theta (Eq. 28).
        self.reflectance = [np.ascontiguousarray(t.reflectance, dtype=np.float32) for t in tables]
        self.transmissivity = [np.ascontiguousarray(t.transmissivity, dtype=np.float32) for t in tables]
        # Natural layers' facets transmit their exact T (absorbing: < 1 - R; the rest is absorbed); None: 1 - R.
        self.transmittance = [None if getattr(t, "transmittance", None) is None
                              else np.ascontiguousarray(t.transmittance, dtype=np.float32) for t in tables]
        if self.walk and any(t is not None for t in self.transmittance):
            raise ValueError("the microsurface walk's facets transmit 1 - R: natural (absorbing, dispersive or "
                             "disordered) layers take microsurface='single'")
        self.rgb = _rgb_matrix()
        self.pdf = wavelength_pdf()
        self.cdf = np.cumsum(self.pdf)
        self.cdf[-1] = 1.0
        self.rgb_weight = self.rgb / self.pdf[:, None]  # M(lambda) / p(lambda)
        self.rho = np.asarray(stack.rho_d, dtype=np.float64)
        self.n1 = stack.n1 if stack.coating else 1.0
        # A coated dispersive host refracts each wavelength its own way: a path carries its hero wavelength
        # alone (K = 1; the others would need directions of their own) and refracts with its index.
        self.dispersive = bool(stack.coating and stack.dispersive_host)
        self.host_n = stack.host_index() if self.dispersive else None
        self.hero_wavelengths = 1 if self.dispersive else HERO_WAVELENGTHS
        self.refracts = stack.coating and (stack.n1 != 1.0 or self.dispersive)
        self.tau_h = float(stack.tau_h)

    # ----------------------------------------------------------------------------------------------
    # Tables and interfaces

    @staticmethod
    def _lookup(table: np.ndarray, cos_theta: np.ndarray, wavelength: np.ndarray) -> np.ndarray:
        """
        A per-angle table (rows every 0.25 deg) at ``acos(cos_theta)`` (shape (n,)), linearly, in columns
        ``wavelength`` (shape (n, K)): shape (n, K).
        """
        c = np.clip(cos_theta, 0.0, 1.0)
        theta = np.arctan2(np.sqrt(np.maximum(1.0 - c * c, 0.0)), c)
        x = theta / microfacet.THETA_STEP
        k = np.minimum(np.floor(x).astype(np.int64), table.shape[0] - 2)
        f = (x - k)[:, None]
        k = k[:, None]
        return table[k, wavelength] * (1.0 - f) + table[k + 1, wavelength] * f

    def _coating_F_air(self, cos_air: np.ndarray, n=None) -> np.ndarray:
        """The coating's Fresnel reflectance seen from air (0 when it does not refract); ``n``: the host's index per
        row (a dispersive host's at each path's wavelength), ``n1`` by default."""
        if not self.refracts:
            return np.zeros_like(cos_air)
        return layered.coating_reflectance(cos_air, self.n1 if n is None else n)

    def _coating_F_host(self, cos_host: np.ndarray, n=None) -> np.ndarray:
        """The coating's Fresnel reflectance seen from the host, total internal reflection included."""
        if not self.refracts:
            return np.zeros_like(cos_host)
        return fresnel_reflectance(np.clip(cos_host, 1e-12, 1.0), self.n1 if n is None else n, 1.0)

    def _into_host(self, direction_air: np.ndarray, n=None) -> np.ndarray:
        """An upward direction in air as seen in the host (Snell), unchanged when the coating does not refract."""
        if not self.refracts:
            return np.asarray(direction_air, dtype=np.float64)
        return layered.refract_into_host(direction_air, self.n1 if n is None else n)

    def sample_wavelengths(self, count: int, groups: int, rng: np.random.Generator) -> np.ndarray:
        """
        :data:`HERO_WAVELENGTHS` wavelength indices per path (1 in a coated dispersive host) for ``groups`` consecutive runs of ``count``
        paths: the first (the hero) drawn from :func:`wavelength_pdf` and stratified within each run, the
        others at the hero's quantile plus ``k / K`` (mod 1), so that each is distributed as the hero
        (Wilkie et al. 2014). Shape ``(groups * count, K)``.
        """
        K = self.hero_wavelengths
        u = ((np.arange(count)[None, :] + rng.random((groups, count))) / count).reshape(-1, 1)
        u = (u + np.arange(K)[None, :] / K) % 1.0
        return np.minimum(np.searchsorted(self.cdf, u, side="right"), self.pdf.size - 1)

    def _walk_layer(self, l, at, d, beta, pi, gap, alive, wavelength, rng) -> None:
        """
        Multiple scattering on layer ``l``'s microsurface for the paths ``at`` (in place): the random walk
        of :func:`explorer.physics.microsurface.walk` takes each to the layer's top (reflected) or bottom
        (transmitted, ballistically after every crossing), its facets reflecting with the layer's ``R_lambda``.
        """
        table = self.reflectance[l]
        d[at], beta[at], pi[at], up, kept, _, _ = microsurface.walk(
            d[at], beta[at], pi[at], self.alphas[l], lambda cos_d, rows: self._lookup(table, cos_d, wavelength[rows]), rng)
        alive[at[~kept]] = False
        gap[at] = np.where(up, l, l + 1)

    # ----------------------------------------------------------------------------------------------
    # The walk

    def trace(
        self, i_air: np.ndarray, o_air: np.ndarray | None, wavelength: np.ndarray, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """
        Trace one path per row of ``i_air`` (unit directions toward the light, in air, ``z > 0``), each with
        its wavelength indices ``wavelength`` (shape (P, K), the first the hero; :meth:`sample_wavelengths`).

        Every choice follows the hero wavelength's probabilities. Each wavelength ``k`` carries its
        throughput ``f_k`` (the product of its weights, not divided by the choices' probabilities) and
        the probability ``pi_k`` that its own choices would have taken this path; a tally divides ``f_k``
        by the mean of the ``pi_j`` (spectral MIS with the balance heuristic, Wilkie et al. 2014).

        Returns
        -------
        albedo : ndarray, shape (P, 3)
            Each path's escaping flux in linear sRGB (the coating's Dirac ``F(theta_i)`` excluded).
        brdf : ndarray, shape (P, 3)
            Each path's next-event estimate of ``f(i, o)`` (1/sr), when ``o_air`` (shape (P, 3)) is given;
            zeros otherwise.
        """
        P = i_air.shape[0]
        L = len(self.tables)
        wl = np.asarray(wavelength).reshape(P, -1)
        K = wl.shape[1]
        albedo = np.zeros((P, 3))
        brdf = np.zeros((P, 3))
        rgb_weight = self.rgb_weight[wl] / K  # M(lambda_k) / (K p(lambda_k)), per path: (P, K, 3)

        def tally(into, rows, value):
            """Add ``value`` (n, K), divided by the MIS denominator, as RGB to the paths ``rows``."""
            value = value / np.maximum(pi[rows].mean(axis=1), 1e-300)[:, None]
            np.add.at(into, pid[rows], np.einsum("nk,nkc->nc", value, rgb_weight[pid[rows]]) * colour[rows])

        # The host's index per path: n1, or a dispersive host's at the path's (only) wavelength.
        n_path = self.host_n[wl[:, 0]] if self.dispersive else None
        # Entering: the part 1 - F crosses the coating (its reflection F is the Dirac, tallied apart).
        beta = np.repeat((1.0 - self._coating_F_air(np.clip(i_air[:, 2], 0.0, 1.0), n_path))[:, None], K, axis=1)
        pi = np.ones((P, K))
        d = -self._into_host(i_air, n_path)  # propagation direction in the host, going down
        gap = np.zeros(P, dtype=np.int64)  # between interfaces gap and gap + 1 (0: coating, L + 1: base)
        colour = np.ones((P, 3))  # the base's RGB albedo, once per bounce on it
        pid = np.arange(P)
        splits = np.zeros(P, dtype=np.int64)  # layer events taken with both branches so far
        nee = o_air is not None
        if nee:
            # What a vertex below layer k sends along o, per unit radiance toward o' in the host:
            # (1 - F(theta_o)) / n1^2 times Eq. 28's transmissivity of every layer above (Eq. 34's factors).
            o_host = self._into_host(o_air, n_path)
            n_exit = self.n1 if n_path is None else n_path
            exit_weight = (1.0 - self._coating_F_air(np.clip(o_air[:, 2], 0.0, 1.0), n_path)) / (n_exit * n_exit)
            exit_weight = np.where((o_air[:, 2] > 0.0) & (i_air[:, 2] > 0.0), exit_weight, 0.0)
            # The host's gaps (tau_h): the one above a vertex and every one above it, crossed along o'.
            gap_o = layered.gap_transmittance(self.tau_h, o_host[:, 2])[:, None]
            E = [np.repeat(exit_weight[:, None], K, axis=1) * gap_o]
            for table in self.transmissivity:
                E.append(E[-1] * self._lookup(table, o_host[:, 2], wl) * gap_o)
        for event in range(MAX_EVENTS):
            if pid.size == 0:
                break
            going_down = d[:, 2] < 0.0
            interface = np.where(going_down, gap + 1, gap)
            if self.tau_h > 0.0:  # every path crosses its gap to the next interface: Beer-Lambert in the host
                beta *= layered.gap_transmittance(self.tau_h, np.abs(d[:, 2]))[:, None]
            alive = np.ones(pid.size, dtype=bool)
            born = []  # the reflected branches of this event's splits
            # -- the coating, from inside: deterministic split (escape 1 - F, reflect F)
            at = np.flatnonzero(interface == 0)
            if at.size:
                F = self._coating_F_host(d[at, 2], None if n_path is None else n_path[pid[at]])
                tally(albedo, at, beta[at] * (1.0 - F)[:, None])
                beta[at] *= F[:, None]
                d[at, 2] = -d[at, 2]
                alive[at[F <= 0.0]] = False
            # -- the rough Bragg layers
            for l in range(L):
                at = np.flatnonzero(interface == l + 1)
                if at.size == 0:
                    continue
                alpha = self.alphas[l]
                if self.walk:
                    self._walk_layer(l, at, d, beta, pi, gap, alive, wl[pid[at]], rng)
                    continue
                from_above = going_down[at]
                cos_in = np.abs(d[at, 2])
                j = wl[pid[at]]
                b = beta[at]
                wi = np.stack([-d[at, 0], -d[at, 1], cos_in], axis=-1)  # toward the light, facing frame
                if nee:
                    # Next event toward o' (upward): only a path arriving from above reflects toward it.
                    up = at[from_above]
                    if up.size:
                        oh = o_host[pid[up]]
                        wiu = wi[from_above]
                        lobe = (0.25 * microfacet.ggx_D(microfacet.half_vector(wiu, oh)[:, 2], alpha)
                                * microfacet.smith_G1_over_cos(wiu[:, 2], alpha)
                                * microfacet.smith_G1_over_cos(oh[:, 2], alpha))
                        R = self._lookup(self.reflectance[l], microfacet.half_vector_cosine(wiu, oh), j[from_above])
                        tally(brdf, up, b[from_above] * R * E[l][pid[up]] * lobe[:, None])
                # A visible normal m (Heitz 2018), the mirror direction o about it, and Yeh's R(i.m) there.
                m = microfacet.sample_ggx_visible_normal(wi, alpha, rng.random(at.size), rng.random(at.size))
                cos_d = np.sum(wi * m, axis=-1)
                o = 2.0 * cos_d[:, None] * m - wi
                R = np.clip(self._lookup(self.reflectance[l], cos_d, j), 0.0, 1.0)  # (n, K)
                G1_i = microfacet.smith_G1(cos_in, alpha)[:, None]
                G1_o = microfacet.smith_G1(o[:, 2], alpha)[:, None]
                # The first SPLIT_EVENTS events take both branches: reflection R G1(o) (Eq. 17's f_r cos / pdf)
                # and transmission f_t cos theta (Eq. 28, its expectation over m). Later ones choose as the
                # facet does, reflection with probability R (the hero's): weights G1(o) R and G1(i) T, each
                # wavelength's probability R or T = 1 - R kept in pi.
                split = splits[at] < SPLIT_EVENTS
                splits[at[split]] += 1
                chosen = rng.random(at.size) < R[:, 0]
                reflect = split | chosen
                transmit = split | ~chosen
                beta_r = b * R * G1_o
                pi_r = pi[at] * np.where(split[:, None], 1.0, R)
                # A natural layer's facet transmits T (<= 1 - R), chosen with probability 1 - R: the rest is absorbed.
                T = 1.0 - R if self.transmittance[l] is None else np.clip(self._lookup(self.transmittance[l], cos_d, j), 0.0, 1.0)
                beta_t = b * np.where(split[:, None], self._lookup(self.transmissivity[l], cos_in, j), T * G1_i)
                pi_t = pi[at] * np.where(split[:, None], 1.0, 1.0 - R)
                sign = np.where(from_above, 1.0, -1.0)
                d_r = np.stack([o[:, 0], o[:, 1], sign * o[:, 2]], axis=-1)
                lost = o[:, 2] <= 0.0  # mirrored into the layer: single scattering loses it (Eq. 30's A)
                # Reflection in place where chosen; a split path's reflected branch is a new path.
                keep = reflect & ~split
                beta[at[keep]], pi[at[keep]], d[at[keep]] = beta_r[keep], pi_r[keep], d_r[keep]
                alive[at[keep & lost]] = False
                new = split & ~lost
                if new.any():
                    born.append((beta_r[new], pi_r[new], d_r[new], gap[at[new]], colour[at[new]], pid[at[new]], splits[at[new]]))
                # Transmission: ballistic (Section 4.2.1), the direction unchanged.
                tr = at[transmit]
                beta[tr], pi[tr] = beta_t[transmit], pi_t[transmit]
                gap[tr] = np.where(from_above[transmit], l + 1, l)
            # -- the Lambertian base
            at = np.flatnonzero(interface == L + 1)
            if at.size:
                if nee:
                    colour_at = colour[at].copy()
                    colour[at] *= self.rho / np.pi
                    tally(brdf, at, beta[at] * E[L][pid[at]])
                    colour[at] = colour_at
                q = float(self.rho.max())
                survive = rng.random(at.size) < q
                alive[at[~survive]] = False
                if q > 0.0:
                    colour[at] *= self.rho / q
                    # A cosine-weighted upward direction: weight rho (f cos / pdf), carried in ``colour``.
                    u1, u2 = rng.random(at.size), rng.random(at.size)
                    radius, phi = np.sqrt(u1), 2.0 * np.pi * u2
                    d[at] = np.stack([radius * np.cos(phi), radius * np.sin(phi), np.sqrt(np.maximum(1.0 - u1, 0.0))], axis=-1)
                    gap[at] = L
            # -- Russian roulette, on the MIS-weighted throughput
            if event >= ROULETTE_DEPTH:
                level = (beta / np.maximum(pi.mean(axis=1), 1e-300)[:, None]).max(axis=1) * colour.max(axis=1)
                low = np.flatnonzero(alive & (level < ROULETTE_THRESHOLD))
                if low.size:
                    q = level[low] / ROULETTE_THRESHOLD
                    keep = rng.random(low.size) < q
                    alive[low[~keep]] = False
                    beta[low[keep]] /= q[keep][:, None]
            if born or not alive.all():
                parts = [(beta[alive], pi[alive], d[alive], gap[alive], colour[alive], pid[alive], splits[alive])] + born
                beta, pi, d, gap, colour, pid, splits = (np.concatenate(column) for column in zip(*parts))
        return albedo, brdf

    # ----------------------------------------------------------------------------------------------
    # Estimates

    def replicate(self, i_air: np.ndarray, o_air: np.ndarray | None, per: int, key: tuple) -> np.ndarray:
        """
        One replicate: ``per`` paths per query (rows of ``i_air``), its generator seeded by ``key``; the
        means of its albedo and BRDF tallies, shape ``(2, Q, 3)``.
        """
        Q = i_air.shape[0]
        rng = np.random.default_rng(key)
        means = np.zeros((2, Q, 3))
        queries_per_batch = max(1, BATCH_PATHS // per)
        for start in range(0, Q, queries_per_batch):
            queries = np.arange(start, min(Q, start + queries_per_batch))
            rows = np.repeat(queries, per)
            wavelength = self.sample_wavelengths(per, queries.size, rng)
            a, f = self.trace(i_air[rows], None if o_air is None else o_air[rows], wavelength, rng)
            for k, tally in enumerate((a, f)):
                means[k, queries] = tally.reshape(queries.size, per, 3).mean(axis=1)
        return means

    def _replicates(
        self, i_air: np.ndarray, o_air: np.ndarray | None, samples: int, seed,
        progress: Callable[[int, int], None] | None = None,
    ) -> np.ndarray:
        """
        The replicates' means of the albedo and BRDF tallies per query (rows of ``i_air``): shape
        ``(replicates, 2, Q, 3)``, from ``samples`` paths in :data:`REPLICATES` independent replicates
        (one path each below 2 per replicate), each seeded by ``(seed, its index)`` so that the result
        does not depend on how many processes trace them (:data:`PARALLEL_PATHS`).
        """
        Q = i_air.shape[0]
        replicates = REPLICATES if samples >= 2 * REPLICATES else samples
        per = samples // replicates
        replicates = samples // per
        keys = [tuple(np.atleast_1d(seed).tolist()) + (rep,) for rep in range(replicates)]
        workers = _workers() if replicates * per * Q >= PARALLEL_PATHS else 1
        means = np.zeros((replicates, 2, Q, 3))
        if workers > 1:
            import concurrent.futures
            import multiprocessing

            with concurrent.futures.ProcessPoolExecutor(
                workers, mp_context=multiprocessing.get_context("fork"), initializer=_set_worker, initargs=(self,)
            ) as pool:
                futures = {pool.submit(_worker_replicate, i_air, o_air, per, key): rep for rep, key in enumerate(keys)}
                for done, future in enumerate(concurrent.futures.as_completed(futures), start=1):
                    means[futures[future]] = future.result()
                    if progress is not None:
                        progress(done * per * Q, replicates * per * Q)
            return means
        for rep, key in enumerate(keys):
            means[rep] = self.replicate(i_air, o_air, per, key)
            if progress is not None:
                progress((rep + 1) * per * Q, replicates * per * Q)
        return means

    @staticmethod
    def _combine(means: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Mean and standard error over replicates: albedo mean, its error, BRDF mean, its error."""
        replicates = means.shape[0]
        mean = means.mean(axis=0)
        if replicates > 1:
            stderr = means.std(axis=0, ddof=1) / np.sqrt(replicates)
        else:
            stderr = np.full_like(mean, np.inf)
        return mean[0], stderr[0], mean[1], stderr[1]

    def _estimate(self, i_air, o_air, samples: int, seed, progress=None):
        """Per query: mean and standard error of the albedo and BRDF tallies from ``samples`` paths."""
        return self._combine(self._replicates(i_air, o_air, samples, seed, progress))

    def albedo(self, theta_deg, samples: int = 20000, seed: int = 0, progress=None,
               target_stderr: float | None = None, max_seconds: float = np.inf) -> PositionFreeResult:
        """
        The directional albedo at incidence ``theta_deg`` (degrees, in air): the flux that escapes after any
        number of bounces, plus the coating's Dirac reflection ``F(theta)``, per unit incident flux.

        Parameters
        ----------
        theta_deg : array_like of float
            Incidence angles in [0, 90) degrees.
        samples : int
            Paths per angle (at least 1).
        seed : int
            The generator's seed: the same seed, angles and samples give the same result.
        progress : callable, optional
            ``progress(done, total)`` (paths) after each batch.
        target_stderr : float, optional
            Progressive: go on by rounds of ``samples`` paths per angle (each round's own seed) until
            every channel's standard error is at most this, or ``max_seconds`` have passed.
        max_seconds : float
            The progressive estimate's time budget (it ends after the round that crosses it).

        Returns
        -------
        PositionFreeResult
            ``value`` and ``stderr`` of shape ``(len(theta_deg), 3)``, linear sRGB; ``paths`` per angle.
        """
        start = time.perf_counter()
        theta = np.radians(np.atleast_1d(np.asarray(theta_deg, dtype=np.float64)))
        if not np.all((theta >= 0.0) & (theta < 0.5 * np.pi)):
            raise ValueError("incidence angles must be in [0, 90) degrees")
        if int(samples) < 1:
            raise ValueError(f"samples must be at least 1, got {samples}")
        i_air = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
        rounds = [self._replicates(i_air, None, int(samples), (seed, 0), progress)]
        while target_stderr is not None and time.perf_counter() - start < max_seconds:
            if self._combine(np.concatenate(rounds))[1].max() <= target_stderr:
                break
            rounds.append(self._replicates(i_air, None, int(samples), (seed, len(rounds)), progress))
        mean, stderr, _, _ = self._combine(np.concatenate(rounds))
        # The coating's Dirac, exactly: F (flat), or the RGB of its spectrum in a dispersive host.
        F = layered.coating_rgb(self.stack, np.cos(theta)) if self.dispersive else self._coating_F_air(np.cos(theta))[:, None]
        return PositionFreeResult(mean + F, stderr, int(samples) * len(rounds), time.perf_counter() - start)

    def brdf(self, i_air, o_air, samples: int = 256, seed: int = 0, progress=None) -> PositionFreeResult:
        """
        The BRDF ``f(i, o)`` (1/sr, linear sRGB) by next-event estimation, without the coating's Dirac.

        Parameters
        ----------
        i_air, o_air : array_like, shape (n, 3)
            Unit directions toward the light and the viewer, in air, ``n = +z``; 0 where either is at or
            below the horizon.
        samples : int
            Paths per pair (at least 1).
        seed, progress
            As in :meth:`albedo`.
        """
        start = time.perf_counter()
        if self.walk:
            raise ValueError("the microsurface walk estimates the directional albedo only (no next-event BRDF)")
        if int(samples) < 1:
            raise ValueError(f"samples must be at least 1, got {samples}")
        i_air, o_air = np.broadcast_arrays(np.atleast_2d(np.asarray(i_air, dtype=np.float64)),
                                           np.atleast_2d(np.asarray(o_air, dtype=np.float64)))
        above = (i_air[:, 2] > 0.0) & (o_air[:, 2] > 0.0)
        value = np.zeros((i_air.shape[0], 3))
        stderr = np.zeros_like(value)
        if above.any():
            _, _, mean, err = self._estimate(np.ascontiguousarray(i_air[above]), np.ascontiguousarray(o_air[above]),
                                             int(samples), seed, progress)
            value[above], stderr[above] = mean, err
        return PositionFreeResult(value, stderr, int(samples), time.perf_counter() - start)


#: Jobs of at least this many paths are traced by :func:`_workers` processes (forked; below, in this one).
PARALLEL_PATHS = 1 << 16
_WORKER: PositionFree | None = None


def _workers() -> int:
    """The processes a large job uses: the CPUs this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def _set_worker(walker: PositionFree) -> None:
    global _WORKER
    _WORKER = walker


def _worker_replicate(i_air, o_air, per, key):
    return _WORKER.replicate(i_air, o_air, per, key)


def directional_albedo(
    stack: layered.LayeredBragg, theta_deg: ArrayLike, samples: int = 20000, seed: int = 0,
    tables: Sequence[layered.LayerTables] | None = None, progress: Callable[[int, int], None] | None = None,
    microsurface: str = "single",
) -> PositionFreeResult:
    """The position-free directional albedo of ``stack`` (:meth:`PositionFree.albedo`; ``microsurface``: :data:`MICROSURFACES`)."""
    return PositionFree(stack, tables, microsurface).albedo(theta_deg, samples, seed, progress)


def brdf(
    stack: layered.LayeredBragg, i_air: ArrayLike, o_air: ArrayLike, samples: int = 256, seed: int = 0,
    tables: Sequence[layered.LayerTables] | None = None, progress: Callable[[int, int], None] | None = None,
) -> PositionFreeResult:
    """The position-free BRDF of ``stack`` by next-event estimation (:meth:`PositionFree.brdf`)."""
    return PositionFree(stack, tables).brdf(i_air, o_air, samples, seed, progress)
