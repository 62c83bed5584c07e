"""
The OpenGL host: builds a material's shader program for a view, uploads the tables, renders.

One program per (material, view): the preprocessor (:mod:`explorer.glsl`) assembles the material's
parameter uniforms, its shader section and the view template; compile errors name the real file and
line. Headless rendering uses a moderngl standalone EGL context (Mesa's llvmpipe without a GPU).
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from pathlib import Path
from typing import Mapping

import numpy as np

from . import colorimetry, luts
from .brd import Material, round_integer
from .glsl import ShaderBuilder, ShaderError
from .models import model_for
from .resources import SHADER_DIR

GLSL_VERSION = "330 core"

EGL_PACKAGES = "libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri"
#: Numpy models (and their tables) kept by :meth:`Renderer.bind`: an interactive session goes back and
#: forth between a few parameter sets (a slider and its start, compare A | B), and a table costs ~10 ms.
MODEL_CACHE_SIZE = 8

VERTEX_SHADER = f"""#version {GLSL_VERSION}
// A full-screen triangle from gl_VertexID: no vertex buffer needed.
void main() {{
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}}
"""


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


def specialisation(material: Material, values: Mapping[str, object]) -> tuple[tuple[str, int], ...]:
    """
    The constants compiled into ``material``'s program: its ``# specialise:`` parameters' values, rounded
    as the uniforms and the numpy models round them (:func:`explorer.brd.round_integer`).
    """
    return tuple((name, round_integer(values[name])) for name in material.specialised)


def build_program_source(material: Material, view: str, constants: tuple[tuple[str, int], ...] = ()):
    """
    The fragment shader of ``material`` in ``view`` (an :class:`explorer.glsl.Program`).

    Each ``(name, value)`` of ``constants`` becomes ``#define SPECIALISED_name value``: the shader
    can branch at compile time on a parameter such as ``method`` (one smaller program per value).
    """
    template = SHADER_DIR / "views" / f"{view}.glsl"
    if not template.exists():
        raise ShaderError(str(template), None, f"no such view {view!r}")
    builder = ShaderBuilder(include_dirs=[SHADER_DIR], version=GLSL_VERSION)
    for name, value in constants:
        builder.define(f"SPECIALISED_{name}", value)
    builder.add_source(material.uniform_declarations(), f"{material.path} (parameters)")
    builder.add_source(material.shader, str(material.path), material.shader_line)
    builder.add_file(template)
    return builder.build()


class Renderer:
    """Renders material views into float32 images; caches programs and library textures."""

    def __init__(self, ctx=None):
        self.ctx = ctx if ctx is not None else create_context()
        self._programs: dict[tuple, object] = {}
        self._library = self._library_textures()
        self._model_textures: dict[str, object] = {}
        self._inputs: dict[str, object] = {}
        self._vertex_arrays: dict[int, object] = {}
        self.last_table_ms: float | None = None
        # (material path, model, values) -> [model, its textures() or None], least recently used first.
        self._models: OrderedDict[tuple, list] = OrderedDict()
        self._models_lock = threading.Lock()  # prepare_model may fill the cache from another thread
        self._model_texture_keys: dict[str, tuple] = {}  # which model's table each model texture holds

    # -- resources ---------------------------------------------------------------------------------

    def _texture_row(self, data: np.ndarray, linear: bool):
        data = np.ascontiguousarray(data, dtype=np.float32).reshape(1, -1, 3)
        texture = self.ctx.texture((data.shape[1], 1), 3, data.tobytes(), dtype="f4")
        import moderngl

        texture.filter = (moderngl.LINEAR, moderngl.LINEAR) if linear else (moderngl.NEAREST, moderngl.NEAREST)
        texture.repeat_x = texture.repeat_y = False
        return texture

    def _model_texture(self, name: str, table: np.ndarray):
        """
        The linearly filtered texture of a model's table, rewritten in place when its shape is unchanged:
        ``(width, 3)`` is a row (height 1), ``(height, width, 3)`` a 2D table (row 0 = texel row 0).
        """
        import moderngl

        data = np.ascontiguousarray(table, dtype=np.float32)
        if data.ndim == 2:
            data = data.reshape(1, -1, 3)
        size = (data.shape[1], data.shape[0])
        texture = self._model_textures.get(name)
        if texture is not None and texture.size == size:
            texture.write(data.tobytes())
            return texture
        if texture is not None:
            texture.release()
        texture = self._model_textures[name] = self.ctx.texture(size, 3, data.tobytes(), dtype="f4")
        texture.filter = (moderngl.LINEAR, moderngl.LINEAR)
        texture.repeat_x = texture.repeat_y = False
        return texture

    def _library_textures(self) -> dict[str, object]:
        return {
            "cmf_1nm": self._texture_row(luts.load("cmf_1nm"), linear=False),
            "cmf_cumulative": self._texture_row(luts.load("cmf_cumulative"), linear=True),
            # (2, 4096, 3): a 4096 x 2 texture, row 0 real and row 1 imaginary parts (lib/thinfilm.glsl texelFetches).
            "sensitivity_fourier": self.ctx.texture((luts.SENSITIVITY_FOURIER_COUNT, 2), 3, luts.load("sensitivity_fourier").astype("f4").tobytes(), dtype="f4"),
        }

    def program(self, material: Material, view: str, values: Mapping[str, object] | None = None):
        """The compiled program (cached), or :class:`ShaderError` naming the file and line."""
        constants = specialisation(material, values if values is not None else material.resolve())
        key = (str(material.path), material.shader, material.uniform_declarations(), view, constants)
        if key not in self._programs:
            import moderngl

            source = build_program_source(material, view, constants)
            try:
                program = self.ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=source.code)
            except moderngl.Error as error:
                raise ShaderError(*_first_error(source, str(error))) from None
            self._programs[key] = program
        return self._programs[key]

    # -- rendering ---------------------------------------------------------------------------------

    def _input_textures(self, inputs: Mapping[str, np.ndarray]) -> dict[str, object]:
        """A view's per-render inputs (``(h, w)`` or ``(h, w, c)`` float arrays, row 0 = texel row 0) as NEAREST textures."""
        import moderngl

        for texture in self._inputs.values():
            texture.release()
        self._inputs = {}
        for name, array in inputs.items():
            data = np.ascontiguousarray(array, dtype=np.float32)
            if data.ndim == 2:
                data = data[..., None]
            texture = self.ctx.texture((data.shape[1], data.shape[0]), data.shape[2], data.tobytes(), dtype="f4")
            texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            texture.repeat_x = texture.repeat_y = False
            self._inputs[name] = texture
        return self._inputs

    def bind(
        self, program, material: Material, values: Mapping[str, object],
        inputs: Mapping[str, np.ndarray] | None = None, uniforms: Mapping[str, object] | None = None,
    ) -> None:
        """
        Set the material's uniforms and bind the library and model textures; ``inputs`` (a view's
        textures, e.g. the textured view's D_inc) and ``uniforms`` (a view's flags) where the program has them.
        ``int`` parameters are uploaded as :meth:`explorer.brd.Material.physical_values` has them (exact integers).
        """
        values = material.physical_values(values)
        for parameter in material.parameters:
            if parameter.name not in program:
                continue  # unused by the shader: optimised away
            value = values[parameter.name]
            if parameter.type == "bool":
                program[parameter.name].value = bool(value)
            elif parameter.type == "color":
                program[parameter.name].value = tuple(float(v) for v in value)
            else:
                program[parameter.name].value = float(value)
        if "xyz_to_rgb_matrix" in program:
            matrix = colorimetry.xyz_to_rgb_matrix()
            program["xyz_to_rgb_matrix"].write(matrix.T.astype(np.float32).tobytes())  # column-major
        textures = dict(self._library)
        if "sensitivity_fourier_prefiltered" in program:  # Section 5's table: built on first use
            if "sensitivity_fourier_prefiltered" not in self._library:
                from .thinfilm import sensitivity_fourier_prefiltered

                table = sensitivity_fourier_prefiltered()
                self._library["sensitivity_fourier_prefiltered"] = self.ctx.texture(
                    (table.shape[1], table.shape[0]), 3, np.ascontiguousarray(table, dtype=np.float32).tobytes(), dtype="f4"
                )
            textures["sensitivity_fourier_prefiltered"] = self._library["sensitivity_fourier_prefiltered"]
        for name, value in (uniforms or {}).items():
            if name in program:
                program[name].value = value
        if inputs:
            textures.update({k: v for k, v in self._input_textures(inputs).items() if k in program})
        start = time.perf_counter()
        key, entry = self._model_entry(material, values)
        if entry is not None:
            if entry[1] is None:
                entry[1] = entry[0].textures()
            for name, table in entry[1].items():
                if name in program:
                    if key is None or self._model_texture_keys.get(name) != key or name not in self._model_textures:
                        self._model_texture(name, table)
                        self._model_texture_keys[name] = key
                    textures[name] = self._model_textures[name]
            self.last_table_ms = (time.perf_counter() - start) * 1e3
        for unit, (name, texture) in enumerate(sorted(textures.items())):
            if name in program:
                texture.use(location=unit)
                program[name].value = unit

    @staticmethod
    def _model_key(material: Material, values: Mapping[str, object]) -> tuple | None:
        """The cache key of ``material``'s model at ``values`` (None: an unhashable value, not cached)."""
        try:
            key = (str(material.path), material.model, tuple(sorted(values.items())))
            hash(key)
        except TypeError:  # an unhashable value (a list)
            return None
        return key

    def _model_entry(self, material: Material, values: Mapping[str, object]) -> tuple[tuple | None, list | None]:
        """``(key, [model, tables])`` of :func:`explorer.models.model_for`, from a small LRU cache (key None: uncached)."""
        values = material.physical_values(values)
        key = self._model_key(material, values)
        if key is None:
            model = model_for(material, values)
            return None, ([model, None] if model is not None else None)
        with self._models_lock:
            entry = self._models.get(key)
            if entry is not None:
                self._models.move_to_end(key)
                return key, entry
        model = model_for(material, values)
        if model is None:
            return key, None
        return key, self._cache_model(key, [model, None])

    def _cache_model(self, key: tuple, entry: list) -> list:
        with self._models_lock:
            self._models[key] = entry
            self._models.move_to_end(key)
            while len(self._models) > MODEL_CACHE_SIZE:
                self._models.popitem(last=False)
        return entry

    def model_ready(self, material: Material, values: Mapping[str, object]) -> bool:
        """Whether binding ``material`` at ``values`` needs no numpy work (its tables are cached, or it has none)."""
        from .models import MODELS

        if (material.model or "") not in MODELS:
            return True
        key = self._model_key(material, material.physical_values(values))
        with self._models_lock:
            entry = self._models.get(key) if key is not None else None
        return entry is not None and entry[1] is not None

    def prepare_model(self, material: Material, values: Mapping[str, object]) -> None:
        """
        Build ``material``'s numpy model at ``values`` and its tables into the cache, without touching GL:
        safe on a worker thread, so that an interactive host can build the next tables (~10 ms) while it
        draws. Errors are raised here as they would be by :meth:`bind`.
        """
        if self.model_ready(material, values):
            return
        values = material.physical_values(values)
        key = self._model_key(material, values)
        model = model_for(material, values)
        if model is None or key is None:
            return
        self._cache_model(key, [model, model.textures()])

    def render(
        self, material: Material, values: Mapping[str, object], view: str, width: int, height: int,
        *, light: tuple[float, float] | None = None, inputs: Mapping[str, np.ndarray] | None = None,
        uniforms: Mapping[str, object] | None = None,
    ) -> np.ndarray:
        """
        ``(height, width, 3)`` float32 linear RGB, rows from the top, unclamped.

        ``light``: ``(theta, phi)`` in degrees of the ``lit`` and ``scatter`` views' directional light
        (default :data:`explorer.views.geometry.DEFAULT_LIGHT`); the other views ignore it. ``inputs`` and
        ``uniforms``: a view's own textures and flags (the ``textured`` view's, from
        :meth:`explorer.thickness.ThicknessTexture.gl_inputs`).
        """
        from .views.geometry import light_direction

        direction = light_direction(light)
        program = self.program(material, view, values)
        self.bind(program, material, values, inputs, uniforms)
        if "light_direction" in program:
            program["light_direction"].value = tuple(float(c) for c in direction)
        framebuffer = self.ctx.framebuffer(color_attachments=[self.ctx.renderbuffer((width, height), 4, dtype="f4")])
        try:
            framebuffer.use()
            framebuffer.clear(0.0, 0.0, 0.0, 1.0)
            if "resolution" in program:
                program["resolution"].value = (float(width), float(height))
            vertex_array = self.ctx.vertex_array(program, [])
            vertex_array.render(vertices=3)
            data = framebuffer.read(components=4, dtype="f4")
            vertex_array.release()
        finally:
            for attachment in framebuffer.color_attachments:
                attachment.release()
            framebuffer.release()
        image = np.frombuffer(data, dtype=np.float32).reshape(height, width, 4)[::-1, :, :3]
        return np.ascontiguousarray(image)

    def time_frame(
        self, material: Material, values: Mapping[str, object], view: str, width: int, height: int,
        *, light: tuple[float, float] | None = None, inputs: Mapping[str, np.ndarray] | None = None,
        uniforms: Mapping[str, object] | None = None,
    ) -> float:
        """
        Time of one frame in ms, bounded by ``glFinish`` on both sides (tables already bound): on a
        software rasteriser such as llvmpipe this is the rendering time. Timer queries are avoided:
        their 32-bit nanosecond results wrap at 4.29 s. ``light``: as in :meth:`render`.
        """
        from .views.geometry import light_direction

        program = self.program(material, view, values)
        self.bind(program, material, values, inputs, uniforms)
        if "light_direction" in program:
            program["light_direction"].value = tuple(float(c) for c in light_direction(light))
        framebuffer = self.ctx.framebuffer(color_attachments=[self.ctx.renderbuffer((width, height), 4, dtype="f4")])
        framebuffer.use()
        if "resolution" in program:
            program["resolution"].value = (float(width), float(height))
        vertex_array = self.ctx.vertex_array(program, [])
        self.ctx.finish()
        start = time.perf_counter()
        vertex_array.render(vertices=3)
        self.ctx.finish()
        elapsed = (time.perf_counter() - start) * 1e3
        vertex_array.release()
        framebuffer.color_attachments[0].release()
        framebuffer.release()
        return elapsed


def _first_error(source, log: str) -> tuple[str, int | None, str]:
    """(file, line, message) of the first error in a driver log, mapped to the real files."""
    from .glsl import compile_error

    error = compile_error(log, source.sources, source.line_stride)
    return error.path, error.line, error.message
