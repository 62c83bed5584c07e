"""
The numpy twins of the material files: each model evaluates, in numpy, what its ``.brd`` shader
evaluates in GLSL, and provides the tables its shader reads (uploaded by the host as textures).

A material names its model in a comment line ``# model: NAME``.
"""

from __future__ import annotations

from typing import Mapping

import functools

import numpy as np

from explorer.physics import bragg, colorimetry, compensation, layered, microfacet, multiscatter_stack, natural
from explorer.materials.brd import round_integer
from explorer.physics.fresnel import fresnel_schlick
from explorer.materials.methods import BraggMethod
from explorer.materials.twins import TWINS, Capabilities, DesignModel, StructureMaps, registry, twin

#: Samples per numpy call of the stack's spectral Eq. 34 (Mitsuba's spectral variants; bounds the (samples, 471) temporaries).
SPECTRAL_CHUNK = 1 << 14


def _cos_half_angle(L, V) -> np.ndarray:
    """clamp(dot(normalize(L + V), L), 0, 1) for unit vectors ``(..., 3)``: the shaders' H.L."""
    L = np.asarray(L, dtype=np.float64)
    H = L + np.asarray(V, dtype=np.float64)
    H = H / np.linalg.norm(H, axis=-1, keepdims=True)
    return np.clip(np.sum(H * L, axis=-1), 0.0, 1.0)


def _theta(v: np.ndarray) -> np.ndarray:
    """The polar angle of local directions ``(n, 3)`` (n = +z), 0 below the surface's plane clamped."""
    return np.arctan2(np.hypot(v[..., 0], v[..., 1]), np.maximum(v[..., 2], 0.0))


def _interp_wavelength(table: np.ndarray, wavelengths: np.ndarray) -> np.ndarray:
    """Rows of spectra on the 1-nm grid (``(n, 471)``) at per-row wavelengths ``(n, W)``, linearly."""
    x = np.clip(wavelengths - colorimetry.WAVELENGTH_MIN, 0.0, colorimetry.WAVELENGTHS.size - 1.0)
    j0 = np.minimum(np.floor(x).astype(np.int64), colorimetry.WAVELENGTHS.size - 2)
    f = x - j0
    rows = np.arange(table.shape[0])[:, None]
    return table[rows, j0] * (1.0 - f) + table[rows, j0 + 1] * f


def _spectral_lobe(compensation, i, o, wavelengths, rho) -> np.ndarray:
    """The multiple-scattering lobe at local directions ``(n, 3)`` and wavelengths ``(n, W)`` with the base's albedo
    ``rho`` ``(n, W)`` (:func:`explorer.physics.multiscatter_stack.lobe_parts`), 0 where either is below the horizon."""
    parts = multiscatter_stack.lobe_parts(compensation, *multiscatter_stack.air_angles(i, o))
    M, TT, aa = (_interp_wavelength(x, wavelengths) for x in parts)
    under = _interp_wavelength(np.broadcast_to(compensation.under, parts[0].shape), wavelengths)
    lobe = M + (TT * rho / (1.0 - rho * under) - rho * aa) * (compensation.radiance_scale / np.pi)
    return np.where(((i[:, 2] > 0.0) & (o[:, 2] > 0.0))[:, None], lobe, 0.0)


@functools.lru_cache(maxsize=16)
def _layer_transmissivity(mirror: bragg.BraggMirror, alpha: float) -> np.ndarray:
    """The rough layer's spectral integrated transmissivity ``f_t cos theta`` (Eq. 28), ``(361, 471)``."""
    F = layered.transmission_filter_for(alpha)
    R = layered.reflectance_table(mirror, np.cos(F.theta))
    return layered.integrated_transmissivity(F, 1.0 - R)


@functools.lru_cache(maxsize=8)
def _natural_layer_transmissivity(mirror: "natural.NaturalMirror", alpha: float) -> np.ndarray:
    """A natural mirror's rough layer: Eq. 28 over its exact transmittance (absorbing layers: ``T < 1 - R``), ``(361, 471)``."""
    F = layered.transmission_filter_for(alpha)
    return layered.integrated_transmissivity(F, natural.transmittance_table(mirror, F.theta))


@functools.lru_cache(maxsize=16)
def _natural_transmission_rgb_table(mirror: "natural.NaturalMirror", alpha: float, size: int) -> np.ndarray:
    """:func:`_transmission_rgb_table` of a natural mirror (its exact transmittance)."""
    T_rgb = colorimetry.spectrum_to_rgb(_natural_layer_transmissivity(mirror, alpha))
    table = layered.lookup(T_rgb, np.arccos(np.linspace(0.0, 1.0, size))).astype(np.float32)
    table.setflags(write=False)
    return table


def host_index(nh):
    """
    The host a mirror's ``nh`` value stands for: a number below 1 means the host is ``n1`` (None), as the shaders
    have it; any other value (an index, a dispersive medium) is the host. The one place of this rule.
    """
    return None if isinstance(nh, (int, float)) and float(nh) < 1.0 else nh


def mirror_of(values: Mapping[str, object]) -> bragg.BraggMirror:
    """
    The Bragg mirror a material's values describe (``n1, n2, Lambda, delta, N``, and ``nh``: :func:`host_index`):
    the one reading of these values, for the twins, the app and design.
    """
    return bragg.BraggMirror(
        n1=float(values["n1"]), n2=float(values["n2"]), Lambda=float(values["Lambda"]), delta=float(values["delta"]),
        N=round_integer(values["N"]), nh=host_index(float(values.get("nh", 0.0))),
    )


# --------------------------------------------------------------------------------------------------
# Inverse design's forward model of a Bragg mirror (declared by both Bragg twins)


def bragg_rgb_batch(values: Mapping[str, np.ndarray], cos_theta, step: float = colorimetry.COARSE_STEP,
                    smooth: float | None = None) -> np.ndarray:
    """The coarse colours ``(B, A, 3)`` of mirrors ``values`` (arrays ``(B,)``, ``N`` continuous) at ``cos_theta`` ``(A,)``."""
    if natural_values(values):  # absorbing layers (k1, k2): the complex indices' batch
        return natural_batch(values, {}, cos_theta, step, smooth)
    nodes, weights = colorimetry.interpolant_nodes(step)
    R = bragg.bragg_reflectance_batch(values["n1"], values["n2"], values["Lambda"], values["delta"], values["N"],
                                      values["nh"], cos_theta, nodes, step=step, smooth=smooth)
    return colorimetry.xyz_to_rgb(R @ weights)


