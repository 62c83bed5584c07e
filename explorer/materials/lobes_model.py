"""
The numpy twin of ``shaders/layered_lobes.brd`` (physics in :mod:`explorer.physics.lobes`): Belcour's (2018)
layered BRDF as a sum of GGX lobes (Bati et al. 2021, Eq. 3) and the FGD tables its shader reads.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from explorer.physics import lobes
from explorer.tables import luts
from explorer.materials.twins import Capabilities, twin
from explorer.materials.brd import round_integer
from explorer.errors import LocatedError

MATERIAL_NAME = "layered_lobes.brd"


class LobesParameterError(LocatedError, ValueError):
    """A parameter set outside the physical constraints (one line, naming which): the CLI's and the app's bad input."""


def stack_from_values(values: Mapping[str, object]) -> lobes.Stack:
    """The :class:`explorer.physics.lobes.Stack` of the material's parameter values (checked)."""
    count = int(np.clip(round_integer(values["layers"]), 1, lobes.MAX_INTERFACES))
    conductor = bool(values.get("conductor", False))
    eta = [float(values[f"eta_{i}"]) for i in range(1, count + 1)]
    if conductor:
        eta[-1] = np.asarray(values["eta_base"], dtype=np.float64)
        if not np.any(np.asarray(values["kappa_base"], dtype=np.float64) > 0.0):
            # The shader would take the conductor path, the adding equations a dielectric one: refuse.
            raise lobes.StackError(f"kappa_base = {list(values['kappa_base'])} must be > 0 on some channel for a conductor base (or set conductor off)")
    return lobes.make_stack(
        eta,
        [float(values[f"alpha_{i}"]) for i in range(1, count + 1)],
        tau=[values[f"tau_{i}"] for i in range(1, count)],
        base_kappa=values["kappa_base"] if conductor else None,
        tir=bool(values.get("tir", False)),
    )


def fgd_texture() -> np.ndarray:
    """``luts/lobes_fgd_correction.npy`` as a ``(33 * 16, 32, 3)`` texture: rows eta-major, the correction in red."""
    table = luts.load("lobes_fgd_correction")
    rows = table.reshape(-1, table.shape[-1])
    return np.stack([rows, np.zeros_like(rows), np.zeros_like(rows)], axis=-1).astype(np.float32)


def moments_texture() -> np.ndarray:
    """``luts/lobes_ggx_moments.npy`` as a ``(16, 32, 3)`` texture: channels E, cbar_d, 0."""
    table = luts.load("lobes_ggx_moments")
    return np.stack([table[0], table[1], np.zeros_like(table[0])], axis=-1).astype(np.float32)


@twin
class LayeredLobesModel:
    """Twin of ``shaders/layered_lobes.brd``: ``reflectance(cos_theta)`` (sum of the lobes' energies) and Eq. 3."""

    name = "layered_lobes"
    capabilities = Capabilities(methods=None, dirac=False, bragg_spectrum=False, numpy=True, albedo=("numpy", "gl"),
                                exports=("mitsuba", "table", "gltf"), design=None)

    def __init__(self, values: Mapping[str, object]):
        self.values = dict(values)
        try:
            self.stack = stack_from_values(values)
        except lobes.StackError as error:
            raise LobesParameterError(MATERIAL_NAME, None, str(error)) from None

    def reflectance(self, cos_theta) -> np.ndarray:
        return lobes.reflectance(self.stack, cos_theta)

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        return lobes.brdf(self.stack, L, V, N)

    def principled_layers(self) -> dict[str, object]:
        """
        Blender's Principled BSDF inputs nearest the stack (docs/blender.md): interface 1 its coat (IOR, roughness
        ``sqrt(alpha)``, tint the round trip's transmittance ``exp(-2 tau_1)`` at normal incidence: Cycles
        raises it to ``1 / cos theta_t``), interface 2 its specular base (a dielectric of the medium's
        absolute index, black, or the conductor of F0 from ``eta_base + i kappa_base``); a one-interface stack
        is the base alone. Interfaces 3 and 4 have no place in Principled: they are left out.
        """
        v, count = self.values, int(np.clip(round_integer(self.values["layers"]), 1, lobes.MAX_INTERFACES))
        conductor = bool(v.get("conductor", False))
        base = 1 if count == 1 else 2
        layers: dict[str, object] = {"Base Color": (0.0, 0.0, 0.0, 1.0), "Metallic": 0.0,
                                     "Roughness": float(np.sqrt(float(v[f"alpha_{base}"])))}
        if conductor and count <= 2:
            n = np.asarray(v["eta_base"], np.float64) + 1j * np.asarray(v["kappa_base"], np.float64)
            outside = float(v["eta_1"]) if count == 2 else 1.0
            f0 = np.abs((n / outside - 1.0) / (n / outside + 1.0)) ** 2
            layers.update({"Metallic": 1.0, "Base Color": (*(float(c) for c in f0), 1.0)})
        else:
            layers["IOR"] = float(v[f"eta_{base}"])
        if count >= 2:
            tint = np.exp(-2.0 * np.asarray(v["tau_1"], np.float64))
            layers.update({"Coat Weight": 1.0, "Coat IOR": float(v["eta_1"]), "Coat Roughness": float(np.sqrt(float(v["alpha_1"]))),
                           "Coat Tint": (*(float(c) for c in tint), 1.0)})
        return layers

    def spectral_brdf(self, i, o, wavelengths, rgb_upsample) -> np.ndarray:
        """For Mitsuba's spectral variants: an RGB model (Belcour 2018's lobes), upsampled."""
        rgb = self.brdf(i, o, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
        return rgb_upsample(rgb, wavelengths)

    def sampling_lobes(self, cos_o):
        """Every layer's roughness, equal weights, a little cosine for the broad tails (the shader's ``sampling_lobes``)."""
        ones = np.ones_like(cos_o)
        count = round_integer(self.values.get("layers", 1))
        alphas = [max(float(self.values[f"alpha_{k}"]), 1e-4) for k in range(1, count + 1)]
        return alphas, [ones] * len(alphas), 0.05 * len(alphas) * ones

    def textures(self) -> dict[str, np.ndarray]:
        return {"lobes_fgd": fgd_texture(), "lobes_ggx_moments": moments_texture()}


def values_from_stack(stack: lobes.Stack) -> dict:
    """The parameter values of ``shaders/layered_lobes.brd`` for ``stack`` (numbers and RGB lists)."""
    if stack.count > lobes.MAX_INTERFACES:
        raise lobes.StackError(f"the material holds at most {lobes.MAX_INTERFACES} interfaces, the stack has {stack.count}")
    values: dict = {"layers": stack.count, "conductor": int(stack.conductor), "tir": int(stack.tir)}
    for i in range(1, stack.count + 1):
        values[f"alpha_{i}"] = float(stack.alpha[i])
        if i == stack.count and stack.conductor:
            values["eta_base"] = [float(v) for v in stack.eta[i]]
            values["kappa_base"] = [float(v) for v in stack.kappa[i]]
        else:
            values[f"eta_{i}"] = float(stack.eta[i].mean())
        if i < stack.count:
            values[f"tau_{i}"] = [float(v) for v in stack.tau[i]]
    return values
