"""
A material's fragment shader for a view: the preprocessor (:mod:`explorer.materials.glsl`) assembles the
material's parameter uniforms, its shader section and the view template; compile errors name the
real file and line.
"""

from __future__ import annotations

from typing import Mapping

from explorer.materials.brd import Material, round_integer
from explorer.materials.glsl import ShaderBuilder, ShaderError, compile_error
from explorer.materials.methods import glsl_defines
from explorer.resources import SHADER_DIR
from explorer.gpu.context import GLSL_VERSION


def specialisation(material: Material, values: Mapping[str, object]) -> tuple[tuple[str, int], ...]:
    """
    The constants compiled into ``material``'s program: its ``# specialise:`` parameters' values, rounded
    as the uniforms and the numpy models round them (:func:`explorer.materials.brd.round_integer`).
    """
    return tuple((name, round_integer(values[name])) for name in material.specialised)


def build_program_source(material: Material, view: str, constants: tuple[tuple[str, int], ...] = (),
                         buffer_tables: bool = False):
    """
    The fragment shader of ``material`` in ``view`` (an :class:`explorer.materials.glsl.Program`).

    Each ``(name, value)`` of ``constants`` becomes ``#define SPECIALISED_name value``: the shader
    can branch at compile time on a parameter such as ``method`` (one smaller program per value). The
    methods' names (:func:`explorer.materials.methods.glsl_defines`, ``BRAGG_TABULATED`` …) are defined
    in every program: the one place their numbers come from. ``buffer_tables``: the host uploads a
    table its shader declares as ``usamplerBuffer`` (packed, one interval a texel) or ``samplerBuffer`` as
    a buffer texture (``#define TABLE_BUFFERS``; a shader declares ``sampler2D`` otherwise, as in a
    ``.brdf`` export, which has no such define).
    """
    template = SHADER_DIR / "views" / f"{view}.glsl"
    if not template.exists():
        raise ShaderError(str(template), None, f"no such view {view!r}")
    builder = ShaderBuilder(include_dirs=[SHADER_DIR], version=GLSL_VERSION)
    for name, value in glsl_defines().items():
        builder.define(name, value)
    for name, value in constants:
        builder.define(f"SPECIALISED_{name}", value)
    if buffer_tables:
        builder.define("TABLE_BUFFERS", 1)
    # The view, and whether it reads a surface texture: code only those views read (a textured mirror's
    # table) is left out of the others and of a .brdf export (no sampler).
    builder.define("VIEW_" + "".join(c if c.isalnum() else "_" for c in view.upper()), 1)  # mesh/lit -> VIEW_MESH_LIT
    from explorer.views.geometry import VIEW_REGISTRY

    registered = VIEW_REGISTRY.get(view.rpartition("/")[2])  # a template (mesh/lit, flat/textured): the view it draws
    if registered is not None and registered.surface_texture:
        builder.define("SURFACE_TEXTURE", 1)
    builder.add_source(material.uniform_declarations(), f"{material.path} (parameters)")
    builder.add_source(material.shader, str(material.path), material.shader_line)
    builder.add_file(template)
    return builder.build()


def first_error(source, log: str) -> tuple[str, int | None, str]:
    """(file, line, message) of the first error in a driver log, mapped to the real files."""
    error = compile_error(log, source.sources, source.line_stride)
    return error.path, error.line, error.message
