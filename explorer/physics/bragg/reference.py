"""
The converged spectral reference: Yeh's exact ``R_lambda`` integrated against the CMFs until the colour has converged
(:func:`reference_rgb`), the reference every accuracy figure is measured against.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike

from explorer.physics import colorimetry
from explorer.physics.bragg.approximation import optical_thickness
from explorer.physics.bragg.mirror import POLARISATIONS, BraggMirror, CellGeometry, cell_geometry
from explorer.physics.bragg.reflectance import ROW_BLOCK, _reflectance_real, _take, reflectance_polarised, reflectance_spectra


def _spectra(cos_theta, mirror: BraggMirror, wavelengths, fast: bool) -> np.ndarray:
    return reflectance_spectra(cos_theta, mirror, wavelengths, float64=not fast)


def substeps_for(mirror: BraggMirror, cos_theta: ArrayLike) -> int:
    """
    The coarsest sampling (samples per nm) that resolves the mirror's fringes: ``N`` fringes per band,
    bands ``pi / n_+`` apart in ``omega``, so fringes as if from an optical path ``2 N n_+``
    (:func:`explorer.physics.colorimetry.substeps_for_fringes`), ``n_+`` the largest over the angles.
    """
    n_plus = optical_thickness(cell_geometry(np.asarray(cos_theta, dtype=np.float64), mirror, "s"))
    return colorimetry.substeps_for_fringes(2.0 * mirror.N * float(np.max(n_plus, initial=0.0)))


def converged_reflectance_spectra(
    cos_theta: ArrayLike, mirror: BraggMirror, tolerance: float = colorimetry.CONVERGENCE_TOLERANCE,
    passes: int = colorimetry.CONVERGENCE_PASSES, fast: bool = True, substeps_max: int = colorimetry.MAX_SUBSTEPS,
) -> tuple[np.ndarray, np.ndarray]:
    """
    The unpolarised ``R_lambda`` averaged over each nm's hat function (:func:`explorer.physics.colorimetry.hat_average`),
    sampled finely enough that the colour has converged (:func:`explorer.physics.colorimetry.converged_spectra`).

    Near band edges the pass band's transmission resonances (Eq. 2's zeros of ``sin N K Lambda``) are
    narrower than a nanometre and narrow further as ``N`` grows: point samples at every nm hit or miss
    them, hat averages integrate them. ``spectra @ colour_matching_functions()`` is the integral of
    ``R_lambda`` against the CMFs interpolated linearly between their 1-nm nodes.

    ``fast``: the tables' real float32 path where it applies (:func:`reflectance_spectra`, ~1e-5);
    otherwise float64 throughout (to ~1e-12 of Yeh's complex :func:`bragg_reflectance`), as
    :func:`reference_rgb` uses.
    ``substeps_max`` caps the refinement (samples per nm).

    Returns
    -------
    spectra : ndarray, shape ``(cos_theta.size, 471)``
    substeps : ndarray of int, shape ``(cos_theta.size,)``
        Samples per nm each angle needed.
    """
    # Each distinct angle once (a view's pixels share a few: the slice view's rows, a sphere's symmetry),
    # up to 1e-12 in cos theta (pixels compute the same angle with different roundings; the colour moves
    # by ~1e-11 over such a step).
    cos_theta, inverse = np.unique(np.round(np.asarray(cos_theta, dtype=np.float64).ravel(), 12), return_inverse=True)
    spectra, substeps = colorimetry.converged_spectra(
        _spectrum_function(cos_theta, mirror, float64=not fast),
        cos_theta.size,
        substeps_min=min(substeps_for(mirror, cos_theta), substeps_max),
        tolerance=tolerance,
        passes=passes,
        substeps_max=substeps_max,
    )
    return spectra[inverse.ravel()], substeps[inverse.ravel()]


def _spectrum_function(cos_theta, mirror: BraggMirror, float64: bool):
    """
    ``spectrum(wavelengths, rows)`` for :func:`explorer.physics.colorimetry.converged_spectra`: the values of
    :func:`reflectance_spectra` at the angles ``cos_theta[rows]`` (rows may repeat; ``wavelengths`` 1D,
    shared, or 2D, one set per row), with the angles' geometry computed once.
    """
    return _row_spectrum_function(
        cos_theta, mirror,
        lambda omega, geometries, rows: _reflectance_real(omega, geometries, rows, float64),
        reflectance_polarised,
    )


def _row_spectrum_function(cos_theta, mirror: BraggMirror, real_path, complex_path):
    """
    The row-blocked ``spectrum(wavelengths, rows)`` shared by the reference and the windowed table: the
    angles' geometry once, rows with real angles through ``real_path(omega, geometries, rows)``, the others
    (a host, evanescent layers) through ``complex_path(omega, geometry)`` averaged over the polarisations.
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64).ravel()
    geometries = tuple(cell_geometry(cos_theta, mirror, pol) for pol in POLARISATIONS)
    first = geometries[0]
    real = (first.cos_theta_1.imag == 0) & (first.cos_theta_2.imag == 0) & first.host_is_n1

    def spectrum(wavelengths, rows):
        omega = 2.0 * np.pi / np.asarray(wavelengths, dtype=np.float64)
        rows = np.asarray(rows)
        per_row = omega.ndim == 2
        out = np.empty((rows.size, omega.shape[-1]))
        is_real = real[rows]
        block = max(1, ROW_BLOCK * 471 // max(omega.shape[-1], 1))
        for mask, fast_path in ((is_real, True), (~is_real, False)):
            # Slices where every row takes one path (the usual case), to spare the gathers.
            where = np.arange(rows.size) if mask.all() else np.flatnonzero(mask)
            for start in range(0, where.size, block):
                at = slice(start, start + block) if mask.all() else where[start : start + block]
                om = omega[at] if per_row else omega
                if fast_path:
                    out[at] = real_path(om, geometries, rows[at])
                else:
                    out[at] = sum(complex_path(om, _take(g, rows[at])) for g in geometries) / len(geometries)
        return out

    return spectrum


def reference_rgb(cos_theta: ArrayLike, mirror: BraggMirror, step: float | None = None) -> np.ndarray:
    """
    The spectral reference: exact ``R_lambda`` (both polarisations averaged) integrated against the CMFs
    (Section 3.2.2), in linear sRGB.

    Parameters
    ----------
    cos_theta : array_like
    mirror : BraggMirror
    step : float, optional
        ``None``: the converged integral (:func:`converged_reflectance_spectra`), the reference every
        accuracy figure is measured against. A number: samples every ``1 / round(1 / step)`` nm against
        the linearly interpolated CMFs; ``step = 1`` is the paper's sum over every nm from 360 to 830,
        which is not converged for ``N`` of a few tens and more.

    Returns
    -------
    ndarray, shape ``cos_theta.shape + (3,)``
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    if step is None:
        spectra, _ = converged_reflectance_spectra(cos_theta, mirror, fast=False)
    else:
        flat = cos_theta.ravel()
        spectra = colorimetry.fixed_step_spectra(
            lambda wavelengths, rows: _spectra(flat[rows], mirror, wavelengths, fast=False), flat.size, step
        )
    return colorimetry.spectrum_to_rgb(spectra).reshape(cos_theta.shape + (3,))


def reference_rgb_many(cos_theta: ArrayLike, mirrors: Sequence[BraggMirror]) -> np.ndarray:
    """
    :func:`reference_rgb` of many mirrors at the angles ``cos_theta`` ``(A,)``: ``(len(mirrors), A, 3)``. Mirrors in
    ``n1`` whose waves all propagate share one refinement per sampling floor (:func:`substeps_for`): their angles are
    rows of :func:`explorer.physics.colorimetry.converged_spectra`, which refines each row on its own, so that each
    colour is the one mirror's (to rounding); the others are taken one at a time.
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64).ravel()
    out = np.empty((len(mirrors), cos_theta.size, 3))
    groups: dict[int, list[int]] = {}
    geometry_of: dict[int, tuple[CellGeometry, ...]] = {}
    for m, mirror in enumerate(mirrors):
        geometry = cell_geometry(cos_theta, mirror, "s")
        if geometry.host_is_n1 and not np.any(geometry.cos_theta_1.imag) and not np.any(geometry.cos_theta_2.imag):
            # substeps_for's floor, from this geometry (its n_+ is the same for both polarisations).
            floor = colorimetry.substeps_for_fringes(2.0 * mirror.N * float(np.max(optical_thickness(geometry), initial=0.0)))
            groups.setdefault(floor, []).append(m)
            geometry_of[m] = tuple(geometry if pol == "s" else cell_geometry(cos_theta, mirror, pol) for pol in POLARISATIONS)
        else:
            out[m] = reference_rgb(cos_theta, mirror)
    for floor, members in groups.items():
        geometries = tuple(_stacked([geometry_of[m][k] for m in members]) for k in range(len(POLARISATIONS)))

        def spectrum(wavelengths, rows, geometries=geometries):
            omega = 2.0 * np.pi / np.asarray(wavelengths, dtype=np.float64)
            rows = np.asarray(rows)
            block = max(1, ROW_BLOCK * 471 // max(omega.shape[-1], 1))
            values = np.empty((rows.size, omega.shape[-1]))
            for start in range(0, rows.size, block):
                at = slice(start, start + block)
                values[at] = _reflectance_real(omega[at] if omega.ndim == 2 else omega, geometries, rows[at], True)
            return values

        spectra, _ = colorimetry.converged_spectra(spectrum, len(members) * cos_theta.size, substeps_min=floor)
        out[members] = colorimetry.spectrum_to_rgb(spectra).reshape(len(members), cos_theta.size, 3)
    return out


def _stacked(geometries: Sequence[CellGeometry]) -> CellGeometry:
    """One geometry whose rows are the given ones' angles in turn, ``N`` per row."""
    first = geometries[0]
    fields = {k: np.concatenate([np.atleast_1d(getattr(g, k)) for g in geometries]) for k, v in vars(first).items()
              if isinstance(v, np.ndarray)}
    N = np.concatenate([np.full(np.size(g.p1), g.N) for g in geometries])
    return CellGeometry(**fields, N=N, host_is_n1=True)
