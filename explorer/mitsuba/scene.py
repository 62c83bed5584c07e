"""
The env view's scene in Mitsuba 3, and its colour convention.

The scene is the GL env view's (``shaders/views/env.glsl``, :mod:`explorer.views.env`): the unit sphere at
the origin seen by an orthographic camera along ``V = (0, 0, 1)`` whose film spans ``[-1, 1]^2``, screen up
``+y``, under an equirectangular environment. Mitsuba's ``envmap`` reads ``u = atan2(x, -z) / 2 pi`` with
texel ``k`` centred at ``u = k / W`` and ``v = k / (H - 1)`` (it appends a wrapped column); ours reads
``u = 0.5 + atan2(x, -z) / 2 pi`` with centres at ``(k + 0.5) / W``. So the scene's bitmap is our
environment resampled (bilinearly, as the GL view reads it) at Mitsuba's texel directions.

Colour convention (docs/mitsuba.md): the explorer's, everywhere. A reflectance spectrum's colour is its
XYZ under illuminant E, adapted to D65 by Bradford and scaled so that white is RGB (1, 1, 1)
(:mod:`explorer.physics.colorimetry`).

- RGB variants: the BSDF returns the explorer's RGB (its numpy twin), multiplied per channel by the
  environment's RGB: the GL estimator's arithmetic.
- Spectral variants: Mitsuba's RGB emitters are D65 spectra; the plugins, given ``illuminant="e"``,
  divide by that D65, so the envmap's white lights the material as illuminant E. The film records XYZ
  (``pixel_format="xyz"``) and :func:`xyz_to_explorer_rgb` takes it to linear sRGB with the explorer's
  matrix.
"""

from __future__ import annotations

import contextlib
import math
import re
import sys
from typing import Callable, Iterator, Mapping

import numpy as np

from explorer.mitsuba.variants import is_spectral
from explorer.physics import colorimetry
from explorer.views.env import EnvironmentMap, uv_to_direction

#: Mitsuba's environment bitmap: this many times our environment's texels per side (bilinear resampling
#: onto shifted texel centres smooths a little; twice as many keeps that below the GL view's own noise).
ENV_OVERSAMPLE = 2
#: Path depth: one bounce off a convex sphere (its reflections never hit it again).
MAX_DEPTH = 2
#: Paths per render pass (width x height x spp): more samples per pixel are rendered in passes of
#: different seeds and averaged (the same estimator), so that a wavefront's memory (Dr.Jit's and the
#: plugins' numpy temporaries) stays bounded at any spp.
PATHS_PER_PASS = 1 << 20


def mitsuba_environment(environment: EnvironmentMap, oversample: int = ENV_OVERSAMPLE) -> np.ndarray:
    """
    Our environment resampled for Mitsuba's ``envmap`` (``(H', W', 3)`` float32): texel ``(j, k)`` holds our
    bilinear radiance toward Mitsuba's direction of ``u = k / W'``, ``v = j / (H' - 1)``, that is our
    ``u + 0.5``.
    """
    width, height = environment.width * oversample, environment.height * oversample
    u_mitsuba = np.arange(width) / width
    v = np.arange(height) / (height - 1)
    d = uv_to_direction((u_mitsuba + 0.5)[None, :], v[:, None])  # our u = Mitsuba's u + 1/2
    return environment.radiance(d).astype(np.float32)


def bsdf_properties(material, values: Mapping[str, object], variant: str | None = None) -> dict:
    """A material's values as plugin properties (``.brd`` names; colours as RGB triples)."""
    import mitsuba as mi

    props: dict = {"type": material.model}
    for p in material.parameters:
        value = values[p.name]
        if p.type == "color":
            props[p.name] = mi.ScalarColor3f(*(float(c) for c in value))
        elif p.type == "bool":
            props[p.name] = bool(value)
        else:
            props[p.name] = float(value)
    if variant is not None and is_spectral(variant):
        props["illuminant"] = "e"
    return props


def env_scene_dict(material, values: Mapping[str, object], environment: EnvironmentMap, width: int, height: int,
                   spp: int, variant: str, env_bitmap=None) -> dict:
    """The env view's scene as a ``mi.load_dict`` dictionary (the variant must be set)."""
    import mitsuba as mi

    T = mi.ScalarTransform4f
    bitmap = env_bitmap if env_bitmap is not None else mi.Bitmap(mitsuba_environment(environment))
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": MAX_DEPTH, "hide_emitters": True},
        "sphere": {"type": "sphere", "bsdf": bsdf_properties(material, values, variant)},
        "environment": {"type": "envmap", "bitmap": bitmap},
        "sensor": {
            "type": "orthographic",
            # Mitsuba's look_at puts the film's +x at world +x here (its camera x axis is 'left').
            "to_world": T().look_at(origin=[0.0, 0.0, 4.0], target=[0.0, 0.0, 0.0], up=[0.0, 1.0, 0.0]),
            "film": {"type": "hdrfilm", "width": int(width), "height": int(height),
                     "pixel_format": "xyz" if is_spectral(variant) else "rgb",
                     "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": int(spp)},
        },
    }


