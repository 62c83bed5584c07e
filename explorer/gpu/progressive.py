"""
Views drawn progressively into offscreen float textures, so that an interactive window never waits long.

Every image is drawn by :class:`explorer.gpu.Renderer`'s own programs, bindings and draw primitive
(:meth:`~explorer.gpu.Renderer.program`, :meth:`~explorer.gpu.Renderer.bindings`,
:meth:`~explorer.gpu.Renderer.draw`) from the same ``shaders/views/*.glsl`` templates, into a float
framebuffer of the view's size: the pixels equal ``Renderer.render``'s. What is added here is how:

* a view whose estimated cost fits the frame's budget is drawn whole;
* otherwise a preview at reduced resolution is drawn first (the only image while a slider is being
  dragged), then the full-resolution image is refined in horizontal bands (scissored draws into the
  full-size framebuffer, which give exactly the pixels of one full draw), a few per frame, top first.

Costs are learned per compiled program (milliseconds per pixel, each draw bounded by ``glFinish``).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from explorer.materials.brd import Material
from explorer.materials.glsl import ShaderError
from explorer.gpu.renderer import Renderer

#: Smallest preview side (pixels).
PREVIEW_MIN = 16
#: First preview side when a program's cost is still unknown.
PREVIEW_PROBE = 32


def _freeze(value):
    if isinstance(value, Mapping):
        return tuple(sorted((k, _freeze(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple, np.ndarray)):
        return tuple(_freeze(v) for v in value)
    return value


class CostModel:
    """Milliseconds per pixel of each compiled program (exponential average of measured draws)."""

    def __init__(self):
        self._ms_per_pixel: dict[int, float] = {}

    def get(self, program) -> float | None:
        return self._ms_per_pixel.get(id(program))

    def update(self, program, pixels: int, elapsed_ms: float) -> None:
        if pixels < 64:
            return  # too small to measure anything but overhead
        sample = max(elapsed_ms, 0.01) / pixels
        old = self._ms_per_pixel.get(id(program))
        self._ms_per_pixel[id(program)] = sample if old is None else 0.5 * (old + sample)


class ProgressiveView:
    """
    One view of one material, drawn progressively into a float texture of ``size``.

    Call :meth:`request` every frame with what should be shown, then :meth:`work` with a time budget.
    ``complete`` tells whether the full-resolution image is done; :meth:`read` returns it.
    """

    def __init__(self, renderer: Renderer, costs: CostModel):
        self.renderer = renderer
        self.ctx = renderer.ctx
        self.costs = costs
        self._key = None
        self.size = (0, 0)
        self.full = None  # framebuffer of the full-resolution image
        self.preview = None  # framebuffer of the preview (its own size)
        self.preview_size = (0, 0)
        self.has_preview = False
        self.refined_rows = 0  # rows of `full` done, counted from the top of the image
        self.complete = False
        self.error: str | None = None
        self.dragging = False
        self.generation = 0  # bumped on every restart (callers cache derived data by it)
        self.last_draw_ms = 0.0
        self._summed = None  # a summed view's image (VIEW_REGISTRY's summed)

    # -- what to draw ------------------------------------------------------------------------------

    def request(
        self, material: Material, values: Mapping[str, object], view: str, size: tuple[int, int], *,
        light: tuple[float, float, float] | None = None, uniforms: Mapping[str, object] | None = None,
        dragging: bool = False, inputs: Mapping[str, object] | None = None, inputs_key=None, environment=None,
    ) -> None:
        """
        What to show; a change restarts the image (``dragging``: stay on the preview). ``inputs``: a view's own
        textures (a mesh's normals, :mod:`explorer.gpu.mesh`; the textured view's), as
        :meth:`explorer.gpu.Renderer.bindings` takes them, named by ``inputs_key`` (arrays are not compared;
        without a key, a new mapping object is a change). ``environment``: what a smooth mirror reflects in the
        lit view (an :class:`explorer.views.env.EnvironmentMap`, default the env view's; :meth:`explorer.gpu.Renderer.bindings`).
        """
        self.dragging = dragging
        key = (id(material), material.shader, _freeze(values), view, tuple(size), _freeze(light), _freeze(uniforms or {}),
               (inputs_key if inputs_key is not None else id(inputs)) if inputs else None,
               None if environment is None else (environment.name, id(environment.pixels), environment.rotation))
        if key == self._key:
            return
        self._key = key
        self.material, self.values, self.view = material, dict(values), view
        self.light = None if light is None else tuple(float(c) for c in light)
        self.uniforms = dict(uniforms or {})
        self.inputs = dict(inputs) if inputs else None
        self.environment = environment
        if tuple(size) != self.size:
            self._allocate(tuple(size))
        self.has_preview = False
        self.refined_rows = 0
        self.complete = False
        self.error = None
        self._summed = None
        self.generation += 1

    def _allocate(self, size: tuple[int, int]) -> None:
        if self.full is not None:
            self.renderer.resources.release(self.full)
        self.size = size
        self.full = self._framebuffer(size)

    def _framebuffer(self, size):
        return self.renderer.resources.framebuffer(*size, origin="view size")

    # -- drawing -----------------------------------------------------------------------------------

    def _program(self):
        return self.renderer.program(self.material, self.view, self.values)

    def _draw(self, framebuffer, size, rows: tuple[int, int] | None = None) -> float:
        """Draw into ``framebuffer`` (rows ``[top, bottom)`` from the top only); returns ms (glFinish-bounded)."""
        program = self._program()
        uniforms, textures = self.renderer.bindings(program, self.material, self.values, getattr(self, "inputs", None), self.uniforms,
                                                    getattr(self, "environment", None), draft=self.dragging)
        if self.light is not None:
            uniforms["light_direction"] = self.light
        elapsed = self.renderer.draw(program, framebuffer, uniforms=uniforms, textures=textures, rows=rows)
        pixels = size[0] * (size[1] if rows is None else rows[1] - rows[0])
        self.costs.update(program, pixels, elapsed)
        self.last_draw_ms = elapsed
        return elapsed

    def _preview_size(self, budget_ms: float) -> tuple[int, int] | None:
        """The preview size that fits ``budget_ms``, or None when the full image does."""
        width, height = self.size
        cost = self.costs.get(self._program())
        if cost is None:
            if width * height <= 64 * 64:
                return None
            scale = PREVIEW_PROBE / max(width, height)
        else:
            if cost * width * height <= budget_ms:
                return None
            scale = np.sqrt(budget_ms / (cost * width * height))
        scale = max(scale, PREVIEW_MIN / max(width, height))
        if scale >= 0.75:
            return None
        return max(1, int(round(width * scale))), max(1, int(round(height * scale)))

    def work(self, budget_ms: float) -> float:
        """Advance the image by about ``budget_ms`` of drawing; returns the ms spent."""
        if self._key is None or self.complete or self.error is not None:
            return 0.0
        spent = 0.0
        try:
            from explorer.views.geometry import VIEW_REGISTRY

            if self.view in VIEW_REGISTRY and VIEW_REGISTRY[self.view].summed:
                # Terms the host sums (the albedo curve): drawn whole, then read from the sum.
                import time

                start = time.perf_counter()
                self._summed = self.renderer.render(self.material, self.values, self.view, *self.size, uniforms=self.uniforms)
                self.refined_rows, self.complete = self.size[1], True
                return (time.perf_counter() - start) * 1e3
            if not self.has_preview and self.refined_rows == 0:
                preview = self._preview_size(max(budget_ms, 4.0))
                if preview is None:
                    spent += self._draw(self.full, self.size)
                    self.refined_rows = self.size[1]
                    self.complete = True
                    return spent
                if preview != self.preview_size:
                    if self.preview is not None:
                        self.renderer.resources.release(self.preview)
                    self.preview = self._framebuffer(preview)
                    import moderngl

                    self.preview.color_attachments[0].filter = (moderngl.LINEAR, moderngl.LINEAR)  # a smooth upscale
                    self.preview_size = preview
                spent += self._draw(self.preview, preview)
                self.has_preview = True
            if self.dragging:
                return spent
            width, height = self.size
            while self.refined_rows < height and spent < budget_ms:
                cost = self.costs.get(self._program()) or 1e-4
                rows = int(max(1, min(height - self.refined_rows, (budget_ms - spent) / max(cost * width, 1e-9))))
                spent += self._draw(self.full, self.size, (self.refined_rows, self.refined_rows + rows))
                self.refined_rows += rows
            self.complete = self.refined_rows >= height
        except ShaderError as error:
            self.error = str(error)
        return spent

    @property
    def progress(self) -> float:
        return self.refined_rows / self.size[1] if self.size[1] else 0.0

    def read(self) -> np.ndarray:
        """The full image, ``(height, width, 3)`` float32 linear RGB, rows from the top (as ``Renderer.render``)."""
        if self._summed is not None:
            return self._summed.copy()
        width, height = self.size
        data = self.full.read(components=4, dtype="f4")
        image = np.frombuffer(data, dtype=np.float32).reshape(height, width, 4)[::-1, :, :3]
        return np.ascontiguousarray(image)

    def release(self) -> None:
        for framebuffer in (self.full, self.preview):
            if framebuffer is not None:
                self.renderer.resources.release(framebuffer)
        self.full = self.preview = None