def bragg_rgb_gradient(values: Mapping[str, np.ndarray], cos_theta, step: float = colorimetry.COARSE_STEP):
    """
    :func:`bragg_rgb_batch` and its analytic derivatives by ``Lambda``, ``delta`` and ``N`` (``(B, A, 3)`` each), for
    lossless mirrors without a separate host (:func:`explorer.physics.bragg.bragg_reflectance_batch_gradient`); None
    for others (the caller differences).
    """
    if natural_values(values):
        return None
    nodes, weights = colorimetry.interpolant_nodes(step)
    found = bragg.bragg_reflectance_batch_gradient(values["n1"], values["n2"], values["Lambda"], values["delta"], values["N"],
                                                   values["nh"], cos_theta, nodes, step=step)
    if found is None:
        return None
    R, grads = found
    return colorimetry.xyz_to_rgb(R @ weights), {k: colorimetry.xyz_to_rgb(v @ weights) for k, v in grads.items()}


def bragg_spectra_batch(values: Mapping[str, np.ndarray], cos_theta, wavelengths, smooth_relative: float) -> np.ndarray:
    """Screening spectra ``(B, A, W)``: fringes narrower than ~``smooth_relative`` lambda averaged out."""
    wavelengths = np.asarray(wavelengths, dtype=np.float64)
    return bragg.bragg_reflectance_batch(values["n1"], values["n2"], values["Lambda"], values["delta"], values["N"],
                                         values["nh"], cos_theta, wavelengths, step=1.0, smooth=smooth_relative * wavelengths)


def bragg_converged_rgb(values: Mapping[str, float], cos_theta, final: bool = True) -> np.ndarray:
    """
    The converged colours of a mirror (:func:`mirror_of`): :func:`explorer.physics.bragg.reference_rgb` when
    ``final``, otherwise the tabulated method's own nodes (float32 where it applies, substeps capped), which the
    polish calls many times.
    """
    if natural_values(values):  # absorbing or disordered layers: the natural mirror's colours
        return natural_converged(values, {}, cos_theta, final)
    mirror = mirror_of(values)
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    if final:
        return bragg.reference_rgb(cos_theta, mirror)
    return bragg.converged_rgb(cos_theta, mirror)


def bragg_converged_many(values: Mapping[str, np.ndarray], cos_theta) -> np.ndarray:
    """:func:`bragg_converged_rgb` (final) of many mirrors ``values`` (arrays ``(B,)``): ``(B, A, 3)``, in one refinement."""
    rows = np.asarray(values["Lambda"]).shape[0]
    if natural_values(values):
        return np.array([natural_converged({k: float(v[i]) for k, v in values.items()}, {}, cos_theta, True) for i in range(rows)])
    mirrors = [mirror_of({k: float(v[i]) for k, v in values.items()}) for i in range(rows)]
    return bragg.reference_rgb_many(np.asarray(cos_theta, dtype=np.float64), mirrors)


# Natural mirrors in design: indices naming media (explorer.design.media), absorbing and disordered layers.

#: The index parameters that may name a medium.
MEDIUM_PARAMETERS = ("n1", "n2", "nh")
#: The natural mirror's other design parameters: each layer's extinction coefficient (added to its index,
#: a number's or a medium's) and the thickness disorder. The search holds them at 0 unless fixed or freed.
NATURAL_PARAMETERS = ("k1", "k2", "sigma")
#: The extinction coefficient of each layer's index.
EXTINCTION = {"n1": "k1", "n2": "k2"}
#: The non-final converged colours (the polish's) sample the spectrum this finely (nm), fringes narrower
#: than a few steps averaged (:func:`explorer.physics.bragg.bragg_reflectance_batch`).
POLISH_STEP = 1.0


def design_indices(values: Mapping[str, np.ndarray], media: Mapping, wavelengths: np.ndarray) -> dict[str, np.ndarray]:
    """
    ``n1``, ``n2``, ``nh`` of rows ``values`` ``(B,)`` with each medium at ``wavelengths`` ``(W,)`` and each layer's
    ``k`` added: ``(B, 1, W)`` or ``(B,)``.
    """
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


def mirror_with_media(values: Mapping[str, float], media: Mapping) -> natural.NaturalMirror:
    """The :class:`explorer.physics.natural.NaturalMirror` of design values (``N`` rounded), media in place of their numbers."""
    index = lambda name: media[name] if name in media else float(values[name])  # noqa: E731
    nh = media.get("nh", host_index(float(values["nh"])))
    extra = {name: float(values.get(name, 0.0)) for name in NATURAL_PARAMETERS}
    return natural.NaturalMirror(n1=index("n1"), n2=index("n2"), Lambda=float(values["Lambda"]), delta=float(values["delta"]),
                                 N=max(1, int(round(float(values["N"])))), nh=nh, **extra)


def natural_values(values: Mapping[str, object]) -> bool:
    """Whether design values ``values`` (numbers or rows) have an absorbing or disordered layer."""
    return any(np.any(np.asarray(values.get(name, 0.0)) != 0.0) for name in NATURAL_PARAMETERS)


def natural_batch(values: Mapping[str, np.ndarray], media: Mapping, cos_theta, step: float, smooth: float | None) -> np.ndarray:
    """The batch model's colours ``(B, A, 3)`` of rows ``values`` with ``media`` and each layer's ``k`` (the ordered mirror)."""
    nodes, weights = colorimetry.interpolant_nodes(step)
    n = design_indices(values, media, nodes)
    R = bragg.bragg_reflectance_batch(n["n1"], n["n2"], values["Lambda"], values["delta"], values["N"], n["nh"],
                                      cos_theta, nodes, step=step, smooth=smooth)
    return colorimetry.xyz_to_rgb(R @ weights)


def natural_converged(values: Mapping[str, float], media: Mapping, cos_theta, final: bool = True) -> np.ndarray:
    """
    The converged colours ``(A, 3)`` of one structure with ``media``, ``k1``, ``k2`` and ``sigma``:
    :func:`explorer.physics.natural.natural_rgb` (final, or disordered: its realisations seeded, a smooth function
    of the structure), else the batch at :data:`POLISH_STEP`.
    """
    cos_theta = np.asarray(cos_theta, dtype=np.float64)
    if final or float(values.get("sigma", 0.0)) > 0.0:
        return natural.natural_rgb(cos_theta, mirror_with_media(values, media))
    rows = {k: np.array([float(v)]) for k, v in values.items()}
    rows["N"] = np.array([max(1.0, float(np.round(values["N"])))])
    return natural_batch(rows, media, cos_theta, POLISH_STEP, None)[0]


#: What design fits of a Bragg mirror, and on which forward model: its specular colour (the rough layer's too: the
#: smooth mirror's colour, which its gradient view shows), the period scanned, searched by optical thicknesses.
BRAGG_DESIGN = DesignModel(parameters=("n1", "n2", "Lambda", "delta", "N", "nh", "k1", "k2", "sigma"), log_parameters=("N", "Lambda"),
                           integer_parameters=("N",), batch=bragg_rgb_batch, converged=bragg_converged_rgb, gradient=bragg_rgb_gradient,
                           converged_many=bragg_converged_many,
                           host_parameter="nh", scale_parameter="Lambda", optical=True, spectra=bragg_spectra_batch,
                           paint_free=("Lambda", "delta", "N"), held=("k1", "k2", "sigma"))


