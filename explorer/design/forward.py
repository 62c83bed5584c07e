"""
The design's forward models: the coarse batch models the search screens and refines on (many structures at once, ``N``
continuous), the converged colours it polishes and reports, and the designable models.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike

from explorer.design.absorbing import absorbing_reflectance_batch
from explorer.design.base import COARSE_STEP, DesignError, DesignModel
from explorer.materials.models import BraggLayerModel, BraggMirrorModel, host_index
from explorer.materials.thinfilm_model import ThinFilmModel
from explorer.materials.twins import capabilities_of
from explorer.physics import bragg, colorimetry, thinfilm
from explorer.physics.dispersion import Dispersion
from explorer.physics.fresnel import cos_theta_transmitted, fresnel_r

#: The public names (re-exported by :mod:`explorer.design`).
__all__ = ["coarse_nodes", "log_nodes", "chebyshev_U_real_N", "bragg_reflectance_batch", "bragg_rgb_batch",
           "thin_film_rgb_batch", "bragg_spectra_batch", "thin_film_spectra_batch", "mirror_of", "bragg_converged_rgb",
           "thin_film_converged_rgb", "DESIGN_MODELS", "DESIGNABLE", "design_model"]

# --------------------------------------------------------------------------------------------------
# Forward models


def _interpolation_weights(step: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Nodes every ``step`` nm over the CMFs' range and the XYZ weights that integrate the spectrum's linear
    interpolant between them against the 1-nm CMFs: ``XYZ = R(nodes) @ weights``.
    """
    lo, hi = colorimetry.WAVELENGTH_MIN, colorimetry.WAVELENGTH_MAX
    return _interpolation_weights_at(np.linspace(lo, hi, int(math.ceil((hi - lo) / step)) + 1))


