"""
Numpy twins of the BRDF Explorer-style test materials in tests/data/brdf (their ``# model:`` lines).

Test support, not product models: :func:`registered` adds them to :data:`explorer.models.MODELS` for the
duration of a test. Each twin's ``brdf(L, V, N, X, Y)`` evaluates, in float64, what the file's GLSL
``BRDF`` evaluates, for unit vectors of shape ``(..., 3)``, and returns linear RGB ``(..., 3)``.
"""

from __future__ import annotations

import contextlib
from typing import Iterator, Mapping

import numpy as np

from explorer import models


def _dot(a, b) -> np.ndarray:
    return np.sum(np.asarray(a, np.float64) * np.asarray(b, np.float64), axis=-1)


def _half_vector(L, V) -> np.ndarray:
    H = np.asarray(L, np.float64) + np.asarray(V, np.float64)
    return H / np.linalg.norm(H, axis=-1, keepdims=True)


def _grey(value: np.ndarray) -> np.ndarray:
    return np.repeat(np.asarray(value, np.float64)[..., None], 3, axis=-1)


class _Twin:
    name = ""

    def __init__(self, values: Mapping[str, object]):
        self.values = dict(values)

    def textures(self) -> dict[str, np.ndarray]:
        return {}


class LambertTwin(_Twin):
    """lambert.brdf: reflectance / pi."""

    name = "lambert"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        return _grey(np.full(np.shape(L)[:-1], float(self.values["reflectance"]) / np.pi))


class ColoredLambertTwin(_Twin):
    """colored_lambert.brdf: albedo / pi, a ``color`` parameter."""

    name = "colored_lambert"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        albedo = np.asarray(self.values["albedo"], dtype=np.float64)
        return np.broadcast_to(albedo / np.pi, (*np.shape(L)[:-1], 3)).copy()


class BlinnPhongTwin(_Twin):
    """blinn_phong.brdf: (n + 8) / (8 pi) max(0, N.H)^n, divided by max(N.L, 1e-4) when the bool is set."""

    name = "blinn_phong"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        n = float(self.values["n"])
        value = (n + 8.0) / (8.0 * np.pi) * np.maximum(_dot(N, _half_vector(L, V)), 0.0) ** n
        if self.values["divide_by_NdotL"]:
            value = value / np.maximum(_dot(N, L), 1e-4)
        return _grey(value)


class AshikhminShirleyTwin(_Twin):
    """ashikhmin_shirley.brdf: anisotropic Phong lobe (nu along X, nv along Y), Schlick Fresnel, diffuse."""

    name = "ashikhmin_shirley"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        Rs, Rd = float(self.values["Rs"]), float(self.values["Rd"])
        nu, nv = float(self.values["nu"]), float(self.values["nv"])
        NdotL, NdotV = _dot(N, L), _dot(N, V)
        H = _half_vector(L, V)
        NdotH, HdotL, HdotX, HdotY = _dot(N, H), _dot(H, L), _dot(H, X), _dot(H, Y)
        sin2 = np.maximum(HdotX**2 + HdotY**2, 1e-12)
        exponent = (nu * HdotX**2 + nv * HdotY**2) / sin2
        with np.errstate(divide="ignore", invalid="ignore"):
            spec = (
                np.sqrt((nu + 1.0) * (nv + 1.0)) / (8.0 * np.pi)
                * np.maximum(NdotH, 0.0) ** exponent
                / (HdotL * np.maximum(NdotL, NdotV))
                * (Rs + (1.0 - Rs) * (1.0 - HdotL) ** 5)
            )
        diffuse = (
            28.0 / (23.0 * np.pi) * Rd * (1.0 - Rs)
            * (1.0 - (1.0 - NdotL / 2.0) ** 5)
            * (1.0 - (1.0 - NdotV / 2.0) ** 5)
        )
        value = np.where((NdotL <= 0.0) | (NdotV <= 0.0), 0.0, spec + diffuse)
        return _grey(value)


TWINS = (LambertTwin, ColoredLambertTwin, BlinnPhongTwin, AshikhminShirleyTwin)


@contextlib.contextmanager
def registered() -> Iterator[None]:
    """Add the twins to explorer.models.MODELS, and take them out again afterwards."""
    added = [twin for twin in TWINS if twin.name not in models.MODELS]
    for twin in added:
        models.MODELS[twin.name] = twin
    try:
        yield
    finally:
        for twin in added:
            models.MODELS.pop(twin.name, None)