#: Structure maps on a smooth mirror: each texel the whole mirror; the tabulated method's table is the material's, so
#: each texel shows the improved approximation (as an export away from its table's values).
BRAGG_MAPS = StructureMaps(fields=bragg.STRUCTURE_FIELDS, integer_fields=("N",),
                           stand_ins={BraggMethod.TABULATED: BraggMethod.IMPROVED})


@twin
class BraggMirrorModel:
    """Twin of ``shaders/bragg_mirror.brd``: its ``reflectance(cos_theta)`` for every ``method``."""

    name = "bragg_mirror"
    capabilities = Capabilities(methods=BraggMethod, dirac=True, bragg_spectrum=True, numpy=True, albedo=("numpy", "gl"),
                                exports=("mitsuba", "brdf", "table", "gltf"), design=BRAGG_DESIGN, maps=BRAGG_MAPS)

    def __init__(self, values: Mapping[str, object]):
        self.values = dict(values)
        self.mirror = mirror_of(values)
        self.method = BraggMethod(round_integer(values.get("method", 0)))
        self.s = round_integer(values.get("s", 3))
        #: Absorbing, dispersive or disordered layers (explorer.physics.natural): every method shows their exact table.
        self.natural = natural_mirror_of(values)
        # The reference's wavelength step (nm): 1 is the paper's 1-nm sum (bragg_layer.brd has no such parameter).
        self.wavelength_step = float(values.get("wavelength_step", 1.0))
        self._table: np.ndarray | None = None

    @property
    def table(self) -> np.ndarray:
        """The tabulated method's RGB over cos(theta) (built once per parameter set)."""
        if self._table is None:
            self._table = bragg.tabulated_rgb_table(self.mirror) if self.natural is None else natural.natural_rgb_table(self.natural)
        return self._table

    def reflectance(self, cos_theta) -> np.ndarray:
        """Linear RGB reflectance at incidence ``cos_theta`` (shape ``(..., 3)``)."""
        if self.natural is not None:  # the shader's natural_structure(): the exact table whatever the method
            return bragg.tabulated_rgb(self.table, np.asarray(cos_theta, dtype=np.float64))
        return BRAGG_REFLECTANCE[self.method](self, np.asarray(cos_theta, dtype=np.float64))

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        """The shader's ``BRDF``: the reflectance at the half-vector angle (unit vectors ``(..., 3)``)."""
        return self.reflectance(_cos_half_angle(L, V))

    def mirror_reflection(self, V, N) -> np.ndarray:
        """
        The smooth mirror's Dirac under an environment: its reflectance at ``cos theta = V.N`` into
        reflect(-V, N) (``(..., 3)``); the env view adds nothing else (:attr:`mirror_only`).
        """
        cos_theta = np.clip(np.sum(np.asarray(V, np.float64) * np.asarray(N, np.float64), axis=-1), 0.0, 1.0)
        return self.reflectance(cos_theta)

    #: The env view integrates no finite BRDF: a smooth mirror is a Dirac (``MIRROR_ONLY`` in the shader).
    mirror_only = True

    def spectral_reflectance(self, cos_theta, wavelengths) -> np.ndarray:
        """The smooth mirror's ``R_lambda(theta)`` (Eqs. 2, 9, 10) at ``cos_theta`` ``(n,)`` and wavelengths ``(n, W)`` (Mitsuba's Dirac)."""
        if self.natural is not None:  # absorbing, dispersive or disordered layers: the exact multilayer
            return natural.unpolarised_reflectance(self.natural, wavelengths, np.asarray(cos_theta, dtype=np.float64))
        return bragg.bragg_reflectance(np.clip(cos_theta, microfacet.COS_THETA_MIN, 1.0)[:, None], wavelengths, self.mirror)

    def texture_table(self, mapping: str) -> np.ndarray:
        """The tabulated method's table over ``(cos theta, T)`` under ``mapping`` (:func:`explorer.physics.bragg.textured_rgb_table`)."""
        return bragg.textured_rgb_table(self.mirror, mapping)

    def textured_reflectance(self, cos_theta, T, mapping: str = "both", structures: np.ndarray | None = None) -> np.ndarray:
        """
        The twin of the shader's ``textured_reflectance``: the mirror at texture values ``T`` (per sample, in [0, 1])
        under ``mapping`` (supplemental Figure 7, :func:`explorer.physics.bragg.textured_mirror`), by ``method``.
        ``mapping="maps"``: ``T`` is a texel index of ``structures`` (:data:`BRAGG_MAPS`' table), each texel its own
        mirror, by its texel method (:meth:`explorer.materials.twins.StructureMaps.texel_method`), 0 off the maps' mask.
        """
        cos_theta = np.asarray(cos_theta, dtype=np.float64)
        T = np.broadcast_to(np.asarray(T, dtype=np.float64), cos_theta.shape)
        if mapping == "maps":
            rgb = np.zeros(cos_theta.shape + (3,))
            for samples, mirror in bragg.mapped_mirrors(structures, T):
                rgb[samples] = self._mirror_rgb(cos_theta[samples], mirror, BraggMethod(BRAGG_MAPS.texel_method(self.method)))
            return rgb
        if self.method == BraggMethod.TABULATED:
            return bragg.textured_tabulated_rgb(self.texture_table(mapping), cos_theta, T)
        return self._mirror_rgb(cos_theta, bragg.textured_mirror(self.mirror, T, mapping))

    def _mirror_rgb(self, cos_theta: np.ndarray, mirror: bragg.BraggMirror, method: BraggMethod | None = None) -> np.ndarray:
        """A per-sample mirror's colours by ``method`` (default the material's; not the tabulated one, which has a table)."""
        method = self.method if method is None else method
        if method == BraggMethod.REFERENCE:
            return bragg.textured_reference_rgb(cos_theta, mirror, self.wavelength_step)
        s = {BraggMethod.BASIC: 0, BraggMethod.SUBDIVIDED: self.s, BraggMethod.IMPROVED: self.s}[method]
        variant = {"variant": "improved"} if method == BraggMethod.IMPROVED else {}
        return bragg.approximate_rgb(cos_theta, mirror, s, **variant)

    def surface_reflectance(self, cos_theta, T, **options) -> np.ndarray:
        """The flat textured view's colour at ``cos_theta`` of texture values ``T`` (the shader's ``surface_reflectance``)."""
        return self.textured_reflectance(cos_theta, T, **options)

    def textured_mirror_reflection(self, V, N, T, mapping: str = "both", structures: np.ndarray | None = None) -> np.ndarray:
        """The env view's Dirac at texture values ``T``: :meth:`textured_reflectance` at ``cos theta = V.N`` (the shader's)."""
        cos_theta = np.clip(np.sum(np.asarray(V, np.float64) * np.asarray(N, np.float64), axis=-1), 0.0, 1.0)
        return self.textured_reflectance(cos_theta, T, mapping, structures)

    def textured_brdf(self, L, V, N, X, Y, T, sigma, prefiltered: bool, mapping: str = "both",
                      structures: np.ndarray | None = None) -> np.ndarray:
        """The shader's ``textured_BRDF``: :meth:`textured_reflectance` at the half-vector angle (no prefiltering)."""
        if prefiltered:
            raise ValueError("a textured Bragg mirror has no prefiltering (Section 5's is the thin film's)")
        return self.textured_reflectance(_cos_half_angle(L, V), T, mapping, structures)

    #: The parameters the tabulated method's table depends on (:func:`mirror_of`, :func:`natural_mirror_of`
    #: where the file declares them), and the integer ones among them.
    MIRROR_PARAMETERS = ("n1", "n2", "Lambda", "delta", "N", "nh", "k1", "k2", "sigma", "medium_n1", "medium_n2", "medium_nh")
    INTEGER_MIRROR_PARAMETERS = ("N", "medium_n1", "medium_n2", "medium_nh")
    #: The shader's improved approximation (method 4, its ``reflectance`` branch): what an exported table
    #: falls back to away from its values.
    IMPROVED_GLSL = "approximate_rgb(cos_theta, bragg_mirror(), s, false, true)"

    def brdf_export(self) -> dict:
        """
        How ``export --to brdf`` bakes the mirror (:mod:`explorer.materials.export_brdf`): the tabulated method's
        table for the exported mirror, whatever the exported method, and the values it holds for: where a
        mirror parameter moves away from them, the file's method 3 reads method 4 (the improved approximation).
        """
        baked = {name: float(self.values[name]) for name in self.MIRROR_PARAMETERS if name in self.values}
        integers = tuple(name for name in self.INTEGER_MIRROR_PARAMETERS if name in baked)
        return {"tables": {"bragg_table": self.table},
                "baked": {"bragg_table": {"values": baked, "integers": integers, "fallback": self.IMPROVED_GLSL,
                                          "fallback_label": f"{int(BraggMethod.IMPROVED)} {BraggMethod.IMPROVED.label}",
                                          "label": f"{int(BraggMethod.TABULATED)} {BraggMethod.TABULATED.label}"}}}

    def textures(self) -> dict[str, np.ndarray]:
        """Tables for the shader's samplers, as ``(width, 3)`` float arrays."""
        # Only the tabulated method reads its table; the others get a placeholder texel.
        needed = self.method.needs_table or self.natural is not None
        return {"bragg_table": self.table if needed else np.zeros((1, 3), np.float32)}

    def draft_textures(self) -> dict[str, np.ndarray] | None:
        """
        Quick stand-ins for :meth:`textures` while a slider moves (the tabulated method's draft table,
        :func:`explorer.physics.bragg.draft_rgb_table`); None when the tables are cheap anyway.
        """
        if self.natural is not None:
            return None  # the exact table only (no draft of complex, dispersive spectra)
        return {"bragg_table": bragg.draft_rgb_table(self.mirror)} if self.method.needs_table else None


