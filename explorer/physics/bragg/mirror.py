"""
A Bragg mirror (``N`` cells of ``(n2, d2), (n1, d1)`` in a host ``nh``), its shared constants and what a cell looks
like at one incidence angle (Snell's law, the polarisation term Omega of Eqs. 6-7, the angular correction). Numpy
only; GLSL twins of the same names in ``shaders/lib/bragg.glsl``. See :mod:`explorer.physics.bragg` for the
conventions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.physics.fresnel import cos_theta_transmitted, fresnel_r

#: Bisection steps for each landmark (Airy point, band-gap edges). The GLSL twin uses the same count.
BISECTION_STEPS = 12
#: The visible range of the approximation: the edges of the 1 nm bins of the spectral reference.
WAVELENGTH_LOW = colorimetry.WAVELENGTH_MIN - 0.5
WAVELENGTH_HIGH = colorimetry.WAVELENGTH_MAX + 0.5
#: Cosines are kept away from exact grazing incidence, where every interface reflects totally.
COS_THETA_MIN = 1e-6
POLARISATIONS = ("s", "p")


@dataclass(frozen=True)
class BraggMirror:
    """
    A Bragg mirror: ``N`` cells of ``(n2, d2), (n1, d1)`` in a host of index ``nh``.

    Parameters
    ----------
    n1, n2 : float
        Refractive indices of the two layers of a cell (real: dielectric media).
    Lambda : float
        Period ``d1 + d2`` in nm.
    delta : float
        Relative thickness ``d1 / Lambda`` in [0, 1].
    N : int
        Number of cells (1 gives a thin film of index ``n2`` and thickness ``d2``).
    nh : float, optional
        Index of the host medium above the mirror; defaults to ``n1`` (Appendix D otherwise).
    """

    n1: float = 1.0
    n2: float = 1.5
    Lambda: float = 500.0
    delta: float = 0.5
    N: int = 20
    nh: float | None = None

    @property
    def d1(self) -> float:
        return self.delta * self.Lambda

    @property
    def d2(self) -> float:
        return (1.0 - self.delta) * self.Lambda

    @property
    def eta_h(self) -> float:
        return self.n1 if self.nh is None else self.nh


# --------------------------------------------------------------------------------------------------
# Per-angle quantities


@dataclass
class CellGeometry:
    """
    What a cell looks like at one incidence angle and polarisation; independent of wavelength.

    ``p1 = n1 cos(theta_1) d1`` and ``p2 = n2 cos(theta_2) d2`` are the optical thicknesses along z,
    so that ``k_1z d1 = omega p1`` and ``k_2z d2 = omega p2``; both are complex under total internal
    reflection (then purely imaginary).
    """

    cos_theta_1: np.ndarray
    cos_theta_2: np.ndarray
    p1: np.ndarray
    p2: np.ndarray
    r12: np.ndarray
    Omega: np.ndarray
    r_h1: np.ndarray
    correction: np.ndarray
    N: int
    host_is_n1: bool


def Omega(polarisation: str, n1: ArrayLike, cos_theta_1: ArrayLike, n2: ArrayLike, cos_theta_2: ArrayLike) -> np.ndarray:
    """The polarisation term of the dispersion relation (Eqs. 6-7); ``Omega >= 2`` for real angles."""
    if polarisation == "s":
        x = (n2 * cos_theta_2) / (n1 * cos_theta_1)
    else:
        x = (n1 * cos_theta_2) / (n2 * cos_theta_1)
    x = np.where(np.abs(x) < 1e-10, 1e-10, x)  # exactly at a critical angle
    return x + 1.0 / x


def cell_geometry(cos_theta_h: ArrayLike, mirror: BraggMirror, polarisation: str) -> CellGeometry:
    """Snell's law into both layers, and the cell's angular terms, for one polarisation."""
    cos_theta_h = np.maximum(np.asarray(cos_theta_h, dtype=np.float64), COS_THETA_MIN)
    eta_h, n1, n2 = mirror.eta_h, mirror.n1, mirror.n2
    cos_theta_1 = cos_theta_transmitted(cos_theta_h, eta_h, n1)
    cos_theta_2 = cos_theta_transmitted(cos_theta_h, eta_h, n2)
    return CellGeometry(
        cos_theta_1=cos_theta_1,
        cos_theta_2=cos_theta_2,
        p1=n1 * cos_theta_1 * mirror.d1,
        p2=n2 * cos_theta_2 * mirror.d2,
        r12=fresnel_r(polarisation, n1, cos_theta_1, n2, cos_theta_2),
        Omega=Omega(polarisation, n1, cos_theta_1, n2, cos_theta_2),
        r_h1=fresnel_r(polarisation, eta_h, cos_theta_h.astype(np.complex128), n1, cos_theta_1),
        correction=angular_correction(cos_theta_1, n1, n2),
        N=int(mirror.N),
        host_is_n1=(eta_h == n1),
    )


def angular_correction(cos_theta_1: ArrayLike, n1: ArrayLike, n2: ArrayLike) -> np.ndarray:
    """
    The angular correction ``w~(theta_1) = w~0 + (1 - w~0)(1 - cos theta_1)^5`` (Appendix B), with
    ``w~0 = 0.735 R12 + 0.532`` and ``R12`` the normal-incidence reflectance between ``n1`` and ``n2``.
    """
    R12 = ((n1 - n2) / (n1 + n2)) ** 2
    w0 = 0.735 * R12 + 0.532
    cos_theta_1 = np.clip(np.real(cos_theta_1), 0.0, 1.0)
    return w0 + (1.0 - w0) * (1.0 - cos_theta_1) ** 5
