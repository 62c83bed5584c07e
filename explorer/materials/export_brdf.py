"""
``export MATERIAL --to brdf out.brdf``: one self-contained file that Disney BRDF Explorer loads as it is.

BRDF Explorer's loader drops every line that starts with ``#``, even inside the shader section, and its
templates (``#version 410`` core) insert ``uniform float NAME;`` (``vec3`` for colours, ``bool`` for
bools) for each parameter, then the shader section verbatim. So the export:

- resolves the preprocessor itself (:func:`flatten`): ``#include`` (once per file), ``#ifdef`` /
  ``#ifndef`` / ``#else`` / ``#endif``, ``#define`` (valued ones substituted); no ``#`` line is left;
- declares ``int`` parameters as ``float`` and rounds them where the shader section reads them as
  integers (``int(floor(x + 0.5))``, the host's ``round_integer`` of a whole value);
- replaces every sampler by ``const`` arrays and lookups of the same filtering (:func:`inline_tables`):
  the CMFs (``cmf_1nm``, ``cmf_cumulative``), the film's ``sensitivity_fourier``, and the tables the host
  computes for the exported values (the tabulated method's ``bragg_table``, the rough layer's
  ``transmission_table``: baked, so they hold for these values only); ``xyz_to_rgb_matrix`` becomes a
  ``const mat3``. The textured view's pre-filtered table (4096 x 256 texels, not used by ``BRDF``) becomes
  a zero stand-in.

References
----------
Disney BRDF Explorer, src/shaderTemplates (the template interface); Fourneau et al. (2024), Appendix D.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Mapping

import numpy as np

from explorer.files import write_text_atomic
from explorer.errors import LocatedError
from explorer.resources import SHADER_DIR

#: The materials with an export (a numpy twin and no view-specific hooks in BRDF).
EXPORTABLE = ("bragg_mirror", "bragg_layer", "thin_film")
_INCLUDE = re.compile(r'\s*#\s*include\s*"([^"]+)"')
_DIRECTIVE = re.compile(r"\s*#\s*(\w+)\s*(.*?)\s*(//.*)?$")


class BrdfExportError(LocatedError):
    """A material that cannot be written as a self-contained .brdf (one line)."""


def flatten(text: str, name: str, defined: dict[str, str] | None = None, seen: set | None = None) -> str:
    """GLSL ``text`` with its includes inlined and its preprocessor evaluated: no line starts with ``#``."""
    defined = {} if defined is None else defined
    seen = set() if seen is None else seen
    out: list[str] = []
    stack: list[bool] = []  # the active state of each open #if block
    for number, line in enumerate(text.splitlines(), start=1):
        active = all(stack)
        if not line.lstrip().startswith("#"):
            if active:
                out.append(line)
            continue
        include = _INCLUDE.match(line)
        if include:
            if active:
                from explorer.materials.shader_constants import GENERATED

                target = include.group(1)
                if target in GENERATED:  # the shared constants, written from the physics (no file)
                    if target not in seen:
                        seen.add(target)
                        out.append(GENERATED[target]().rstrip("\n"))
                    continue
                path = (SHADER_DIR / target).resolve()
                if path not in seen:
                    seen.add(path)
                    out.append(flatten(path.read_text(encoding="utf-8"), str(path), defined, seen))
            continue
        match = _DIRECTIVE.match(line)
        directive, argument = (match.group(1), match.group(2)) if match else ("", "")
        if directive in ("ifdef", "ifndef"):
            stack.append((argument in defined) == (directive == "ifdef"))
        elif directive == "else":
            stack[-1] = not stack[-1]
        elif directive == "endif":
            stack.pop()
        elif directive == "define":
            if active:
                key, _, value = argument.partition(" ")
                defined[key] = value.strip()
        elif directive in ("version", ""):
            continue
        else:
            raise BrdfExportError(name, number, f"#{directive} is not supported by the .brdf export")
    flat = "\n".join(out)
    for key, value in defined.items():
        if value:
            flat = re.sub(rf"\b{re.escape(key)}\b", value, flat)
    return flat


def _vec3_array(name: str, data: np.ndarray) -> str:
    rows = ",\n    ".join(", ".join(f"vec3({r:.8g}, {g:.8g}, {b:.8g})" for r, g, b in data[k:k + 4]) for k in range(0, len(data), 4))
    return f"const vec3 {name}[{len(data)}] = vec3[](\n    {rows});"