def natural_mirror_of(values: Mapping[str, object]) -> "natural.NaturalMirror | None":
    """
    The natural mirror of a ``bragg_mirror``'s (or ``bragg_layer``'s) values when they have absorbing, dispersive
    or disordered layers (``k1``, ``k2``, ``sigma``, ``medium_*``), else None (the paper's mirror).
    """
    from explorer.materials.media import index_value

    k1, k2, sigma = (float(values.get(name, 0.0)) for name in ("k1", "k2", "sigma"))
    n1, n2 = index_value(values, "n1"), index_value(values, "n2")
    nh_value = index_value(values, "nh") if "nh" in values else 0.0
    media = any(not isinstance(v, float) for v in (n1, n2, nh_value))
    if not (k1 > 0.0 or k2 > 0.0 or sigma > 0.0 or media):
        return None
    nh = host_index(nh_value)
    return natural.NaturalMirror(n1=n1, n2=n2, Lambda=float(values["Lambda"]), delta=float(values["delta"]),
                                 N=round_integer(values["N"]), nh=nh, k1=k1, k2=k2, sigma=sigma)


#: The Bragg mirror's reflectance per method (the shader's branches on BRAGG_* in bragg_mirror.brd).
BRAGG_REFLECTANCE = {
    BraggMethod.REFERENCE: lambda model, c: bragg.reference_rgb(c, model.mirror, step=model.wavelength_step),
    BraggMethod.BASIC: lambda model, c: bragg.approximate_rgb(c, model.mirror, 0),
    BraggMethod.SUBDIVIDED: lambda model, c: bragg.approximate_rgb(c, model.mirror, model.s),
    BraggMethod.TABULATED: lambda model, c: bragg.tabulated_rgb(model.table, c),
    BraggMethod.IMPROVED: lambda model, c: bragg.approximate_rgb(c, model.mirror, model.s, variant="improved"),
}


@functools.lru_cache(maxsize=16)
def _transmission_rgb_table(mirror: bragg.BraggMirror, alpha: float, size: int) -> np.ndarray:
    """
    The RGB of a rough Bragg layer's integrated transmissivity ``f_t(theta) cos theta`` (Eq. 28) at
    ``cos theta = k / (size - 1)``: ``1 - R_lambda`` of ``mirror`` at the 0.25 degree nodes, filtered by
    the cached ``F_alpha`` (:func:`explorer.physics.layered.transmission_filter_for`), integrated to RGB and
    interpolated linearly in ``theta`` (:func:`explorer.physics.layered.lookup`).
    """
    F = layered.transmission_filter_for(alpha)
    R = layered.reflectance_table(mirror, np.cos(F.theta))
    T_rgb = colorimetry.spectrum_to_rgb(layered.integrated_transmissivity(F, 1.0 - R))
    theta = np.arccos(np.linspace(0.0, 1.0, size))
    table = layered.lookup(T_rgb, theta).astype(np.float32)
    table.setflags(write=False)
    return table


class CompensatedTwin:
    """
    What the rough Bragg twins (``bragg_layer``, ``bragg_stack``) share about multiple scattering
    (:mod:`explorer.physics.multiscatter_stack`): the compensation's weight by roughness, its lobe's RGB table and
    two hooks. A twin defines ``multiple_scattering``, ``compensation`` (unweighted, None when the weight is 0),
    ``_roughness`` (the alpha that decides the weight) and ``_base_albedo`` (the base the lobe bounces on).
    """

    #: The furnace's test hook: when set (a number in [0, 1]), every layer's facets reflect this at every angle and
    #: wavelength (``R_lambda = value``, the transmissivity of Eq. 28 from ``1 - value``), in the tables the numpy twin,
    #: the shader and the random walk read alike: the same code path with white (``1.0``) facets. ``None``: Yeh's.
    facet_reflectance_override: float | None = None
    #: The studies' hook (numpy only): the compensation at full weight whatever the roughness, to show what the fade
    #: leaves out at alpha <= 0.4 (``explorer.dev.multiscatter_validation``). The app, GL and exports never set it.
    full_compensation: bool = False

    @property
    def compensation_weight(self) -> float:
        """
        The share of the compensation added: :func:`explorer.physics.compensation.compensation_weight` of
        ``_roughness`` (0 up to alpha = 0.4: Eq. 17 / Eq. 34 as published; 1 from 0.5), 0 when ``multiple_scattering``
        is off. The shader computes the same from its uniforms (``compensation_weight`` in lib/multiscatter.glsl).
        """
        if not self.multiple_scattering:
            return 0.0
        return 1.0 if self.full_compensation else float(compensation.compensation_weight(self._roughness))

    @property
    def compensation_rgb(self) -> np.ndarray | None:
        """The compensation's lobe in RGB over (theta_i, theta_o) in air (:func:`explorer.physics.multiscatter_stack.rgb_table`)."""
        if self.compensation is None:
            return None
        if self._compensation_rgb is None:
            self._compensation_rgb = multiscatter_stack.rgb_table(self.compensation, self._base_albedo)
        return self._compensation_rgb


