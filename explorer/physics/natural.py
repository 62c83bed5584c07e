"""
Natural Bragg mirrors: the paper's mirror (Fourneau et al. 2024, Section 3; Appendix D with a host) with
what its Section 6 says real structures have, absorbing layers (``k1``, ``k2``), dispersive layers (an
index that names a medium of :mod:`explorer.physics.dispersion`) and thickness disorder (``sigma``), and
its exact spectra (:func:`mirror_spectrum`, by :mod:`explorer.physics.multilayer`).

The structure is the one of :class:`explorer.physics.bragg.BraggMirror`: a host ``nh`` above, then ``N``
cells of ``n2`` (``d2 = (1 - delta) Lambda``) over ``n1`` (``d1 = delta Lambda``), on a base of ``n1``.
Light comes from a lossless host: where the host is ``n1`` (``nh`` unset) and ``n1`` absorbs, the host is
``Re n1`` (a semi-infinite absorbing incidence medium would leave nothing to reflect); a host naming an
absorbing medium is refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import multilayer
from explorer.physics.bragg.mirror import BraggMirror
from explorer.physics.dispersion import RANGE_NM, Dispersion, complex_index

IndexValue = float | Dispersion

#: The spectra's default wavelength step (nm): the 1-nm grid of the CMFs.
DEFAULT_STEP_NM = 1.0
#: The finest step a grid takes (a CSV medium's rows or a reference's step may ask for finer).
MIN_STEP_NM = 0.01


@dataclass(frozen=True)
class NaturalMirror(BraggMirror):
    """
    A Bragg mirror with complex, dispersive indices and thickness disorder: the paper's mirror
    (:class:`explorer.physics.bragg.BraggMirror`, whose cell geometry ``Lambda``, ``delta``, ``N``, ``d1``, ``d2``
    it keeps) with three more things.

    Parameters
    ----------
    n1, n2 : float or Dispersion
        The layers' indices (a number, or a medium giving ``n + i k`` over wavelength).
    Lambda, delta, N
        As :class:`explorer.physics.bragg.BraggMirror`.
    nh : float, Dispersion or None
        The host above; None: ``n1`` (its real part).
    k1, k2 : float
        Extinction coefficients added to ``n1``, ``n2`` (>= 0).
    sigma : float
        Relative thickness disorder: layer ``i`` is ``d_i (1 + sigma eps_i)`` (:mod:`explorer.physics.multilayer`).
    """

    n1: IndexValue = 1.0
    n2: IndexValue = 1.5
    nh: IndexValue | None = None
    k1: float = 0.0
    k2: float = 0.0
    sigma: float = 0.0

    def __post_init__(self) -> None:
        if self.k1 < 0.0 or self.k2 < 0.0:
            raise ValueError("k1 and k2 must be >= 0")
        if not 0.0 <= self.sigma <= 1.0 / multilayer.TRUNCATION:
            raise ValueError(f"sigma must be in [0, {1.0 / multilayer.TRUNCATION:g}] (a thickness stays >= 0)")
        if isinstance(self.nh, Dispersion) and self.nh.absorbing:
            raise ValueError(f"the host {self.nh.name} absorbs: light comes from a lossless host")

    def index_1(self, wavelength_nm: ArrayLike) -> np.ndarray:
        return complex_index(self.n1, self.k1, wavelength_nm)

    def index_2(self, wavelength_nm: ArrayLike) -> np.ndarray:
        return complex_index(self.n2, self.k2, wavelength_nm)

    def index_host(self, wavelength_nm: ArrayLike) -> np.ndarray:
        """The lossless host's index: ``nh``, or the real part of ``n1``."""
        if self.nh is None:
            return self.index_1(wavelength_nm).real.astype(np.complex128)
        return complex_index(self.nh, 0.0, wavelength_nm)

    def layer_stack(self, wavelength_nm: ArrayLike) -> tuple[np.ndarray, list[np.ndarray], np.ndarray, np.ndarray]:
        """``(host, layer indices, thicknesses, base)`` as :func:`explorer.physics.multilayer.stack_optics` takes them."""
        n1, n2 = self.index_1(wavelength_nm), self.index_2(wavelength_nm)
        return self.index_host(wavelength_nm), [n2, n1] * int(self.N), np.array([self.d2, self.d1] * int(self.N)), n1

    @property
    def dispersive(self) -> bool:
        return any(isinstance(v, Dispersion) for v in (self.n1, self.n2, self.nh))


