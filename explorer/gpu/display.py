"""
The app's display pass: linear float images (:class:`~explorer.gpu.progressive.ProgressiveView`, or the
env view's sums) turned into 8-bit sRGB textures for ImGui (exposure, gamut overlay, the compare split),
on the GPU, through the renderer's draw primitive.
"""

from __future__ import annotations

import numpy as np

from explorer.gpu.context import GLSL_VERSION, VERTEX_SHADER
from explorer.gpu.progressive import ProgressiveView
from explorer.gpu.renderer import Renderer


DISPLAY_SHADER = """
// Linear float images -> 8-bit sRGB for the screen: exposure, the gamut overlay, the tone map, the compare
// split. Rows above `refined` (a GL v coordinate) come from the full image, the others from the preview.
#include "lib/tonemap.glsl"
uniform sampler2D full_a;
uniform sampler2D preview_a;
uniform float refined_a;
uniform sampler2D full_b;
uniform sampler2D preview_b;
uniform float refined_b;
uniform float split;      // x in [0, 1] where image b starts; > 1: image a only
uniform float exposure;
uniform bool gamut;       // mark colours outside sRGB (a negative channel or above white)
uniform int tonemap_curve;  // TONEMAP_NONE, TONEMAP_AGX, TONEMAP_ACES (lib/tonemap.glsl)
uniform vec2 resolution;
out vec4 frag_colour;

uniform bool accumulated_a;  // the full image holds sums of samples with their count in alpha (env)
uniform bool accumulated_b;

vec3 sample_image(sampler2D full, sampler2D preview, float refined, bool accumulated, vec2 uv) {
    if (uv.y < refined) return texture(preview, uv).rgb;
    vec4 texel = texelFetch(full, ivec2(gl_FragCoord.xy), 0);
    return accumulated ? texel.rgb / max(texel.a, 1.0) : texel.rgb;
}

float encode(float c) {
    c = clamp(c, 0.0, 1.0);
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

void main() {
    vec2 uv = gl_FragCoord.xy / resolution;
    bool b = uv.x >= split;
    vec3 rgb = exposure * (b ? sample_image(full_b, preview_b, refined_b, accumulated_b, uv)
                             : sample_image(full_a, preview_a, refined_a, accumulated_a, uv));
    vec3 shown = tonemap(rgb, tonemap_curve);
    vec3 colour = vec3(encode(shown.r), encode(shown.g), encode(shown.b));
    // The overlay judges the exposed linear colour, before the tone map (which brings everything into [0, 1]).
    if (gamut && (any(lessThan(rgb, vec3(-1e-6))) || any(greaterThan(rgb, vec3(1.0 + 1e-6))))) {
        // A magenta and black hatching: visible on any colour, and the colour still shows in between.
        colour = mod(floor((gl_FragCoord.x + gl_FragCoord.y) / 3.0), 2.0) < 1.0 ? vec3(1.0, 0.0, 1.0) : colour * 0.5;
    }
    if (split <= 1.0 && abs(gl_FragCoord.x - split * resolution.x) < 0.5) colour = vec3(1.0);
    frag_colour = vec4(colour, 1.0);
}
"""


UPSCALE_SHADER = f"""#version {GLSL_VERSION}
// An 8-bit sRGB preview stretched to the display's size (bilinear): on llvmpipe ~4x cheaper than the
// display pass at full size, whose float fetches and pow()s per pixel were most of a dragged frame's GL time.
uniform sampler2D encoded;
uniform vec2 resolution;
out vec4 frag_colour;

void main() {{ frag_colour = texture(encoded, gl_FragCoord.xy / resolution); }}
"""


def display_shader_source() -> str:
    """:data:`DISPLAY_SHADER` with the shader library's ``#include``s expanded (the tone map's GLSL twin)."""
    from explorer.materials.glsl import ShaderBuilder
    from explorer.resources import SHADER_DIR

    builder = ShaderBuilder(include_dirs=[SHADER_DIR], version=GLSL_VERSION)
    builder.add_source(DISPLAY_SHADER, "display pass (explorer/gpu/display.py)")
    return builder.build().code


