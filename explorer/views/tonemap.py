"""
Tone mapping for 8-bit output: a display curve applied to the exposed linear RGB just before the sRGB
encode, in PNGs (``render --tonemap``), screenshots and the app's display pass (the GLSL twin of
:func:`tonemap` is ``shaders/lib/tonemap.glsl``, same names, same constants). Display only: ``.npy`` and
``.exr`` keep the linear values, and the gamut overlay is computed on the linear values before the curve.

Curves
------
- ``none``: clamp to [0, 1] (the colorimetric views: a reflectance shown as its colour).
- ``agx``: Troy Sobotka's AgX (github.com/sobotka/AgX, Blender 4.0's default view transform), in Benjamin
  Wrensch's minimal fit (iolite-engine.com, "Minimal AgX implementation", 2023): an inset of the primaries
  (mixing toward white before the curve, so that a vivid channel that overflows desaturates toward white
  instead of clipping to another hue), log2 encoding over [-12.47, 4.03] stops around 0.18, the default
  contrast sigmoid as a 6th-degree polynomial (mean squared error 3.7e-6), the outset (inverse inset)
  and the 2.2 display EOTF back to linear. Middle grey 0.18 stays near 0.18; 1.0 lands at ~0.8 of white;
  16 (four stops above) reaches white.
- ``aces``: Krzysztof Narkowicz's fit of the ACES filmic curve (knarkowicz.wordpress.com, "ACES Filmic
  Tone Mapping Curve", 2016), per channel ``x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)`` of 0.6 x
  (his exposure bias), clamped: contrasty, saturating; vivid channels clip to other hues sooner than AgX.

Default: :func:`default_tonemap` is ``agx`` for the radiance views (``lit``, ``env``, ``textured``:
lights and highlights go far above 1 and vivid Bragg colours have negative channels) and ``none`` for the
reflectance views and plots (``gradient``, ``sphere``, ``slice``, ... whose pixels are colours to compare,
e.g. a strip read back by ``design --target-strip``).
"""

from __future__ import annotations

import numpy as np

#: The curves, in the order the app's combo lists them (their GLSL numbers: TONEMAP_NONE = 0, ...).
TONEMAPS = ("none", "agx", "aces")
#: The views whose pixels are radiances under lights: tone mapped with AgX unless told otherwise.
RADIANCE_VIEWS = ("lit", "env", "textured")

# AgX (Wrensch's fit of Sobotka's AgX): the inset matrix as GLSL's mat3 lists it (column by column) ...
AGX_INSET = np.array([[0.842479062253094, 0.0423282422610123, 0.0423756549057051],
                      [0.0784335999999992, 0.878468636469772, 0.0784336],
                      [0.0792237451477643, 0.0791661274605434, 0.879142973793104]])
# ... its inverse (the outset), and the log2 range (stops) mapped to [0, 1].
AGX_OUTSET = np.array([[1.19687900512017, -0.0528968517574562, -0.0529716355144438],
                       [-0.0980208811401368, 1.15190312990417, -0.0980434501171241],
                       [-0.0990297440797205, -0.0989611768448433, 1.15107367264116]])
AGX_MIN_EV = -12.47393
AGX_MAX_EV = 4.026069
#: The default contrast sigmoid's polynomial, highest degree first (x^6 ... x^0).
AGX_SIGMOID = (15.5, -40.14, 31.96, -6.868, 0.4298, 0.1191, -0.00232)
#: Smallest value taken to log2 (the inset keeps in-gamut colours positive; out-of-gamut ones may not be).
AGX_FLOOR = 1e-10
#: Narkowicz's ACES fit: a, b, c, d, e of x (a x + b) / (x (c x + d) + e), and his exposure bias.
ACES_FIT = (2.51, 0.03, 2.43, 0.59, 0.14)
ACES_BIAS = 0.6


def default_tonemap(view: str) -> str:
    """``agx`` for the radiance views (:data:`RADIANCE_VIEWS`), ``none`` for colours and plots."""
    return "agx" if view in RADIANCE_VIEWS else "none"


def check_tonemap(name: str) -> str:
    """``name`` if it is a curve of :data:`TONEMAPS`, else a one-line ``ValueError``."""
    if name not in TONEMAPS:
        raise ValueError(f"unknown tone map {name!r}; expected one of {', '.join(TONEMAPS)}")
    return name


def agx(rgb: np.ndarray) -> np.ndarray:
    """AgX of linear RGB (..., 3): linear display RGB in [0, 1] (see the module notes)."""
    # GLSL's `agx_inset * v` with the matrix given column by column is v @ AGX_INSET in numpy.
    x = np.asarray(rgb, dtype=np.float64) @ AGX_INSET
    x = np.clip(np.log2(np.maximum(x, AGX_FLOOR)), AGX_MIN_EV, AGX_MAX_EV)
    x = (x - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV)
    x = np.polyval(AGX_SIGMOID, x)
    x = x @ AGX_OUTSET
    return np.clip(x, 0.0, 1.0) ** 2.2


def aces(rgb: np.ndarray) -> np.ndarray:
    """Narkowicz's ACES fit of linear RGB (..., 3), per channel: linear display RGB in [0, 1]."""
    a, b, c, d, e = ACES_FIT
    x = np.maximum(np.asarray(rgb, dtype=np.float64) * ACES_BIAS, 0.0)
    return np.clip(x * (a * x + b) / (x * (c * x + d) + e), 0.0, 1.0)


def tonemap(rgb: np.ndarray, curve: str = "none") -> np.ndarray:
    """Exposed linear RGB (..., 3) to linear display RGB in [0, 1] by ``curve`` (:data:`TONEMAPS`)."""
    check_tonemap(curve)
    if curve == "agx":
        return agx(rgb)
    if curve == "aces":
        return aces(rgb)
    return np.clip(np.asarray(rgb, dtype=np.float64), 0.0, 1.0)


def display_srgb8(image: np.ndarray, exposure: float = 1.0, curve: str = "none") -> np.ndarray:
    """The 8-bit sRGB a PNG (and the app's display) shows of linear ``image``: ``curve`` of ``exposure * image``, encoded."""
    from explorer.physics.colorimetry import encode_srgb8

    exposed = np.asarray(image) * np.float32(exposure)
    return encode_srgb8(exposed if check_tonemap(curve) == "none" else tonemap(exposed, curve))