def _table(name: str, data: np.ndarray) -> str:
    """A (height, width, 3) table as a const array with texelFetch and GL LINEAR / CLAMP_TO_EDGE lookups."""
    height, width = data.shape[:2]
    flat = np.ascontiguousarray(data, dtype=np.float64).reshape(-1, 3)
    return f"""{_vec3_array(f"{name}_texels", flat)}
vec4 {name}_fetch(int i, int j) {{ return vec4({name}_texels[clamp(j, 0, {height - 1}) * {width} + clamp(i, 0, {width - 1})], 1.0); }}
vec4 {name}_linear(float u) {{
    float x = clamp(u * {float(width)} - 0.5, -1.0, {float(width)});  // as CLAMP_TO_EDGE, before int() can overflow
    float i = floor(x);
    return mix({name}_fetch(int(i), 0), {name}_fetch(int(i) + 1, 0), x - i);
}}"""


def inline_tables(flat: str, tables: Mapping[str, np.ndarray]) -> str:
    """Replace each ``uniform sampler2D`` by its const table (or a zero stand-in) and rewrite its lookups."""
    from explorer.physics import colorimetry

    matrix = colorimetry.xyz_to_rgb_matrix().T.ravel()  # column-major
    flat = re.sub(r"uniform\s+mat3\s+xyz_to_rgb_matrix\s*;",
                  f"const mat3 xyz_to_rgb_matrix = mat3({', '.join(f'{v:.10g}' for v in matrix)});", flat)
    for name in re.findall(r"uniform\s+sampler2D\s+(\w+)\s*;", flat):
        if name in tables:
            data = tables[name]
            data = data.reshape(1, *data.shape) if data.ndim == 2 else data
            height, width = data.shape[:2]
            declaration = _table(name, data)
        else:  # not read by BRDF: a zero stand-in of the right size
            height, width = (256, 4096) if name == "sensitivity_fourier_prefiltered" else (1, 1)
            declaration = (f"vec4 {name}_fetch(int i, int j) {{ return vec4(0.0); }}\n"
                           f"vec4 {name}_linear(float u) {{ return vec4(0.0); }}")
        flat = re.sub(rf"uniform\s+sampler2D\s+{name}\s*;[^\n]*", lambda _m: declaration, flat, count=1)
        flat = re.sub(rf"texelFetch\(\s*{name}\s*,\s*ivec2\(([^()]*),([^()]*)\)\s*,\s*0\s*\)", rf"{name}_fetch(\1,\2)", flat)
        flat = re.sub(rf"textureSize\(\s*{name}\s*,\s*0\s*\)", f"ivec2({width}, {height})", flat)
        flat = re.sub(rf"texture\(\s*{name}\s*,\s*vec2\((.*), 0\.5\)\)", rf"{name}_linear(\1)", flat)
        flat = re.sub(rf"tabulated_rgb\(\s*{name}\s*,", f"tabulated_rgb_{name}(", flat)
        if f"tabulated_rgb_{name}(" in flat:
            flat += (f"\nvec3 tabulated_rgb_{name}(float cos_theta) {{\n"
                     f"    return {name}_linear((clamp(cos_theta, 0.0, 1.0) * {width - 1.0:.1f} + 0.5) / {float(width):.1f}).rgb;\n}}")
    # The generic tabulated_rgb(sampler2D, float) has no caller left: drop it (no sampler may remain).
    flat = re.sub(r"vec3 tabulated_rgb\(sampler2D table, float cos_theta\) \{.*?\n\}", "", flat, flags=re.S)
    if "sampler2D" in flat or re.search(r"\btexture(Size|Lod)?\(|\btexelFetch\(", flat):
        raise BrdfExportError("<export>", None, "a texture lookup is left in the exported shader")
    return flat


def _forward_declare(flat: str, names: list[str]) -> str:
    """Prototypes of the functions appended after their callers (tabulated_rgb_NAME)."""
    protos = "".join(f"vec3 tabulated_rgb_{n}(float cos_theta);\n" for n in names if f"vec3 tabulated_rgb_{n}(float cos_theta) {{" in flat)
    return protos + flat