@twin
class BraggLayerModel(CompensatedTwin, BraggMirrorModel):
    """
    Twin of ``shaders/bragg_layer.brd``: one rough Bragg layer (Eq. 17, GGX microfacets that are Bragg
    mirrors) over a Lambertian base of RGB albedo ``rho_d``:
    ``D G1(L) G1(V) R_rgb(theta_d) / (4 cos_i cos_o) + (rho_d / pi) T_rgb(theta_i) T_rgb(theta_o)``, with
    ``R_rgb`` the ``method``'s RGB reflectance of the smooth mirror (:class:`BraggMirrorModel`) and
    ``T_rgb`` the RGB of the layer's integrated transmissivity (Eq. 28), tabulated over ``cos theta``
    (:func:`_transmission_rgb_table`): an RGB approximation of Eq. 34's base term for one layer, n1 = 1.
    """

    name = "bragg_layer"
    capabilities = Capabilities(methods=BraggMethod, dirac=False, bragg_spectrum=True, numpy=True, albedo=("numpy", "gl"),
                                exports=("mitsuba", "brdf", "table", "gltf"), design=BRAGG_DESIGN)
    # A rough layer is no Dirac: the env view integrates its BRDF. No textured view (no '# texture:').
    mirror_reflection = None
    mirror_only = False
    textured_brdf = None
    textured_mirror_reflection = None

    def __init__(self, values: Mapping[str, object]):
        super().__init__(values)
        self.alpha = float(values["alpha"])
        microfacet.check_alpha(self.alpha)
        self.rho_d = np.broadcast_to(np.asarray(values.get("rho_d", 0.0), dtype=np.float64), (3,)).copy()
        self.multiple_scattering = bool(values.get("multiple_scattering", True))
        self._compensation = None
        self._compensation_rgb: np.ndarray | None = None
        # The furnace hook flattens the tables (the tabulated method's bragg_table, Eq. 28's transmission_table, the
        # compensation's layer tables): the other methods compute Yeh's reflectance in the shader, out of its reach.
        if (self.facet_reflectance_override is not None and self.natural is None
                and self.method != BraggMethod.TABULATED):
            raise ValueError("the facet reflectance hook acts on the tables: it needs the tabulated method")

    @property
    def _roughness(self) -> float:
        return self.alpha

    @property
    def layer_structure(self) -> tuple[layered.LayeredBragg, tuple[layered.LayerTables]]:
        """
        The one-layer structure the compensation is built for, and its tables: the layer seen from inside its host,
        no coating, over the base (as ``bragg_stack``'s one layer; a dispersive host at its index at 550 nm), with
        :attr:`facet_reflectance_override`'s flat tables when set. What the random walk's reference simulates.
        """
        nat = self.natural
        if nat is None:
            host = self.mirror.nh if self.mirror.nh is not None else self.mirror.n1
            n1, n2, media, k1, k2, sigma = self.mirror.n1, self.mirror.n2, {}, 0.0, 0.0, 0.0
        else:
            # A dispersive host enters the compensation at its index at 550 nm (its angles need one number).
            nh = nat.nh if nat.nh is not None else nat.n1  # no host given: the host is n1
            host = float(nh) if isinstance(nh, (int, float)) else float(nh.real_at(550.0))
            media = {f"medium_{k}": m for k, m in (("n1", nat.n1), ("n2", nat.n2)) if not isinstance(m, float)}
            n1 = nat.n1 if isinstance(nat.n1, float) else host + 1.0  # a medium stands for n1: not the host
            n2 = nat.n2 if isinstance(nat.n2, float) else 1.5
            k1, k2, sigma = nat.k1, nat.k2, nat.sigma
        layer = layered.RoughBraggLayer(
            n2=float(n2), Lambda=self.mirror.Lambda, delta=self.mirror.delta, N=self.mirror.N, alpha=self.alpha,
            n1=None if n1 == host else float(n1), k1=k1, k2=k2, sigma=sigma, **media)
        stack = layered.LayeredBragg(layers=(layer,), n1=host, rho_d=tuple(self.rho_d), coating=False)
        table = _layer_tables(layer, host)
        if self.facet_reflectance_override is not None:
            table = _flat_tables(table, float(self.facet_reflectance_override))
        return stack, (table,)

    @property
    def compensation(self):
        """
        The layer's multiple-scattering compensation (:mod:`explorer.physics.multiscatter_stack`, as
        ``bragg_stack``'s for :attr:`layer_structure`; natural layers as ``bragg_stack``'s), or None when off or
        when its weight is 0 (alpha <= 0.4: no table is built). Unweighted: :attr:`compensation_weight` scales it.
        """
        if self.compensation_weight == 0.0:
            return None
        if self._compensation is None:
            stack, (table,) = self.layer_structure
            terms = None if self.facet_reflectance_override is not None else (_layer_terms(table),)
            self._compensation = multiscatter_stack.stack_compensation(stack, (table,), terms)
        return self._compensation

    @property
    def _base_albedo(self):
        return self.rho_d

    @property
    def table(self) -> np.ndarray:
        """The tabulated method's RGB over cos(theta); with :attr:`facet_reflectance_override`, that of the flat spectrum."""
        if self.facet_reflectance_override is None:
            return super().table
        rgb = colorimetry.spectrum_to_rgb(np.full(colorimetry.WAVELENGTHS.size, float(self.facet_reflectance_override)))
        return np.broadcast_to(rgb, (bragg.TABLE_SIZE, 3)).astype(np.float32)

    @property
    def transmission_table(self) -> np.ndarray:
        """``T_rgb`` at ``cos theta = k / 255`` (Eq. 28 in RGB), ``(256, 3)`` float32."""
        alpha = float(microfacet.check_alpha(self.alpha))
        if self.facet_reflectance_override is not None:  # the hook's flat facets: Eq. 28 of 1 - value
            (table,) = self.layer_structure[1]
            T_rgb = colorimetry.spectrum_to_rgb(table.transmissivity)
            return layered.lookup(T_rgb, np.arccos(np.linspace(0.0, 1.0, bragg.TABLE_SIZE))).astype(np.float32)
        if self.natural is not None:
            return _natural_transmission_rgb_table(self.natural, alpha, bragg.TABLE_SIZE)
        return _transmission_rgb_table(self.mirror, alpha, bragg.TABLE_SIZE)

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        """The shader's ``BRDF`` for unit vectors ``(..., 3)``; 0 where ``L`` or ``V`` is at or below the surface."""
        lobe, cos_theta_d, above = microfacet.microfacet_lobe(L, V, N, self.alpha)
        result = np.zeros(lobe.shape + (3,))
        if not above.any():
            return result
        N = np.broadcast_to(N, lobe.shape + (3,))
        cos_i = np.sum(N * np.broadcast_to(L, N.shape), axis=-1)[above]
        cos_o = np.sum(N * np.broadcast_to(V, N.shape), axis=-1)[above]
        specular = lobe[above, None] * self.reflectance(cos_theta_d[above])
        table = self.transmission_table
        base = (self.rho_d / np.pi) * bragg.tabulated_rgb(table, cos_i) * bragg.tabulated_rgb(table, cos_o)
        result[above] = specular + base
        if self.compensation_rgb is not None:
            # The lobe needs the polar angles only: atan2(|d - (d.n) n|, d.n), as the shader's atan(length(xy), z).
            polar = lambda d, c: np.arctan2(np.linalg.norm(np.broadcast_to(d, N.shape)[above] - c[:, None] * N[above], axis=-1), c)  # noqa: E731
            lobe_rgb = multiscatter_stack.lookup_rgb(self.compensation_rgb, polar(L, cos_i), polar(V, cos_o))
            result[above] += np.float32(self.compensation_weight) * lobe_rgb
        return result

    spectral_reflectance = None

    def spectral_brdf(self, i, o, wavelengths, rgb_upsample) -> np.ndarray:
        """
        Eq. 17 per wavelength for Mitsuba: ``D G1 G1 R_lambda(theta_d) / (4 cos cos)`` plus the base seen through
        the layer twice, at local directions ``(n, 3)`` above the surface and wavelengths ``(n, W)``.
        """
        lobe, cos_d, _ = microfacet.microfacet_lobe(i, o, np.array([0.0, 0.0, 1.0]), self.alpha)
        if self.natural is not None:  # absorbing, dispersive or disordered layers: the exact multilayer
            R = natural.unpolarised_reflectance(self.natural, wavelengths, np.maximum(cos_d, microfacet.COS_THETA_MIN))
        else:
            R = bragg.bragg_reflectance(np.maximum(cos_d, microfacet.COS_THETA_MIN)[:, None], wavelengths, self.mirror)
        value = lobe[:, None] * R
        if self.rho_d.any():
            T = (_natural_layer_transmissivity(self.natural, float(self.alpha)) if self.natural is not None
                 else _layer_transmissivity(self.mirror, float(self.alpha)))
            Ti = _interp_wavelength(layered.lookup(T, _theta(i)), wavelengths)
            To = _interp_wavelength(layered.lookup(T, _theta(o)), wavelengths)
            value = value + rgb_upsample(np.broadcast_to(self.rho_d, (i.shape[0], 3)), wavelengths) / np.pi * Ti * To
        if self.compensation is not None:
            rho = rgb_upsample(np.broadcast_to(self.rho_d, (i.shape[0], 3)), wavelengths)
            value = value + self.compensation_weight * _spectral_lobe(self.compensation, i, o, wavelengths, rho)
        return value

    def sampling_lobes(self, cos_o):
        """``(alphas, weights, cosine_weight)`` at view cosines ``(n,)``: the shader's ``sampling_lobes`` (Eq. 31)."""
        t = bragg.tabulated_rgb(self.transmission_table, np.clip(cos_o, 0.0, 1.0)).mean(axis=-1)
        p_trans = np.clip(2.0 * t / (1.0 + microfacet.smith_G1(np.clip(cos_o, 1e-9, 1.0), self.alpha)), 0.0, 1.0)
        rho = float(np.mean(self.rho_d))
        return [max(self.alpha, 1e-4)], [1.0 - p_trans + 1e-3], p_trans * rho

    def textures(self) -> dict[str, np.ndarray]:
        """The method-3 reflectance table (a placeholder texel otherwise), ``T_rgb`` and the multiple-scattering
        lobe's table ``layer_lobe`` (:func:`explorer.physics.multiscatter_stack.rgb_table`; zeros when off)."""
        lobe = np.zeros((multiscatter_stack.TABLE_ROWS, multiscatter_stack.TABLE_ROWS, 3), np.float32)
        if self.compensation_rgb is not None:
            lobe[...] = self.compensation_rgb
        return {**super().textures(), "transmission_table": self.transmission_table, "layer_lobe": lobe}


