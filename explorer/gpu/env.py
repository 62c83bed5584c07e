"""
The ``env`` view on the GPU: progressive Monte Carlo under an environment map (``shaders/views/env.glsl``;
the estimator and the direction convention are described in :mod:`explorer.views.env`, whose exact integral
is its numpy twin), every pass through the renderer's draw primitive.
"""

from __future__ import annotations

import time
from typing import Callable, Mapping

import numpy as np

from explorer.errors import LocatedError
from explorer.views.env import (
    ENVIRONMENT_SHARE_MAX, ENVIRONMENT_SHARE_SCALE, EnvironmentMap, env_integral_numpy, environment_sampling_tables,
    environment_solid_angle,
)
from explorer.views.geometry import disc
from explorer.gpu.renderer import Renderer

#: The share of samples drawn from the environment before it followed the material (one-sample MIS with the
#: material's own sampling, the balance heuristic: shaders/views/env.glsl); ``environment_sampling=`` this
#: fixes it. By default each pixel's share follows its lobes (:func:`explorer.views.env.environment_share`).
ENVIRONMENT_SAMPLING_WEIGHT = 0.5
#: A pass of ProgressiveEnvRender aims at this many milliseconds (a UI stays responsive).
PASS_BUDGET_MS = 50.0
#: Samples per pixel in one pass at most (the shader's loop).
MAX_SAMPLES_PER_PASS = 256


def environment_texture(resources, environment: EnvironmentMap):
    """``environment`` as a float RGB texture (``resources``: the renderer's :class:`explorer.gpu.resources.GLResources`):
    LINEAR, repeat in u, clamp in v, row 0 at v = 0. Beyond GL_MAX_TEXTURE_SIZE the driver would make no
    texture and sampling read zeros: the limits are checked first."""
    return resources.texture(environment.pixels.reshape(environment.height, environment.width, 3), linear=True,
                             repeat_x=True, origin=environment.name)


#: The most samples per pixel: the float32 count (alpha) of the sums stops growing at 2^24, and the mean
#: would then be silently wrong.
MAX_SPP = 1 << 24

#: The first band of :meth:`ProgressiveEnvRender.advance` when a pixel's cost is not yet known: rows
#: holding at least this many pixels of the disc (about one row through the middle of a 512² sphere).
BAND_PROBE_PIXELS = 512
#: A pixel outside the disc costs this fraction of one inside (it returns at once: env.glsl's main).
OUTSIDE_PIXEL_WEIGHT = 0.02


def disc_weights(width: int, height: int) -> np.ndarray:
    """
    Per row from the top, the cost of a sample in pixels of the disc: the pixels inside it (as the
    shader decides, :func:`explorer.views.geometry.disc`) plus :data:`OUTSIDE_PIXEL_WEIGHT` per other pixel.
    A band's cost is proportional to its weight, not its rows: the top rows of the sphere are cheap.
    """
    _, _, r2 = disc(width, height)
    inside = (r2 < np.float32(1.0)).sum(axis=1)
    return inside + OUTSIDE_PIXEL_WEIGHT * (width - inside)