def wavelength_grid(mirror: NaturalMirror, step_nm: float | None = None) -> np.ndarray:
    """
    360 to 830 nm every ``min(1 nm, step_nm, a tabulated medium's step)``, the ends included: the grid of
    the ``spectrum`` command.
    """
    steps = [DEFAULT_STEP_NM] + ([step_nm] if step_nm else [])
    steps += [v.step_nm for v in (mirror.n1, mirror.n2, mirror.nh) if isinstance(v, Dispersion) and v.step_nm]
    step = max(min(steps), MIN_STEP_NM)
    count = int(round((RANGE_NM[1] - RANGE_NM[0]) / step))
    return np.linspace(RANGE_NM[0], RANGE_NM[1], count + 1)


def mirror_spectrum(mirror: NaturalMirror, wavelength_nm: ArrayLike, theta_deg: ArrayLike) -> dict[str, np.ndarray]:
    """
    The exact spectra of ``mirror`` at incidence angles ``theta_deg`` (degrees, in the host), one row per
    angle: ``R`` (unpolarised), ``Rs``, ``Rp``, ``T`` (into the base, unpolarised) and ``A = 1 - R - T``
    (absorbed in the layers). With ``sigma > 0`` each is the ensemble mean over
    :data:`explorer.physics.multilayer.REALISATIONS` seeded realisations.
    """
    wavelength_nm = np.asarray(wavelength_nm, dtype=np.float64)
    thetas = np.atleast_1d(np.asarray(theta_deg, dtype=np.float64))
    if np.any((thetas < 0.0) | (thetas > 90.0)) or not np.all(np.isfinite(thetas)):
        raise ValueError("incidence angles are in [0, 90] degrees")
    host, indices, thicknesses, base = mirror.layer_stack(wavelength_nm)
    realised = multilayer.disordered_thicknesses(thicknesses, mirror.sigma)
    out = {key: np.zeros((thetas.size, wavelength_nm.size)) for key in ("R", "Rs", "Rp", "T", "A")}
    for row, theta in enumerate(thetas):
        if theta == 90.0:  # exact grazing: every interface reflects totally
            out["Rs"][row] = out["Rp"][row] = out["R"][row] = 1.0
            continue
        sin_theta = np.sin(np.radians(theta))
        T = 0.0
        for pol in ("s", "p"):
            if mirror.sigma == 0.0:  # ordered: N cells by repeated squaring (equal to the recursion to ~1e-11)
                optics = multilayer.periodic_optics(pol, host, base, indices[0], mirror.d1, mirror.d2, mirror.N, wavelength_nm, sin_theta)
                R_pol, T_pol = optics.R, optics.T
            else:
                R_pol, T_pol = multilayer.mean_optics(pol, host, indices, realised, base, wavelength_nm, sin_theta)
            out["R" + pol][row] = R_pol
            T = T + 0.5 * T_pol
        out["R"][row] = 0.5 * (out["Rs"][row] + out["Rp"][row])
        out["T"][row] = T
    out["A"] = 1.0 - out["R"] - out["T"]
    return out


