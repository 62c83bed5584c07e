"""
``bragg-explorer check``'s renders: each view a material supports drawn by the GPU and by its numpy twin, compared
under the harness's named tolerances (:mod:`explorer.views.twin_check`). Here, above the views, because the env view's
GPU side is the progressive Monte Carlo render (:class:`explorer.gpu.env.ProgressiveEnvRender`) and its standard error.
"""

from __future__ import annotations

import numpy as np

from explorer.gpu.env import ProgressiveEnvRender
from explorer.materials.models import model_for
from explorer.views.env import env_integral_numpy
from explorer.views.twin_check import (
    CHECK_SIZES, ENV_PIXELS, ENV_SPP, Comparison, Twins, check_views, compare, env_pixels, render_albedo_both, render_both,
    smooth_environment,
)


def render_env_both(renderer, material, values, size, spp: int = ENV_SPP, environment=None, seed: int = 0,
                    pixels: int | None = ENV_PIXELS) -> Twins:
    """
    The env view on the GPU (its Monte Carlo mean after ``spp`` samples a pixel, and its standard error) and the
    twin's exact integral (:func:`explorer.views.env.env_integral_numpy`) at :func:`env_pixels`, under ``environment``
    (default :func:`smooth_environment`).
    """
    width, height = size
    environment = smooth_environment() if environment is None else environment
    render = ProgressiveEnvRender(renderer, material, values, environment, width, height, seed=seed)
    try:
        while render.samples < spp:
            render.step(min(spp - render.samples, max(1, render.samples_per_pass)))
        gl, error = render.image(), render.standard_error()
        dropped = render.dropped_samples()
    finally:
        render.release()
    if dropped:
        gl = np.full_like(gl, np.nan)  # samples dropped: the GLSL BRDF returned NaN or infinity somewhere
    compared = env_pixels(width, height, pixels)
    rows, columns = np.nonzero(compared)
    reference = np.zeros((height, width, 3))
    reference[rows, columns] = env_integral_numpy(model_for(material, values), environment, width, height,
                                                  np.stack([rows, columns], axis=-1))
    return Twins(gl, reference, compared, "env", None, error)


def render_view_both(renderer, material, values, view: str) -> Twins:
    """``check``'s pair of images of ``view`` at :data:`CHECK_SIZES` (the textured view on the material's default texture)."""
    if view == "env":
        return render_env_both(renderer, material, values, CHECK_SIZES["env"])
    if view == "albedo":
        return render_albedo_both(renderer, material, values)
    thickness = None
    if view == "textured":
        from explorer.views.surface_texture import default_texture

        thickness = default_texture(material)
    return render_both(renderer, material, values, view, CHECK_SIZES[view], thickness=thickness)


def check_material(renderer, material, values, views=None) -> list[Comparison]:
    """
    ``bragg-explorer check``: every view of ``views`` (default :func:`check_views`) of ``material`` at
    ``values`` rendered by the GPU and by its numpy twin (sizes :data:`CHECK_SIZES`), each compared under
    the view's named tolerance (:func:`tolerance_for`).
    """
    views = check_views(material) if views is None else tuple(views)
    return [compare(render_view_both(renderer, material, values, view)) for view in views]
