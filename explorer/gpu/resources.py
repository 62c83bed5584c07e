"""
The one owner of the package's GL textures and framebuffers (after moderngl-window's resource owners).

Every texture and framebuffer the host makes comes from a :class:`GLResources` (the renderer's, shared
by the app's passes and panels): one factory for textures (float or 8-bit, from an array or empty,
filtered and wrapped as asked, or a buffer texture; checked against the context's limits), one for
framebuffers with their attachments, and one way to release both. What it made it releases:
:meth:`release` frees an object (a framebuffer with its attachments), :meth:`replace` rewrites a texture
in place or swaps it for a new one of another shape, and :meth:`close` (or leaving a ``with`` block)
frees everything still owned.
"""

from __future__ import annotations

import numpy as np

from explorer.gpu.context import GLLimitError, GLLimits, gl_limits

#: ``GL_SAMPLER_BUFFER``: the type (moderngl's ``Uniform.gl_type``) of a program's ``samplerBuffer`` uniform.
GL_SAMPLER_BUFFER = 0x8DC2
#: ``GL_UNSIGNED_INT_SAMPLER_BUFFER``: a ``usamplerBuffer`` uniform's.
GL_UNSIGNED_INT_SAMPLER_BUFFER = 0x8DD8
#: The buffer sampler types (moderngl leaves their uniforms unwritten: :func:`set_buffer_sampler`).
BUFFER_SAMPLERS = frozenset({GL_SAMPLER_BUFFER, GL_UNSIGNED_INT_SAMPLER_BUFFER})


def _opengl(ctx):
    """PyOpenGL's GL, ``ctx``'s pending error cleared: PyOpenGL checks glGetError after each call and would
    blame a moderngl call's unread error on its own."""
    from OpenGL import GL

    ctx.clear_errors()
    return GL


class BufferTexture:
    """
    A buffer texture (GL 3.1 core; GLSL ``samplerBuffer`` or ``usamplerBuffer``, read by
    ``texelFetch(table, i)``): RGBA texels, float32 or uint32, in a moderngl buffer. moderngl makes no
    such texture, so its texture object is made and bound through PyOpenGL; it has the ``size``,
    ``components``, ``dtype``, ``use``, ``write`` and ``release`` of a moderngl texture, which is all
    :class:`GLResources` and the renderer's draw ask of one.

    Why (docs/performance.md *Tabulated shading*): on Mesa's llvmpipe its ``texelFetch`` skips
    the 2D path's wrap and coordinate work (two float fetches and a ``mix``: ~13% less CPU than from a 2D
    texture), and a packed table (:mod:`explorer.gpu.packed_tables`) needs one fetch a lookup.
    """

    def __init__(self, ctx, data: np.ndarray):
        GL = _opengl(ctx)
        self.ctx = ctx
        self.buffer = ctx.buffer(data.tobytes())
        self.glo = int(GL.glGenTextures(1))
        GL.glBindTexture(GL.GL_TEXTURE_BUFFER, self.glo)
        texel_format = GL.GL_RGBA32UI if data.dtype == np.uint32 else GL.GL_RGBA32F
        GL.glTexBuffer(GL.GL_TEXTURE_BUFFER, texel_format, self.buffer.glo)
        GL.glBindTexture(GL.GL_TEXTURE_BUFFER, 0)
        self.size, self.components = (int(data.shape[1]), 1), 4
        self.dtype = "u4" if data.dtype == np.uint32 else "f4"

    def use(self, location: int = 0) -> None:
        GL = _opengl(self.ctx)
        GL.glActiveTexture(GL.GL_TEXTURE0 + location)  # moderngl sets the active unit before each of its own binds
        GL.glBindTexture(GL.GL_TEXTURE_BUFFER, self.glo)

    def write(self, data: bytes) -> None:
        self.buffer.write(data)

    def release(self) -> None:
        if self.glo:
            GL = _opengl(self.ctx)
            GL.glDeleteTextures([self.glo])
            self.glo = 0
            self.buffer.release()


def set_buffer_sampler(program, name: str, location: int) -> None:
    """Point ``program``'s buffer sampler ``name`` at texture unit ``location``: moderngl (5.13) does not
    write such a uniform (its value setter leaves it at unit 0)."""
    GL = _opengl(program.ctx)
    GL.glUseProgram(program.glo)  # moderngl binds its program before every draw
    GL.glUniform1i(program[name].location, location)


def buffer_textures_supported(ctx) -> bool:
    """Whether :class:`BufferTexture` works in ``ctx`` (PyOpenGL reaches its GL: one made and released)."""
    try:
        probe = BufferTexture(ctx, np.arange(8, dtype=np.float32).reshape(1, 2, 4))
        probe.release()
        return ctx.error == "GL_NO_ERROR"
    except Exception:  # no PyOpenGL, no GL library it can load, no texture buffers: 2D textures then
        return False


