"""
Numpy twins of the BRDF Explorer-style test materials in tests/data/brdf (their ``# model:`` lines).

Test support, not product models: :func:`registered` adds them to :data:`explorer.materials.models.MODELS` for the
duration of a test. Each twin's ``brdf(L, V, N, X, Y)`` evaluates, in float64, what the file's GLSL
``BRDF`` evaluates, for unit vectors of shape ``(..., 3)``, and returns linear RGB ``(..., 3)``.
"""

from __future__ import annotations

import contextlib
from typing import Iterator, Mapping

import numpy as np

from explorer.materials import models


def _dot(a, b) -> np.ndarray:
    return np.sum(np.asarray(a, np.float64) * np.asarray(b, np.float64), axis=-1)


def _half_vector(L, V) -> np.ndarray:
    H = np.asarray(L, np.float64) + np.asarray(V, np.float64)
    return H / np.linalg.norm(H, axis=-1, keepdims=True)


def glsl_pow(x, y) -> np.ndarray:
    """
    GLSL's ``pow(x, y)`` as GPUs compute it, ``exp2(y log2(x))``: NaN for ``x < 0`` and for ``x = 1``,
    ``y = NaN`` (where the GLSL specification leaves it undefined), which numpy's ``**`` is not
    (``(-2.0) ** 2.0 = 4``, ``1.0 ** nan = 1``). Float64.
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return np.exp2(np.asarray(y, np.float64) * np.log2(np.asarray(x, np.float64)))


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


class AppAllKindsTwin(_Twin):
    """app_all_kinds.brdf: albedo / pi + ks (n + 2) / (8 pi) max(0, N.H)^n, divided by max(N.L, 1e-4) when the bool is set."""

    name = "app_all_kinds"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        n, ks = float(self.values["n"]), float(self.values["ks"])
        value = ks * glsl_pow(np.maximum(_dot(N, _half_vector(L, V)), 0.0), n) * (n + 2.0) / (8.0 * 3.14159265)
        if self.values["divide_by_NdotL"]:
            value = value / np.maximum(_dot(N, L), 1e-4)
        return np.asarray(self.values["albedo"], np.float64) / 3.14159265 + _grey(value)


# The failure patterns of BRDF Explorer's own files (NaN, infinities, negative values out of the BRDF's
# domain): twins evaluate them everywhere with GLSL's arithmetic, NaN included; the views' rule
# (explorer.views.geometry.view_brdf) decides what is shown.


class LimbDarkeningTwin(_Twin):
    """limb_darkening.brdf: Minnaert's albedo (k + 1) / (2 pi) (N.L N.V)^(k - 1); NaN below the horizon."""

    name = "limb_darkening"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        k = float(self.values["k"])
        darkening = glsl_pow(_dot(N, L) * _dot(N, V), k - 1.0)
        return np.asarray(self.values["albedo"], np.float64) * ((k + 1.0) / (2.0 * np.pi) * darkening)[..., None]


class AnisotropicWardTwin(_Twin):
    """anisotropic_ward.brdf: rho_d / pi + rho_s exp(-(s_x^2 + s_y^2)) / (4 pi a_x a_y sqrt(N.L N.V))."""

    name = "anisotropic_ward"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        a_x, a_y = float(self.values["a_x"]), float(self.values["a_y"])
        H = _half_vector(L, V)
        HdotN = _dot(H, N)
        with np.errstate(divide="ignore", invalid="ignore"):
            s_x, s_y = _dot(H, X) / (a_x * HdotN), _dot(H, Y) / (a_y * HdotN)
            lobe = np.exp(-(s_x**2 + s_y**2)) / (4.0 * np.pi * a_x * a_y * np.sqrt(_dot(N, L) * _dot(N, V)))
        rho_s, rho_d = (np.asarray(self.values[name], np.float64) for name in ("rho_s", "rho_d"))
        return rho_d / np.pi + rho_s * lobe[..., None]


class CompactLobeTwin(_Twin):
    """compact_lobe.brdf: ks D / (4 N.L N.V) + kd / pi, D's (1 - t^2)^n NaN beyond t = 1 (GLSL's pow)."""

    name = "compact_lobe"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        m, n, ks, kd = (float(self.values[name]) for name in ("m", "n", "ks", "kd"))
        c2 = _dot(N, _half_vector(L, V)) ** 2
        with np.errstate(divide="ignore", invalid="ignore"):
            t2 = (1.0 - c2) / (c2 * m * m)
            D = (n + 1.0) / (np.pi * m * m * c2 * c2) * glsl_pow(1.0 - t2, n)
            return _grey(ks * D / (4.0 * _dot(N, L) * _dot(N, V)) + kd / np.pi)


class AzimuthRatioTwin(_Twin):
    """azimuth_ratio.brdf: kd / pi + ks (n + 8) / (8 pi) (1 + a cos 2 phi_h) (N.H)^n; 0 / 0 where H = N."""

    name = "azimuth_ratio"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        n, a, ks, kd = (float(self.values[name]) for name in ("n", "a", "ks", "kd"))
        H = _half_vector(L, V)
        hx, hy = _dot(H, X), _dot(H, Y)
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_2phi = (hx * hx - hy * hy) / (hx * hx + hy * hy)
        lobe = (n + 8.0) / (8.0 * np.pi) * (1.0 + a * cos_2phi) * glsl_pow(np.maximum(_dot(N, H), 0.0), n)
        return _grey(kd / np.pi + ks * lobe)