def band_gaps(mirror: NaturalMirror, wavelength_nm: ArrayLike, theta_deg: float) -> np.ndarray:
    """
    Where either polarisation is in a band gap at ``theta_deg``: ``|cos K Lambda| > 1`` (Eq. 8) with the
    real parts of the indices at each wavelength (absorption blurs the edges; dispersion moves them).
    """
    wavelength_nm = np.asarray(wavelength_nm, dtype=np.float64)
    host = mirror.index_host(wavelength_nm).real
    n1, n2 = mirror.index_1(wavelength_nm).real, mirror.index_2(wavelength_nm).real
    n_sin = host * np.sin(np.radians(theta_deg))
    kz1, kz2 = multilayer.forward_kz(n1, n_sin), multilayer.forward_kz(n2, n_sin)
    omega = 2.0 * np.pi / wavelength_nm
    psi, phi = omega * kz1 * mirror.d1, omega * kz2 * mirror.d2
    gap = np.zeros(wavelength_nm.shape, dtype=bool)
    for x in (kz2 / kz1, (n1 * n1 * kz2) / (n2 * n2 * kz1)):  # s, then p (Eqs. 6-7 with kz = n cos theta)
        x = np.where(np.abs(x) < 1e-10, 1e-10, x)
        a = np.real(np.cos(psi) * np.cos(phi) - 0.5 * (x + 1.0 / x) * np.sin(psi) * np.sin(phi))
        gap |= np.abs(a) > 1.0
    return gap


# --------------------------------------------------------------------------------------------------
# Colours: the exact spectra against the CMFs (the reference and the tabulated method of a natural mirror)

#: Realisations per colour of a disordered mirror: a colour averages its spectrum's noise over wavelength, so
#: fewer than :data:`explorer.physics.multilayer.REALISATIONS` (within 2.4e-3 per channel of 2,048 for a
#: 10-cell chitin mirror at sigma = 0.1).
COLOUR_REALISATIONS = 128
#: Thick disordered stacks take fewer (realisations x layers at most this, at least the minimum): their
#: colours are noisier (~1e-2 at 16 realisations) but cost what a 20-cell mirror's do.
DISORDER_LAYER_BUDGET = 128 * 40
MIN_COLOUR_REALISATIONS = 16
#: Entries of a natural mirror's table over cos theta (linear interpolation, as the tabulated method's); a
#: disordered mirror's colour varies slowly with angle (no fringes) and costs realisations: fewer entries.
NATURAL_TABLE_SIZE = 129
DISORDERED_TABLE_SIZE = 33
#: A disordered mirror's spectra are sampled every this many nm (within 2.5e-4 of the 1-nm sum in the
#: ``explorer.dev.natural_studies`` cases; the realisations' noise, ~2e-3, is larger).
DISORDERED_STEP_NM = 2.0
#: The finest sampling (samples per nm) of an ordered natural mirror's colour.
NATURAL_MAX_SUBSTEPS = 64


def _unpolarised(mirror: NaturalMirror, wavelength_nm: np.ndarray, cos_theta: ArrayLike, realised: np.ndarray) -> np.ndarray:
    """Mean unpolarised R at ``wavelength_nm`` (broadcast against ``cos_theta``), over the rows of ``realised``."""
    return _unpolarised_rt(mirror, wavelength_nm, cos_theta, realised)[0]


