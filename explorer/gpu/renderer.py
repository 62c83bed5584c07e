"""
The :class:`Renderer`: a material's programs (one per view and specialisation), its uniforms and
tables as bindings, and the one draw primitive every image goes through (:meth:`Renderer.draw`: the
headless renders, the app's progressive views and display passes, the environment view's passes).
"""

from __future__ import annotations

import time
from typing import Mapping

import numpy as np

from explorer.physics import colorimetry, thinfilm
from explorer.tables import luts
from explorer.materials.brd import Material
from explorer.materials.glsl import ShaderError
from explorer.views.geometry import light_direction
from explorer.gpu.context import VERTEX_SHADER, GLLimits, create_context, gl_limits
from explorer.gpu.programs import build_program_source, first_error, specialisation
from explorer.gpu.tables import ModelCache
from explorer.gpu.packed_tables import pack_table_intervals
from explorer.gpu.resources import (
    BUFFER_SAMPLERS, GL_UNSIGNED_INT_SAMPLER_BUFFER, BufferTexture, GLResources,
    buffer_textures_supported, set_buffer_sampler,
)


#: The views' own uniforms at their headless values, bound to every draw that does not set them (a
#: program is shared: the app's Slice window may have set another phi_d on it).
VIEW_UNIFORM_DEFAULTS = {"slice_phi_d": float(np.pi / 2), "fill": 0.0, "surface_nearest": False, "texture_mapping": 0}
#: Fill tables kept (explorer.views.fill): the shown material's, Compare's two, a few more.
FILL_TABLES_KEPT = 8

#: GL's sampler types (1D ... 2D rectangle shadow, the array/buffer/integer ones, the multisample ones).
SAMPLER_TYPES = frozenset([*range(0x8B5D, 0x8B65), *range(0x8DC0, 0x8DD9), *range(0x9108, 0x910E)])


#: How a model's table is uploaded for a sampler of each GL type (others: "2d", a filtered 2D texture).
TABLE_KINDS = {GL_UNSIGNED_INT_SAMPLER_BUFFER: "packed"}


def _buffer_samplers(program) -> dict[str, int]:
    """``{name: GL type}`` of ``program``'s samplers if one is a buffer sampler (else {}): unbound, they
    would all read unit 0, and GL refuses a draw whose samplers of two types share a unit."""
    samplers = {name: program[name].gl_type for name in program if program[name].gl_type in SAMPLER_TYPES}
    return samplers if BUFFER_SAMPLERS & set(samplers.values()) else {}