def round_int_parameters(shader: str, names: list[str]) -> str:
    """
    In the material's shader section, read each ``int`` parameter (a float in BRDF Explorer) as the
    nearest integer, except inside functions that declare a parameter of that name (BRDF's normal ``N``).
    """
    out, depth, current_params = [], 0, set()
    for line in shader.splitlines():
        if depth == 0:
            signature = re.match(r"\s*\w+\s+\w+\s*\(([^)]*)\)", line)
            current_params = set(re.findall(r"(\w+)\s*(?:,|$)", signature.group(1))) if signature else set()
        if depth > 0 or "{" in line:
            body = line if depth > 0 else line[line.index("{"):]
            head = line[: len(line) - len(body)]
            for name in names:
                if name not in current_params:
                    body = re.sub(rf"(?<![.\w]){re.escape(name)}\b(?!\s*\()", f"int(floor({name} + 0.5))", body)
            line = head + body
        depth += line.count("{") - line.count("}")
        out.append(line)
    return "\n".join(out)


def _parameter_lines(material, values: Mapping[str, object]) -> list[str]:
    lines = []
    for p in material.parameters:
        value = values[p.name]
        if p.type == "color":
            lines.append(f"color {p.name} {' '.join(f'{float(c):.9g}' for c in value)}")
        elif p.type == "bool":
            lines.append(f"bool {p.name} {1 if value else 0}")
        else:
            lines.append(f"float {p.name} {p.min:.9g} {p.max:.9g} {float(value):.9g}")
    return lines


def material_tables(material, values: Mapping[str, object]) -> dict[str, np.ndarray]:
    """The library's tables and the material's own (for its values), as (height, width, 3) arrays."""
    from explorer.materials.models import model_for
    from explorer.tables import luts

    tables = {
        "cmf_1nm": luts.load("cmf_1nm").reshape(1, -1, 3),
        "cmf_cumulative": luts.load("cmf_cumulative").reshape(1, -1, 3),
        "sensitivity_fourier": luts.load("sensitivity_fourier").reshape(2, -1, 3),
    }
    model = model_for(material, material.physical_values(values))
    for name, table in model.textures().items():
        table = np.asarray(table, dtype=np.float64)
        tables[name] = table.reshape(1, -1, 3) if table.ndim == 2 else table
    if material.model == "bragg_layer":
        tables["transmission_table"] = np.asarray(model.transmission_table, np.float64).reshape(1, -1, 3)
    return tables


def brdf_text(material, values: Mapping[str, object]) -> str:
    """The self-contained ``.brdf`` text of ``material`` at ``values``."""
    if material.model not in EXPORTABLE:
        raise BrdfExportError(material.path, None, f"no self-contained .brdf export for this material (exports: {', '.join(EXPORTABLE)})")
    ints = [p.name for p in material.parameters if p.type == "int"]
    shader = round_int_parameters(material.shader, ints)
    defined = {}
    tables = material_tables(material, values)
    if material.model == "thin_film":
        # The film's export is specialised to its method: the 4096 x 2 sensitivity_fourier table, inlined,
        # takes Mesa's compiler many minutes, so only methods 1-3 (which read it) carry it.
        from explorer.materials.brd import round_integer

        method = round_integer(values["method"])
        defined["SPECIALISED_method"] = str(method)
        from explorer.materials.thinfilm_model import TABULATED_FOURIER

        if method not in TABULATED_FOURIER:
            tables.pop("sensitivity_fourier")
    # The methods' names, which the host #defines in every program: constants here (no preprocessor).
    from explorer.materials.methods import glsl_defines

    names = "".join(f"const int {name} = {value};\n" for name, value in glsl_defines().items())
    flat = flatten(names + shader, str(material.path), defined)
    flat = _forward_declare(inline_tables(flat, tables), list(tables))
    flat = "\n".join(line for line in flat.splitlines() if line.strip())
    if any(line.lstrip().startswith("#") for line in flat.splitlines()):
        raise BrdfExportError(material.path, None, "a preprocessor line is left in the exported shader")
    header = ("analytic\n\n"
              "::begin parameters\n" + "\n".join(_parameter_lines(material, values)) + "\n::end parameters\n\n")
    return (header + "::begin shader\n"
            f"// {material.model} exported by bragg-explorer (export --to brdf): self-contained, no preprocessor;\n"
            "// the tables are baked for the exported values.\n"
            f"{flat}\n::end shader\n")


def export_brdf(material, values: Mapping[str, object], out: Path) -> Path:
    """Write :func:`brdf_text` to ``out`` (``.brdf``) atomically."""
    if out.suffix.lower() != ".brdf":
        raise BrdfExportError(out, None, "a BRDF Explorer file: name it .brdf")
    text = brdf_text(material, values)
    write_text_atomic(out, text)  # explorer.files: a temporary file renamed; OutputError (one line) otherwise
    return out
