"""
The explorer's materials as Mitsuba 3 BSDFs (Python plugins), one class per registered twin that declares
a Mitsuba export (its spectral BRDF and sampling lobes are the twin's hooks).

Each plugin reads the ``.brd`` parameters by their names (``<float name="Lambda" value="600"/>``,
``<rgb name="rho_d" .../>``) and exposes them through ``traverse``; a change through ``mi.traverse``
rebuilds the numpy model in ``parameters_changed`` (nothing is JIT-compiled from the values: the kernels
call back into numpy, so no parameter change recompiles one).

- RGB variants evaluate the material's numpy twin (:func:`explorer.materials.models.model_for`), its
  converged tables included: exactly the explorer's colours (``render --view env``).
- Spectral variants evaluate the physics at the path's four wavelengths: Yeh's Bragg reflectance
  (Eqs. 2, 9, 10), Eq. 17's rough layer, Eq. 34's stack, Belcour & Barla's Airy film. Under the
  explorer's convention white is illuminant E, where Mitsuba's RGB emitters are D65: with
  ``illuminant="e"`` (what :mod:`explorer.mitsuba.scene` writes) the BSDF divides by Mitsuba's
  normalised D65, so a white emitter lights it as E does; ``"d65"`` (default) is the bare physics
  (docs/mitsuba.md).

Sampling (``sample``/``pdf``): a smooth mirror (a twin that declares ``dirac``) is a Dirac (``DeltaReflection``); the rough
ones draw one-sample MIS over GGX visible-normal lobes (Heitz 2018) and a cosine lobe, with the
mixture's density as ``pdf`` (the env view's sampler, ``shaders/views/env.glsl``), so ``eval``,
``sample`` and ``pdf`` agree for any lobe weights.

References
----------
Fourneau, Pacanowski, Barla (2024), Eqs. 17, 31, 34, 35.
Belcour, Barla (2017). A Practical Extension to Microfacet Theory for the Modeling of Varying Iridescence.
Heitz (2018). Sampling the GGX Distribution of Visible Normals. JCGT 7(4).
"""

from __future__ import annotations

import functools

import numpy as np

from explorer.materials.methods import BraggMethod
from explorer.materials.brd import load_material, round_integer
from explorer.materials.models import model_for
from explorer.materials.twins import names_with, supporting, twin_class
from explorer.physics import bragg, colorimetry, microfacet
from explorer.resources import material_path

#: The plugins' ``method`` where the scene sets none (see ExplorerBSDF.__init__).
DEFAULT_METHOD = 3
#: Samples per numpy call of the RGB evaluation (bounds the (samples, 471) temporaries of a stack's twin).
CHUNK = 1 << 14


def plugin_names() -> tuple[str, ...]:
    """The plugin names: every registered twin that declares a Mitsuba export (the material of the same name)."""
    return supporting("mitsuba")


def rough_plugin_names() -> tuple[str, ...]:
    """The rough ones, not Dirac reflectors (Mitsuba's chi2 test runs on these)."""
    return names_with(lambda c: "mitsuba" in c.exports and not c.dirac)


# --------------------------------------------------------------------------------------------------
# Spectral physics per material: the twin's hooks (directions local, n = +z; wavelengths (n, W) in nm)


def spectral_brdf(model, i: np.ndarray, o: np.ndarray, wavelengths: np.ndarray, rgb_upsample) -> np.ndarray:
    """
    The spectral BRDF (1/sr) of a numpy twin ``model`` at local directions ``i`` (light), ``o`` (view),
    ``(n, 3)``, and wavelengths ``(n, W)``: its ``spectral_brdf`` hook where both lie above the surface, 0
    elsewhere and where not finite. ``rgb_upsample(rgb (n, 3), wavelengths)`` turns RGB albedos (and RGB-only
    models) into spectra (Mitsuba's sRGB model).
    """
    above = (i[:, 2] > 0.0) & (o[:, 2] > 0.0)
    out = np.zeros(wavelengths.shape)
    if not above.any():
        return out
    value = model.spectral_brdf(i[above], o[above], wavelengths[above], rgb_upsample)
    out[above] = np.where(np.isfinite(value), value, 0.0)
    return out


#: Nodes in cos(theta) of the thin film's reference colours in the RGB variants (linear interpolation).
REFERENCE_NODES = 1024


