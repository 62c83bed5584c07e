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

- :data:`ENV_TOLERANCE`, the env view's: the GPU's Monte Carlo mean against the twin's exact integral, within
  :data:`ENV_STANDARD_ERRORS` of the pixel's standard error plus the quadrature's own :data:`ENV_QUADRATURE_RTOL`;
- :data:`ALBEDO_TOLERANCE`, the directional albedo's (the gl engine's scatter sum against the numpy quadrature):
  :data:`ALBEDO_ATOL` absolute per channel.

:func:`tolerance_for` picks one by view. The test suite (``tests/twins.py``) and ``bragg-explorer check``
(:func:`explorer.gpu.twin_check.check_material`, for anyone writing a material) share all of it.
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
#: The env view: a pixel within this many standard errors of its Monte Carlo mean (P(|z| > 5.5) ~ 4e-8 a value) ...
ENV_STANDARD_ERRORS = 5.5
#: ... plus the twin's quadrature's own error, relative (measured: < 2e-4 against twice the subdivisions).
ENV_QUADRATURE_RTOL = 1e-3
#: The directional albedo: the gl engine's scatter sum against the numpy quadrature, absolute per channel.
ALBEDO_ATOL = 1e-3
#: The angles of incidence (degrees) of ``check``'s albedo comparison.
ALBEDO_THETA = (20.0, 70.0)
#: The views ``check`` compares, and their sizes there: small (the spectral references run per pixel). The env view
#: is 12^2 at :data:`ENV_SPP` samples per pixel, compared at :data:`ENV_PIXELS` of them (the twin's exact integral costs
#: up to ~0.5 s a pixel); the albedo is
#: one row of :data:`ALBEDO_THETA`'s angles (the gl engine's scatter view at its own size, 512^2 or more).
CHECK_SIZES = {"gradient": (180, 1), "sphere": (32, 32), "lit": (32, 32), "slice": (32, 32), "scatter": (32, 32),
               "theta_v": (64, 1), "theta_h": (64, 1), "theta_d": (64, 1), "lobe3d": (32, 8),
               "textured": (32, 32), "env": (12, 12), "albedo": (len(ALBEDO_THETA), 1)}
#: Samples per pixel of ``check``'s env view, and the pixels across its disc where the twin's integral is compared.
ENV_SPP, ENV_PIXELS = 1024, 16


@dataclass(frozen=True)
class Tolerance:
    """A pixel passes when max over channels |GL - numpy| <= max(atol, rtol x value), value = the twin's largest |channel|."""

    name: str
    atol: float
    rtol: float = 0.0
    #: Monte Carlo images: this many of the pixel's standard error (its largest channel's) on top.
    standard_errors: float = 0.0

    def allowed(self, reference: np.ndarray, standard_error: np.ndarray | None = None) -> np.ndarray:
        allowed = np.maximum(self.atol, self.rtol * np.abs(reference).max(axis=-1))
        if self.standard_errors and standard_error is not None:
            allowed = allowed + self.standard_errors * np.asarray(standard_error, np.float64).max(axis=-1)
        return allowed


COLOUR_TOLERANCE = Tolerance(f"{GL_ATOL:g} absolute per channel", atol=GL_ATOL)
BRDF_TOLERANCE = Tolerance(f"{RTOL:g} x max(value, {FLOOR:g})", atol=RTOL * FLOOR, rtol=RTOL)
ENV_TOLERANCE = Tolerance(f"{ENV_STANDARD_ERRORS:g} standard errors + {ENV_QUADRATURE_RTOL:g} x value", atol=RTOL * FLOOR,
                          rtol=ENV_QUADRATURE_RTOL, standard_errors=ENV_STANDARD_ERRORS)
ALBEDO_TOLERANCE = Tolerance(f"{ALBEDO_ATOL:g} absolute per channel", atol=ALBEDO_ATOL)


