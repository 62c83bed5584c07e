"""
The colour design of a mirror whose fixed indices name media (``--fix n2=chitin``): the batch model with each
medium's ``n + i k`` at the design's own wavelengths (:mod:`explorer.physics.dispersion`), and the converged
colours of :func:`explorer.physics.natural.natural_rgb`. The batch model takes complex indices by :mod:`explorer.design.absorbing`.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from explorer.design.base import DesignError, DesignModel
from explorer.physics import colorimetry
from explorer.physics.dispersion import Dispersion

#: The wavelength (nm) whose real index stands for a medium where the search needs one number: the box
#: check, the optical period's split into ``Lambda`` and ``delta`` (a reparametrisation, exact at any
#: value), and the scale scan (below).
REFERENCE_NM = 550.0
#: The index parameters that may name a medium.
MEDIUM_PARAMETERS = ("n1", "n2", "nh")
#: The natural mirror's other design parameters: each layer's extinction coefficient (added to its index,
#: a number's or a medium's) and the thickness disorder. The search holds them at 0 unless fixed or freed.
NATURAL_PARAMETERS = ("k1", "k2", "sigma")
#: The extinction coefficient of each layer's index.
EXTINCTION = {"n1": "k1", "n2": "k2"}
#: The non-final converged colours (the polish's) sample the spectrum this finely (nm), fringes narrower
#: than a few steps averaged (:func:`explorer.design.forward.bragg_reflectance_batch`).
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
        else:
            index = medium.index(wavelengths)
            # A lossless medium stays real: the real batch model (and its coherent fringe average) takes it.
            if not np.any(np.imag(index)):
                index = np.real(index)
            out[name] = np.broadcast_to(index.reshape(1, 1, -1), (rows, 1, index.size))
        k = values.get(EXTINCTION.get(name, ""))
        if k is not None and np.any(np.asarray(k) != 0.0):
            # n + i k, as NaturalMirror.index_1 / index_2 add a layer's k to its number or its medium.
            k = np.broadcast_to(np.asarray(k, dtype=np.float64), (rows,))
            out[name] = out[name] + 1j * (k.reshape(-1, 1, 1) if np.ndim(out[name]) == 3 else k)
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
    natural = {name: float(values.get(name, 0.0)) for name in NATURAL_PARAMETERS}
    return NaturalMirror(n1=index("n1"), n2=index("n2"), Lambda=float(values["Lambda"]), delta=float(values["delta"]),
                         N=max(1, int(round(float(values["N"])))), nh=nh, **natural)


def natural_values(values: Mapping[str, object]) -> bool:
    """Whether design values ``values`` (numbers or rows) have an absorbing or disordered layer."""
    return any(np.any(np.asarray(values.get(name, 0.0)) != 0.0) for name in NATURAL_PARAMETERS)


def natural_batch(values: Mapping[str, np.ndarray], media: Mapping[str, Dispersion], cos_theta, step: float,
                  smooth: float | None) -> np.ndarray:
    """The batch model's colours ``(B, A, 3)`` of rows ``values`` with ``media`` and each layer's ``k`` (the ordered mirror)."""
    from explorer.design import forward

    nodes, weights = forward.coarse_nodes(step)
    n = _indices(values, media, nodes)
    R = forward.bragg_reflectance_batch(n["n1"], n["n2"], values["Lambda"], values["delta"], values["N"], n["nh"],
                                        cos_theta, nodes, step=step, smooth=smooth)
    return colorimetry.xyz_to_rgb(R @ weights)


def natural_converged(values: Mapping[str, float], media: Mapping[str, Dispersion], cos_theta, final: bool = True) -> np.ndarray:
    """
    The converged colours ``(A, 3)`` of one structure with ``media``, ``k1``, ``k2`` and ``sigma``:
    :func:`explorer.physics.natural.natural_rgb` (final, or disordered), else the batch at :data:`POLISH_STEP`.
    """
    from explorer.physics.natural import natural_rgb

    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    if final or float(values.get("sigma", 0.0)) > 0.0:
        return natural_rgb(cos_theta, mirror_with_media(values, media))
    rows = {k: np.array([float(v)]) for k, v in values.items()}
    rows["N"] = np.array([max(1.0, float(np.round(values["N"])))])
    return natural_batch(rows, media, cos_theta, POLISH_STEP, None)[0]


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

    from explorer.design import forward

    if not media and not natural:
        return model
    if not model.optical:
        raise DesignError(f"{model.name}: the colour design takes media for a Bragg mirror's indices only")
    for name, medium in media.items():
        if name not in MEDIUM_PARAMETERS:
            raise DesignError(f"{name}: only {', '.join(MEDIUM_PARAMETERS)} may name a medium")
        if name == "nh" and medium.absorbing:
            raise DesignError(f"the host {medium.name} absorbs: light comes from a lossless host")

    def batch(values, cos_theta, step=forward.COARSE_STEP, smooth=None):
        return natural_batch(values, media, cos_theta, step, smooth)

    def spectra(values, cos_theta, wavelengths, smooth_relative):
        n = _indices(values, media, np.array([REFERENCE_NM]))
        # The real parts: the scan only screens (band positions), on the lossless model's fast path.
        n = {k: np.real(v[:, 0, 0] if np.ndim(v) == 3 else v) for k, v in n.items()}
        wavelengths = np.asarray(wavelengths, dtype=np.float64)
        return forward.bragg_reflectance_batch(n["n1"], n["n2"], values["Lambda"], values["delta"], values["N"], n["nh"],
                                               cos_theta, wavelengths, step=1.0, smooth=smooth_relative * wavelengths)

    def converged(values, cos_theta, final=True):
        return natural_converged(values, media, cos_theta, final)

    return replace(model, batch=batch, spectra=spectra, converged=converged, rescreen=True)