_INVALID_SAMPLE = re.compile(r"Invalid sample value: \[([^\]]*)\]")


def out_of_gamut_sample(text: str) -> bool:
    """Whether a Mitsuba log line is ImageBlock's "Invalid sample value" for a finite sample (a negative channel)."""
    match = _INVALID_SAMPLE.search(text)
    if match is None:
        return False
    try:
        values = [float(x) for x in match.group(1).split(",")]
    except ValueError:
        return False
    return bool(values) and all(math.isfinite(x) for x in values)


@contextlib.contextmanager
def out_of_gamut_counted(mi, note: Callable[[str], None] | None = None) -> Iterator[None]:
    """
    While rendering: Mitsuba's "Invalid sample value" warnings for finite samples (the scalar RGB variants'
    ImageBlock warns for each sample with a channel below 0, one line per sample) are counted, not printed,
    and summed up in one ``note`` afterwards (stderr by default). A vivid Bragg colour has negative
    linear-sRGB channels: the GL view and the numpy twin keep them, so the render keeps them too (colours
    unchanged). Every other message, NaN and infinite samples included, passes through.
    """
    logger = mi.logger() if hasattr(mi, "logger") else mi.Thread.thread().logger()
    appenders = [logger.appender(k) for k in range(logger.appender_count())]

    class Counting(mi.Appender):
        def __init__(self):
            super().__init__()
            self.count = 0

        def append(self, level, text):
            if level == mi.LogLevel.Warn and out_of_gamut_sample(text):
                self.count += 1
                return
            for appender in appenders:
                appender.append(level, text)

        def log_progress(self, progress, name, formatted, eta, ptr=None):
            for appender in appenders:
                appender.log_progress(progress, name, formatted, eta, ptr)

    counting = Counting()
    logger.clear_appenders()
    logger.add_appender(counting)
    try:
        yield
    finally:
        logger.clear_appenders()
        for appender in appenders:
            logger.add_appender(appender)
        if counting.count:
            (note or (lambda m: print(m, file=sys.stderr)))(
                f"note: {counting.count} samples had negative linear-sRGB channels (out-of-gamut colours, kept as the "
                "GL view keeps them; Mitsuba's 'Invalid sample value' warnings for them not shown)")


def render_in_passes(mi, scene, spp: int | None = None, seed: int = 0, note: Callable[[str], None] | None = None) -> np.ndarray:
    """
    ``mi.render(scene, spp)``'s first three channels (float64), rendered in passes of at most
    :data:`PATHS_PER_PASS` paths with seeds of their own and averaged, weighted by their spp (the same
    estimator, bounded memory). ``spp`` None or 0: the scene's sampler's count. Out-of-gamut samples'
    warnings become one ``note`` (:func:`out_of_gamut_counted`).
    """
    sensor = scene.sensors()[0]
    spp = int(spp or sensor.sampler().sample_count())
    width, height = (int(c) for c in sensor.film().crop_size())
    passes = max(1, -(-spp * width * height // PATHS_PER_PASS))  # ceil
    counts = [spp // passes + (k < spp % passes) for k in range(passes)]
    with out_of_gamut_counted(mi, note):
        return sum(count * np.asarray(mi.render(scene, spp=count, seed=int(seed) * passes + k), dtype=np.float64)[..., :3]
                   for k, count in enumerate(counts) if count) / spp


def xyz_to_explorer_rgb(xyz: np.ndarray) -> np.ndarray:
    """Mitsuba's XYZ film (flat spectrum of 1 -> Y = 1, its CIE 1931 tables) to the explorer's linear sRGB."""
    return colorimetry.xyz_to_rgb(xyz)


def render_env_mitsuba(material, values: Mapping[str, object], width: int, height: int, spp: int = 64,
                       environment: EnvironmentMap | None = None, variant: str | None = None,
                       note: Callable[[str], None] | None = None, seed: int = 0) -> np.ndarray:
    """
    The env view rendered by Mitsuba: ``(height, width, 3)`` float32 linear sRGB in the explorer's colour
    convention. ``variant`` defaults to ``llvm_ad_rgb`` (scalar where LLVM cannot run, with a ``note``).
    """
    from explorer.mitsuba.registry import register
    from explorer.mitsuba.variants import choose_variant

    variant = choose_variant(variant, note)
    mi = register(variant)
    environment = environment if environment is not None else EnvironmentMap.default()
    scene = mi.load_dict(env_scene_dict(material, values, environment, width, height, spp, variant))
    image = render_in_passes(mi, scene, int(spp), seed, note)
    if is_spectral(variant):
        image = xyz_to_explorer_rgb(image)
    return image.astype(np.float32)
