"""
Why the spectral variants differ from the GL env view: a noise-free decomposition on the smooth mirror.

The GL env view (and the RGB variants) shade a pixel as ``RGB(R) * RGB(L)``, channel by channel: the
material's colour times the environment's. A spectral renderer shades it as the colour of the product of
spectra, ``RGB(R(lambda) L(lambda))``. For a smooth ``bragg_mirror`` both are exact per pixel (a Dirac:
one reflected direction, no Monte Carlo), so their difference is computed here in numpy, pixel by pixel:

- ``roundtrip``: the environment's RGB has no spectrum; Mitsuba's spectral ``envmap`` upsamples each texel
  with its sRGB model (Jakob & Hanika 2019, fitted on the colour divided by twice its maximum, under D65)
  and our plugins divide its D65 out (illuminant E, docs/mitsuba.md). The colour of that spectrum in the
  explorer's convention is not exactly the texel's RGB (illuminant E + Bradford vs D65 unadapted);
- ``product``: the median ΔE2000 of ``RGB(R L_up)`` against ``RGB(R) * RGB(L)``, Mitsuba's upsampling;
- ``product_consistent``: the same with each texel's spectrum pre-corrected so that its explorer colour is
  exactly its RGB (a fixed point on the model's input), isolating the product's own difference;
- ``white``: the same under a white environment (flat spectrum): zero, the product is then exact.

``python -m explorer.mitsuba.spectral_gap`` prints them (docs/mitsuba.md).

References
----------
Jakob, Hanika (2019). A Low-Dimensional Function Space for Efficient Spectral Upsampling.
Fourneau, Pacanowski, Barla (2024), Eqs. 2, 9, 10 (the mirror's R_lambda).
"""

from __future__ import annotations

import functools

import numpy as np

from explorer.materials.methods import BraggMethod
from explorer.physics import bragg, colorimetry


def _srgb_model_spectra(rgb: np.ndarray) -> np.ndarray:
    """Mitsuba's spectral ``envmap`` upsampling of RGB radiances ``(n, 3)`` on the 1-nm grid, D65 divided out."""
    import mitsuba as mi

    if not mi.variant():
        mi.set_variant("scalar_spectral")
    scale = np.maximum(rgb.max(axis=-1), 1e-8) * 2.0  # envmap.cpp: the colour at half its maximum
    unit = rgb / scale[:, None]
    coeff = np.array([np.asarray(mi.srgb_model_fetch(mi.ScalarColor3f(*(float(c) for c in row)))).ravel()[:3] for row in unit])
    w = colorimetry.WAVELENGTHS
    x = (coeff[:, :1] * w + coeff[:, 1:2]) * w + coeff[:, 2:3]
    return (0.5 + x / (2.0 * np.sqrt(1.0 + x * x))) * scale[:, None]


def _consistent_spectra(rgb: np.ndarray, iterations: int = 6) -> np.ndarray:
    """Spectra of the sRGB model whose explorer colour is ``rgb``: its input corrected by a fixed point."""
    target = np.asarray(rgb, dtype=np.float64)
    given = target.copy()
    for _ in range(iterations):
        given = given + (target - colorimetry.spectrum_to_rgb(_srgb_model_spectra(np.maximum(given, 1e-9))))
    return _srgb_model_spectra(np.maximum(given, 1e-9))