@functools.lru_cache(maxsize=32)
def _layer_tables(layer: layered.RoughBraggLayer, n1: float) -> layered.LayerTables:
    """A layer's tables, cached: changing one layer of a stack rebuilds that layer's only."""
    return layered.layer_tables(layer, n1)


_TERMS_CACHE: dict = {}


def _layer_terms(table: layered.LayerTables):
    """A layer's albedos with multiple scattering from its (cached) tables, cached per layer and host (32 of them)."""
    key = (table.layer, table.n1)
    if key not in _TERMS_CACHE:
        if len(_TERMS_CACHE) >= 32:
            _TERMS_CACHE.pop(next(iter(_TERMS_CACHE)))
        _TERMS_CACHE[key] = multiscatter_stack.layer_terms_of(table)
    return _TERMS_CACHE[key]


def _flat_tables(table: layered.LayerTables, R: float) -> layered.LayerTables:
    """``table`` with facets reflecting ``R`` everywhere (the furnace hook of :class:`BraggStackModel`)."""
    reflectance = np.full_like(table.reflectance, R)
    transmissivity = (layered.transmission_filter_for(table.layer.alpha).weights.astype(np.float32)
                      @ (np.float32(1.0) - reflectance)).astype(np.float32)
    return layered.LayerTables(table.layer, table.n1, table.theta, reflectance, transmissivity)


def _number(values: Mapping[str, object], name: str) -> float:
    return float(values[name])


