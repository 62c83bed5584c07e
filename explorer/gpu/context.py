"""
OpenGL contexts: a headless moderngl context through EGL (Mesa's llvmpipe without a GPU), and what
every program shares (the GLSL version, the full-screen vertex shader).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

from explorer.errors import LocatedError

GLSL_VERSION = "330 core"
EGL_PACKAGES = "libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri"

VERTEX_SHADER = f"""#version {GLSL_VERSION}
// A full-screen triangle from gl_VertexID: no vertex buffer needed.
void main() {{
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}}
"""


#: Bytes of one float image the host allocates and reads back at once (a render target, an input
#: texture): 1 GiB, an 8192 x 8192 float RGBA image. Past it, Mesa's llvmpipe reports float targets near
#: 2 GiB incomplete (11585 x 11585) or completes them and then overflows moderngl's 32-bit sizes on
#: readback (16384 x 8192: SIGSEGV); no GL query reports this, so it is the host's own budget.
MAX_IMAGE_BYTES = 1 << 30


class GLLimitError(LocatedError):
    """An image or texture beyond what this GL context allows (one line naming the limit)."""


@dataclass(frozen=True)
class GLLimits:
    """
    The sizes a GL context allows, read from it once (:func:`gl_limits`) and checked before allocating.

    Attributes
    ----------
    max_texture_size : int
        ``GL_MAX_TEXTURE_SIZE``: the largest side of a 2D texture.
    max_renderbuffer_size : int
        ``GL_MAX_RENDERBUFFER_SIZE``: the largest side of a render target.
    max_viewport : (int, int)
        ``GL_MAX_VIEWPORT_DIMS``.
    max_image_bytes : int
        :data:`MAX_IMAGE_BYTES`.
    max_texture_buffer_texels : int
        Texels of a buffer texture: GL 3.3's guaranteed ``GL_MAX_TEXTURE_BUFFER_SIZE`` (moderngl does not
        query it; the tables it holds have at most 4097).
    """

    max_texture_size: int
    max_renderbuffer_size: int
    max_viewport: tuple[int, int]
    max_image_bytes: int = MAX_IMAGE_BYTES
    max_texture_buffer_texels: int = 65536

    @property
    def max_target_side(self) -> tuple[int, int]:
        """The largest width and height of a float render target (renderbuffer, texture and viewport limits)."""
        side = min(self.max_renderbuffer_size, self.max_texture_size)
        return min(side, self.max_viewport[0]), min(side, self.max_viewport[1])

    def max_pixels(self, channels: int) -> int:
        """The most float32 pixels of ``channels`` channels within :attr:`max_image_bytes`."""
        return self.max_image_bytes // (4 * channels)

    def check_target(self, width: int, height: int, origin: str = "--size") -> None:
        """A ``width x height`` float RGBA render target, or :class:`GLLimitError` naming the limit."""
        max_w, max_h = self.max_target_side
        pixels = self.max_pixels(4)
        if not (1 <= width <= max_w and 1 <= height <= max_h and width * height <= pixels):
            square = min(max_w, max_h, int(pixels**0.5))
            raise GLLimitError(origin, None, (
                f"{width}x{height} is beyond what this GL allows: at most {max_w}x{max_h} "
                f"(GL_MAX_RENDERBUFFER_SIZE {self.max_renderbuffer_size}, GL_MAX_VIEWPORT_DIMS "
                f"{self.max_viewport[0]}x{self.max_viewport[1]}) and {pixels} pixels (a float image under "
                f"{self.max_image_bytes >> 20} MiB), e.g. {square}x{square}"))

    def check_texture(self, width: int, height: int, channels: int, origin: str) -> None:
        """A ``width x height`` float texture of ``channels`` channels, or :class:`GLLimitError` naming the limit."""
        side, pixels = self.max_texture_size, self.max_pixels(channels)
        if not (1 <= width <= side and 1 <= height <= side and width * height <= pixels):
            raise GLLimitError(origin, None, (
                f"a {width}x{height} image is beyond this GL's largest texture: at most {side} texels a side "
                f"(GL_MAX_TEXTURE_SIZE) and {pixels} texels (under {self.max_image_bytes >> 20} MiB); "
                f"downsample it"))

    def check_buffer_texture(self, texels: int, origin: str) -> None:
        """A buffer texture of ``texels`` texels, or :class:`GLLimitError` naming the limit."""
        if not 1 <= texels <= self.max_texture_buffer_texels:
            raise GLLimitError(origin, None, f"a table of {texels} entries is beyond a buffer texture's "
                                             f"{self.max_texture_buffer_texels} (GL_MAX_TEXTURE_BUFFER_SIZE)")

_LIMITS: "weakref.WeakKeyDictionary[object, GLLimits]" = weakref.WeakKeyDictionary()


def gl_limits(ctx) -> GLLimits:
    """The :class:`GLLimits` of a moderngl context, queried on first use and cached with it."""
    limits = _LIMITS.get(ctx)
    if limits is None:
        info = ctx.info
        viewport = info["GL_MAX_VIEWPORT_DIMS"]
        limits = _LIMITS[ctx] = GLLimits(
            int(info["GL_MAX_TEXTURE_SIZE"]), int(info["GL_MAX_RENDERBUFFER_SIZE"]), (int(viewport[0]), int(viewport[1]))
        )
    return limits


class GLUnavailable(RuntimeError):
    """No OpenGL 3.3 context could be created (one-line message naming what to install)."""


def create_context():
    """A headless moderngl context through EGL, or :class:`GLUnavailable` saying what is missing."""
    try:
        import moderngl
    except ImportError as error:  # pragma: no cover - a dependency of the package
        raise GLUnavailable(f"moderngl is not installed ({error}); run: python3 -m explorer") from None
    try:
        return moderngl.create_standalone_context(require=330, backend="egl")
    except Exception as error:  # glcontext raises plain Exceptions
        reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise GLUnavailable(
            f"no OpenGL through EGL ({reason}); install Mesa's EGL: apt-get install {EGL_PACKAGES}"
        ) from None