def reference_table(model) -> np.ndarray:
    """The reference method's RGB over ``cos theta = k / (size - 1)``: Bragg's converged table, or the film's sum."""
    if isinstance(getattr(model, "mirror", None), bragg.BraggMirror):
        return bragg.tabulated_rgb_table(model.mirror)
    return model.reflectance(np.linspace(0.0, 1.0, REFERENCE_NODES))


def mixture_pdf(alphas, weights, cosine_weight, l: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The one-sample MIS density of ``l`` (1/sr, solid angle) for weights normalised here."""
    total = cosine_weight + sum(weights)
    pdf = cosine_weight * np.maximum(l[:, 2], 0.0) / np.pi
    for alpha, w in zip(alphas, weights):
        pdf = pdf + w * microfacet.ggx_reflection_pdf(l, v, alpha)
    return np.where((total > 0.0) & (l[:, 2] > 0.0) & (v[:, 2] > 0.0), pdf / np.where(total > 0.0, total, 1.0), 0.0)


def mixture_sample(alphas, weights, cosine_weight, v: np.ndarray, u_lobe: np.ndarray, u: np.ndarray) -> np.ndarray:
    """A direction from the mixture: the lobe whose cumulative weight passes ``u_lobe``, then that lobe."""
    total = cosine_weight + sum(weights)
    total = np.where(total > 0.0, total, 1.0)
    choice = u_lobe * total - cosine_weight
    r = np.sqrt(u[:, 0])  # Malley's method
    phi = 2.0 * np.pi * u[:, 1]
    l = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1.0 - u[:, 0]))], axis=-1)
    done = choice < 0.0
    for alpha, w in zip(alphas, weights):
        pick = ~done & ((choice < w) | (alpha is alphas[-1]))
        if pick.any():
            m = microfacet.sample_ggx_visible_normal(v[pick], alpha, u[pick, 0], u[pick, 1])
            l[pick] = 2.0 * np.sum(v[pick] * m, axis=-1, keepdims=True) * m - v[pick]
        done = done | pick
        choice = choice - w
    return l


# --------------------------------------------------------------------------------------------------
# The plugin classes (built per variant: mi.BSDF is the active variant's)


def _float_property(props, name: str, default):
    if name not in props:
        return None
    value = props[name]
    try:
        return float(value)
    except TypeError:
        return tuple(float(c) for c in np.ravel(np.asarray(value)))[:3]


def define_bsdfs(mi, dr, names=None) -> dict[str, type]:
    """The plugin classes of ``names`` (default :func:`plugin_names`) for the active variant ``mi.variant()``."""
    spectral = "spectral" in mi.variant()
    jit = dr.is_jit_v(mi.Float)

    def to_numpy(x) -> np.ndarray:
        return np.atleast_1d(np.asarray(x, dtype=np.float64))

    def vec_to_numpy(v) -> np.ndarray:
        return np.stack(np.broadcast_arrays(to_numpy(v.x), to_numpy(v.y), to_numpy(v.z)), axis=-1)

    def vec_from_numpy(a: np.ndarray):
        if jit:
            return mi.Vector3f(*(mi.Float(a[:, k].astype(np.float32)) for k in range(3)))
        return mi.Vector3f(*(float(a[0, k]) for k in range(3)))

    def float_from_numpy(a: np.ndarray):
        return mi.Float(a.astype(np.float32)) if jit else mi.Float(float(a[0]))

    def spectrum_from_numpy(a: np.ndarray):
        """(n, C) -> mi.Spectrum (C = 3 RGB or 4 wavelengths)."""
        a = np.where(np.isfinite(a), a, 0.0)
        if jit:
            return mi.Spectrum(*(mi.Float(a[:, k].astype(np.float32)) for k in range(a.shape[1])))
        return mi.Spectrum(np.ascontiguousarray(a[0], dtype=np.float32))

    def wavelengths_of(si) -> np.ndarray:
        w = si.wavelengths
        return np.stack(np.broadcast_arrays(*(to_numpy(w[k]) for k in range(4))), axis=-1)

    @functools.lru_cache(maxsize=4096)
    def srgb_coefficients(rgb: tuple[float, float, float]) -> np.ndarray:
        return np.asarray(mi.srgb_model_fetch(mi.ScalarColor3f(*rgb)), dtype=np.float64).ravel()[:3]

    def rgb_upsample(rgb: np.ndarray, wavelengths: np.ndarray) -> np.ndarray:
        """
        RGB (n, 3) -> spectra at (n, W): Mitsuba's sRGB model (Jakob & Hanika 2019, the sigmoid of a
        quadratic in lambda), fitted on the colour scaled into [0, 1] and scaled back.
        """
        scale = np.maximum(np.max(np.abs(rgb), axis=-1), 1e-12)
        unit = np.clip(rgb / scale[:, None], 0.0, 1.0)
        keys = np.round(unit, 4)
        coeff = np.array([srgb_coefficients(tuple(float(c) for c in row)) for row in keys]) if len(np.unique(keys, axis=0)) > 1 \
            else np.broadcast_to(srgb_coefficients(tuple(float(c) for c in keys[0])), (rgb.shape[0], 3))
        x = (coeff[:, :1] * wavelengths + coeff[:, 1:2]) * wavelengths + coeff[:, 2:3]
        with np.errstate(all="ignore"):
            s = np.where(np.isinf(x), (x > 0).astype(np.float64), 0.5 + x / (2.0 * np.sqrt(1.0 + x * x)))
        return s * scale[:, None]

    @functools.lru_cache(maxsize=1)
    def d65_table() -> np.ndarray:
        """Mitsuba's normalised D65 (its RGB emitters' white) on the 1-nm grid."""
        values = []
        for w in colorimetry.WAVELENGTHS:
            d = mi.cie_d65(mi.ScalarFloat(w)) if not jit else mi.cie_d65(mi.Float(w))
            values.append(float(np.asarray(d).ravel()[0]))
        return np.asarray(values)  # mi.cie_d65 is normalised already (the d65 texture's values)

    def d65_weight(wavelengths: np.ndarray) -> np.ndarray:
        """1 / Mitsuba's normalised D65 at ``wavelengths``: its white emitters then light as illuminant E."""
        return 1.0 / np.interp(wavelengths, colorimetry.WAVELENGTHS, d65_table())

    class ExplorerBSDF(mi.BSDF):
        material_name = ""
        dirac = False

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.material = load_material(getattr(twin_class(self.material_name), "material_file", None)
                                          or material_path(self.material_name))
            overrides = {}
            for p in self.material.parameters:
                value = _float_property(props, p.name, p.default)
                if value is not None:
                    overrides[p.name] = bool(value) if p.type == "bool" else value
            if "method" not in overrides and "method" in self.values_declared():
                # RGB renders default to the converged table (Bragg) or Eq. 10's m_max = 3 (thin film): the
                # explorer's colours at a table lookup per sample, not a 471-wavelength sum.
                overrides["method"] = DEFAULT_METHOD
            self.values = self.material.resolve(overrides)
            self.illuminant = props["illuminant"] if "illuminant" in props else "d65"
            if self.illuminant not in ("d65", "e"):
                raise ValueError(f"{self.material_name}: illuminant must be 'd65' or 'e', got {self.illuminant!r}")
            self._rebuild()
            if self.dirac:
                flags = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide
            else:
                flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        def values_declared(self):
            return {p.name for p in self.material.parameters}

        def _rebuild(self):
            self.model = model_for(self.material, self.values)
            natural = getattr(self.model, "natural", None) is not None  # already the exact table, whatever the method
            if not spectral and not natural and round_integer(self.values.get("method", -1)) == int(BraggMethod.REFERENCE):
                # The reference method in RGB: its colours over cos(theta) tabulated once (the Bragg
                # materials' converged table, the film's 1-nm sum at REFERENCE_NODES), looked up per sample.
                self.model.reflectance = functools.partial(bragg.tabulated_rgb, reference_table(self.model))

        # -- parameters
        def traverse(self, callback):
            # Dr.Jit holders (mi.traverse assigns into them): Color3f for colours, Color1f for the rest
            # (bools as 0 / 1, ints as floats, as BRDF Explorer's files have them).
            self._holders = {}
            for p in self.material.parameters:
                value = self.values[p.name]
                holder = mi.Color3f(*(float(c) for c in value)) if p.type == "color" else mi.Color1f(float(value))
                self._holders[p.name] = holder
                callback.put(p.name, holder, mi.ParamFlags.NonDifferentiable)

        def parameters_changed(self, keys=None):
            # Read the holders back (one value each), check them against the .brd ranges, rebuild the model.
            overrides = {}
            for p in self.material.parameters:
                holder = self._holders.get(p.name) if hasattr(self, "_holders") else None
                if holder is None:
                    continue
                flat = np.asarray(holder, dtype=np.float64).ravel()
                if p.type == "color":
                    overrides[p.name] = tuple(float(c) for c in flat[:3])
                elif p.type == "bool":
                    overrides[p.name] = bool(flat[0] != 0.0)
                else:
                    overrides[p.name] = float(flat[0])
            self.values = self.material.resolve(overrides)
            self._rebuild()

        def to_string(self):
            return f"{type(self).__name__}[{', '.join(f'{k}={v}' for k, v in self.values.items())}]"

        # -- evaluation (numpy)
        def _value(self, si, l: np.ndarray, v: np.ndarray) -> np.ndarray:
            """f(l, v) cos theta_l, ``(n, C)``."""
            cos_l = np.maximum(l[:, 2], 0.0)
            if spectral:
                wl = wavelengths_of(si)
                wl = np.broadcast_to(wl, (l.shape[0], wl.shape[1])) if wl.shape[0] != l.shape[0] else wl
                f = spectral_brdf(self.model, l, v, wl, rgb_upsample)
                if self.illuminant == "e":
                    f = f * d65_weight(wl)
            else:
                # In CHUNK rows: a wavefront holds millions of samples, and bragg_stack's twin makes
                # (samples, 471) spectra (64x64 at 1024 spp unchunked: 22 GB, killed).
                f = np.empty((l.shape[0], 3))
                frame = (np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
                with np.errstate(all="ignore"):
                    for start in range(0, l.shape[0], CHUNK):
                        part = slice(start, start + CHUNK)
                        f[part] = self.model.brdf(l[part], v[part], *frame)
                above = (l[:, 2] > 0.0) & (v[:, 2] > 0.0)
                f = np.where(above[:, None] & np.isfinite(f), f, 0.0)
            return f * cos_l[:, None]

        def _lobes(self, v):
            return self.model.sampling_lobes(v[:, 2])

        def eval(self, ctx, si, wo, active=True):
            if self.dirac:
                return mi.Spectrum(0.0)
            v, l = vec_to_numpy(si.wi), vec_to_numpy(wo)
            v, l = np.broadcast_arrays(v, l)
            return dr.select(active, spectrum_from_numpy(self._value(si, l, v)), 0.0)

        def pdf(self, ctx, si, wo, active=True):
            if self.dirac:
                return mi.Float(0.0)
            v, l = np.broadcast_arrays(vec_to_numpy(si.wi), vec_to_numpy(wo))
            return dr.select(active, float_from_numpy(mixture_pdf(*self._lobes(v), l, v)), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            v, u1 = vec_to_numpy(si.wi), to_numpy(sample1)
            u2 = np.stack(np.broadcast_arrays(to_numpy(sample2.x), to_numpy(sample2.y)), axis=-1)
            n = max(v.shape[0], u1.shape[0], u2.shape[0])
            v, u1, u2 = np.broadcast_to(v, (n, 3)), np.broadcast_to(u1, (n,)), np.broadcast_to(u2, (n, 2))
            bs = mi.BSDFSample3f()
            bs.eta = 1.0
            bs.sampled_component = 0
            if self.dirac:
                l = v * np.array([-1.0, -1.0, 1.0])
                cos = v[:, 2]
                if spectral:
                    wl = wavelengths_of(si)
                    weight = self.model.spectral_reflectance(cos, np.broadcast_to(wl, (n, wl.shape[1])))
                    if self.illuminant == "e":
                        weight = weight * d65_weight(np.broadcast_to(wl, weight.shape))
                else:
                    weight = self.model.reflectance(np.clip(cos, 0.0, 1.0))
                weight = np.where((cos > 0.0)[:, None], weight, 0.0)
                pdf = np.where(cos > 0.0, 1.0, 0.0)
                bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DeltaReflection)
            else:
                lobes = self._lobes(v)
                l = mixture_sample(*lobes, v, u1, u2)
                norm = np.linalg.norm(l, axis=-1, keepdims=True)
                l = l / np.where(norm > 0.0, norm, 1.0)
                pdf = mixture_pdf(*lobes, l, v)
                value = self._value(si, l, v)
                ok = pdf > 0.0
                weight = np.where(ok[:, None], value / np.where(ok, pdf, 1.0)[:, None], 0.0)
                bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.wo = vec_from_numpy(l)
            bs.pdf = float_from_numpy(pdf)
            active = active & (bs.pdf > 0.0)
            return bs, dr.select(active, spectrum_from_numpy(weight), 0.0)

    classes = {}
    for name in plugin_names() if names is None else names:
        classes[name] = type(name, (ExplorerBSDF,), {"material_name": name, "dirac": twin_class(name).capabilities.dirac})
    return classes
