"""
The colour design of a mirror whose fixed indices name media (``--fix n2=chitin``): the batch model with each
medium's ``n + i k`` at the design's own wavelengths (:mod:`explorer.physics.dispersion`), and the converged
colours of :func:`explorer.physics.natural.natural_rgb`. The batch model takes complex indices (:func:`explorer.physics.bragg.absorbing_reflectance_batch`).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from explorer.design.base import DesignError, DesignModel
from explorer.materials.models import (  # noqa: F401  (the natural mirror's forward models, declared with the Bragg twins)
    EXTINCTION,
    MEDIUM_PARAMETERS,
    NATURAL_PARAMETERS,
    POLISH_STEP,
    design_indices as _indices,
    mirror_with_media,
    natural_batch,
    natural_converged,
    natural_values,
)
from explorer.physics import bragg, colorimetry
from explorer.physics.dispersion import Dispersion

#: The wavelength (nm) whose real index stands for a medium where the search needs one number: the box
#: check, the optical period's split into ``Lambda`` and ``delta`` (a reparametrisation, exact at any
#: value), and the scale scan (below).
REFERENCE_NM = 550.0


# --------------------------------------------------------------------------------------------------
# The design model with media


def reference_value(medium: Dispersion) -> float:
    """The number that stands for ``medium`` in the search's fixed values: its real index at :data:`REFERENCE_NM`."""
    return float(np.real(medium.index(REFERENCE_NM)))


def with_media(model: DesignModel, media: Mapping[str, Dispersion], natural: bool = False) -> DesignModel:
    """
    ``model`` (a Bragg mirror's) with the indices ``media`` names held at those media (and, with ``natural``,
    its layers' extinction ``k1``, ``k2`` and disorder ``sigma`` taken from the values): its batch at each medium's
    ``n + i k`` on the coarse nodes, its scale scan at each medium's real index at :data:`REFERENCE_NM` (the scan's
    spectra depend on ``s / lambda`` only without dispersion; the refinement that follows sees the dispersion),
    its converged colours those of :func:`explorer.physics.natural.natural_rgb` (final) or the batch at
    :data:`POLISH_STEP` (the polish's). The disorder is seen by the converged colours only (the batch and the
    scan take the ordered mirror: its ensemble costs realisations); a disordered mirror's polish takes the final
    colours, its realisations fixed by their seed (a smooth function of the structure).
    """
    from dataclasses import replace

    if not media and not natural:
        return model
    if not model.optical:
        raise DesignError(f"{model.name}: the colour design takes media for a Bragg mirror's indices only")
    for name, medium in media.items():
        if name not in MEDIUM_PARAMETERS:
            raise DesignError(f"{name}: only {', '.join(MEDIUM_PARAMETERS)} may name a medium")
        if name == "nh" and medium.absorbing:
            raise DesignError(f"the host {medium.name} absorbs: light comes from a lossless host")

    def batch(values, cos_theta, step=colorimetry.COARSE_STEP, smooth=None):
        return natural_batch(values, media, cos_theta, step, smooth)

    def spectra(values, cos_theta, wavelengths, smooth_relative):
        n = _indices(values, media, np.array([REFERENCE_NM]))
        # The real parts: the scan only screens (band positions), on the lossless model's fast path.
        n = {k: np.real(v[:, 0, 0] if np.ndim(v) == 3 else v) for k, v in n.items()}
        wavelengths = np.asarray(wavelengths, dtype=np.float64)
        return bragg.bragg_reflectance_batch(n["n1"], n["n2"], values["Lambda"], values["delta"], values["N"], n["nh"],
                                             cos_theta, wavelengths, step=1.0, smooth=smooth_relative * wavelengths)

    def converged(values, cos_theta, final=True):
        return natural_converged(values, media, cos_theta, final)

    return replace(model, batch=batch, spectra=spectra, converged=converged, rescreen=True, gradient=None,
                   converged_many=None)
