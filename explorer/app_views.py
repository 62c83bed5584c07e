"""
The explorer app's images: the headless renderer's views drawn progressively into offscreen textures.

Every image is drawn by :class:`explorer.gl.Renderer`'s own program and bindings
(:meth:`~explorer.gl.Renderer.program`, :meth:`~explorer.gl.Renderer.bind`) from the same
``shaders/views/*.glsl`` templates, into a float framebuffer of the view's size: the pixels equal
``Renderer.render``'s. What is added here is scheduling, so that the window never waits long:

* a view whose estimated cost fits the frame's budget is drawn whole;
* otherwise a preview at reduced resolution is drawn first (the only image while a slider is being
  dragged), then the full-resolution image is refined in horizontal bands (scissored draws into the
  full-size framebuffer, which give exactly the pixels of one full draw), a few per frame, top first.

Costs are learned per compiled program (milliseconds per pixel, each draw bounded by ``glFinish``).
:class:`DisplayPass` turns linear float images into 8-bit sRGB textures for ImGui (exposure, gamut
overlay, the compare split), on the GPU.
"""

from __future__ import annotations

import time
from typing import Mapping

import numpy as np

from .brd import Material
from .gl import GLSL_VERSION, VERTEX_SHADER, Renderer

#: Per-frame budget of GL work (ms): ~30 ms of drawing plus the UI's own frame keeps >= 15 fps.
FRAME_BUDGET_MS = 30.0
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
        self._vaos: dict[int, object] = {}

    # -- what to draw ------------------------------------------------------------------------------

    def request(
        self, material: Material, values: Mapping[str, object], view: str, size: tuple[int, int], *,
        light: tuple[float, float, float] | None = None, uniforms: Mapping[str, object] | None = None,
        dragging: bool = False,
    ) -> None:
        """What to show; a change restarts the image (``dragging``: stay on the preview)."""
        self.dragging = dragging
        key = (id(material), material.shader, _freeze(values), view, tuple(size), _freeze(light), _freeze(uniforms or {}))
        if key == self._key:
            return
        self._key = key
        self.material, self.values, self.view = material, dict(values), view
        self.light = None if light is None else tuple(float(c) for c in light)
        self.uniforms = dict(uniforms or {})
        if tuple(size) != self.size:
            self._allocate(tuple(size))
        self.has_preview = False
        self.refined_rows = 0
        self.complete = False
        self.error = None
        self.generation += 1

    def _allocate(self, size: tuple[int, int]) -> None:
        if self.full is not None:
            self._release(self.full)
        self.size = size
        self.full = self._framebuffer(size)

    def _framebuffer(self, size):
        texture = self.ctx.texture(size, 4, dtype="f4")
        import moderngl

        texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        return self.ctx.framebuffer(color_attachments=[texture])

    @staticmethod
    def _release(framebuffer) -> None:
        for attachment in framebuffer.color_attachments:
            attachment.release()
        framebuffer.release()

    # -- drawing -----------------------------------------------------------------------------------

    def _program(self):
        return self.renderer.program(self.material, self.view, self.values)

    def _draw(self, framebuffer, size, rows: tuple[int, int] | None = None) -> float:
        """Draw into ``framebuffer`` (rows ``[top, bottom)`` from the top only); returns ms (glFinish-bounded)."""
        program = self._program()
        self.renderer.bind(program, self.material, self.values, None, self.uniforms)
        if "light_direction" in program and self.light is not None:
            program["light_direction"].value = self.light
        if "resolution" in program:
            program["resolution"].value = (float(size[0]), float(size[1]))
        vao = self._vaos.get(id(program))
        if vao is None:
            vao = self._vaos[id(program)] = self.ctx.vertex_array(program, [])
        framebuffer.use()
        if rows is None:
            self.ctx.scissor = None
        else:
            top, bottom = rows  # GL rows count from the bottom
            self.ctx.scissor = (0, size[1] - bottom, size[0], bottom - top)
        start = time.perf_counter()
        vao.render(vertices=3)
        self.ctx.finish()
        elapsed = (time.perf_counter() - start) * 1e3
        self.ctx.scissor = None
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
        from .glsl import ShaderError

        spent = 0.0
        try:
            if not self.has_preview and self.refined_rows == 0:
                preview = self._preview_size(max(budget_ms, 4.0))
                if preview is None:
                    spent += self._draw(self.full, self.size)
                    self.refined_rows = self.size[1]
                    self.complete = True
                    return spent
                if preview != self.preview_size:
                    if self.preview is not None:
                        self._release(self.preview)
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
        width, height = self.size
        data = self.full.read(components=4, dtype="f4")
        image = np.frombuffer(data, dtype=np.float32).reshape(height, width, 4)[::-1, :, :3]
        return np.ascontiguousarray(image)

    def release(self) -> None:
        for framebuffer in (self.full, self.preview):
            if framebuffer is not None:
                self._release(framebuffer)
        for vao in self._vaos.values():
            vao.release()
        self.full = self.preview = None
        self._vaos = {}


