"""
The views, in numpy: the twin of every image the GL renderer makes (``shaders/views/*.glsl``), on the
geometry of :mod:`explorer.views.geometry`.

``gradient`` and ``sphere`` show a material's ``reflectance(cos_theta)``; ``lit``, ``slice`` and
``scatter`` call its ``BRDF(L, V, N, X, Y)`` (any material of the format, BRDF Explorer's own files
included), whose numpy twin is the model's ``brdf(L, V, N, X, Y) -> (..., 3)``, under one rule
(:func:`explorer.views.geometry.view_brdf`).
"""

from __future__ import annotations

import numpy as np

from explorer.views.geometry import brdf_view_geometry, view_brdf, view_cos_theta, view_named

#: Pixels a model evaluates at once: a spectral model's per-wavelength arrays stay a few hundred MB
#: whatever the image size (every model is per pixel, so the chunks change no value).
CHUNK_PIXELS = 1 << 14


def _chunked(function, *arrays) -> np.ndarray:
    """``function(*arrays)`` over the first axis in chunks of :data:`CHUNK_PIXELS`, concatenated."""
    count = len(arrays[0])
    if count <= CHUNK_PIXELS:
        return function(*arrays)
    return np.concatenate([function(*(a[i:i + CHUNK_PIXELS] for a in arrays)) for i in range(0, count, CHUNK_PIXELS)])


def render_numpy(
    model, view: str, width: int, height: int, *, light: tuple[float, float] | None = None, thickness=None,
    environment=None, mesh=None, slice_phi_d: float = 90.0, plot=None, fill: float = 0.0,
) -> np.ndarray:
    """
    The view of a material's numpy twin: ``(height, width, 3)`` float32 linear RGB, unclamped.

    ``light`` (``lit``, ``scatter``, ``textured``): ``(theta, phi)`` in degrees, default :data:`explorer.views.geometry.DEFAULT_LIGHT`.
    ``thickness`` (``textured``): an :class:`explorer.views.thickness.ThicknessTexture` (default: the default
    texture over the default D_inc range, without prefiltering) or, for a Bragg mirror, an
    :class:`explorer.views.surface_texture.BraggTexture` (default: the default texture, both mappings).
    ``environment`` (``env``): an :class:`explorer.views.env.EnvironmentMap` (default: the shipped one); the
    image is the exact integral :func:`explorer.views.env.env_integral_numpy` (slow: use small sizes). In the
    ``lit`` view, what a smooth mirror (a model whose ``mirror_only`` is true) reflects, with the light as a
    glint (:func:`explorer.views.mirror.mirror_lit`); other materials ignore it.
    ``mesh`` (``lit``, ``env``): an :class:`explorer.views.mesh.Mesh` drawn instead of the sphere, its normals
    by :func:`explorer.views.mesh.rasterise`.
    ``slice_phi_d`` (``slice``): phi_d in degrees (the app's Slice window; 90 as BRDF Explorer).
    ``plot`` (the plots, :mod:`explorer.views.plots`): a :class:`explorer.views.plots.PlotSettings` (default: its defaults).
    ``fill`` (``lit``, not a smooth mirror): the environment fill's radiance (:mod:`explorer.views.fill`); 0: the light alone.
    """
    evaluates = view_named(view).evaluates
    if mesh is not None and view not in ("lit", "env", "textured"):
        raise ValueError(f"a mesh is drawn in the lit, textured and env views, not {view}")
    if view_named(view).plot is not None:
        from explorer.views.geometry import light_direction
        from explorer.views.plots import PlotSettings, plot_numpy

        return plot_numpy(model, view, width, height, light_direction(light), plot or PlotSettings())
    if evaluates == "environment":
        from explorer.views.env import EnvironmentMap, env_integral_numpy

        if not callable(getattr(model, "brdf", None)):
            raise ValueError(f"the env view needs the model's brdf(L, V, N, X, Y); {type(model).__name__} has none")
        return env_integral_numpy(model, EnvironmentMap.default() if environment is None else environment, width, height, mesh=mesh)
    if evaluates == "textured_brdf":
        from explorer.views.thickness import ThicknessTexture

        if not callable(getattr(model, "textured_brdf", None)):
            raise ValueError(f"the textured view needs the model's textured_brdf(); {type(model).__name__} has none")
        if thickness is None:  # the default texture of what the model varies
            from explorer.views.surface_texture import BraggTexture

            thickness = BraggTexture.from_file() if callable(getattr(model, "texture_table", None)) else ThicknessTexture.from_file()
        from explorer.views.geometry import surface_values

        raster = None
        if mesh is not None:  # its normals and texture coordinates (views/mesh/textured.glsl)
            from explorer.views.mesh import mesh_view_geometry, rasterise

            raster = rasterise(mesh, width, height)
            L, V, N, X, Y, inside, factor = mesh_view_geometry(raster.normals, raster.covered, light)
        else:
            L, V, N, X, Y, inside, factor = brdf_view_geometry("lit", width, height, light)
        d_inc, sigma = surface_values(thickness, width, height, raster)
        image = np.zeros((height, width, 3), dtype=np.float32)
        vectors = [a[inside] for a in (L, V, N, X, Y)]

        def textured_brdf(L, V, N, X, Y, d_inc, sigma):
            return model.textured_brdf(L, V, N, X, Y, d_inc, sigma, thickness.prefilter, **thickness.model_options())

        rgb = _chunked(lambda *a: view_brdf(textured_brdf, *a), *vectors, d_inc[inside], sigma[inside])
        image[inside] = rgb * factor[inside][:, None]
        return image
    if evaluates == "brdf":
        if not callable(getattr(model, "brdf", None)):
            raise ValueError(f"the {view} view needs the model's brdf(L, V, N, X, Y); {type(model).__name__} has none")
        if mesh is not None:
            from explorer.views.mesh import mesh_view_geometry, rasterise

            surface = rasterise(mesh, width, height)
            L, V, N, X, Y, inside, factor = mesh_view_geometry(surface.normals, surface.covered, light)
        else:
            L, V, N, X, Y, inside, factor = brdf_view_geometry(view, width, height, light, slice_phi_d)
        image = np.zeros((height, width, 3), dtype=np.float32)
        if view == "lit" and getattr(model, "mirror_only", False):  # a Dirac: the mirror ball (explorer.views.mirror)
            from explorer.views.env import EnvironmentMap
            from explorer.views.geometry import light_direction
            from explorer.views.mirror import mirror_lit

            environment = EnvironmentMap.default() if environment is None else environment
            direction = light_direction(light).astype(np.float64)
            image[inside] = _chunked(lambda v, n: mirror_lit(model, v, n, direction, environment), V[inside], N[inside])
            return image
        vectors = [a[inside] for a in (L, V, N, X, Y)]
        image[inside] = _chunked(lambda *a: view_brdf(model.brdf, *a), *vectors) * factor[inside][:, None]
        if view == "lit" and fill > 0.0:  # the environment fill (explorer.views.fill), lit.glsl's fill_radiance
            from explorer.views.fill import fill_albedo_numpy, fill_radiance

            image[inside] += fill_radiance(fill_albedo_numpy(model), np.sum(N[inside] * V[inside], axis=-1), fill).astype(np.float32)
        return image
    cos_theta, inside = view_cos_theta(view, width, height)
    image = np.zeros((height, width, 3), dtype=np.float32)
    if view == "gradient":
        # Every row is the same.
        image[:] = model.reflectance(cos_theta[0])[None, :, :]
    else:
        image[inside] = _chunked(model.reflectance, cos_theta[inside])
    return image
