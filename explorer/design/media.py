"""
The colour design of a mirror whose fixed indices name media (``--fix n2=chitin``): the batch model with each
medium's ``n + i k`` at the design's own wavelengths (:mod:`explorer.physics.dispersion`), and the converged
colours of :func:`explorer.physics.natural.natural_rgb`. The batch model takes complex indices (:func:`explorer.physics.bragg.absorbing_reflectance_batch`).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from explorer.design.base import DesignError, DesignModel
from explorer.physics import bragg, colorimetry
from explorer.physics.dispersion import Dispersion

#: The wavelength (nm) whose real index stands for a medium where the search needs one number: the box
#: check, the optical period's split into ``Lambda`` and ``delta`` (a reparametrisation, exact at any
#: value), and the scale scan (below).
REFERENCE_NM = 550.0
#: The index parameters that may name a medium.
MEDIUM_PARAMETERS = ("n1", "n2", "nh")
#: The non-final converged colours (the polish's) sample the spectrum this finely (nm), fringes narrower
#: than a few steps averaged (:func:`explorer.physics.bragg.bragg_reflectance_batch`).
POLISH_STEP = 1.0


# --------------------------------------------------------------------------------------------------
# The design model with media


def reference_value(medium: Dispersion) -> float:
    """The number that stands for ``medium`` in the search's fixed values: its real index at :data:`REFERENCE_NM`."""
    return float(np.real(medium.index(REFERENCE_NM)))


def _indices(values: Mapping[str, np.ndarray], media: Mapping[str, Dispersion], wavelengths: np.ndarray) -> dict[str, np.ndarray]:
    """``n1``, ``n2``, ``nh`` of rows ``values`` ``(B,)`` with each medium at ``wavelengths`` ``(W,)``: ``(B, 1, W)`` or ``(B,)``."""
    rows = np.asarray(values["Lambda"]).shape[0]
    out = {}
    for name in MEDIUM_PARAMETERS:
        medium = media.get(name)
        if medium is None:
            out[name] = np.asarray(values[name], dtype=np.float64)
            continue
        index = medium.index(wavelengths)
        # A lossless medium stays real: the real batch model (and its coherent fringe average) takes it.
        if not np.any(np.imag(index)):
            index = np.real(index)
        out[name] = np.broadcast_to(index.reshape(1, 1, -1), (rows, 1, index.size))
    if not any(np.iscomplexobj(v) for v in out.values()):
        return out
    # Complex: every index per wavelength (the absorbing batch model's broadcast).
    return {k: np.asarray(v) for k, v in out.items()}


def mirror_with_media(values: Mapping[str, float], media: Mapping[str, Dispersion]):
    """The :class:`explorer.physics.natural.NaturalMirror` of design values (``N`` rounded), media in place of their numbers."""
    from explorer.materials.models import host_index
    from explorer.physics.natural import NaturalMirror

    index = lambda name: media.get(name, float(values[name]))
    nh = media.get("nh", host_index(float(values["nh"])))
    return NaturalMirror(n1=index("n1"), n2=index("n2"), Lambda=float(values["Lambda"]), delta=float(values["delta"]),
                         N=max(1, int(round(float(values["N"])))), nh=nh)


def with_media(model: DesignModel, media: Mapping[str, Dispersion]) -> DesignModel:
    """
    ``model`` (a Bragg mirror's) with the indices ``media`` names held at those media: its batch at each medium's
    ``n + i k`` on the coarse nodes, its scale scan at each medium's real index at :data:`REFERENCE_NM` (the scan's
    spectra depend on ``s / lambda`` only without dispersion; the refinement that follows sees the dispersion),
    its converged colours those of :func:`explorer.physics.natural.natural_rgb` (final) or the batch at
    :data:`POLISH_STEP` (the polish's).
    """
    from dataclasses import replace

    from explorer.physics.natural import natural_rgb

    if not media:
        return model
    if not model.optical:
        raise DesignError(f"{model.name}: the colour design takes media for a Bragg mirror's indices only")
    for name, medium in media.items():
        if name not in MEDIUM_PARAMETERS:
            raise DesignError(f"{name}: only {', '.join(MEDIUM_PARAMETERS)} may name a medium")
        if name == "nh" and medium.absorbing:
            raise DesignError(f"the host {medium.name} absorbs: light comes from a lossless host")

    def rgb_at(values, cos_theta, step, smooth):
        nodes, weights = colorimetry.interpolant_nodes(step)
        n = _indices(values, media, nodes)
        R = bragg.bragg_reflectance_batch(n["n1"], n["n2"], values["Lambda"], values["delta"], values["N"], n["nh"],
                                            cos_theta, nodes, step=step, smooth=smooth)
        return colorimetry.xyz_to_rgb(R @ weights)

    def batch(values, cos_theta, step=colorimetry.COARSE_STEP, smooth=None):
        return rgb_at(values, cos_theta, step, smooth)

    def spectra(values, cos_theta, wavelengths, smooth_relative):
        n = _indices(values, media, np.array([REFERENCE_NM]))
        # The real parts: the scan only screens (band positions), on the lossless model's fast path.
        n = {k: np.real(v[:, 0, 0] if np.ndim(v) == 3 else v) for k, v in n.items()}
        wavelengths = np.asarray(wavelengths, dtype=np.float64)
        return bragg.bragg_reflectance_batch(n["n1"], n["n2"], values["Lambda"], values["delta"], values["N"], n["nh"],
                                               cos_theta, wavelengths, step=1.0, smooth=smooth_relative * wavelengths)

    def converged(values, cos_theta, final=True):
        cos_theta = np.asarray(cos_theta, dtype=np.float64)
        if final:
            return natural_rgb(cos_theta, mirror_with_media(values, media))
        rows = {k: np.array([float(v)]) for k, v in values.items()}
        rows["N"] = np.array([max(1.0, float(np.round(values["N"])))])
        return rgb_at(rows, cos_theta, POLISH_STEP, None)[0]

    return replace(model, batch=batch, spectra=spectra, converged=converged, rescreen=True)