def _interpolation_weights_at(nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    :func:`_interpolation_weights` at ascending ``nodes`` (nm) that span the CMFs' range: the interpolant
    sampled every ``1 / K`` nm and integrated against the CMFs' hats as the converged colours are
    (:func:`explorer.physics.colorimetry.hat_average`), ``K`` the power of two that puts a sample in every
    node interval (``K = 1``, the 1-nm sum, for nodes 1 nm apart or more).
    """
    count = nodes.size
    K = 2 ** max(0, math.ceil(math.log2(1.0 / float(np.min(np.diff(nodes))))))
    fine = colorimetry.fine_wavelengths(K)
    position = np.interp(fine, nodes, np.arange(count))
    left = np.minimum(np.floor(position).astype(int), count - 2)
    frac = position - left
    interpolation = np.zeros((fine.size, count))
    interpolation[np.arange(fine.size), left] = 1.0 - frac
    interpolation[np.arange(fine.size), left + 1] += frac
    # Fortran order: at K = 1 the same product, bit for bit, as the 1-nm sum of the interpolant.
    return nodes, np.asfortranarray(colorimetry.hat_average(interpolation.T, K)) @ colorimetry.colour_matching_functions()


_WEIGHTS: dict[float, tuple[np.ndarray, np.ndarray]] = {}


def coarse_nodes(step: float = COARSE_STEP) -> tuple[np.ndarray, np.ndarray]:
    """Cached :func:`_interpolation_weights`."""
    if step not in _WEIGHTS:
        _WEIGHTS[step] = _interpolation_weights(step)
    return _WEIGHTS[step]


_LOG_WEIGHTS: dict[float, tuple[np.ndarray, np.ndarray]] = {}


def log_nodes(ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Wavelengths ``lambda_max r^-j`` (ascending) down to below ``lambda_min``, and the XYZ weights that
    integrate the spectrum's linear interpolant between them against the 1-nm CMFs (the scale scan's).
    """
    if ratio not in _LOG_WEIGHTS:
        lo, hi = colorimetry.WAVELENGTH_MIN, colorimetry.WAVELENGTH_MAX
        count = int(np.ceil(np.log(hi / lo) / np.log(ratio))) + 1
        _LOG_WEIGHTS[ratio] = _interpolation_weights_at(hi / ratio ** np.arange(count)[::-1])
    return _LOG_WEIGHTS[ratio]


def chebyshev_U_real_N(a: ArrayLike, N: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    :func:`explorer.physics.bragg.chebyshev_U` for a real (array) ``N``, with the band edges' limits ``N`` and
    ``N - 1`` where ``|sin t| < 1e-9`` (the coarse search's continuous ``N`` lands there at any value).
    """
    U_N1, U_N2, scale = bragg.chebyshev_U(a, N)
    in_band = np.abs(a) < 1.0
    edge = in_band & (np.abs(np.sin(np.arccos(np.clip(a, -1.0, 1.0)))) < 1e-9)
    if edge.any():
        N = np.broadcast_to(np.asarray(N, dtype=np.float64), U_N1.shape)
        U_N1, U_N2 = np.where(edge, N, U_N1), np.where(edge, N - 1.0, U_N2)
    return U_N1, U_N2, scale


def bragg_reflectance_batch(
    n1: ArrayLike, n2: ArrayLike, Lambda: ArrayLike, delta: ArrayLike, N: ArrayLike, nh: ArrayLike, cos_theta: ArrayLike,
    wavelengths: ArrayLike, step: float | None = None, smooth: float | None = None,
) -> np.ndarray:
    """
    Unpolarised ``R_lambda`` of many mirrors at once: parameters of shape ``(B,)`` (``nh < 1``: the host is
    ``n1``; ``N`` may be fractional), ``cos_theta`` ``(A,)`` in the host, ``wavelengths`` ``(W,)`` nm;
    returns ``(B, A, W)``. Appendix D's coefficient ``r_hN = (r_N + r_h1) / (1 + r_h1 r_N)`` with
    ``r_N = r1 U_{N-1} / (U_{N-1} - U_{N-2} t1 e^{i k_1z d1})`` and the slab's ``r1, t1`` (Eq. 10);
    ``|r_N|^2`` is Yeh's Eq. 2 when the host is ``n1`` (``r_h1 = 0``). Equals
    :func:`explorer.physics.bragg.bragg_reflectance` at integer ``N`` (tested) when ``step`` is None.

    ``step`` (nm): the spectrum is to be sampled that coarsely, so where the fringes are narrower than a
    few steps it is blended into its average over the fringes
    (:func:`explorer.physics.bragg.reflectance_fringe_average`, :func:`explorer.physics.bragg.fringe_average_under_host`),
    which is what the converged colour of such a mirror integrates; point samples would alias.
    ``smooth`` (nm, default ``step``) averages out fringes narrower than a few times it: the screening's
    smoother landscape (the envelope's band gaps without the fringes' ripples).
    """
    if any(np.iscomplexobj(v) for v in (n1, n2, nh)):
        return absorbing_reflectance_batch(n1, n2, Lambda, delta, N, nh, cos_theta, wavelengths, step, smooth)
    # An index may also be ``(B, 1, W)``: a dispersive medium's, per wavelength (:mod:`explorer.design.media`).
    col = lambda v: (lambda a: a.reshape(-1, 1, 1) if a.ndim <= 1 else a)(np.asarray(v, dtype=np.float64))
    n1, n2, Lambda, delta, N, nh = (col(v) for v in (n1, n2, Lambda, delta, N, nh))
    host = nh >= 1.0
    eta_h = np.where(host, nh, n1)
    cos_h = np.maximum(np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1), bragg.COS_THETA_MIN)
    wavelengths = np.asarray(wavelengths, dtype=np.float64).reshape(1, 1, -1)
    omega = 2.0 * np.pi / wavelengths
    cos_1 = cos_theta_transmitted(cos_h, eta_h, n1)
    cos_2 = cos_theta_transmitted(cos_h, eta_h, n2)
    p1 = n1 * cos_1 * delta * Lambda
    p2 = n2 * cos_2 * (1.0 - delta) * Lambda
    psi = bragg.clamp_decay(omega * p1)
    phi = bragg.clamp_decay(omega * p2)
    e_psi, e_phi = np.exp(1j * psi), np.exp(1j * phi)
    cos_psi, sin_psi = (e_psi + 1.0 / e_psi) / 2.0, (e_psi - 1.0 / e_psi) / 2j
    cos_phi, sin_phi = (e_phi + 1.0 / e_phi) / 2.0, (e_phi - 1.0 / e_phi) / 2j
    shape = np.broadcast_shapes(cos_1.shape, wavelengths.shape, n1.shape)
    if step is None:
        w_point = np.ones(shape)
    else:
        # Fringes lambda^2 / (2 N path) apart (path: the cell's optical thickness along z); a point sample
        # per step resolves them from ~4 per fringe, and averages them out below 1 per fringe.
        path = np.maximum(np.real(p1) + np.real(p2), 1e-9)
        fringe = wavelengths**2 / (2.0 * N * path)
        w_point = np.broadcast_to(np.clip((fringe / (step if smooth is None else smooth) - 1.0) / 3.0, 0.0, 1.0), shape)
    # Each sample computes only the reflectances its weight needs: a scan's spectrum runs from point
    # samples (thin, short cells) to averages (thick stacks), blending both over a factor ~4 in between.
    point, averaged = w_point > 0.0, w_point < 1.0
    total = 0.0
    for pol in bragg.POLARISATIONS:
        r12 = fresnel_r(pol, n1, cos_1, n2, cos_2)
        Omega = bragg.Omega(pol, n1, cos_1, n2, cos_2)
        a = np.real(cos_psi * cos_phi - 0.5 * Omega * sin_psi * sin_phi)  # Eq. 8
        phase2 = e_phi * e_phi
        r12_2 = r12 * r12
        denominator = 1.0 - r12_2 * phase2
        r1 = r12 * (1.0 - phase2) / denominator
        t1 = (1.0 - r12_2) * e_phi / denominator
        r_h1 = np.where(host, fresnel_r(pol, eta_h, cos_h.astype(np.complex128), n1, cos_1), 0.0)
        R = _where_needed(point, _point_reflectance, a, N, r1, t1, e_psi, r_h1)
        if averaged.any():
            average = _where_needed(averaged, _averaged_reflectance, r1, t1, omega, p1, r_h1, a)
            R = w_point * R + (1.0 - w_point) * average
        total = total + R
    return np.clip(total / 2.0, 0.0, 1.0)


def _point_reflectance(a, N, r1, t1, e_psi, r_h1) -> np.ndarray:
    """``|r_hN|^2`` of :func:`bragg_reflectance_batch` at its samples (Appendix D, ``N`` real)."""
    U_N1, U_N2, _ = chebyshev_U_real_N(a, N)
    r_N = r1 * U_N1 / (U_N1 - U_N2 * t1 * e_psi)
    return np.abs(bragg.reflection_coefficient_host(r_N, r_h1)) ** 2


def _averaged_reflectance(r1, t1, omega, p1, r_h1, a) -> np.ndarray:
    """``|r_hN|^2`` of :func:`bragg_reflectance_batch` averaged over its fringes (Appendix D)."""
    return bragg.fringe_average_under_host(r1, t1, omega, _Geometry(p1, r_h1), a)


def _where_needed(mask: np.ndarray, function: Callable[..., np.ndarray], *arrays) -> np.ndarray:
    """``function(*arrays)`` where ``mask`` (the arrays broadcast to its shape), 0 elsewhere."""
    if mask.all():
        return np.broadcast_to(function(*arrays), mask.shape)
    out = np.zeros(mask.shape)
    if mask.any():
        out[mask] = function(*(np.broadcast_to(v, mask.shape)[mask] for v in arrays))
    return out


@dataclass
class _Geometry:
    """What :func:`explorer.physics.bragg.fringe_average_under_host` reads of a cell (``r_h1 = 0``: no host)."""

    p1: np.ndarray
    r_h1: np.ndarray


def bragg_rgb_batch(values: Mapping[str, np.ndarray], cos_theta: ArrayLike, step: float = COARSE_STEP,
                    smooth: float | None = None) -> np.ndarray:
    """The coarse colours ``(B, A, 3)`` of mirrors ``values`` (arrays ``(B,)``) at ``cos_theta`` ``(A,)``."""
    if natural_values(values):  # absorbing layers (k1, k2): the complex indices' batch
        return natural_batch(values, {}, cos_theta, step, smooth)
    nodes, weights = coarse_nodes(step)
    R = bragg_reflectance_batch(values["n1"], values["n2"], values["Lambda"], values["delta"], values["N"],
                                values["nh"], cos_theta, nodes, step=step, smooth=smooth)
    return colorimetry.xyz_to_rgb(R @ weights)


def thin_film_rgb_batch(values: Mapping[str, np.ndarray], cos_theta: ArrayLike, step: float = COARSE_STEP,
                        smooth: float | None = None) -> np.ndarray:
    """
    The coarse colours ``(B, A, 3)`` of films ``values`` (``d``, ``eta1``, ``eta2``, ``eta3``, ``kappa3``); a
    film's few fringes are its colour, so ``smooth`` is not used.
    """
    nodes, weights = coarse_nodes(step)
    col = lambda name: np.asarray(values[name], dtype=np.float64).reshape(-1, 1, 1)
    cos = np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1)
    R = thinfilm.airy_reflectance(col("eta1"), col("eta2"), col("eta3"), col("kappa3"), cos, col("d"), nodes)
    return colorimetry.xyz_to_rgb(R @ weights)


def bragg_spectra_batch(
    values: Mapping[str, np.ndarray], cos_theta: ArrayLike, wavelengths: ArrayLike, smooth_relative: float,
) -> np.ndarray:
    """Screening spectra ``(B, A, W)``: fringes narrower than ~``smooth_relative`` lambda averaged out."""
    wavelengths = np.asarray(wavelengths, dtype=np.float64)
    return bragg_reflectance_batch(values["n1"], values["n2"], values["Lambda"], values["delta"], values["N"], values["nh"],
                                   cos_theta, wavelengths, step=1.0, smooth=smooth_relative * wavelengths)


def thin_film_spectra_batch(
    values: Mapping[str, np.ndarray], cos_theta: ArrayLike, wavelengths: ArrayLike, smooth_relative: float,
) -> np.ndarray:
    """The films' spectra ``(B, A, W)`` (not smoothed: a film's fringes are its colour)."""
    col = lambda name: np.asarray(values[name], dtype=np.float64).reshape(-1, 1, 1)
    cos = np.asarray(cos_theta, dtype=np.float64).reshape(1, -1, 1)
    return thinfilm.airy_reflectance(col("eta1"), col("eta2"), col("eta3"), col("kappa3"), cos, col("d"), np.asarray(wavelengths, float))


def mirror_of(values: Mapping[str, float]) -> bragg.BraggMirror:
    """The :class:`explorer.physics.bragg.BraggMirror` of design values (``nh``: :func:`explorer.materials.models.host_index`)."""
    return bragg.BraggMirror(n1=float(values["n1"]), n2=float(values["n2"]), Lambda=float(values["Lambda"]),
                             delta=float(values["delta"]), N=max(1, int(round(float(values["N"])))),
                             nh=host_index(float(values["nh"])))


def bragg_converged_rgb(values: Mapping[str, float], cos_theta: ArrayLike, final: bool = True) -> np.ndarray:
    """
    The converged colours of a mirror (``N`` rounded): :func:`explorer.physics.bragg.reference_rgb` when
    ``final``, otherwise the tabulated method's own nodes (float32 where it applies, substeps capped),
    which the polish calls many times.
    """
    if natural_values(values):  # absorbing or disordered layers: the natural mirror's colours
        return natural_converged(values, {}, cos_theta, final)
    mirror = mirror_of(values)
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    if final:
        return bragg.reference_rgb(cos_theta, mirror)
    return bragg.converged_rgb(cos_theta, mirror)


def thin_film_converged_rgb(values: Mapping[str, float], cos_theta: ArrayLike, final: bool = True) -> np.ndarray:
    """The film's converged colours (:func:`explorer.physics.thinfilm.reference_rgb`)."""
    return thinfilm.reference_rgb(float(values["eta1"]), float(values["eta2"]), float(values["eta3"]),
                                  float(values["kappa3"]), np.asarray(cos_theta, dtype=np.float64), float(values["d"]))


# --------------------------------------------------------------------------------------------------
# Natural mirrors: indices naming media (explorer.design.media), absorbing and disordered layers

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

    index = lambda name: media[name] if name in media else float(values[name])  # noqa: E731
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
    nodes, weights = coarse_nodes(step)
    n = _indices(values, media, nodes)
    R = bragg_reflectance_batch(n["n1"], n["n2"], values["Lambda"], values["delta"], values["N"], n["nh"],
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




_BRAGG = dict(parameters=("n1", "n2", "Lambda", "delta", "N", "nh", "k1", "k2", "sigma"), log_parameters=("N", "Lambda"),
              integer_parameters=("N",), batch=bragg_rgb_batch, converged=bragg_converged_rgb, host_parameter="nh",
              scale_parameter="Lambda", optical=True, spectra=bragg_spectra_batch, paint_free=("Lambda", "delta", "N"), held=("k1", "k2", "sigma"))
#: The forward model of each twin that declares ``design`` (:mod:`explorer.materials.twins`); its specular
#: colour is what is designed (the rough Bragg layer's: the smooth mirror's colour, which its gradient view shows).
DESIGN_MODELS: dict[str, DesignModel] = {model.name: model for model in (
    DesignModel(BraggMirrorModel.name, **_BRAGG),
    DesignModel(BraggLayerModel.name, **_BRAGG),
    DesignModel(ThinFilmModel.name, ("d", "eta1", "eta2", "eta3", "kappa3"), (), (), thin_film_rgb_batch, thin_film_converged_rgb,
                scale_parameter="d", spectra=thin_film_spectra_batch, paint_free=("d",)),
)}
DESIGNABLE = tuple(DESIGN_MODELS)


def design_model(name: str | None) -> DesignModel:
    """The :class:`DesignModel` of a material model name whose twin declares ``design``, or a :class:`DesignError`."""
    if name not in DESIGN_MODELS or not capabilities_of(name).design:
        raise DesignError(f"model {name or '(none)'} cannot be designed (designable: {', '.join(DESIGNABLE)})")
    return DESIGN_MODELS[name]