DISPLAY_SHADER = f"""#version {GLSL_VERSION}
// Linear float images -> 8-bit sRGB for the screen: exposure, the gamut overlay, the compare split.
// Rows above `refined` (a GL v coordinate) come from the full image, the others from the preview.
uniform sampler2D full_a;
uniform sampler2D preview_a;
uniform float refined_a;
uniform sampler2D full_b;
uniform sampler2D preview_b;
uniform float refined_b;
uniform float split;      // x in [0, 1] where image b starts; > 1: image a only
uniform float exposure;
uniform bool gamut;       // mark colours outside sRGB (a negative channel or above white)
uniform vec2 resolution;
out vec4 frag_colour;

uniform bool accumulated_a;  // the full image holds sums of samples with their count in alpha (env)
uniform bool accumulated_b;

vec3 sample_image(sampler2D full, sampler2D preview, float refined, bool accumulated, vec2 uv) {{
    if (uv.y < refined) return texture(preview, uv).rgb;
    vec4 texel = texelFetch(full, ivec2(gl_FragCoord.xy), 0);
    return accumulated ? texel.rgb / max(texel.a, 1.0) : texel.rgb;
}}

float encode(float c) {{
    c = clamp(c, 0.0, 1.0);
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}}

void main() {{
    vec2 uv = gl_FragCoord.xy / resolution;
    bool b = uv.x >= split;
    vec3 rgb = exposure * (b ? sample_image(full_b, preview_b, refined_b, accumulated_b, uv)
                             : sample_image(full_a, preview_a, refined_a, accumulated_a, uv));
    vec3 colour = vec3(encode(rgb.r), encode(rgb.g), encode(rgb.b));
    if (gamut && (any(lessThan(rgb, vec3(-1e-6))) || any(greaterThan(rgb, vec3(1.0 + 1e-6))))) {{
        // A magenta and black hatching: visible on any colour, and the colour still shows in between.
        colour = mod(floor((gl_FragCoord.x + gl_FragCoord.y) / 3.0), 2.0) < 1.0 ? vec3(1.0, 0.0, 1.0) : colour * 0.5;
    }}
    if (split <= 1.0 && abs(gl_FragCoord.x - split * resolution.x) < 0.5) colour = vec3(1.0);
    frag_colour = vec4(colour, 1.0);
}}
"""


class AccumulatedImage:
    """
    A progressive env render (:class:`explorer.env.ProgressiveEnvRender`) as a source of
    :class:`DisplayPass`: its float texture of sample sums, divided by each pixel's count on the GPU
    (reading it back and encoding 512² pixels in numpy would cost ~40 ms a frame).
    """

    preview = None
    has_preview = False

    def __init__(self, render):
        self.render = render
        self.full = render._framebuffer  # attachment 0: the sums, the count in alpha
        self.size = (render.width, render.height)
        self.refined_rows = render.height

    @property
    def generation(self) -> tuple[int, int, int]:
        """Changes with every pass or band: the display redraws only then."""
        return (id(self.render), self.render.passes, self.render._band_rows)


class DisplayPass:
    """Draws one or two :class:`ProgressiveView` images into an RGBA8 texture for ``imgui.image``."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.program = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=DISPLAY_SHADER)
        self.vao = ctx.vertex_array(self.program, [])
        self._targets: dict[object, object] = {}
        self._drawn: dict[object, tuple] = {}  # what each target shows: redrawn only when that changes
        self._blank = ctx.texture((1, 1), 4, np.zeros(4, np.float32).tobytes(), dtype="f4")
        # Bound after each draw: moderngl rebinds its current framebuffer when it creates others, which
        # must never be the released temporary one.
        self._parking = ctx.framebuffer(color_attachments=[ctx.texture((1, 1), 4)])

    def target(self, key, size):
        """The RGBA8 texture shown for ``key`` (created or resized on demand)."""
        texture = self._targets.get(key)
        if texture is None or texture.size != tuple(size):
            if texture is not None:
                texture.release()
            texture = self._targets[key] = self.ctx.texture(tuple(size), 4)
            import moderngl

            texture.filter = (moderngl.NEAREST, moderngl.NEAREST)  # shown 1:1; and cheaper to sample
        return texture

    def _bind(self, view: ProgressiveView, suffix: str, unit: int) -> None:
        full = view.full.color_attachments[0]
        preview = view.preview.color_attachments[0] if (view.preview is not None and view.has_preview) else self._blank
        full.use(location=unit)
        preview.use(location=unit + 1)
        self.program[f"full_{suffix}"].value = unit
        self.program[f"preview_{suffix}"].value = unit + 1
        # The refined rows are the top ones, i.e. GL v >= 1 - rows / height. Neither a preview nor a row of
        # the new image yet (a view that got no budget this frame): the previous image, rather than black.
        if view.refined_rows == 0 and view.has_preview:
            refined = 2.0
        else:
            refined = 1.0 - view.refined_rows / view.size[1] if view.refined_rows else 0.0
        self.program[f"refined_{suffix}"].value = refined
        if f"accumulated_{suffix}" in self.program:
            self.program[f"accumulated_{suffix}"].value = isinstance(view, AccumulatedImage)

    def draw(self, key, a: ProgressiveView, b: ProgressiveView | None = None, *, split: float = 2.0,
             exposure: float = 1.0, gamut: bool = False):
        """The display texture of ``a`` (left of ``split``) and ``b`` (right of it); returns the texture."""
        texture = self.target(key, a.size)
        state = tuple((id(v), v.generation, v.refined_rows, v.has_preview) for v in (a, b) if v is not None)
        state += (split, exposure, gamut, texture.glo)
        if self._drawn.get(key) == state:
            return texture
        self._drawn[key] = state
        self._bind(a, "a", 0)
        self._bind(b if b is not None else a, "b", 2)
        for name, value in (("split", float(split) if b is not None else 2.0), ("exposure", float(exposure)),
                            ("gamut", bool(gamut)), ("resolution", (float(a.size[0]), float(a.size[1])))):
            if name in self.program:
                self.program[name].value = value
        # A framebuffer only for this draw: on llvmpipe, sampling a texture that is still attached to a
        # framebuffer makes every ImGui draw that shows it flush the window's whole scene (~25 ms each).
        framebuffer = self.ctx.framebuffer(color_attachments=[texture])
        framebuffer.use()
        self.vao.render(vertices=3)
        self._parking.use()
        framebuffer.release()
        return texture