class AccumulatedImage:
    """
    A progressive env render (:class:`explorer.gpu.env.ProgressiveEnvRender`) as a source of
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

    def __init__(self, renderer: Renderer):
        self.renderer = renderer
        self.ctx = ctx = renderer.ctx
        self.program = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=display_shader_source())
        self.upscale = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=UPSCALE_SHADER)
        self._targets: dict[object, object] = {}
        self._encoded: dict[object, object] = {}  # per key, a preview encoded at its own size (see draw)
        self._drawn: dict[object, tuple] = {}  # what each target shows: redrawn only when that changes
        self.resources = renderer.resources
        self._blank = self.resources.texture(np.zeros((1, 1, 4), np.float32))
        # Bound after each draw: moderngl rebinds its current framebuffer when it creates others, which
        # must never be the released temporary one.
        self._parking = self.resources.framebuffer(1, 1, dtype="f1", origin="display")

    def target(self, key, size):
        """The RGBA8 texture shown for ``key`` (created or resized on demand)."""
        # NEAREST: shown 1:1, and cheaper to sample.
        texture = self._targets[key] = self.resources.replace(self._targets.get(key), size=tuple(size), components=4,
                                                              dtype="f1", origin="display")
        return texture

    def _bindings(self, view: ProgressiveView, suffix: str, uniforms: dict, textures: dict) -> None:
        textures[f"full_{suffix}"] = view.full.color_attachments[0]
        textures[f"preview_{suffix}"] = view.preview.color_attachments[0] if (view.preview is not None and view.has_preview) else self._blank
        # The refined rows are the top ones, i.e. GL v >= 1 - rows / height. Neither a preview nor a row of
        # the new image yet (a view that got no budget this frame): the previous image, rather than black.
        if view.refined_rows == 0 and view.has_preview:
            refined = 2.0
        else:
            refined = 1.0 - view.refined_rows / view.size[1] if view.refined_rows else 0.0
        uniforms[f"refined_{suffix}"] = refined
        uniforms[f"accumulated_{suffix}"] = isinstance(view, AccumulatedImage)

    def draw(self, key, a: ProgressiveView, b: ProgressiveView | None = None, *, split: float = 2.0,
             exposure: float = 1.0, gamut: bool = False, tonemap: str = "none"):
        """
        The display texture of ``a`` (left of ``split``) and ``b`` (right of it), exposed and tone mapped by
        ``tonemap`` (:data:`explorer.views.tonemap.TONEMAPS`); returns the texture.
        """
        from explorer.views.tonemap import TONEMAPS, check_tonemap

        texture = self.target(key, a.size)
        state = tuple((id(v), v.generation, v.refined_rows, v.has_preview) for v in (a, b) if v is not None)
        state += (split, exposure, gamut, tonemap, texture.glo)
        if self._drawn.get(key) == state:
            return texture
        self._drawn[key] = state
        uniforms = {"split": float(split) if b is not None else 2.0, "exposure": float(exposure), "gamut": bool(gamut),
                    "tonemap_curve": TONEMAPS.index(check_tonemap(tonemap))}
        textures: dict[str, object] = {}
        self._bindings(a, "a", uniforms, textures)
        self._bindings(b if b is not None else a, "b", uniforms, textures)
        if b is None and not gamut and uniforms["refined_a"] > 1.0:
            # Only a preview to show (a slider is moving): encoded at the preview's size, then stretched
            # (the gamut hatching, drawn per screen pixel, keeps the full-size pass).
            encoded = self._encoded[key] = self.resources.replace(self._encoded.get(key), size=tuple(a.preview_size), components=4,
                                                                  dtype="f1", origin="display")
            import moderngl

            encoded.filter = (moderngl.LINEAR, moderngl.LINEAR)
            self._pass(self.program, encoded, uniforms, textures)
            self._pass(self.upscale, texture, {}, {"encoded": encoded})
            return texture
        self._pass(self.program, texture, uniforms, textures)
        return texture

    def _pass(self, program, texture, uniforms: dict, textures: dict) -> None:
        """One draw of ``program`` into ``texture``, not waited for."""
        # A framebuffer only for this draw: on llvmpipe, sampling a texture that is still attached to a
        # framebuffer makes every ImGui draw that shows it flush the window's whole scene (~25 ms each).
        framebuffer = self.resources.wrap([texture])
        self.renderer.draw(program, framebuffer, uniforms=uniforms, textures=textures, finish=False)
        self._parking.use()
        self.resources.release(framebuffer)