@twin
class BraggStackModel(CompensatedTwin):
    """
    Twin of ``shaders/bragg_stack.brd``: the single-reflection BRDF (Eq. 34) of 1 to 3 rough Bragg layers
    in a host ``nh`` over a Lambertian base, under a coating (:func:`explorer.physics.layered.single_reflection_brdf`
    from the per-layer tables, the "LUT version" of Table 2), and the tables its shader reads.

    Parameters ``layers``, ``nh``, ``coating``, ``rho_d`` and, per layer ``k`` in 1..3, ``n1_k``, ``n2_k``,
    ``Lambda_k``, ``delta_k``, ``N_k``, ``alpha_k`` (layers beyond ``layers`` are ignored).
    """

    name = "bragg_stack"
    capabilities = Capabilities(methods=None, dirac=False, bragg_spectrum=False, numpy=True,
                                albedo=("numpy", "gl", "position-free"), exports=("mitsuba", "table", "gltf"), design=None)

    def __init__(self, values: Mapping[str, object]):
        self.values = dict(values)
        self.stack = self.stack_of(values)
        self.multiple_scattering = bool(values.get("multiple_scattering", True))
        self._tables: tuple | None = None
        self._compensation = None
        self._compensation_rgb: np.ndarray | None = None
        self.rho_d = np.broadcast_to(np.asarray(values.get("rho_d", 0.0), dtype=np.float64), (3,)).copy()

    @staticmethod
    def stack_of(values: Mapping[str, object]) -> layered.LayeredBragg:
        """The structure the values describe (no tables built)."""
        count = round_integer(values["layers"])
        if not 1 <= count <= layered.MAX_LAYERS:
            raise ValueError(f"layers must be 1 to {layered.MAX_LAYERS}, got {values['layers']}")
        from explorer.materials.media import SLIDER_WAVELENGTH_NM, index_value

        nh = _number(values, "nh")
        layers = []
        for k in range(1, count + 1):
            n1_k = _number(values, f"n1_{k}")
            # Natural layers (explorer.physics.natural): k1_k, k2_k, sigma_k and media medium_n1_k, medium_n2_k.
            media = {f"medium_{name}": (index_value(values, f"{name}_{k}") if f"medium_{name}_{k}" in values else None)
                     for name in ("n1", "n2")}
            media = {key: (None if isinstance(value, float) else value) for key, value in media.items()}
            layers.append(layered.RoughBraggLayer(
                n2=_number(values, f"n2_{k}"), Lambda=_number(values, f"Lambda_{k}"),
                delta=_number(values, f"delta_{k}"), N=round_integer(values[f"N_{k}"]),
                alpha=_number(values, f"alpha_{k}"), n1=None if n1_k == nh else n1_k,
                k1=float(values.get(f"k1_{k}", 0.0)), k2=float(values.get(f"k2_{k}", 0.0)),
                sigma=float(values.get(f"sigma_{k}", 0.0)), **media,
            ))
        # A host naming a medium (medium_nh; --set nh=chitin): nh holds its n at 550 nm, the physics reads the medium.
        host = index_value(values, "nh") if "medium_nh" in values else nh
        medium = None if isinstance(host, float) else host
        # A medium's n1 is its index at 550 nm (what Eq. 35's estimate and the multiple-scattering lobe take), not
        # the slider's value, which its range may clamp (TiO2).
        return layered.LayeredBragg(
            layers=tuple(layers), n1=nh if medium is None else medium.real_at(SLIDER_WAVELENGTH_NM),
            rho_d=values.get("rho_d", 0.0), coating=bool(values.get("coating", True)),
            tau_h=float(values.get("tau_h", 0.0)), medium_n1=medium,
        )

    @property
    def tables(self) -> tuple:
        """Every layer's tables (:func:`explorer.physics.layered.layer_tables`, cached per layer), built on first use."""
        if self._tables is None:
            self._tables = tuple(_layer_tables(layer, self.stack.host) for layer in self.stack.layers)
            if self.facet_reflectance_override is not None:
                self._tables = tuple(_flat_tables(t, float(self.facet_reflectance_override)) for t in self._tables)
        return self._tables

    @property
    def _roughness(self) -> float:
        """The roughest used layer's alpha decides the compensation's weight (the shader's ``compensation_fade``)."""
        return max(layer.alpha for layer in self.stack.layers)

    @property
    def compensation(self):
        """The structure's multiple-scattering compensation (:mod:`explorer.physics.multiscatter_stack`), or None when
        off or when its weight is 0 (every layer at alpha <= 0.4: no table is built). Unweighted, as the layer's."""
        if self.compensation_weight == 0.0:
            return None
        if self._compensation is None:
            terms = None if self.facet_reflectance_override is not None else tuple(_layer_terms(t) for t in self.tables)
            self._compensation = multiscatter_stack.stack_compensation(self.stack, self.tables, terms)
        return self._compensation

    @property
    def _base_albedo(self):
        return self.stack.rho_d

    def reflectance(self, cos_theta) -> np.ndarray:
        """The smooth limit's specular colour (:func:`explorer.physics.layered.stack_specular_rgb`)."""
        return layered.stack_specular_rgb(self.stack, cos_theta, self.tables)

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        """The shader's ``BRDF``: Eq. 34 in the frame (X, Y, N); 0 where L or V is at or below the surface."""
        def local(d):
            d = np.asarray(d, dtype=np.float64)
            return np.stack([np.sum(d * X, axis=-1), np.sum(d * Y, axis=-1), np.sum(d * N, axis=-1)], axis=-1)

        X, Y, N = (np.asarray(a, dtype=np.float64) for a in (X, Y, N))
        i, o = local(L), local(V)
        value = layered.single_reflection_brdf(self.stack, i, o, self.tables)
        if self.compensation_rgb is not None:
            above = ((i[..., 2] > 0.0) & (o[..., 2] > 0.0))[..., None]
            lobe_rgb = np.float32(self.compensation_weight) * multiscatter_stack.lookup_rgb(self.compensation_rgb, *multiscatter_stack.air_angles(i, o))
            value = value + np.where(above, lobe_rgb, 0.0)
        return value

    def mirror_reflection(self, V, N) -> np.ndarray:
        """The weight of the coating's Dirac reflection (Eq. 34's f_r,0) into reflect(-V, N): ``(..., 3)``."""
        cos_theta = np.sum(np.asarray(V, np.float64) * np.asarray(N, np.float64), axis=-1)
        return layered.coating_rgb(self.stack, cos_theta)  # a dispersive host's: the RGB of F's spectrum

    def spectral_brdf(self, i, o, wavelengths, rgb_upsample) -> np.ndarray:
        """Eq. 34 per wavelength for Mitsuba (its layers and its base, the base's RGB albedo upsampled; with the
        multiple-scattering compensation when on, as :meth:`brdf`), in chunks."""
        value = np.empty(wavelengths.shape)
        for start in range(0, i.shape[0], SPECTRAL_CHUNK):
            part = slice(start, start + SPECTRAL_CHUNK)
            spectra = layered.single_reflection_spectra(self.stack, i[part], o[part], self.tables)
            layers = spectra.layers
            rho = rgb_upsample(np.broadcast_to(self.rho_d, (layers.shape[0], 3)), wavelengths[part])
            layers = _interp_wavelength(layers, wavelengths[part])
            base = _interp_wavelength(spectra.base, wavelengths[part])
            value[part] = layers + rho * base
            if self.compensation is not None:
                value[part] += self.compensation_weight * _spectral_lobe(self.compensation, i[part], o[part], wavelengths[part], rho)
        return value

    def sampling_lobes(self, cos_o):
        """``(alphas, weights, cosine_weight)`` at view cosines ``(n,)``: the shader's layer choice (Eq. 35)."""
        p_refl, p_base = layered.layer_choice_probabilities(self.stack, np.clip(cos_o, 0.0, 1.0), self.tables)
        alphas = [max(layer.alpha, 1e-4) for layer in self.stack.layers]
        rho = float(np.max(self.rho_d))
        return alphas, [p_refl[..., k] + 1e-3 for k in range(len(alphas))], p_base * rho

    def textures(self) -> dict[str, np.ndarray]:
        """
        ``stack_reflectance`` and ``stack_transmissivity``: ``(361, 471, 3)``, rows theta = k 0.25 deg,
        columns the wavelengths, channel l layer l (zeros beyond the used layers); ``stack_sampling``:
        ``(361, 3)``, each layer's wavelength-averaged transmissivity (Eq. 31's numerator); ``stack_transmittance``
        as ``stack_reflectance``: each smooth layer's ``T_lambda`` (exact for natural layers, else ``1 - R``).
        """
        return {**self._textures_of(self.tables, self.compensation_rgb), "stack_host": self._host_texture()}

    def _host_texture(self) -> np.ndarray:
        """``stack_host``: ``(471, 3)``, channel 0 the host's index at each wavelength (the shader refracts per
        wavelength with it where a coated host disperses; :meth:`explorer.physics.layered.LayeredBragg.host_index`)."""
        host = np.zeros((colorimetry.WAVELENGTHS.size, 3), np.float32)
        host[:, 0] = self.stack.host_index()
        return host

    def draft_textures(self) -> dict[str, np.ndarray]:
        """
        Quick stand-ins for :meth:`textures` while a slider moves: the layers' tables from ``R_lambda`` at
        every nm (``layered.layer_tables(draft=True)``), not converged; the real ones follow on release.
        """
        tables = tuple(layered.layer_tables(layer, self.stack.host, draft=True) for layer in self.stack.layers)
        # The multiple-scattering lobe is not drafted (its walk and quadratures take a second or more): a
        # draft shows Eq. 34 alone until the real textures follow on release.
        return {**self._textures_of(tables, None), "stack_host": self._host_texture()}

    @staticmethod
    def _textures_of(tables, compensation_rgb=None) -> dict[str, np.ndarray]:
        shape = (microfacet.THETA_COUNT, colorimetry.WAVELENGTHS.size, 3)
        reflectance = np.zeros(shape, np.float32)
        transmissivity = np.zeros(shape, np.float32)
        transmittance = np.zeros(shape, np.float32)
        for l, table in enumerate(tables):
            reflectance[..., l] = table.reflectance
            transmissivity[..., l] = table.transmissivity
            # The smooth limit's T: a natural layer's exact one (absorbing: < 1 - R), else 1 - R.
            transmittance[..., l] = np.float32(1.0) - table.reflectance if table.transmittance is None else table.transmittance
        # stack_missing: the multiple-scattering lobe in RGB, rows theta_i and columns theta_o every 2 deg in air (zeros: off).
        missing = np.zeros((multiscatter_stack.TABLE_ROWS, multiscatter_stack.TABLE_ROWS, 3), np.float32)
        if compensation_rgb is not None:
            missing[...] = compensation_rgb
        return {
            "stack_reflectance": reflectance,
            "stack_transmissivity": transmissivity,
            "stack_sampling": transmissivity.mean(axis=1, dtype=np.float64).astype(np.float32),
            "stack_missing": missing,
            "stack_transmittance": transmittance,
        }


