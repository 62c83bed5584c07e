"""
GL images against their numpy twins: one way to render both, one assertion with named tolerances.

:func:`render_both` draws a material's view with :meth:`explorer.gpu.Renderer.render` (float32 GLSL on
the GPU, or Mesa's llvmpipe) and with :func:`explorer.views.render.render_numpy` (its numpy twin, float64),
and says which pixels are compared (all but the disc's float32 rim). :func:`assert_twins_equal` compares
them per pixel under a :class:`Tolerance`:

- :data:`COLOUR_TOLERANCE`, the specular colour views' (``gradient``, ``sphere``): :data:`GL_ATOL`
  absolute per linear RGB channel;
- :data:`BRDF_TOLERANCE`, the BRDF views' (``lit``, ``slice``, ``scatter``, ``textured``, ``env``):
  :data:`RTOL` relative to a pixel's value (its largest |channel|) where the value exceeds :data:`FLOOR`,
  absolute (``RTOL x FLOOR``) below. Linear RGB of vivid colours crosses zero in single channels, where a
  per-channel relative error means nothing; per channel, the float32 basic approximation of the Bragg
  mirror (method 1) misses 2e-3 at isolated near-zero channels (1e-4 on a channel of 0.017 in a pixel
  of 0.665).

:func:`tolerance_for` picks one by view; a test passes another where it has a reason to.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from explorer.materials.models import model_for
from explorer.views.geometry import brdf_view_geometry, rim_distance, view_cos_theta, view_named
from explorer.views.render import render_numpy

#: Per linear RGB channel, absolute: the specular colour views.
GL_ATOL = 2e-3
#: The BRDF views: relative to a pixel's largest |channel| ...
RTOL = 2e-3
#: ... above this value; below it the tolerance is absolute, RTOL x FLOOR.
FLOOR = 1e-3
#: Disc pixels with |x^2 + y^2 - 1| below this are skipped (float32 decides inside/outside there).
RIM_EXCLUSION = 1e-4
#: The views whose pixel is a reflectance colour (no light, no BRDF).
COLOUR_VIEWS = ("gradient", "sphere")
#: The light of each BRDF view in the comparisons: off the x axis, so that phi matters.
LIGHTS = {"lit": (30.0, 120.0), "slice": None, "scatter": (50.0, 200.0)}


@dataclass(frozen=True)
class Tolerance:
    """A pixel passes when max over channels |GL - numpy| <= max(atol, rtol x value), value = the twin's largest |channel|."""

    name: str
    atol: float
    rtol: float = 0.0

    def allowed(self, reference: np.ndarray) -> np.ndarray:
        return np.maximum(self.atol, self.rtol * np.abs(reference).max(axis=-1))


COLOUR_TOLERANCE = Tolerance(f"{GL_ATOL:g} absolute per channel", atol=GL_ATOL)
BRDF_TOLERANCE = Tolerance(f"{RTOL:g} x max(value, {FLOOR:g})", atol=RTOL * FLOOR, rtol=RTOL)


def tolerance_for(view: str) -> Tolerance:
    """The colour views' absolute tolerance, or the BRDF views' relative one."""
    return COLOUR_TOLERANCE if view in COLOUR_VIEWS else BRDF_TOLERANCE


def compared_pixels(view: str, width: int, height: int) -> np.ndarray:
    """Every pixel but those on the disc's float32 rim (all of them in the gradient and slice views)."""
    return rim_distance(view, width, height) > RIM_EXCLUSION


@dataclass(frozen=True)
class Twins:
    """A view's GL image, its numpy twin's, the pixels compared; unpacks as ``gl, reference, compared``."""

    gl: np.ndarray
    reference: np.ndarray
    compared: np.ndarray
    view: str = ""
    light: tuple[float, float] | None = None

    def __iter__(self):
        return iter((self.gl, self.reference, self.compared))

    def where(self, compared: np.ndarray) -> "Twins":
        """The same images, compared on ``compared`` only."""
        return dataclasses.replace(self, compared=compared)

    @classmethod
    def of(cls, gl, reference, view: str, light=None) -> "Twins":
        """Two images of ``view`` made elsewhere (by the CLI, or two GL images)."""
        height, width = np.shape(gl)[:2]
        return cls(np.asarray(gl), np.asarray(reference), compared_pixels(view, width, height), view, light)


