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


#: The thin film's ``sensitivity_fourier`` envelope in the export: every ENVELOPE_STRIDE-th node of the
#: 4096-node table (70 nm apart: 586 nodes, 4095 = 7 x 585, so the last node is kept), read by Catmull-Rom
#: cubic interpolation. It departs from the GL view's linear reading of all nodes by at most 1.0e-4 of the
#: envelope's peak (``python -m explorer.materials.export_brdf``); the full table, 8192 ``vec3`` inlined,
#: took Mesa's compiler more than 15 minutes, this one seconds.
ENVELOPE_STRIDE = 7


def envelope_nodes(stride: int = ENVELOPE_STRIDE) -> np.ndarray:
    """The coarse envelope's nodes: ``(2, count, 3)``, rows real and imaginary parts, ``mu = 10 stride k`` nm."""
    from explorer.physics import thinfilm
    from explorer.tables import luts

    table = luts.load("sensitivity_fourier").reshape(2, thinfilm.SENSITIVITY_FOURIER_COUNT, 3)
    last = thinfilm.SENSITIVITY_FOURIER_COUNT - 1
    if last % stride:
        raise ValueError(f"the stride {stride} must divide {last} (the last node is kept)")
    return table[:, ::stride]


def catmull_rom(nodes: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``nodes`` (``(count, ...)``) at fractional indices ``x``, Catmull-Rom, the end nodes repeated (the GLSL's)."""
    last = nodes.shape[0] - 1
    i = np.clip(np.floor(x).astype(np.int64), 0, last - 1)
    f = (x - i).reshape(-1, *([1] * (nodes.ndim - 1)))
    p0, p1, p2, p3 = (nodes[np.clip(i + k, 0, last)] for k in (-1, 0, 1, 2))
    return p1 + 0.5 * f * (p2 - p0 + f * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3 + f * (3.0 * (p1 - p2) + p3 - p0)))


def envelope_error(stride: int = ENVELOPE_STRIDE, samples: int = 200_001) -> float:
    """Largest ``|coarse cubic - fine linear|`` of the envelope over its range, over the envelope's peak."""
    from explorer.physics import thinfilm  # noqa: F401 (declares the table)
    from explorer.tables import luts

    fine = luts.load("sensitivity_fourier").reshape(2, -1, 3)
    x = np.linspace(0.0, fine.shape[1] - 1.0, samples)
    i = np.minimum(np.floor(x).astype(np.int64), fine.shape[1] - 2)
    f = (x - i)[:, None]
    linear = fine[:, i] * (1.0 - f) + fine[:, i + 1] * f
    coarse = envelope_nodes(stride)
    cubic = np.stack([catmull_rom(coarse[r], x / stride) for r in range(2)])
    peak = np.abs(fine[0] + 1j * fine[1]).max()
    return float(np.abs((cubic[0] - linear[0]) + 1j * (cubic[1] - linear[1])).max() / peak)


def _envelope_glsl(stride: int = ENVELOPE_STRIDE) -> str:
    """GLSL ``sensitivity_fourier_envelope`` reading :func:`envelope_nodes` (same contract as lib/thinfilm.glsl's)."""
    nodes = envelope_nodes(stride)
    last = nodes.shape[1] - 1
    return f"""{_vec3_array("sensitivity_fourier_envelope_re", nodes[0])}
{_vec3_array("sensitivity_fourier_envelope_im", nodes[1])}
// The demodulated envelope E_j(mu) (lib/thinfilm.glsl), from every {stride}th node of the table by
// Catmull-Rom (the export's stand-in for the 4096-node table: explorer/materials/export_brdf.py).
bool sensitivity_fourier_envelope(float mu, out vec3 re, out vec3 im) {{
    float x = mu / SENSITIVITY_FOURIER_STEP;
    re = vec3(0.0);
    im = vec3(0.0);
    if (!(x >= 0.0 && x <= {float(last * stride)})) return false;
    float y = x / {float(stride)};
    int i = min(int(floor(y)), {last - 1});
    float f = y - float(i);
    int i0 = max(i - 1, 0), i3 = min(i + 2, {last});
    vec4 w = vec4(f * (-0.5 + f * (1.0 - 0.5 * f)), 1.0 + f * f * (-2.5 + 1.5 * f),
                  f * (0.5 + f * (2.0 - 1.5 * f)), f * f * (-0.5 + 0.5 * f));
    re = w.x * sensitivity_fourier_envelope_re[i0] + w.y * sensitivity_fourier_envelope_re[i]
       + w.z * sensitivity_fourier_envelope_re[i + 1] + w.w * sensitivity_fourier_envelope_re[i3];
    im = w.x * sensitivity_fourier_envelope_im[i0] + w.y * sensitivity_fourier_envelope_im[i]
       + w.z * sensitivity_fourier_envelope_im[i + 1] + w.w * sensitivity_fourier_envelope_im[i3];
    return true;
}}"""


def _coarse_envelope(flat: str) -> str:
    """Replace the film's table-reading ``sensitivity_fourier_envelope`` by :func:`_envelope_glsl`."""
    pattern = r"bool sensitivity_fourier_envelope\(float mu, out vec3 re, out vec3 im\) \{.*?\n\}"
    if not re.search(pattern, flat, flags=re.S):
        raise BrdfExportError("<export>", None, "lib/thinfilm.glsl's sensitivity_fourier_envelope was not found")
    return re.sub(pattern, lambda _m: _envelope_glsl(), flat, count=1, flags=re.S)


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
    """The parameter section, each line with its unit and meaning as a trailing comment (BRDF Explorer ignores it)."""
    lines = []
    for p in material.parameters:
        value = values[p.name]
        if p.type == "color":
            line = f"color {p.name} {' '.join(f'{float(c):.9g}' for c in value)}"
        elif p.type == "bool":
            line = f"bool {p.name} {1 if value else 0}"
        else:
            line = f"float {p.name} {p.min:.9g} {p.max:.9g} {float(value):.9g}"
        if p.doc:
            line += f"  # {p.unit or '1'}: {p.doc}"
        lines.append(line)
    return lines


def material_tables(material, values: Mapping[str, object], model=None) -> dict[str, np.ndarray]:
    """The library's tables and the material's own (its twin's ``textures()`` for its values), as (height, width, 3) arrays."""
    from explorer.materials.models import model_for
    from explorer.physics.thinfilm import fourier  # noqa: F401  (registers sensitivity_fourier)
    from explorer.tables import luts

    tables = {
        "cmf_1nm": luts.load("cmf_1nm").reshape(1, -1, 3),
        "cmf_cumulative": luts.load("cmf_cumulative").reshape(1, -1, 3),
        "sensitivity_fourier": luts.load("sensitivity_fourier").reshape(2, -1, 3),
    }
    model = model_for(material, values) if model is None else model
    for name, table in model.textures().items():
        table = np.asarray(table, dtype=np.float64)
        tables[name] = table.reshape(1, -1, 3) if table.ndim == 2 else table
    return tables


def brdf_text(material, values: Mapping[str, object]) -> str:
    """The self-contained ``.brdf`` text of ``material`` at ``values``."""
    from explorer.materials.models import model_for
    from explorer.materials.twins import capabilities_of, supporting

    if not capabilities_of(material).supports("brdf"):
        raise BrdfExportError(material.path, None, f"no self-contained .brdf export for this material (exports: {', '.join(supporting('brdf'))})")
    from explorer.materials.media import file_media_in

    files = file_media_in(values)
    if files:  # the file's sliders hold the shipped media's numbers only
        raise BrdfExportError(material.path, None, f"{files[0]} is a medium from a file: a .brdf carries the shipped media "
                                                   "only (give that index as a number)")
    ints = [p.name for p in material.parameters if p.type == "int"]
    shader = round_int_parameters(material.shader, ints)
    model = model_for(material, values)
    tables = material_tables(material, values, model)
    # A twin may specialise its export (its brdf_export hook): #defines, tables it leaves out, a coarse envelope.
    hook = getattr(model, "brdf_export", None)
    special = hook() if callable(hook) else {}
    defined = dict(special.get("defines", {}))
    for name in special.get("drop_tables", ()):
        tables.pop(name, None)
    for name, table in special.get("tables", {}).items():  # baked whatever the exported method
        table = np.asarray(table, dtype=np.float64)
        tables[name] = table.reshape(1, -1, 3) if table.ndim == 2 else table
    baked = special.get("baked", {})
    # The methods' names, which the host #defines in every program: substituted by their values, as PI is
    # (a `const int BRAGG_REFERENCE` would break the explorer's own loading of the file, whose host
    # #defines the same names).
    from explorer.materials.methods import glsl_defines

    defined.update({name: str(value) for name, value in glsl_defines().items()})
    flat = flatten(shader, str(material.path), defined)
    if special.get("coarse_envelope", False):
        flat = _coarse_envelope(flat)
    flat = inline_tables(flat, tables)
    for name, bake in baked.items():
        flat = _fall_back(flat, name, bake)
    flat = _forward_declare(flat, list(tables))
    flat = "\n".join(line for line in flat.splitlines() if line.strip())
    if any(line.lstrip().startswith("#") for line in flat.splitlines()):
        raise BrdfExportError(material.path, None, "a preprocessor line is left in the exported shader")
    notes = [f"{material.model} exported by bragg-explorer (export --to brdf): self-contained, no preprocessor;",
             "the tables are computed for the exported values."]
    notes += [baked_note(name, bake) for name, bake in baked.items()]
    header = ("analytic\n\n" + "".join(f"# {line}\n" for line in notes) + "\n"
              "::begin parameters\n" + "\n".join(_parameter_lines(material, values)) + "\n::end parameters\n\n")
    return (header + "::begin shader\n" + "".join(f"// {line}\n" for line in notes) + f"{flat}\n::end shader\n")


def _baked_values(bake: Mapping) -> str:
    return ", ".join(f"{name} = {value:.9g}" for name, value in bake["values"].items())


def baked_note(name: str, bake: Mapping) -> str:
    """The header's line on a baked table: what it holds for, and what the file reads elsewhere."""
    return (f"{name}: method {bake['label']}'s table, baked for {_baked_values(bake)}; where one of these moves, "
            f"method {bake['label']} falls back to method {bake['fallback_label']} (never a stale or black table).")


def _fall_back(flat: str, name: str, bake: Mapping) -> str:
    """
    Guard ``tabulated_rgb_NAME`` (:func:`inline_tables`) by the values its table was baked for: elsewhere it
    returns ``bake["fallback"]`` (GLSL of ``cos_theta``). Floats compare within 1e-6 relative (float32
    uniforms), integers within 0.5.
    """
    head = f"vec3 tabulated_rgb_{name}(float cos_theta) {{\n"
    if head not in flat:
        raise BrdfExportError("<export>", None, f"the baked table {name} has no lookup to guard")
    tests = []
    for parameter, value in bake["values"].items():
        tolerance = 0.5 if parameter in bake.get("integers", ()) else 1e-6 * max(1.0, abs(value))
        tests.append(f"abs({parameter} - {value:.9g}) <= {tolerance:.9g}")
    guard = (f"// {name}: baked for {_baked_values(bake)}; elsewhere method {bake['fallback_label']}.\n"
             f"bool {name}_baked() {{\n    return " + "\n        && ".join(tests) + ";\n}\n")
    return flat.replace(head, guard + head + f"    if (!{name}_baked()) return {bake['fallback']};\n", 1)


def bparam_text(brdf_file: str, parameters, values: Mapping[str, object]) -> str:
    """
    A ``.bparam`` naming ``brdf_file``, as BRDF Explorer's "Save Params" writes it
    (``BRDFBase::saveParamsFile``): ``bparam FILE``, then ``%f`` floats (``name min max value``; our ``int``
    parameters too, which its files do not know), bools, colours. Opening it, BRDF Explorer loads
    ``FILE`` (relative to its working directory unless absolute) and sets these values.
    """
    lines = [f"bparam {brdf_file}", "", "::begin parameters"]
    lines += [f"float {p.name} {p.min:f} {p.max:f} {float(values[p.name]):f}" for p in parameters if p.type in ("float", "int")]
    lines += [f"bool {p.name} {1 if values[p.name] else 0}" for p in parameters if p.type == "bool"]
    lines += [f"color {p.name} {' '.join(f'{float(c):f}' for c in values[p.name])}" for p in parameters if p.type == "color"]
    return "\n".join(lines + ["::end parameters"]) + "\n"


def export_brdf(material, values: Mapping[str, object], out: Path) -> tuple[Path, Path]:
    """
    Write :func:`brdf_text` to ``out`` (``.brdf``) and, beside it, ``out`` with ``.bparam`` holding the
    exported values and naming the ``.brdf`` by its absolute path (the pair opens in BRDF Explorer from any
    working directory); both atomically. Returns ``(brdf, bparam)``.
    """
    if out.suffix.lower() != ".brdf":
        raise BrdfExportError(out, None, "a BRDF Explorer file: name it .brdf")
    text = brdf_text(material, values)
    bparam = out.with_suffix(".bparam")
    write_text_atomic(out, text)  # explorer.files: a temporary file renamed; OutputError (one line) otherwise
    write_text_atomic(bparam, bparam_text(str(out.resolve()), material.parameters, values))
    return out, bparam


if __name__ == "__main__":  # the coarse envelope's error (docs/export.md)
    print(f"sensitivity_fourier envelope, every {ENVELOPE_STRIDE}th node, Catmull-Rom: "
          f"max |cubic - linear| = {envelope_error():.2e} of the peak")