class LommelSeeligerTwin(_Twin):
    """lommel_seeliger.brdf: w / (4 pi (N.L + N.V)); negative, and a pole, below the horizon."""

    name = "lommel_seeliger"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        with np.errstate(divide="ignore"):
            inverse = 1.0 / (4.0 * np.pi * (_dot(N, L) + _dot(N, V)))
        return np.asarray(self.values["w"], np.float64) * inverse[..., None]


class NonFiniteChannelsTwin(_Twin):
    """non_finite_channels.brdf: (sqrt(-k), exp(1000 k), -k / 4): NaN, infinite and negative channels."""

    name = "non_finite_channels"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        k = np.full(np.shape(L)[:-1], float(self.values["k"]))
        with np.errstate(invalid="ignore", over="ignore"):
            return np.stack([np.sqrt(-k), np.exp(1000.0 * k), -0.25 * k], axis=-1)


def _mix(a, b, t):
    """GLSL's ``mix``: ``a (1 - t) + b t`` (so an infinite ``b`` with ``t = 0`` is NaN there too)."""
    return a * (1.0 - t) + b * t


class DisneyTwin(_Twin):
    """tests/data/brdf_explorer/disney.brdf: Burley 2012's principled BRDF (diffuse, subsurface, sheen, GTR2, clearcoat)."""

    name = "disney"

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        v = {k: (np.asarray(x, np.float64) if isinstance(x, tuple) else float(x)) for k, x in self.values.items()}
        base, roughness = v["baseColor"], v["roughness"]
        n_dot_l, n_dot_v = _dot(N, L)[..., None], _dot(N, V)[..., None]
        H = _half_vector(L, V)
        n_dot_h, l_dot_h = _dot(N, H)[..., None], _dot(L, H)[..., None]

        def schlick(u):
            m = np.clip(1.0 - u, 0.0, 1.0)
            return m**5

        luminance = 0.3 * base[0] + 0.6 * base[1] + 0.1 * base[2]
        tint = base / luminance if luminance > 0.0 else np.ones(3)
        specular0 = _mix(v["specular"] * 0.08 * _mix(np.ones(3), tint, v["specularTint"]), base, v["metallic"])
        sheen_colour = _mix(np.ones(3), tint, v["sheenTint"])
        fl, fv = schlick(n_dot_l), schlick(n_dot_v)
        fd90 = 0.5 + 2.0 * l_dot_h**2 * roughness
        fd = _mix(1.0, fd90, fl) * _mix(1.0, fd90, fv)
        fss90 = l_dot_h**2 * roughness
        fss = _mix(1.0, fss90, fl) * _mix(1.0, fss90, fv)
        with np.errstate(divide="ignore", invalid="ignore"):
            ss = 1.25 * (fss * (1.0 / (n_dot_l + n_dot_v) - 0.5) + 0.5)
        aspect = np.sqrt(1.0 - v["anisotropic"] * 0.9)
        ax, ay = max(0.001, roughness**2 / aspect), max(0.001, roughness**2 * aspect)
        h_x, h_y = _dot(H, X)[..., None], _dot(H, Y)[..., None]
        ds = 1.0 / (np.pi * ax * ay * ((h_x / ax) ** 2 + (h_y / ay) ** 2 + n_dot_h**2) ** 2)
        fh = schlick(l_dot_h)
        fs = _mix(specular0, 1.0, fh)

        def smith_aniso(n_dot, w):
            return 1.0 / (n_dot + np.sqrt((_dot(w, X)[..., None] * ax) ** 2 + (_dot(w, Y)[..., None] * ay) ** 2 + n_dot**2))

        gs = smith_aniso(n_dot_l, L) * smith_aniso(n_dot_v, V)
        a = _mix(0.1, 0.001, v["clearcoatGloss"])
        dr = np.full_like(n_dot_h, 1.0 / np.pi) if a >= 1.0 else (a * a - 1.0) / (np.pi * np.log(a * a) * (1.0 + (a * a - 1.0) * n_dot_h**2))
        fr = _mix(0.04, 1.0, fh)

        def smith(n_dot, alpha):
            return 1.0 / (n_dot + np.sqrt(alpha**2 + n_dot**2 - alpha**2 * n_dot**2))

        gr = smith(n_dot_l, 0.25) * smith(n_dot_v, 0.25)
        with np.errstate(invalid="ignore"):
            diffuse = ((1.0 / np.pi) * _mix(fd, ss, v["subsurface"]) * base + fh * v["sheen"] * sheen_colour) * (1.0 - v["metallic"])
            value = diffuse + gs * fs * ds + 0.25 * v["clearcoat"] * gr * fr * dr
        return np.where((n_dot_l < 0.0) | (n_dot_v < 0.0), 0.0, value)


TWINS = (
    LambertTwin, ColoredLambertTwin, BlinnPhongTwin, AshikhminShirleyTwin, AppAllKindsTwin, LimbDarkeningTwin,
    AnisotropicWardTwin, CompactLobeTwin, AzimuthRatioTwin, LommelSeeligerTwin, NonFiniteChannelsTwin, DisneyTwin,
)


@contextlib.contextmanager
def registered() -> Iterator[None]:
    """Add the twins to explorer.materials.models.MODELS, and take them out again afterwards."""
    added = [twin for twin in TWINS if twin.name not in models.MODELS]
    for twin in added:
        models.MODELS[twin.name] = twin
    try:
        yield
    finally:
        for twin in added:
            models.MODELS.pop(twin.name, None)
