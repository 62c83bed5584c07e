"""
GL images against their numpy twins: one way to render both, one comparison with named tolerances.

:func:`render_both` draws a material's view with :meth:`explorer.gpu.Renderer.render` (float32 GLSL on
the GPU, or Mesa's llvmpipe) and with :func:`explorer.views.render.render_numpy` (its numpy twin, float64),
and says which pixels are compared (all but the disc's float32 rim). :func:`compare` measures them per
pixel under a :class:`Tolerance`:

- :data:`COLOUR_TOLERANCE`, the specular colour views' (``gradient``, ``sphere``): :data:`GL_ATOL`
  absolute per linear RGB channel;
- :data:`BRDF_TOLERANCE`, the BRDF views' (``lit``, ``slice``, ``scatter``, ``textured``, ``env``, the plots):
  :data:`RTOL` relative to a pixel's value (its largest |channel|) where the value exceeds :data:`FLOOR`,
  absolute (``RTOL x FLOOR``) below. Linear RGB of vivid colours crosses zero in single channels, where a
  per-channel relative error means nothing; per channel, the float32 basic approximation of a Bragg
  mirror (method 1) misses 2e-3 at isolated near-zero channels (1e-4 on a channel of 0.017 in a pixel
  of 0.665).

:func:`tolerance_for` picks one by view. The test suite (``tests/twins.py``) and ``bragg-explorer check``
(:func:`check_material`, for anyone writing a material) share all of it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from explorer.materials.models import model_for
from explorer.views.geometry import rim_distance, view_named
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
#: The views ``check`` compares, and their sizes there: small (the spectral references run per pixel).
CHECK_SIZES = {"gradient": (180, 1), "sphere": (32, 32), "lit": (32, 32), "slice": (32, 32), "scatter": (32, 32),
               "theta_v": (64, 1), "theta_h": (64, 1), "theta_d": (64, 1), "lobe3d": (32, 8)}


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
    if gl.shape != reference.shape or reference.shape != (height, width, 3):
        raise ValueError(f"{view}: GL image {gl.shape}, numpy image {reference.shape}, expected {(height, width, 3)}")
    if gl.dtype != np.float32:
        raise ValueError(f"{view}: GL image of {gl.dtype}, not float32")
    return Twins(gl, reference, compared_pixels(view, width, height), view, light)


@dataclass(frozen=True)
class Comparison:
    """How far a view's GL image is from its twin's: the largest difference, and the worst pixel against ``tolerance``."""

    view: str
    tolerance: Tolerance
    #: The largest max-over-channels |GL - numpy| over the compared pixels.
    max_difference: float
    #: The largest |GL - numpy| / allowed over the compared pixels (at most 1 passes).
    worst_ratio: float
    #: The worst pixel (row, column), its difference, what was allowed there, both images' values.
    pixel: tuple[int, int]
    allowed: float
    gl_value: tuple[float, ...]
    reference_value: tuple[float, ...]
    #: Which side is non-finite on the compared pixels ("" when both are finite).
    non_finite: str = ""

    @property
    def passed(self) -> bool:
        return not self.non_finite and self.worst_ratio <= 1.0

    def message(self, what: str = "") -> str:
        """One line: the view, the largest difference against the named tolerance, the worst pixel."""
        what = what or self.view
        if self.non_finite:
            return f"{what}: {self.non_finite} non-finite"
        return (f"{what}: |GL - numpy| = {self.max_difference:.2e} (worst pixel {self.pixel}: "
                f"{self.worst_ratio:.2f} of its allowed {self.allowed:.2e}, {self.tolerance.name}; "
                f"GL {np.round(self.gl_value, 6).tolist()}, numpy {np.round(self.reference_value, 6).tolist()})")

    def as_dict(self) -> dict:
        return {"view": self.view, "tolerance": self.tolerance.name, "max_difference": self.max_difference,
                "worst_ratio": self.worst_ratio, "pixel": list(self.pixel), "allowed": self.allowed,
                "passed": self.passed, "non_finite": self.non_finite or None}


def compare(twins: Twins, tolerance: Tolerance | None = None) -> Comparison:
    """``twins`` compared per pixel under ``tolerance`` (default :func:`tolerance_for` the view)."""
    gl, reference, compared = twins.gl, twins.reference, twins.compared
    tolerance = tolerance or tolerance_for(twins.view)
    if gl.shape != reference.shape:
        raise ValueError(f"{twins.view}: shapes {gl.shape} and {reference.shape}")
    non_finite = ("numpy twin" if not np.isfinite(reference[compared]).all()
                  else "GLSL" if not np.isfinite(gl[compared]).all() else "")
    error = np.abs(gl.astype(np.float64) - reference).max(axis=-1)
    allowed = tolerance.allowed(reference)
    ratio = np.where(compared, error / allowed, 0.0)
    ratio = np.where(np.isfinite(ratio), ratio, np.inf)
    worst = np.unravel_index(ratio.argmax(), ratio.shape)
    return Comparison(
        twins.view, tolerance, float(np.where(compared, error, 0.0).max()), float(ratio.max()),
        tuple(int(i) for i in worst), float(allowed[worst]),
        tuple(float(v) for v in gl[worst]), tuple(float(v) for v in reference[worst]), non_finite)


def check_views(material) -> tuple[str, ...]:
    """
    The views of :data:`CHECK_SIZES` that ``material`` supports: the colour views when its shader defines
    ``reflectance(cos_theta)``, the BRDF views and BRDF plots always.
    """
    import re

    has_reflectance = re.search(r"\bvec3\s+reflectance\s*\(", material.shader) is not None
    return tuple(view for view in CHECK_SIZES if has_reflectance or view not in COLOUR_VIEWS)


def check_material(renderer, material, values, views=None) -> list[Comparison]:
    """
    ``bragg-explorer check``: every view of ``views`` (default :func:`check_views`) of ``material`` at
    ``values`` rendered by the GPU and by its numpy twin (sizes :data:`CHECK_SIZES`), each compared under
    the view's named tolerance (:func:`tolerance_for`).
    """
    views = check_views(material) if views is None else tuple(views)
    return [compare(render_both(renderer, material, values, view, CHECK_SIZES[view])) for view in views]