def mirror_pixels(size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The env view's pixels on its unit sphere (orthographic, V = +z, rows from the top): the mask of the
    pixel centres inside the disc, their normals and reflected directions ``(n, 3)``."""
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    x, y = np.meshgrid(c, -c)
    inside = x * x + y * y < 1.0
    n = np.stack([x[inside], y[inside], np.sqrt(1.0 - x[inside] ** 2 - y[inside] ** 2)], axis=-1)
    return inside, n, 2.0 * n[:, 2:3] * n - np.array([0.0, 0.0, 1.0])


def mirror_images(model, environment, size: int = 64, consistent: bool = False) -> dict[str, np.ndarray]:
    """
    Per pixel inside the disc (``mask``), for a smooth mirror ``model`` (its numpy twin): ``gl``, the GL env
    view's ``RGB(R) * RGB(L)``; ``spectral``, ``RGB(R(lambda) L_up(lambda))`` with the sky upsampled as
    Mitsuba does (``consistent``: corrected to its exact RGB); ``sky``, its RGB, and ``sky_upsampled``,
    the explorer colour of its upsampled spectrum.
    """
    inside, normals, reflected = mirror_pixels(size)
    cos_theta = normals[:, 2]
    radiance = environment.radiance(reflected).astype(np.float64)
    R = bragg.bragg_reflectance(cos_theta[:, None], colorimetry.WAVELENGTHS[None, :], model.mirror)
    sky = _consistent_spectra(radiance) if consistent else _srgb_model_spectra(radiance)
    return {"mask": inside, "gl": model.reflectance(cos_theta) * radiance, "reflectance": model.reflectance(cos_theta),
            "reflectance_spectral": colorimetry.spectrum_to_rgb(R), "spectral": colorimetry.spectrum_to_rgb(R * sky),
            "sky": radiance, "sky_upsampled": colorimetry.spectrum_to_rgb(sky)}


def spectral_gap(model, environment, size: int = 64) -> dict[str, float]:
    """The decomposition of the module docstring for a smooth mirror ``model`` (its numpy twin)."""
    from explorer.mitsuba.bench import median_delta_e

    mitsuba_sky = mirror_images(model, environment, size)
    corrected = mirror_images(model, environment, size, consistent=True)
    return {
        "roundtrip": median_delta_e(mitsuba_sky["sky_upsampled"], mitsuba_sky["sky"]),
        "roundtrip_max": float(np.max(colorimetry.delta_E_2000(np.clip(mitsuba_sky["sky_upsampled"], 0, None), mitsuba_sky["sky"]))),
        "product": median_delta_e(mitsuba_sky["spectral"], mitsuba_sky["gl"]),
        "product_consistent": median_delta_e(corrected["spectral"], corrected["gl"]),
        "white": median_delta_e(mitsuba_sky["reflectance_spectral"], mitsuba_sky["reflectance"]),
    }


@functools.lru_cache(maxsize=1 << 16)
def _srgb_coefficients(rgb: tuple[float, float, float]) -> tuple[float, float, float]:
    import mitsuba as mi

    if not mi.variant():
        mi.set_variant("scalar_spectral")
    return tuple(float(c) for c in np.asarray(mi.srgb_model_fetch(mi.ScalarColor3f(*rgb))).ravel()[:3])


def reflectance_spectra(rgb: np.ndarray, wavelengths: np.ndarray) -> np.ndarray:
    """RGB reflectances ``(n, 3)`` -> spectra ``(n, W)``: Mitsuba's sRGB model, as the spectral plugins upsample."""
    rgb = np.asarray(rgb, dtype=np.float64)
    scale = np.maximum(np.max(np.abs(rgb), axis=-1), 1e-12)
    keys = np.round(np.clip(rgb / scale[:, None], 0.0, 1.0), 4)
    coeff = np.array([_srgb_coefficients(tuple(float(c) for c in row)) for row in keys])
    x = (coeff[:, :1] * wavelengths + coeff[:, 1:2]) * wavelengths + coeff[:, 2:3]
    with np.errstate(all="ignore"):
        s = np.where(np.isinf(x), (x > 0).astype(np.float64), 0.5 + x / (2.0 * np.sqrt(1.0 + x * x)))
    return s * scale[:, None]


#: The rough materials' quadrature: the environment averaged down to this many texels (one cell each), the
#: spectra every :data:`GAP_STEP` nm (interpolated to 1 nm for the colour).
GAP_ENVIRONMENT = (48, 24)
GAP_STEP = 5


def material_gap(material, values, environment, size: int = 16) -> dict[str, float]:
    """
    For any material with a spectral plugin: per pixel of the env view (``size``², pixel centres), GL's product
    of RGBs ``sum f_rgb L_rgb cos dw`` and the spectral product ``RGB(sum f(lambda) L_up(lambda) cos dw)``
    (:func:`explorer.mitsuba.bsdfs.spectral_brdf`, the sky upsampled as Mitsuba's envmap does) over the same
    quadrature (the environment averaged to :data:`GAP_ENVIRONMENT`); their median ΔE2000 (``sky``), and the
    same under a white environment (``white``).
    """
    import cv2

    from explorer.materials.models import model_for
    from explorer.mitsuba.bench import median_delta_e
    from explorer.mitsuba.bsdfs import spectral_brdf
    from explorer.views.env import EnvironmentMap
    from explorer.views.geometry import brdf_view_geometry

    model = model_for(material, values)
    coarse = EnvironmentMap(cv2.resize(np.asarray(environment.pixels), GAP_ENVIRONMENT, interpolation=cv2.INTER_AREA),
                            environment.name, environment.rotation)
    directions, solid_angle, radiance = coarse.quadrature(1)
    grid = colorimetry.WAVELENGTHS[::GAP_STEP]
    sky = _srgb_model_spectra(radiance.astype(np.float64))[:, ::GAP_STEP]
    _, V, N, X, Y, inside, _ = brdf_view_geometry("lit", size, size)
    result = {}
    for label, rgb_light, spectral_light in (("sky", radiance, sky), ("white", np.ones_like(radiance), np.ones_like(sky))):
        gl, spectral = [], []
        for n, x, y, v in zip(*(a[inside].astype(np.float64) for a in (N, X, Y, V))):
            cos = directions @ n
            up = cos > 0.0
            l = directions[up]
            frame = np.stack([x, y, n])
            weight = (cos[up] * solid_angle[up])[:, None]
            f_rgb = model.brdf(l, np.broadcast_to(v, l.shape), n, x, y)
            gl.append(np.sum(np.nan_to_num(f_rgb) * rgb_light[up] * weight, axis=0))
            f = spectral_brdf(model, l @ frame.T, np.broadcast_to(frame @ v, l.shape),
                              np.broadcast_to(grid, (l.shape[0], grid.size)), reflectance_spectra)
            spectrum = np.sum(f * spectral_light[up] * weight, axis=0)
            spectral.append(colorimetry.spectrum_to_rgb(np.interp(colorimetry.WAVELENGTHS, grid, spectrum)))
        result[label] = median_delta_e(np.array(spectral), np.array(gl))
    return result


#: The mirrors of the printed table: the defaults (Lambda = 500 nm) and two other periods.
MIRRORS = ({}, {"Lambda": 400.0}, {"Lambda": 600.0})


def main() -> None:
    from explorer.materials.brd import load_material
    from explorer.materials.models import BraggMirrorModel, model_for
    from explorer.resources import material_path
    from explorer.views.env import EnvironmentMap

    material = load_material(material_path(BraggMirrorModel.name))
    print(f"{BraggMirrorModel.name} (method 3), default sky, 64x64 pixel centres: median ΔE2000 of")
    print("  roundtrip: the sky's RGB upsampled as Mitsuba does, read in the explorer's convention, vs its RGB")
    print("  product: spectral RGB(R L) vs GL's RGB(R) RGB(L); consistent: the sky's spectra corrected to its RGB")
    print("  white: the same under a white sky")
    for overrides in MIRRORS:
        values = material.resolve({"method": int(BraggMethod.TABULATED), **overrides})
        gap = spectral_gap(model_for(material, values), EnvironmentMap.default())
        label = ", ".join(f"{k} = {v:g}" for k, v in overrides.items()) or "defaults"
        print(f"  {label:<14} roundtrip {gap['roundtrip']:.2f} (max {gap['roundtrip_max']:.2f})  product {gap['product']:.2f}"
              f"  consistent {gap['product_consistent']:.2f}  white {gap['white']:.2f}")


def main_materials(size: int = 12) -> None:
    """Every material with a Mitsuba plugin at its defaults (the Bragg layer with the tabulated method)."""
    from explorer.materials.brd import load_material
    from explorer.materials.twins import capabilities_of
    from explorer.mitsuba.bsdfs import plugin_names
    from explorer.resources import material_path
    from explorer.views.env import EnvironmentMap

    print(f"every material, defaults, default sky, {size}x{size} pixel centres, the sky averaged to "
          f"{GAP_ENVIRONMENT[0]}x{GAP_ENVIRONMENT[1]} texels: median ΔE2000 of the spectral product vs GL's product of RGBs")
    from explorer.materials.models import model_for

    for name in plugin_names():
        material = load_material(material_path(name))
        values = material.resolve({})
        model = model_for(material, values)
        if isinstance(getattr(model, "mirror", None), bragg.BraggMirror):  # the Bragg twins: the tabulated method
            values = material.resolve({"method": int(BraggMethod.TABULATED)})
            model = model_for(material, values)
        if capabilities_of(material).dirac:  # a Dirac: the exact per-pixel decomposition above
            gap = spectral_gap(model, EnvironmentMap.default(), size)
            gap = {"sky": gap["product"], "white": gap["white"]}
        else:
            gap = material_gap(material, values, EnvironmentMap.default(), size)
        print(f"  {name:<14} sky {gap['sky']:.2f}  white {gap['white']:.2f}", flush=True)


if __name__ == "__main__":
    main()
    main_materials()