class ProgressiveEnvRender:
    """
    Progressive Monte Carlo rendering of the env view on the GPU (``shaders/views/env.glsl``).

    Samples accumulate in two float32 RGBA textures by additive blending: the sum of the samples (and
    their count, alpha) and the sum of their squares (and, alpha, the samples whose BRDF was NaN or
    infinite, counted as 0);
    :meth:`image` divides by :attr:`samples`, :meth:`standard_error` is the per-pixel standard error
    of that mean. Random numbers hash (pixel, sample index, seed): a render is reproducible, the same
    however its samples are split into passes.

    Parameters
    ----------
    renderer : explorer.gpu.Renderer
        Its programs, bindings and draw primitive are reused (:meth:`~explorer.gpu.Renderer.program`,
        :meth:`~explorer.gpu.Renderer.bindings`, :meth:`~explorer.gpu.Renderer.draw`).
    material : explorer.materials.brd.Material
    values : mapping
        The material's resolved parameter values.
    environment : EnvironmentMap
    width, height : int
    seed : int, optional
        Selects an independent sequence of random numbers (0 to 2^32 - 1).
    pass_budget_ms : float, optional
        Target duration of one pass; the samples per pass adapt to it (at least 1, at most
        :data:`MAX_SAMPLES_PER_PASS`).

    Notes
    -----
    Each pass is an additive draw (:meth:`explorer.gpu.Renderer.draw`), which leaves ``BLEND`` disabled
    as the other views expect. Float32 sums limit the relative precision of the variance to about
    ``1e-7 n / (SE/mean)^2``, far below the statistical error for any realistic sample count.
    """

    def __init__(
        self, renderer, material, values: Mapping[str, object], environment: EnvironmentMap, width: int, height: int,
        *, seed: int = 0, pass_budget_ms: float = PASS_BUDGET_MS, mesh=None, background: bool = False,
        environment_sampling: float | None = None, surface=None,
    ):
        if not 0 <= int(seed) < 1 << 32:
            raise ValueError(f"seed must be in [0, 2^32), got {seed}")
        if mesh is not None and surface is not None and mesh.uvs is None:
            raise LocatedError("--mesh", None, f"{mesh.name} has no texture coordinates ('vt'): no surface texture on it")
        self.renderer = renderer
        self.ctx = renderer.ctx
        self.material = material
        self.environment = environment
        self.width, self.height = int(width), int(height)
        self.seed = int(seed)
        self.pass_budget_ms = float(pass_budget_ms)
        #: Samples per pixel of the next pass (adapted after each pass to :attr:`pass_budget_ms`).
        self.samples_per_pass = 1
        #: Duration of the last pass in milliseconds (bounded by glFinish), None before the first.
        self.last_pass_ms: float | None = None
        #: Measured cost of one sample over the whole image (ms), None before the first.
        self.sample_ms: float | None = None
        #: Measured cost of one sample of one pixel of the disc (ms; :func:`disc_weights`), None before the first band.
        self.pixel_ms: float | None = None
        renderer.limits.check_target(self.width, self.height)  # before the environment's texture
        self._texture = environment_texture(renderer.resources, environment)
        if environment_sampling is not None and not 0.0 <= float(environment_sampling) < 1.0:
            raise ValueError(f"environment_sampling must be in [0, 1), got {environment_sampling}")
        #: The share of samples drawn from the environment's luminance (explorer.views.env.environment_sampling_tables):
        #: None, each pixel's own (explorer.views.env.environment_share, at most ENVIRONMENT_SHARE_MAX); a number, fixed.
        self.environment_sampling = None if environment_sampling is None else float(environment_sampling)
        self._share_scale = ENVIRONMENT_SHARE_SCALE / environment_solid_angle(environment)
        marginal, conditional = environment_sampling_tables(environment)
        self._marginal = renderer.resources.texture(marginal, origin=environment.name)
        self._conditional = renderer.resources.texture(conditional, origin=environment.name)
        self._framebuffer = renderer.target(self.width, self.height, count=2, texture=True)
        #: A mesh drawn instead of the sphere (explorer.gpu.mesh): its rasterised normals and texture coordinates, read
        #: by views/mesh/env.glsl.
        self._mesh_normals = self._mesh_uvs = None
        if mesh is not None:
            from explorer.gpu.mesh import mesh_surface

            normals, uvs = mesh_surface(renderer, mesh, self.width, self.height)
            self._mesh_normals = renderer.resources.texture(normals, origin="--mesh")
            self._mesh_uvs = renderer.resources.texture(uvs, origin="--mesh")
        self._row_weights = disc_weights(self.width, self.height)
        self._cumulative_weights = np.concatenate([[0.0], np.cumsum(self._row_weights)])
        self._targets = list(self._framebuffer.color_attachments)
        self.values = dict(values)
        #: Off the object, the environment behind it (exact, no samples needed), else black.
        self.background = bool(background)
        #: The material's surface texture (explorer.views.surface_texture), or None.
        self.surface = surface
        self._surface_textures: dict = {}
        # A program keeps its uniforms between renders: an untextured render must say so.
        self._surface_uniforms: dict = {"textured": False}
        self.reset()

    def reset(self, values: Mapping[str, object] | None = None) -> None:
        """Drop every sample; with ``values``, render the material with those parameters from now on."""
        if values is not None:
            self.values = dict(values)
        self.program = self.renderer.program(self.material, "env" if self._mesh_normals is None else "mesh/env", self.values)
        if self.surface is not None:  # uploaded once per reset (a textured mirror's table follows its values)
            self.renderer.resources.release(*self._surface_textures.values())
            arguments = self.surface.gl_arguments(self.material, self.values, self.width, self.height)
            self._surface_textures = {name: self.renderer.resources.texture(array, origin=name)
                                      for name, array in arguments["inputs"].items()}
            self._surface_uniforms = {**arguments["uniforms"], "textured": True}
        self._framebuffer.use()
        self._framebuffer.clear(0.0, 0.0, 0.0, 0.0)
        #: Samples per pixel so far (complete ones: rows of a band hold one more, see :meth:`advance`).
        self.samples = 0
        self.passes = 0
        self._band_rows = 0  # rows done of the sample in progress by bands

    def _bindings(self) -> dict:
        """The program's uniforms and textures for :meth:`_pass` (the material's, the environment, the seed)."""
        uniforms, textures = self.renderer.bindings(self.program, self.material, self.values)
        uniforms["seed"] = self.seed
        uniforms["environment_turn"] = self.environment.turn
        uniforms["show_background"] = self.background
        adaptive = self.environment_sampling is None
        uniforms["environment_sampling_weight"] = ENVIRONMENT_SHARE_MAX if adaptive else self.environment_sampling
        uniforms["environment_share_scale"] = self._share_scale if adaptive else -1.0
        textures["environment_marginal"] = self._marginal
        textures["environment_conditional"] = self._conditional
        uniforms.update(self._surface_uniforms)
        textures.update(self._surface_textures)
        textures["environment"] = self._texture
        if self._mesh_normals is not None:
            textures["mesh_normals"] = self._mesh_normals
            textures["mesh_uvs"] = self._mesh_uvs
        return {"uniforms": uniforms, "textures": textures}

    def _pass(self, bindings: dict, count: int, rows: tuple[int, int] | None = None) -> float:
        """Add ``count`` samples (numbered from :attr:`samples`) to rows ``[top, bottom)`` (all: None); ms."""
        uniforms = {**bindings["uniforms"], "samples_per_pass": count, "first_sample": self.samples}
        return self.renderer.draw(self.program, self._framebuffer, uniforms=uniforms, textures=bindings["textures"],
                                  rows=rows, additive=True)

    def step(self, spp: int = 1) -> None:
        """Add ``spp`` samples per pixel, in passes of about :attr:`pass_budget_ms` each."""
        spp = int(spp)
        if spp < 1:
            raise ValueError(f"spp must be at least 1, got {spp}")
        self._finish_band()
        bindings = self._bindings()
        remaining = spp
        while remaining > 0:
            count = min(remaining, self.samples_per_pass)
            self.last_pass_ms = self._pass(bindings, count)
            self.passes += 1
            self.samples += count
            remaining -= count
            per_sample = max(self.last_pass_ms / count, 1e-3)
            self.sample_ms = per_sample
            self.pixel_ms = per_sample / self._cumulative_weights[-1]
            self.samples_per_pass = int(min(MAX_SAMPLES_PER_PASS, max(1, self.pass_budget_ms // per_sample)))

    def advance(self, budget_ms: float) -> None:
        """
        Add samples for about ``budget_ms``: whole passes when one sample of the whole image fits, or else
        one sample in bands of rows, so that an interactive caller never waits much longer than its budget
        for an expensive material (a two-layer stack's 471 wavelengths cost seconds per sample at 512² on
        llvmpipe). A band's rows are chosen by their pixels inside the disc (:func:`disc_weights`) at the
        measured cost per pixel: the first band of a render is a probe of :data:`BAND_PROBE_PIXELS` (at most
        a 16th of the image), so that even its first frame keeps to the budget. Pixels of a band hold one
        sample more than :attr:`samples` until the sample is complete.
        """
        budget_ms = max(float(budget_ms), 1.0)
        if self._band_rows == 0 and self.sample_ms is not None and self.sample_ms <= budget_ms:
            self.step(max(1, min(MAX_SAMPLES_PER_PASS, int(budget_ms // self.sample_ms))))
            return
        start = time.perf_counter()
        bindings = self._bindings()  # new tables' uploads count against the budget
        spent = (time.perf_counter() - start) * 1e3
        bands = 0
        while spent < budget_ms or bands == 0:  # at least one row a call: progress whatever the estimate
            top = self._band_rows
            done = self._cumulative_weights[top]
            if self.pixel_ms is None:  # a probe: at most 1/16 of the image
                wanted = min(BAND_PROBE_PIXELS, self._cumulative_weights[-1] / 16.0)
            else:
                wanted = (budget_ms - spent) / self.pixel_ms
                if wanted < self._row_weights[top] and bands:
                    break  # the next row would overrun the budget: the next frame's
            bottom = int(np.searchsorted(self._cumulative_weights, done + wanted, side="right")) - 1
            bottom = min(self.height, max(top + 1, bottom))
            elapsed = self._pass(bindings, 1, (top, bottom))
            spent += elapsed
            bands += 1
            self.pixel_ms = max(elapsed / max(self._cumulative_weights[bottom] - done, 1e-9), 1e-9)
            self._band_rows = bottom
            if bottom >= self.height:
                self.sample_ms = self.pixel_ms * self._cumulative_weights[-1]
                self.samples += 1
                self.passes += 1
                self._band_rows = 0
                break

    def _finish_band(self) -> None:
        """Complete a sample left in bands by :meth:`advance` (whole-image passes assume equal counts)."""
        if self._band_rows == 0:
            return
        self._pass(self._bindings(), 1, (self._band_rows, self.height))
        self.samples += 1
        self.passes += 1
        self._band_rows = 0

    def _read(self, attachment: int) -> np.ndarray:
        data = self._framebuffer.read(components=4, attachment=attachment, dtype="f4")
        return np.frombuffer(data, dtype=np.float32).reshape(self.height, self.width, 4)[::-1]

    def image(self) -> np.ndarray:
        """The mean so far, ``(height, width, 3)`` float32 linear RGB, rows from the top (0 before any sample)."""
        if self.samples == 0 and self._band_rows == 0:
            return np.zeros((self.height, self.width, 3), dtype=np.float32)
        if self._band_rows == 0:
            return np.ascontiguousarray(self._read(0)[:, :, :3] / np.float32(self.samples))
        first = self._read(0)  # a sample in progress: each pixel's own count (alpha)
        return np.ascontiguousarray(first[:, :, :3] / np.maximum(first[:, :, 3:], np.float32(1.0)))

    def sums(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(sum, sum of squares, count, dropped)`` per pixel as accumulated (float64, rows from the top)."""
        first, second = self._read(0).astype(np.float64), self._read(1).astype(np.float64)
        return first[:, :, :3], second[:, :, :3], first[:, :, 3], second[:, :, 3]

    def standard_error(self) -> np.ndarray:
        """
        The standard error of :meth:`image` per pixel and channel, ``sqrt(s^2 / n)`` with the unbiased
        sample variance ``s^2``; ``(height, width, 3)`` float32, infinite before two samples.
        """
        if self.samples < 2:
            return np.full((self.height, self.width, 3), np.inf, dtype=np.float32)
        total, squares, count, _ = self.sums()
        n = count[..., None]  # each pixel's own count: rows of a sample in progress hold one more
        mean = total / n
        variance = np.maximum(squares / n - mean * mean, 0.0) * (n / (n - 1))
        return np.sqrt(variance / n).astype(np.float32)

    def dropped_samples(self) -> int:
        """Samples where the material's BRDF returned NaN or infinity, counted as 0 (0 for a sound material)."""
        return int(round(float(self.sums()[3].sum())))

    def release(self) -> None:
        """Free the GL objects (textures, framebuffer)."""
        self.renderer.resources.release(self._framebuffer, self._texture, self._mesh_normals, self._mesh_uvs, self._marginal, self._conditional,
                                        *self._surface_textures.values())
        self._surface_textures = {}


def render_env(
    material, values: Mapping[str, object], width: int, height: int, *, engine: str = "gl",
    environment: EnvironmentMap | None = None, spp: int = 64, renderer=None, seed: int = 0,
    progress: Callable[[int, int], None] | None = None, warn: Callable[[str], None] | None = None, mesh=None,
    background: bool = False, surface=None,
) -> np.ndarray:
    """
    The env view of ``material`` as an image: the GPU's Monte Carlo mean after ``spp`` samples per pixel
    (``engine="gl"``), or the numpy twin's exact integral (``engine="numpy"``, :func:`env_integral_numpy`;
    tens of milliseconds per pixel, ``spp`` unused). ``progress(done, total)`` reports samples per
    pixel (gl) or pixels (numpy); ``warn(message)`` is told of samples dropped as non-finite. ``mesh`` (an
    :class:`explorer.views.mesh.Mesh`) is drawn instead of the sphere; ``background``: the environment behind it. ``surface``: the
    material's surface texture (:mod:`explorer.views.surface_texture`; no prefiltering), or None (not with a mesh).
    """
    if not 1 <= spp <= MAX_SPP:
        raise LocatedError("--spp", None, f"{spp} samples per pixel: at least 1 and at most {MAX_SPP} (a float32 count)")
    environment = EnvironmentMap.default() if environment is None else environment
    if engine == "numpy":
        from explorer.materials.models import model_for

        model = model_for(material, values)
        return env_integral_numpy(model, environment, width, height, progress=progress, mesh=mesh, background=background,
                                  surface=surface)
    renderer = Renderer() if renderer is None else renderer
    render = ProgressiveEnvRender(renderer, material, values, environment, width, height, seed=seed, mesh=mesh,
                                  background=background, surface=surface)
    try:
        while render.samples < spp:
            render.step(min(spp - render.samples, max(1, render.samples_per_pass)))
            if progress is not None:
                progress(render.samples, spp)
        dropped = render.dropped_samples()
        if dropped and warn is not None:
            warn(f"{dropped} samples counted as 0: the material's BRDF returned NaN or infinity there")
        return render.image()
    finally:
        render.release()