def _unpolarised_rt(mirror: NaturalMirror, wavelength_nm: np.ndarray, cos_theta: ArrayLike,
                    realised: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean unpolarised ``(R, T)`` at ``wavelength_nm`` (broadcast against ``cos_theta``), over the rows of ``realised``."""
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    shape = np.broadcast_shapes(wavelength_nm.shape, cos_theta.shape)
    wavelength_nm = np.broadcast_to(wavelength_nm, shape)
    host, indices, _, base = mirror.layer_stack(wavelength_nm)
    sin_theta = np.sqrt(np.maximum(0.0, 1.0 - cos_theta * cos_theta))
    R = T = 0.0
    with np.errstate(divide="ignore", invalid="ignore"):  # exact grazing: 0/0 at index-matched interfaces
        for pol in ("s", "p"):
            if realised.shape[0] == 1:  # ordered: N cells by repeated squaring, O(log N)
                optics = multilayer.periodic_optics(pol, host, base, indices[0], mirror.d1, mirror.d2, mirror.N,
                                                    wavelength_nm, sin_theta)
                R_pol, T_pol = optics.R, optics.T
            else:
                R_pol, T_pol = multilayer.mean_optics(pol, host, indices, realised, base, wavelength_nm, sin_theta)
            R, T = R + 0.5 * R_pol, T + 0.5 * T_pol
    # Exact grazing (or within rounding of it, cos(pi / 2) = 6e-17: 0/0 there): total reflection.
    grazing = (cos_theta <= 0.0) | ~np.isfinite(R)
    return np.where(grazing, 1.0, R), np.where(grazing, 0.0, np.nan_to_num(T))


#: Angular step (degrees) of a disordered mirror's transmittance table, interpolated linearly in theta
#: between (disorder smooths the spectra; every 0.25 degree would cost 8 times as many realisations).
DISORDERED_ANGLE_STEP_DEG = 2.0


def transmittance_table(mirror: NaturalMirror, theta: ArrayLike) -> np.ndarray:
    """
    The mean unpolarised transmittance into the base at angles ``theta`` (radians, in the host) and the CMFs'
    wavelengths, ``(n_angles, 471)``: what a rough layer's transmission filter integrates (Eq. 28) where the
    layers absorb (``T < 1 - R``). Ordered: at every angle, 1-nm samples. Disordered: every
    :data:`DISORDERED_STEP_NM` nm and :data:`DISORDERED_ANGLE_STEP_DEG` degrees over :func:`colour_realisations`
    realisations, interpolated linearly.
    """
    return spectral_tables(mirror, theta)[1]


def spectral_tables(mirror: NaturalMirror, theta: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """
    The mean unpolarised ``(R, T)`` at angles ``theta`` (radians, in the host) and the CMFs' wavelengths, each
    ``(n_angles, 471)``, sampled as :func:`transmittance_table` says: a rough layer's tables (Eq. 17's facet
    reflectance, Eq. 28's transmittance) when its layers absorb, disperse or are disordered.
    """
    from explorer.physics import colorimetry

    theta = np.asarray(theta, dtype=np.float64)
    wavelengths = colorimetry.WAVELENGTHS
    thicknesses = np.array([mirror.d2, mirror.d1] * int(mirror.N))
    if mirror.sigma == 0.0:
        return _unpolarised_rt(mirror, wavelengths[np.newaxis, :], np.cos(theta)[:, np.newaxis], thicknesses[np.newaxis, :])
    realised = multilayer.disordered_thicknesses(thicknesses, mirror.sigma, colour_realisations(mirror))
    nodes = np.radians(np.append(np.arange(0.0, 90.0, DISORDERED_ANGLE_STEP_DEG), 90.0))
    # Only the nodes that bracket the angles asked for.
    index = np.searchsorted(nodes, np.clip(theta.ravel(), 0.0, nodes[-1]))
    nodes = nodes[np.unique(np.clip(np.concatenate([index - 1, index]), 0, nodes.size - 1))]
    coarse = np.append(np.arange(RANGE_NM[0], RANGE_NM[1], DISORDERED_STEP_NM), RANGE_NM[1])
    tables = []
    for table in _unpolarised_rt(mirror, coarse[np.newaxis, :], np.cos(nodes)[:, np.newaxis], realised):
        table = np.array([np.interp(wavelengths, coarse, row) for row in table])
        tables.append(np.array([np.interp(theta, nodes, column) for column in table.T]).T)
    return tables[0], tables[1]


def colour_realisations(mirror: NaturalMirror) -> int:
    """Realisations of a disordered mirror's colours: :data:`COLOUR_REALISATIONS`, fewer for thick stacks."""
    return int(min(COLOUR_REALISATIONS, max(MIN_COLOUR_REALISATIONS, DISORDER_LAYER_BUDGET // (2 * int(mirror.N)))))


def unpolarised_reflectance(mirror: NaturalMirror, wavelength_nm: ArrayLike, cos_theta: ArrayLike) -> np.ndarray:
    """
    The exact unpolarised ``R_lambda`` at ``cos_theta`` ``(n,)`` (in the host) and ``wavelength_nm`` ``(n, W)``: a
    spectral renderer's (Mitsuba's) reflectance. With ``sigma > 0`` the mean over :func:`colour_realisations`
    seeded realisations, the colours' own.
    """
    thicknesses = np.array([mirror.d2, mirror.d1] * int(mirror.N))
    realised = (multilayer.disordered_thicknesses(thicknesses, mirror.sigma, colour_realisations(mirror))
                if mirror.sigma > 0.0 else thicknesses[np.newaxis, :])
    cos_theta = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    return _unpolarised(mirror, np.asarray(wavelength_nm, dtype=np.float64), cos_theta[:, np.newaxis], realised)


def natural_rgb(cos_theta: ArrayLike, mirror: NaturalMirror) -> np.ndarray:
    """
    The mirror's linear sRGB at incidence ``cos theta`` (in the host): its exact unpolarised ``R_lambda``
    integrated against the CMFs. Ordered (``sigma = 0``): hat averages refined until the colour converges
    (:func:`explorer.physics.colorimetry.converged_spectra`, from a sampling that resolves the fringes).
    Disordered: the 1-nm sum over :data:`COLOUR_REALISATIONS` seeded realisations (disorder smooths the fringes).
    """
    from explorer.physics import colorimetry

    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    flat = np.unique(np.round(cos_theta.ravel(), 12), return_inverse=True)
    angles, inverse = flat
    thicknesses = np.array([mirror.d2, mirror.d1] * int(mirror.N))
    if mirror.sigma > 0.0:
        realised = multilayer.disordered_thicknesses(thicknesses, mirror.sigma, colour_realisations(mirror))
        # Disorder smooths the fringes: every DISORDERED_STEP_NM, interpolated linearly to the CMFs' nm.
        coarse = np.append(np.arange(RANGE_NM[0], RANGE_NM[1], DISORDERED_STEP_NM), RANGE_NM[1])
        samples = _unpolarised(mirror, coarse[np.newaxis, :], angles[:, np.newaxis], realised)
        spectra = np.array([np.interp(colorimetry.WAVELENGTHS, coarse, row) for row in samples])
    else:
        realised = thicknesses[np.newaxis, :]

        def spectrum(wavelengths, rows):
            wavelengths = wavelengths if wavelengths.ndim == 2 else wavelengths[np.newaxis, :]
            return _unpolarised(mirror, wavelengths, angles[rows][:, np.newaxis], realised)

        n_max = max(float(np.max(mirror.index_1(360.0).real)), float(np.max(mirror.index_2(360.0).real)))
        substeps = colorimetry.substeps_for_fringes(2.0 * int(mirror.N) * n_max * mirror.Lambda)
        spectra, _ = colorimetry.converged_spectra(spectrum, angles.size, substeps_min=min(substeps, NATURAL_MAX_SUBSTEPS),
                                                   substeps_max=NATURAL_MAX_SUBSTEPS)
    rgb = colorimetry.spectrum_to_rgb(spectra)
    return rgb[inverse.ravel()].reshape(cos_theta.shape + (3,))


_TABLES: dict = {}


def natural_rgb_table(mirror: NaturalMirror, size: int | None = None) -> np.ndarray:
    """
    :func:`natural_rgb` at ``cos theta = k / (size - 1)``, float32 (a 1D texture; cached, 16 mirrors); ``size``
    :data:`NATURAL_TABLE_SIZE`, or :data:`DISORDERED_TABLE_SIZE` with ``sigma > 0``.
    """
    size = size or (DISORDERED_TABLE_SIZE if mirror.sigma > 0.0 else NATURAL_TABLE_SIZE)
    key = (mirror, size)
    if key not in _TABLES:
        if len(_TABLES) >= 16:
            _TABLES.pop(next(iter(_TABLES)))
        table = natural_rgb(np.linspace(0.0, 1.0, size), mirror).astype(np.float32)
        table.setflags(write=False)
        _TABLES[key] = table
    return _TABLES[key]