class GLResources:
    """Textures and framebuffers of one GL context, released by whoever made them: this object."""

    def __init__(self, ctx, limits: GLLimits | None = None):
        self.ctx = ctx
        self.limits = limits if limits is not None else gl_limits(ctx)
        self._owned: dict[int, object] = {}  # id -> object, in creation order
        self._wrappers: set[int] = set()  # framebuffers over textures owned elsewhere: released alone

    # -- textures ----------------------------------------------------------------------------------

    def texture(self, data: np.ndarray | None = None, *, size: tuple[int, int] | None = None, components: int = 3,
                dtype: str = "f4", linear: bool = False, repeat_x: bool = False, repeat_y: bool = False,
                origin: str = "texture", buffer: bool = False):
        """
        A texture of ``data`` (``(height, width)`` or ``(height, width, components)``; row 0 = texel row 0),
        or an empty one of ``size = (width, height)`` and ``components``. ``dtype``: ``"f4"`` (float) or
        ``"f1"`` (8 bits, ``data`` in bytes). Nearest or linear filtering, clamped unless repeated.
        Checked against the context's limits first (``origin`` names the input in the error).
        ``buffer``: a :class:`BufferTexture` of ``data``, one row of RGBA texels, ``dtype`` ``"f4"`` (float, a
        ``samplerBuffer``) or ``"u4"`` (uint32, a ``usamplerBuffer``).
        """
        import moderngl

        if buffer:
            return self._buffer_texture(data, dtype, origin)
        if data is not None:
            data = np.ascontiguousarray(data, dtype=np.float32 if dtype == "f4" else np.uint8)
            if data.ndim == 2:
                data = data[..., None]
            size, components = (data.shape[1], data.shape[0]), data.shape[2]
        if size is None:
            raise ValueError("a texture needs data or a size")
        self.limits.check_texture(int(size[0]), int(size[1]), components, origin)
        texture = self.ctx.texture(tuple(int(s) for s in size), components, None if data is None else data.tobytes(), dtype=dtype)
        texture.filter = (moderngl.LINEAR, moderngl.LINEAR) if linear else (moderngl.NEAREST, moderngl.NEAREST)
        texture.repeat_x, texture.repeat_y = repeat_x, repeat_y
        self._owned[id(texture)] = texture
        return texture

    def _buffer_texture(self, data: np.ndarray, dtype: str, origin: str) -> BufferTexture:
        data = np.ascontiguousarray(data, dtype=np.uint32 if dtype == "u4" else np.float32)
        if data.ndim != 3 or data.shape[0] != 1 or data.shape[2] != 4:
            raise ValueError(f"{origin}: a buffer texture takes one row of RGBA texels, not {data.shape}")
        self.limits.check_buffer_texture(data.shape[1], origin)
        texture = BufferTexture(self.ctx, data)
        self._owned[id(texture)] = texture
        return texture

    def replace(self, texture, data: np.ndarray | None = None, **options):
        """
        ``texture`` rewritten with ``data`` when the shape is the same, else released and replaced by a new
        one (:meth:`texture` with ``options``); ``texture`` may be None. Returns the texture to use.
        """
        dtype = options.get("dtype", "f4")
        if data is not None:
            array = np.ascontiguousarray(data, dtype={"f4": np.float32, "u4": np.uint32}.get(dtype, np.uint8))
            shape = (array.shape[1], array.shape[0])
            components = array.shape[2] if array.ndim == 3 else 1
            same_kind = (isinstance(texture, BufferTexture) == bool(options.get("buffer"))
                         and getattr(texture, "dtype", dtype) == dtype)
            if texture is not None and same_kind and texture.size == shape and texture.components == components:
                texture.write(array.tobytes())
                return texture
        elif texture is not None and texture.size == tuple(options.get("size", ())):
            return texture
        if texture is not None:
            self.release(texture)
        return self.texture(data, **options)

    # -- framebuffers ------------------------------------------------------------------------------

    def framebuffer(self, width: int, height: int, count: int = 1, *, texture: bool = True, dtype: str = "f4",
                    origin: str = "--size"):
        """
        A framebuffer of ``count`` RGBA attachments (NEAREST textures, or renderbuffers), checked against
        the limits; a driver that still finds it incomplete raises :class:`GLLimitError` too.
        """
        import moderngl

        self.limits.check_target(width, height, origin=origin)
        if texture:
            attachments = [self.texture(size=(width, height), components=4, dtype=dtype, origin=origin) for _ in range(count)]
        else:
            attachments = [self.ctx.renderbuffer((width, height), 4, dtype=dtype) for _ in range(count)]
            for attachment in attachments:
                self._owned[id(attachment)] = attachment
        try:
            framebuffer = self.ctx.framebuffer(color_attachments=attachments)
        except moderngl.Error as error:
            self.release(*attachments)
            raise GLLimitError(origin, None, f"{width}x{height}: this GL cannot allocate it ({' '.join(str(error).split())})") from None
        self._owned[id(framebuffer)] = framebuffer
        return framebuffer

    def wrap(self, attachments):
        """A framebuffer over textures already owned (drawn into once; :meth:`release` leaves them)."""
        framebuffer = self.ctx.framebuffer(color_attachments=list(attachments))
        self._owned[id(framebuffer)] = framebuffer
        self._wrappers.add(id(framebuffer))
        return framebuffer

    # -- release -----------------------------------------------------------------------------------

    def release(self, *objects) -> None:
        """Free ``objects`` (a framebuffer with the attachments it was made with); None is skipped."""
        for obj in objects:
            if obj is None:
                continue
            if hasattr(obj, "color_attachments") and id(obj) not in self._wrappers:
                self.release(*obj.color_attachments)
            if obj is self.ctx.fbo:  # GL unbinds a deleted framebuffer, moderngl's ctx.fbo would still name it
                self.default_framebuffer().use()
            self._wrappers.discard(id(obj))
            self._owned.pop(id(obj), None)
            obj.release()

    def default_framebuffer(self):
        """The window's framebuffer, or GL's framebuffer 0 in a standalone context."""
        return self.ctx.screen if self.ctx.screen is not None else self.ctx.detect_framebuffer(0)

    def owned(self) -> int:
        """How many objects are still owned (tests, leak checks)."""
        return len(self._owned)

    def close(self) -> None:
        """Release everything still owned, newest first."""
        for obj in reversed(list(self._owned.values())):
            obj.release()
        self._owned.clear()
        self._wrappers.clear()

    def __enter__(self) -> GLResources:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