@twin
class SchlickFresnelModel:
    """Twin of ``shaders/schlick_fresnel.brd``."""

    name = "schlick_fresnel"
    capabilities = Capabilities(methods=None, dirac=False, bragg_spectrum=False, numpy=True, albedo=("numpy", "gl"),
                                exports=("table", "gltf"), design=None)

    def __init__(self, values: Mapping[str, object]):
        self.F0 = float(values["F0"])

    def reflectance(self, cos_theta) -> np.ndarray:
        value = fresnel_schlick(np.asarray(cos_theta, dtype=np.float64), self.F0)
        return np.repeat(value[..., None], 3, axis=-1)

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        # Fresnel-weighted Lambertian: F(theta_d) / pi, so that the albedo is at most 1.
        return self.reflectance(_cos_half_angle(L, V)) / np.pi

    def textures(self) -> dict[str, np.ndarray]:
        return {}


@twin
class GGXSchlickModel:
    """
    Twin of ``shaders/ggx_schlick.brd``: a GGX microfacet BRDF (:mod:`explorer.physics.microfacet`) with Schlick's
    Fresnel, ``D(h) G1(L) G1(V) F(theta_d) / (4 cos theta_i cos theta_o)``; the thin-film bench's baseline.
    """

    name = "ggx_schlick"
    capabilities = Capabilities(methods=None, dirac=False, bragg_spectrum=False, numpy=True, albedo=("numpy", "gl"),
                                exports=("table", "gltf"), design=None)

    def __init__(self, values: Mapping[str, object]):
        self.alpha = float(values["alpha"])
        self.F0 = float(values["F0"])
        microfacet.check_alpha(self.alpha)

    def reflectance(self, cos_theta) -> np.ndarray:
        value = fresnel_schlick(np.asarray(cos_theta, dtype=np.float64), self.F0)
        return np.repeat(value[..., None], 3, axis=-1)

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        """The shader's ``BRDF`` for unit vectors ``(..., 3)``; 0 where ``L`` or ``V`` is at or below the surface."""
        lobe, cos_theta_d, above = microfacet.microfacet_lobe(L, V, N, self.alpha)
        result = np.zeros(lobe.shape + (3,))
        result[above] = lobe[above, None] * self.reflectance(cos_theta_d[above])
        return result

    def sampling_lobes(self, cos_o):
        """``(alphas, weights, cosine_weight)`` at view cosines ``(n,)``: one GGX lobe (the shader's ``sampling_lobes``)."""
        ones = np.ones_like(cos_o)
        return [max(self.alpha, 1e-4)], [ones], 0.0 * ones

    def textures(self) -> dict[str, np.ndarray]:
        return {}


#: Every numpy twin by ``# model:`` name (the registry of :mod:`explorer.materials.twins`, filled by
#: :func:`explorer.materials.twins.registry`).
MODELS = TWINS


def model_for(material, values: Mapping[str, object]):
    """
    The numpy twin of ``material`` with parameter ``values`` (None when it names no known model), read as
    :class:`explorer.materials.brd.Values` (:meth:`explorer.materials.brd.Material.typed_values`: ``int``
    parameters rounded as the GL host rounds them; a resolved set as it is).
    """
    measured = getattr(material, "measured", None)
    if measured is not None:  # a measured material's data makes its twin (explorer.materials.merl)
        return measured.twin(values)
    factory = registry().get(material.model or "")
    if factory is None:
        return None
    return factory(material.typed_values(values))