class Renderer:
    """Renders material views into float32 images; caches programs, library textures and model tables."""

    def __init__(self, ctx=None):
        self.ctx = ctx if ctx is not None else create_context()
        #: What this context allows, checked before every size-dependent allocation.
        self.limits: GLLimits = gl_limits(self.ctx)
        #: The owner of every texture and framebuffer made for this context (explorer.gpu.resources).
        self.resources = GLResources(self.ctx, self.limits)
        #: Whether programs may read 1D tables from buffer textures (``TABLE_BUFFERS``; needs PyOpenGL here):
        #: the tabulated methods then read packed tables (one fetch a lookup).
        self.buffer_tables = buffer_textures_supported(self.ctx)
        self._programs: dict[tuple, object] = {}
        self._library = self._library_textures()
        self._model_textures: dict[tuple[str, str], object] = {}  # (name, kind: "2d" or "packed") -> texture
        self._model_texture_keys: dict[tuple[str, str], tuple] = {}  # which model's table each model texture holds
        self._inputs: dict[str, object] = {}
        # id(program) -> (program, its vertex array, its samplers' GL types if one is a buffer sampler, else {})
        self._vertex_arrays: dict[int, tuple[object, object, dict]] = {}
        self.models = ModelCache()
        #: Milliseconds the last :meth:`bindings` spent on the model's tables (None: no model yet).
        self.last_table_ms: float | None = None
        #: What a smooth mirror reflects in the lit view (:meth:`mirror_environment`): (pixels, texture), or None.
        self._mirror_environment: tuple | None = None
        self._fill_tables: dict = {}  # (material, values) -> the lit view's fill table, least recently used first
        self._fill_last: dict = {}  # id(material) -> its last fill table (a dragged slider's previews)
        self._default_environment = None

    # -- resources ---------------------------------------------------------------------------------

    def _texture(self, data: np.ndarray, linear: bool):
        """A float RGB(A) texture of ``(height, width, 3 or 4)`` data (row 0 = texel row 0), clamped."""
        return self.resources.texture(data, linear=linear)

    def _model_texture(self, name: str, table: np.ndarray, kind: str = "2d"):
        """
        The texture of a model's table as the program reads it, rewritten in place when its shape is
        unchanged. ``kind`` ``"2d"``: a linearly filtered texture, ``(width, 3)`` a row (height 1),
        ``(height, width, 3)`` a 2D table (row 0 = texel row 0); ``"packed"``: a row packed one interval a texel
        (:func:`explorer.gpu.packed_tables.pack_table_intervals`, ``usamplerBuffer``).
        """
        data = np.ascontiguousarray(table, dtype=np.float32)
        if kind != "2d" and data.ndim != 2:
            raise ValueError(f"{name}: a buffer texture holds a row, not a {data.shape} table")
        if kind == "packed":
            data, options = pack_table_intervals(data)[None], {"buffer": True, "dtype": "u4"}
        else:
            if data.ndim == 2:
                data = data.reshape(1, -1, 3)
            # RGBA (alpha 1, as an RGB texture reads): 16-byte texels fetch faster than 12-byte ones
            # (llvmpipe: the tabulated method's sphere ~10% faster; bench --tables).
            data = np.concatenate([data, np.ones(data.shape[:2] + (1,), np.float32)], axis=-1)
            options = {"linear": True}
        key = (name, kind)
        texture = self._model_textures[key] = self.resources.replace(self._model_textures.get(key), data, origin=name, **options)
        return texture

    def _library_textures(self) -> dict[str, object]:
        # (2, 4096, 3) as a 4096 x 2 texture: rows 0 and 1, the real and imaginary parts.
        fourier = self.resources.texture(luts.load("sensitivity_fourier").reshape(2, thinfilm.SENSITIVITY_FOURIER_COUNT, 3))
        return {
            "cmf_1nm": self._texture(luts.load("cmf_1nm").reshape(1, -1, 3), linear=False),
            "cmf_cumulative": self._texture(luts.load("cmf_cumulative").reshape(1, -1, 3), linear=True),
            # (2, 4096, 3): a 4096 x 2 texture, row 0 real and row 1 imaginary parts (lib/thinfilm.glsl texelFetches).
            "sensitivity_fourier": fourier,
        }

    def _input_textures(self, inputs: Mapping[str, np.ndarray]) -> dict[str, object]:
        """A view's per-render inputs (``(h, w)`` or ``(h, w, c)`` float arrays, row 0 = texel row 0) as NEAREST textures."""

        for name, array in inputs.items():
            shape = np.shape(array)
            self.limits.check_texture(shape[1], shape[0], shape[2] if len(shape) > 2 else 1, name)
        self.resources.release(*self._inputs.values())
        self._inputs = {name: self.resources.texture(array, origin=name) for name, array in inputs.items()}
        return self._inputs

    def program(self, material: Material, view: str, values: Mapping[str, object] | None = None):
        """The compiled program (cached), or :class:`ShaderError` naming the file and line."""
        constants = specialisation(material, values if values is not None else material.resolve())
        key = (str(material.path), material.shader, material.uniform_declarations(), view, constants)
        if key not in self._programs:
            import moderngl

            source = build_program_source(material, view, constants, self.buffer_tables)
            try:
                program = self.ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=source.code)
            except moderngl.Error as error:
                raise ShaderError(*first_error(source, str(error))) from None
            self._programs[key] = program
        return self._programs[key]

    def mirror_environment(self, environment=None):
        """
        The texture of what a smooth mirror reflects in the lit view (``shaders/views/lit.glsl``'s ``mirror_environment``):
        ``environment`` (an :class:`explorer.views.env.EnvironmentMap`), or the env view's default; one texture
        kept, made again only for other texels.
        """
        from explorer.views.env import EnvironmentMap

        if environment is None:
            if self._default_environment is None:
                self._default_environment = EnvironmentMap.default()
            environment = self._default_environment
        kept = self._mirror_environment
        if kept is None or kept[0] is not environment.pixels:
            if kept is not None:
                self.resources.release(kept[1])
            texture = self.resources.texture(environment.pixels, linear=True, repeat_x=True, origin=environment.name)  # as the env view's
            self._mirror_environment = kept = (environment.pixels, texture)
        return kept[1]

    # -- the model cache ---------------------------------------------------------------------------

    def model_ready(self, material: Material, values: Mapping[str, object]) -> bool:
        """Whether binding ``material`` at ``values`` needs no numpy work (its tables are cached, or it has none)."""
        return self.models.ready(material, values)

    def prepare_model(self, material: Material, values: Mapping[str, object]) -> None:
        """
        Build ``material``'s numpy model at ``values`` and its tables into the cache, without touching GL:
        safe on a worker thread, so that an interactive host can build the next tables (~10 ms) while it
        draws. Errors are raised here as they would be by :meth:`bindings`.
        """
        self.models.prepare(material, values)

    def model_drawable(self, material: Material, values: Mapping[str, object]) -> bool:
        """Whether binding ``material`` at ``values`` needs no numpy work if its draft tables will do."""
        return self.models.drawable(material, values)

    def prepare_draft(self, material: Material, values: Mapping[str, object]) -> bool:
        """Quick draft tables of ``material`` at ``values`` (tens of ms), True when it can be drawn with them now."""
        return self.models.prepare_draft(material, values)

    # -- bindings and the draw primitive ------------------------------------------------------------

    def fill_table(self, material: Material, values: Mapping[str, object], draft: bool = False) -> tuple:
        """
        The lit view's fill table (:mod:`explorer.views.fill`): the albedo view drawn at the fill's angles on its
        quadrature, as the shader's ``vec3 fill_albedo[]``; the last few kept (Compare's two materials, a slider's
        other views). ``draft`` (a preview while a slider moves): the material's last table when these values have
        none yet; the image drawn once the slider is released gets its own.
        """
        from explorer.views.fill import FILL_ANGLES, fill_uniforms

        key = (id(material), material.shader, tuple(sorted((k, str(v)) for k, v in values.items())))
        table = self._fill_tables.get(key)
        if table is None and draft and id(material) in self._fill_last:
            return self._fill_last[id(material)]
        if table is None:
            # The albedo view sums its terms on the host (one node a fragment: see _render_summed).
            row = self.render(material, values, "albedo", FILL_ANGLES, 1, uniforms=fill_uniforms())[0]
            table = tuple(tuple(float(c) for c in texel) for texel in row)
            if len(self._fill_tables) >= FILL_TABLES_KEPT:
                self._fill_tables.pop(next(iter(self._fill_tables)))
        else:
            self._fill_tables.pop(key)  # to the back: the most recently used
        self._fill_tables[key] = self._fill_last[id(material)] = table
        return table

    def bindings(
        self, program, material: Material, values: Mapping[str, object],
        inputs: Mapping[str, np.ndarray] | None = None, uniforms: Mapping[str, object] | None = None, environment=None,
        draft: bool = False,
    ) -> tuple[dict[str, object], dict[str, object]]:
        """
        ``(uniforms, textures)`` of ``material`` at ``values`` for ``program``, as :meth:`draw` takes them:
        the parameters (``int`` ones as :meth:`explorer.materials.brd.Material.typed_values` has them, exact
        integers), the colour matrix, the library and model tables; ``inputs`` (a view's textures, e.g.
        the textured view's D_inc) and ``uniforms`` (a view's flags) added. A smooth mirror's lit view
        (``MIRROR_ONLY``) gets ``environment`` (default: the env view's) and its glint (:mod:`explorer.views.mirror`).
        """
        given_values = values
        values = material.typed_values(values)
        bound: dict[str, object] = {}
        for parameter in material.parameters:
            if parameter.name not in program:
                continue  # unused by the shader: optimised away
            value = values[parameter.name]
            if parameter.type == "bool":
                bound[parameter.name] = bool(value)
            elif parameter.type == "color":
                bound[parameter.name] = tuple(float(v) for v in value)
            else:
                bound[parameter.name] = float(value)
        if "xyz_to_rgb_matrix" in program:
            bound["xyz_to_rgb_matrix"] = tuple(float(v) for v in colorimetry.xyz_to_rgb_matrix().T.ravel())  # column-major
        bound.update({name: value for name, value in VIEW_UNIFORM_DEFAULTS.items() if name in program})
        bound.update(uniforms or {})
        if "fill_albedo" in program and float(bound.get("fill", 0.0)) > 0.0:  # the lit view's environment fill
            bound["fill_albedo"] = self.fill_table(material, given_values, draft)
        textures = dict(self._library)
        if "sensitivity_fourier_prefiltered" in program:  # Section 5's table: built on first use
            if "sensitivity_fourier_prefiltered" not in self._library:
                from explorer.physics.thinfilm import sensitivity_fourier_prefiltered

                self._library["sensitivity_fourier_prefiltered"] = self.resources.texture(sensitivity_fourier_prefiltered())
            textures["sensitivity_fourier_prefiltered"] = self._library["sensitivity_fourier_prefiltered"]
        if inputs:
            textures.update(self._input_textures(inputs))
        if "mirror_environment" in program:
            from explorer.views.mirror import GLINT_PEAK, GLINT_SIN2

            textures["mirror_environment"] = self.mirror_environment(environment)
            turn = environment.turn if environment is not None else self._default_environment.turn
            bound.update(mirror_environment_turn=turn, glint_sin2=GLINT_SIN2, glint_peak=GLINT_PEAK)
        start = time.perf_counter()
        key, entry = self.models.entry(material, values)
        if entry is not None:
            for name, table in entry.ensure_tables().items():
                if name in program:
                    # As the program declares it: a usamplerBuffer or samplerBuffer (TABLE_BUFFERS), or a sampler2D.
                    slot = (name, TABLE_KINDS.get(program[name].gl_type, "2d"))
                    # A draft and the real tables share the values' key: the texture's key tells them apart.
                    texture_key = None if key is None else (key, entry.draft)
                    if texture_key is None or self._model_texture_keys.get(slot) != texture_key or slot not in self._model_textures:
                        self._model_texture(name, table, slot[1])
                        self._model_texture_keys[slot] = texture_key
                    textures[name] = self._model_textures[slot]
            self.last_table_ms = (time.perf_counter() - start) * 1e3
        return bound, textures

    def draw(
        self, program, framebuffer, *, uniforms: Mapping[str, object] | None = None,
        textures: Mapping[str, object] | None = None, rows: tuple[int, int] | None = None,
        additive: bool = False, finish: bool = True,
    ) -> float:
        """
        The draw primitive: one full-screen pass of ``program`` into ``framebuffer``.

        Parameters
        ----------
        program : moderngl.Program
        framebuffer : moderngl.Framebuffer
            Drawn whole, or only ``rows``; the program's ``resolution`` uniform is its size.
        uniforms : mapping, optional
            Values of the program's uniforms (names the program lacks are skipped: optimised away).
        textures : mapping, optional
            Textures by sampler name, bound to consecutive units (those the program lacks are skipped).
        rows : (top, bottom), optional
            Only rows ``[top, bottom)`` counted from the top of the image (a scissor).
        additive : bool
            Add to what the framebuffer holds (blending ``ONE, ONE``), as accumulating passes do.
        finish : bool
            Bound the draw by ``glFinish`` on both sides and time it; else return 0 at once.

        Returns
        -------
        float
            The draw's milliseconds (0 without ``finish``). Timer queries are avoided: their 32-bit
            nanosecond results wrap at 4.29 s.
        """
        import moderngl

        width, height = framebuffer.size
        values = {**(uniforms or {}), "resolution": (float(width), float(height))}
        for name, value in values.items():
            if name in program:
                program[name].value = value
        bound = sorted((name, texture) for name, texture in (textures or {}).items() if name in program)
        cached = self._vertex_arrays.get(id(program))
        if cached is None or cached[0] is not program:
            cached = self._vertex_arrays[id(program)] = (program, self.ctx.vertex_array(program, []), _buffer_samplers(program))
        for unit, (name, texture) in enumerate(bound):
            texture.use(location=unit)
            if isinstance(texture, BufferTexture):
                set_buffer_sampler(program, name, unit)
            else:
                program[name].value = unit
        if cached[2]:  # samplers left unbound: one spare unit per type (GL refuses two types on one unit)
            names = {name for name, _ in bound}
            types = sorted(set(cached[2].values()))
            for name, gl_type in cached[2].items():
                if name not in names:
                    unit = len(bound) + types.index(gl_type)
                    if gl_type in BUFFER_SAMPLERS:
                        set_buffer_sampler(program, name, unit)
                    else:
                        program[name].value = unit
        framebuffer.use()
        if rows is not None:
            top, bottom = rows  # GL rows count from the bottom
            self.ctx.scissor = (0, height - bottom, width, bottom - top)
        if additive:
            self.ctx.enable(moderngl.BLEND)
            self.ctx.blend_func = moderngl.ONE, moderngl.ONE
            self.ctx.blend_equation = moderngl.FUNC_ADD
        try:
            if finish:
                self.ctx.finish()
            start = time.perf_counter()
            cached[1].render(vertices=3)
            if finish:
                self.ctx.finish()
            return (time.perf_counter() - start) * 1e3 if finish else 0.0
        finally:
            self.ctx.scissor = None
            if additive:  # the other passes expect no blending
                self.ctx.blend_func = moderngl.DEFAULT_BLENDING
                self.ctx.disable(moderngl.BLEND)

    # -- whole images ------------------------------------------------------------------------------

    def _headless(self, material, values, view, width, height, light, inputs, uniforms, environment=None):
        """The program and a float framebuffer of one headless render, bound: ``(program, framebuffer, bindings)``."""
        self.limits.check_target(width, height)  # before the program, the tables and the target
        direction = light_direction(light)
        program = self.program(material, view, values)
        bound, textures = self.bindings(program, material, values, inputs, uniforms, environment)
        bound["light_direction"] = tuple(float(c) for c in direction)
        framebuffer = self.target(width, height)
        return program, framebuffer, {"uniforms": bound, "textures": textures}

    def target(self, width: int, height: int, count: int = 1, texture: bool = False):
        """
        A framebuffer of ``count`` float RGBA attachments (renderbuffers, or textures), checked against
        :attr:`limits` first; a driver that still finds it incomplete is a :class:`GLLimitError` too.
        """
        return self.resources.framebuffer(width, height, count, texture=texture)

    def render(
        self, material: Material, values: Mapping[str, object], view: str, width: int, height: int,
        *, light: tuple[float, float] | None = None, inputs: Mapping[str, np.ndarray] | None = None,
        uniforms: Mapping[str, object] | None = None, environment=None,
    ) -> np.ndarray:
        """
        ``(height, width, 3)`` float32 linear RGB, rows from the top, unclamped.

        ``light``: ``(theta, phi)`` in degrees of the ``lit`` and ``scatter`` views' directional light
        (default :data:`explorer.views.geometry.DEFAULT_LIGHT`); the other views ignore it. ``inputs`` and
        ``uniforms``: a view's own textures and flags (the ``textured`` view's, from
        :meth:`explorer.views.thickness.ThicknessTexture.gl_inputs`). ``environment``: what a smooth mirror reflects
        in the ``lit`` view (an :class:`explorer.views.env.EnvironmentMap`; default the env view's).
        """
        from explorer.views.geometry import VIEW_REGISTRY

        registered = VIEW_REGISTRY.get(view)  # None for a mesh's templates (mesh/lit, mesh/env)
        if registered is not None and registered.summed:
            return self._render_summed(material, values, view, width, height, uniforms)
        return self._render_image(material, values, view, width, height, light, inputs, uniforms, environment)

    def _render_image(self, material, values, view, width, height, light=None, inputs=None, uniforms=None, environment=None):
        """One draw of ``view``'s program into a ``width x height`` float target, read back (rows from the top)."""
        program, framebuffer, bindings = self._headless(material, values, view, width, height, light, inputs, uniforms, environment)
        try:
            framebuffer.use()
            framebuffer.clear(0.0, 0.0, 0.0, 1.0)
            self.draw(program, framebuffer, **bindings, finish=False)
            data = framebuffer.read(components=4, dtype="f4")
        finally:
            self.resources.release(framebuffer)
        image = np.frombuffer(data, dtype=np.float32).reshape(height, width, 4)[::-1, :, :3]
        return np.ascontiguousarray(image)

    def _render_summed(self, material, values, view, width, height, uniforms) -> np.ndarray:
        """
        The albedo view (``shaders/views/albedo.glsl``): its terms drawn one quadrature node a fragment, in
        batches of incidence columns that fit a render target, and summed per column in float64.
        """
        from explorer.views.albedo import sum_albedo_terms
        from explorer.views.plots import albedo_uniforms

        bound = {**albedo_uniforms(), **(uniforms or {})}
        nodes, azimuths = int(bound["albedo_nodes"]), int(bound["albedo_phi_nodes"])
        rows = min(self.limits.max_target_side[1], self.limits.max_pixels(4) // azimuths)
        batch = max(1, rows // nodes)
        curve = np.zeros((width, 3))
        for first in range(0, width, batch):
            count = min(batch, width - first)
            terms = self._render_image(material, values, view, azimuths, count * nodes,
                                       uniforms={**bound, "albedo_first_column": first, "albedo_columns": width})
            curve[first:first + count] = sum_albedo_terms(terms, count)
        return np.ascontiguousarray(np.broadcast_to(curve[None].astype(np.float32), (height, width, 3)))

    def time_frame(
        self, material: Material, values: Mapping[str, object], view: str, width: int, height: int,
        *, light: tuple[float, float] | None = None, inputs: Mapping[str, np.ndarray] | None = None,
        uniforms: Mapping[str, object] | None = None, environment=None,
    ) -> float:
        """
        Time of one frame in ms, bounded by ``glFinish`` on both sides (tables already bound): on a
        software rasteriser such as llvmpipe this is the rendering time. ``light``, ``environment``: as in :meth:`render`.
        """
        program, framebuffer, bindings = self._headless(material, values, view, width, height, light, inputs, uniforms, environment)
        try:
            return self.draw(program, framebuffer, **bindings)
        finally:
            self.resources.release(framebuffer)