def tolerance_for(view: str) -> Tolerance:
    """The colour views' absolute tolerance, the env view's statistical one, the albedo's, or the BRDF views' relative one."""
    return {"env": ENV_TOLERANCE, "albedo": ALBEDO_TOLERANCE}.get(view, COLOUR_TOLERANCE if view in COLOUR_VIEWS else BRDF_TOLERANCE)


def smooth_environment(width: int = 64, height: int = 32):
    """
    The env comparisons' environment (an :class:`explorer.views.env.EnvironmentMap`): a sky gradient, a tint
    along x and a broad glow toward (0.5, 0.6, 0.62), smooth at every scale, so that the twin's quadrature is
    converged and the Monte Carlo error is the only one.
    """
    from explorer.views.env import EnvironmentMap, uv_to_direction

    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    d = uv_to_direction(u[None, :], v[:, None])
    image = 0.5 + 0.3 * d[..., 1:2] * np.array([0.5, 1.0, 1.5]) + 0.2 * d[..., 0:1] * np.array([1.0, 0.5, 0.0])
    glow = np.array([0.5, 0.6, 0.62]) / np.linalg.norm([0.5, 0.6, 0.62])
    image = image + 2.0 * np.exp(-(1.0 - d @ glow) / 0.06)[..., None] * np.array([1.0, 0.9, 0.7])
    return EnvironmentMap(image.astype(np.float32), "<smooth>")


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
    #: A Monte Carlo GL image's standard error per pixel and channel (the env view), else None.
    standard_error: np.ndarray | None = None

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
    allowed = tolerance.allowed(reference, twins.standard_error)
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
    ``reflectance(cos_theta)``, the textured view when it declares ``# texture:``, the albedo when its twin
    declares both the ``numpy`` and ``gl`` albedo engines, the BRDF views, plots and env view always.
    """
    import re

    from explorer.materials.twins import capabilities_of

    has_reflectance = re.search(r"\bvec3\s+reflectance\s*\(", material.shader) is not None
    albedo = {"numpy", "gl"} <= set(capabilities_of(material).albedo)
    supported = {"textured": getattr(material, "texture", None) is not None, "albedo": albedo}
    return tuple(view for view in CHECK_SIZES
                 if supported.get(view, True) and (has_reflectance or view not in COLOUR_VIEWS))


def env_pixels(width: int, height: int, count: int | None = ENV_PIXELS) -> np.ndarray:
    """
    The env view's compared pixels: ``count`` spread evenly over the disc (its float32 rim left out), or every
    one of them (``count`` None). The twin's exact integral costs up to ~0.5 s a pixel for a spectral stack.
    """
    from explorer.views.geometry import brdf_view_geometry

    inside = brdf_view_geometry("lit", width, height)[5] & compared_pixels("env", width, height)  # the same sphere
    if count is None:
        return inside
    chosen = np.flatnonzero(inside)
    chosen = chosen[np.round(np.linspace(0, chosen.size - 1, min(count, chosen.size))).astype(int)]
    mask = np.zeros(inside.size, bool)
    mask[chosen] = True
    return mask.reshape(inside.shape)


def render_albedo_both(renderer, material, values, theta_deg=ALBEDO_THETA) -> Twins:
    """
    The directional albedo at ``theta_deg`` by the gl engine (:func:`explorer.views.albedo.albedo_gl`, at the size
    its twin's lobes need) and by the numpy quadrature (:func:`explorer.views.albedo.albedo_numpy`), as one row.
    """
    from explorer.views.albedo import albedo_gl, albedo_numpy, gl_size_for

    model = model_for(material, values)
    gl = albedo_gl(material, values, theta_deg, renderer=renderer, size=gl_size_for(model), model=model)
    reference = albedo_numpy(model, theta_deg)
    return Twins(np.asarray(gl, np.float64)[None], np.asarray(reference, np.float64)[None],
                 np.ones((1, len(theta_deg)), bool), "albedo")