_VIEW_LIGHT = object()


def render_both(renderer, material, values, view: str, size, light=_VIEW_LIGHT, thickness=None, plot=None, fill: float = 0.0) -> Twins:
    """
    ``material`` at ``values`` (as given: resolve them first, or not) in ``view`` at ``size = (W, H)``, on
    the GPU and in numpy. ``light`` defaults to the view's in :data:`LIGHTS` (none for the colour
    views); ``thickness`` (an :class:`explorer.views.thickness.ThicknessTexture`) is the textured view's,
    ``plot`` (an :class:`explorer.views.plots.PlotSettings`) the plot views'; ``fill`` the lit view's environment
    fill (:mod:`explorer.views.fill`; 0, the light alone, by default).
    """
    width, height = size
    if light is _VIEW_LIGHT:
        light = LIGHTS.get(view)
    gl_inputs = {}
    if thickness is not None:
        gl_inputs = thickness.gl_arguments(material, values, width, height)
        numpy_inputs = {"thickness": thickness}
    else:
        numpy_inputs = {}
    if view_named(view).plot is not None:
        from explorer.views.plots import gl_uniforms

        gl_inputs = {"uniforms": gl_uniforms(view, plot)}
        numpy_inputs = {"plot": plot}
    if fill:
        gl_inputs, numpy_inputs = {**gl_inputs, "uniforms": {"fill": float(fill)}}, {**numpy_inputs, "fill": float(fill)}
    gl = renderer.render(material, values, view, width, height, light=light, **gl_inputs)
    reference = render_numpy(model_for(material, values), view, width, height, light=light, **numpy_inputs)
    assert gl.shape == reference.shape == (height, width, 3), (gl.shape, reference.shape)
    assert gl.dtype == np.float32, gl.dtype
    return Twins(gl, reference, compared_pixels(view, width, height), view, light)


def assert_twins_equal(twins: Twins, what: str = "", tolerance: Tolerance | None = None) -> None:
    """Both images finite and equal within ``tolerance`` (default :func:`tolerance_for` the view) on the compared pixels."""
    gl, reference, compared = twins.gl, twins.reference, twins.compared
    tolerance = tolerance or tolerance_for(twins.view)
    what = what or twins.view
    assert gl.shape == reference.shape, f"{what}: shapes {gl.shape} and {reference.shape}"
    assert np.isfinite(reference[compared]).all(), f"{what}: numpy twin non-finite"
    assert np.isfinite(gl[compared]).all(), f"{what}: GLSL non-finite"
    error = np.abs(gl.astype(np.float64) - reference).max(axis=-1)
    ratio = error / tolerance.allowed(reference)
    ratio[~compared] = 0.0
    worst = np.unravel_index(ratio.argmax(), ratio.shape)
    assert ratio.max() <= 1.0, (
        f"{what}: |GL - numpy| = {error[worst]:.2e} > {tolerance.allowed(reference)[worst]:.2e} "
        f"({tolerance.name}) at pixel {worst} (GL {gl[worst]}, numpy {reference[worst]})"
    )


def assert_black_outside(twins: Twins) -> None:
    """Off the disc (rim excluded), both images are exactly 0; the disc leaves some pixels out."""
    height, width = twins.gl.shape[:2]
    if twins.view in COLOUR_VIEWS:
        inside = view_cos_theta(twins.view, width, height)[1]
    else:
        inside = brdf_view_geometry(twins.view, width, height, twins.light)[5]
    outside = ~inside & twins.compared
    assert outside.any(), f"{twins.view}: no pixel outside the disc"
    np.testing.assert_array_equal(twins.gl[outside], 0.0)
    np.testing.assert_array_equal(twins.reference[outside], 0.0)
