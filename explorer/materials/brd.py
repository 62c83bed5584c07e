"""Material files in Disney BRDF Explorer's analytic format.

Our materials use the ``.brd`` extension; BRDF Explorer's own ``.brdf`` files
load unchanged.  A file looks like this::

    analytic

    # Lambertian diffuse reflector.
    # model: lambert

    ::begin parameters
    float reflectance 0 1 .8
    bool  clamp_to_hemisphere 1
    color tint 1 .9 .8
    int   N 1 1000 20
    ::end parameters

    ::begin shader
    vec3 BRDF( vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y ) { ... }
    ::end shader

Rules, following BRDF Explorer's ``BRDFBase::loadBRDF`` where it has one:

* The first non-blank, non-comment line is the kind; only ``analytic`` is
  supported (BRDF Explorer itself insists on the very first line and ignores
  any words after the kind; we accept both).
* ``#`` lines are comments everywhere outside the shader section.  Inside it,
  BRDF Explorer drops them too, so a ``#`` line that is not a GLSL
  preprocessor directive is blanked there (keeping line numbers); real
  directives (``#define``, ``#include``, ...) are kept.
* Sections do not nest; ``::end X`` must close the open ``::begin X``.
  Unknown sections (including BRDF Explorer's ``isFunc``) are skipped with a
  warning.
* ``# model: NAME`` outside the shader names the material's numpy twin.
* ``int NAME MIN MAX DEFAULT`` (our ``.brd`` files only; BRDF Explorer's
  ``.brdf`` files have float, bool and color) declares an integer: a count
  or a switch such as ``N`` or ``method``.  Its bounds and default are
  integers; a value is rounded by `round_integer` (halves up) everywhere it
  meets the physics, and it reaches GLSL as a ``float`` uniform holding that
  exact integer, so shader code reads it like any float.

* ``color NAME R G B [MIN MAX]``: each component lies in the declared range, or in
  `COLOR_RANGE` ([0, 1], a reflectance) when the line declares none (a ``.brdf``
  file cannot declare one: its range is widened to hold its default).

This module never imports GL: it only turns text into data and GLSL snippets.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
import re
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Union

from explorer.errors import LocatedError

__all__ = [
    "MaterialError",
    "UnknownParameterError",
    "Parameter",
    "Material",
    "parse_material",
    "load_material",
    "parse_assignment",
    "round_integer",
    "Values",
    "GLSL_KEYWORDS",
]

Value = Union[float, bool, tuple]
"""A resolved parameter value: float, bool or an (r, g, b) tuple of floats."""

# A plain decimal number as BRDF Explorer's files write them: "1", "-2.", ".5",
# "1e-3".  Stricter than float(), which also takes "nan", "inf" and "1_0".
_NUMBER_RE = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?\Z")
_IDENTIFIER_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_MODEL_RE = re.compile(r"#\s*model\s*:\s*(.*?)\s*\Z", re.IGNORECASE)
_SPECIALISE_RE = re.compile(r"#\s*speciali[sz]e\s*:\s*(.*?)\s*\Z", re.IGNORECASE)
#: ``# texture: KIND``: what the textured view's grey texture varies (explorer.views.surface_texture).
_TEXTURE_RE = re.compile(r"#\s*texture\s*:\s*([A-Za-z_][A-Za-z0-9_]*)\s*\Z", re.IGNORECASE)
_MODEL_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*\Z")
# Preprocessor directives a GLSL compiler understands, plus our own #include.
_GLSL_DIRECTIVE_RE = re.compile(
    r"\s*#\s*(?:(?:define|undef|if|ifdef|ifndef|else|elif|endif|error|pragma"
    r"|extension|version|line|include)\b.*)?\Z"
)
_NEWLINE_RE = re.compile(r"\r\n|\r|\n")
#: A parameter line's trailing ``# UNIT: what it means`` (the unit one token: ``nm``, ``1``, ``1/nm``).
_DESCRIBED_RE = re.compile(r"\s*(\S+?):\s+(.*?)\s*\Z")

# Keywords and reserved words of GLSL 3.30 up to 4.60: a uniform with one of
# these names would not compile (now or when the shaders move to a newer GLSL).
GLSL_KEYWORDS: frozenset[str] = frozenset(
    """
    attribute const uniform varying buffer shared coherent volatile restrict
    readonly writeonly atomic_uint layout centroid flat smooth noperspective
    patch sample invariant precise break continue do for while switch case
    default if else subroutine in out inout int void bool true false float
    double discard return vec2 vec3 vec4 ivec2 ivec3 ivec4 bvec2 bvec3 bvec4
    uint uvec2 uvec3 uvec4 dvec2 dvec3 dvec4 mat2 mat3 mat4 mat2x2 mat2x3
    mat2x4 mat3x2 mat3x3 mat3x4 mat4x2 mat4x3 mat4x4 dmat2 dmat3 dmat4
    dmat2x2 dmat2x3 dmat2x4 dmat3x2 dmat3x3 dmat3x4 dmat4x2 dmat4x3 dmat4x4
    lowp mediump highp precision struct
    sampler1D sampler2D sampler3D samplerCube sampler1DShadow sampler2DShadow
    samplerCubeShadow sampler1DArray sampler2DArray sampler1DArrayShadow
    sampler2DArrayShadow isampler1D isampler2D isampler3D isamplerCube
    isampler1DArray isampler2DArray usampler1D usampler2D usampler3D
    usamplerCube usampler1DArray usampler2DArray sampler2DRect
    sampler2DRectShadow isampler2DRect usampler2DRect samplerBuffer
    isamplerBuffer usamplerBuffer sampler2DMS isampler2DMS usampler2DMS
    sampler2DMSArray isampler2DMSArray usampler2DMSArray samplerCubeArray
    samplerCubeArrayShadow isamplerCubeArray usamplerCubeArray
    image1D iimage1D uimage1D image2D iimage2D uimage2D image3D iimage3D
    uimage3D image2DRect iimage2DRect uimage2DRect imageCube iimageCube
    uimageCube imageBuffer iimageBuffer uimageBuffer image1DArray
    iimage1DArray uimage1DArray image2DArray iimage2DArray uimage2DArray
    imageCubeArray iimageCubeArray uimageCubeArray image2DMS iimage2DMS
    uimage2DMS image2DMSArray iimage2DMSArray uimage2DMSArray
    common partition active asm class union enum typedef template this
    resource goto inline noinline public static extern external interface
    long short half fixed unsigned superp input output hvec2 hvec3 hvec4
    fvec2 fvec3 fvec4 sampler3DRect filter sizeof cast namespace using
    row_major
    """.split()
)

_PARAMETER_USAGE = {
    "float": "float NAME MIN MAX DEFAULT",
    "int": "int NAME MIN MAX DEFAULT",
    "bool": "bool NAME 0|1",
    "color": "color NAME R G B [MIN MAX]",
}
#: A colour's range when its line declares none: a reflectance or an albedo, what BRDF Explorer's
#: colour picker edits. A ``.brd`` colour that is another quantity (an index, an optical depth) declares
#: its own (``color NAME R G B MIN MAX``); a ``.brdf`` file, which cannot, gets [0, 1] widened to its default.
COLOR_RANGE = (0.0, 1.0)
# An int is uploaded as a float uniform holding an exact integer: shader code keeps its float arithmetic.
_GLSL_TYPES = {"float": "float", "int": "float", "bool": "bool", "color": "vec3"}
# BRDF Explorer's other kinds of BRDF file (BRDFBase subclasses): named when a file starts with one.
_OTHER_KINDS = frozenset({"measured", "image", "imageslice", "merl", "lobe"})
_TRUE_WORDS = frozenset({"1", "true", "yes", "on"})
_FALSE_WORDS = frozenset({"0", "false", "no", "off"})


class MaterialError(LocatedError):
    """A material file, or a value meant for one, is wrong (see `explorer.errors.LocatedError`)."""


class UnknownParameterError(MaterialError, KeyError):
    """A parameter name that the material does not define.

    Also a ``KeyError``, so ``Material.parameter`` behaves like a mapping.
    """


def round_integer(value: float) -> int:
    """The integer an ``int`` parameter's value stands for: the nearest one, halves rounded up.

    The one rounding rule of the project, shared by the GL host (uniforms and ``# specialise:``
    constants), the numpy models, the app and the CLI.  It is GLSL's ``floor(x + 0.5)``, evaluated
    exactly: ``0.49999999999999994 + 0.5`` is 1.0 in float64, its fractional part is not.  Python's
    ``round`` (halves to even: ``round(0.5) == 0``) is not this rule.

    Parameters
    ----------
    value : float
        Finite.

    Returns
    -------
    int

    Examples
    --------
    >>> [round_integer(x) for x in (0.5, 1.5, 2.4999, 2.5, 2.5001, -0.5)]
    [1, 2, 2, 3, 3, 0]
    """
    x = float(value)
    whole = math.floor(x)
    return int(whole) + (1 if x - whole >= 0.5 else 0)  # x - floor(x) is exact for |x| < 2**52


def _fmt(x: float) -> str:
    """Format a number the way a material file would write it (no ``.0``)."""
    return str(int(x)) if float(x).is_integer() and abs(x) < 1e15 else repr(float(x))


def _to_float(value: numbers.Real) -> float:
    """``float(value)``; an integer too large for a float is infinite (then outside every range), not an error."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def _short(value: Any, limit: int = 60) -> str:
    """``repr(value)``, cut to ``limit`` characters (a message stays one short line whatever the input)."""
    try:
        text = repr(value)
    except ValueError:  # an int beyond Python's digit limit for str()
        text = f"<an integer of more than {sys.get_int_max_str_digits()} digits>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _parse_number(text: str) -> float | None:
    """Return `text` as a float, or None when it is not a plain number."""
    text = text.strip()
    return float(text) if _NUMBER_RE.match(text) else None


@dataclass(frozen=True)
class Parameter:
    """One line of a material's parameter section.

    Attributes
    ----------
    name : str
        The GLSL uniform name.
    type : {'float', 'int', 'bool', 'color'}
        The parameter kind (``int``: declared so in a ``.brd`` file).
    min, max : float or None
        The range of a float or an int (its slider), and of each component of a color
        (:data:`COLOR_RANGE` unless declared); None for a bool.
    default : float or bool or tuple of 3 floats
        The value used when nothing overrides it.
    line : int
        1-based line of the declaration in the material file.
    unit, doc : str
        From the line's trailing comment ``# UNIT: what it means`` (BRDF Explorer ignores what follows the
        fields): the unit (``1`` for a pure number, ``nm``, ...) and one line of meaning; empty without one.
    """

    name: str
    type: str
    min: float | None
    max: float | None
    default: Value
    line: int
    unit: str = ""
    doc: str = ""

    @property
    def glsl_type(self) -> str:
        """The GLSL type of the uniform: ``float``, ``bool`` or ``vec3``."""
        return _GLSL_TYPES[self.type]

    def is_integer(self) -> bool:
        """Whether the parameter is a declared ``int`` (an integer slider in a UI).

        A float whose range and default happen to be whole numbers (BRDF
        Explorer's ``metallic 0 1 0``, an exponent ``n 1 1000 100``) stays a
        float: only the declaration makes an integer.
        """
        return self.type == "int"

    def coerce(self, value: str | float | bool | Sequence[float]) -> Value:
        """Validate a value for this parameter and convert it to its type.

        Parameters
        ----------
        value : str or float or bool or sequence of float
            A Python value, or a string as ``--set name=value`` gives it:
            a number for a float; ``0|1|true|false|yes|no|on|off`` for a bool;
            ``r,g,b`` or one number (grey) for a color.

        Returns
        -------
        float or bool or tuple of 3 floats
            An int's value is a float holding an exact integer.

        Raises
        ------
        ValueError
            With a one-line reason when the value does not fit (for a float,
            naming the value and the range).
        """
        if self.type == "float":
            return self._coerce_float(value)
        if self.type == "int":
            # The range is checked before rounding; integer bounds keep the rounded value inside.
            return float(round_integer(self._coerce_float(value)))
        if self.type == "bool":
            return self._coerce_bool(value)
        return self._coerce_color(value)

    def _coerce_float(self, value: Any) -> float:
        if isinstance(value, str):
            number = _parse_number(value)
            if number is None:
                raise ValueError(f"{_short(value)} is not a number")
        elif isinstance(value, numbers.Real) and not isinstance(value, bool):
            number = _to_float(value)  # also numpy scalars
        else:
            raise ValueError(f"expected a number, got {_short(value)}")
        assert self.min is not None and self.max is not None
        # "not (a <= x <= b)" also rejects NaN.
        if not self.min <= number <= self.max:
            raise ValueError(
                f"value {_fmt(number) if math.isfinite(number) else number} is outside "
                f"its range [{_fmt(self.min)}, {_fmt(self.max)}]"
            )
        return number

    @staticmethod
    def _coerce_bool(value: Any) -> bool:
        if isinstance(value, bool):
            return value
        if isinstance(value, numbers.Integral) and value in (0, 1):
            return bool(value)
        if isinstance(value, str):
            word = value.strip().lower()
            if word in _TRUE_WORDS:
                return True
            if word in _FALSE_WORDS:
                return False
        raise ValueError(f"{_short(value)} is not a boolean (use 0|1|true|false|yes|no|on|off)")

    def _coerce_color(self, value: Any) -> tuple[float, float, float]:
        if isinstance(value, str):
            parts = [_parse_number(p) for p in value.split(",")]
            if len(parts) not in (1, 3) or None in parts:
                raise ValueError(f"{_short(value)} is not a color (use r,g,b or one number for grey)")
            components = [float(p) for p in parts if p is not None]
        elif isinstance(value, numbers.Real) and not isinstance(value, bool):
            components = [_to_float(value)]
        else:
            try:
                if isinstance(value, (bool, str, bytes)) or not all(
                    isinstance(c, numbers.Real) and not isinstance(c, bool) for c in value
                ):
                    raise TypeError
                components = [_to_float(c) for c in value]
            except TypeError:
                raise ValueError(f"{_short(value)} is not a color (use r,g,b or one number for grey)") from None
            if len(components) != 3:
                raise ValueError(f"a color needs 3 components, got {len(components)}")
        if not all(math.isfinite(c) for c in components):
            raise ValueError(f"{_short(value)} is not a finite color")
        lo, hi = (COLOR_RANGE if self.min is None or self.max is None else (self.min, self.max))
        for c in components:
            if not lo <= c <= hi:
                raise ValueError(f"component {_fmt(c)} is outside its range [{_fmt(lo)}, {_fmt(hi)}]")
        r, g, b = components * 3 if len(components) == 1 else components
        return (r, g, b)

    def info(self) -> dict[str, Any]:
        """JSON-friendly description: name, type, min, max, default."""
        default: Any = list(self.default) if isinstance(self.default, tuple) else self.default
        return {"name": self.name, "type": self.type, "min": self.min, "max": self.max, "default": default,
                "unit": self.unit, "doc": self.doc}

    @property
    def meaning(self) -> str:
        """``"doc (unit)"`` for a tooltip or ``info``: what the parameter means; empty without a comment."""
        unit = f" ({self.unit})" if self.unit and self.unit != "1" else ""
        return f"{self.doc}{unit}" if self.doc else self.unit


class Values(dict):
    """A material's parameter values, typed and frozen: what :meth:`Material.resolve` returns and every consumer reads.

    Each declared parameter holds its type's value: a float, a bool, an ``(r, g, b)`` tuple of floats, and
    for an ``int`` a float holding the exact integer `round_integer` gives (as its GL uniform holds it), so
    that the GL host, the numpy twins, the exports and the app evaluate the same numbers. Built once
    (:meth:`Material.resolve`: ranges checked; :meth:`Material.typed_values` for values from elsewhere);
    a consumer never rounds again. A ``dict`` that refuses changes (``{**values, name: v}`` makes a new
    mapping; resolve it again).
    """

    __slots__ = ()

    def _frozen(self, *args, **kwargs):
        raise TypeError("a material's values are frozen: resolve a new set (Material.resolve({**values, name: value}))")

    __setitem__ = __delitem__ = update = pop = popitem = clear = setdefault = __ior__ = _frozen  # type: ignore[assignment]

    def __reduce__(self):
        return (type(self), (dict(self),))

    def integer(self, name: str) -> int:
        """An ``int`` parameter's value as a Python ``int``."""
        return int(self[name])


@dataclass
class Material:
    """A parsed material file.

    Attributes
    ----------
    path : str
        Where it came from (used in every message).
    parameters : list of Parameter
        In file order.
    shader : str
        The shader section's text, lines ending in ``\\n``; verbatim except
        that ``#`` comment lines (which BRDF Explorer drops) are blanked.
    shader_line : int
        1-based file line of the shader text's first line, so that GLSL
        compile errors can be mapped back (see ``explorer.materials.glsl``).
    model : str or None
        The numpy twin named by a ``# model: NAME`` comment.
    warnings : list of str
        One-line ``"{path}:{line}: ..."`` notes about things that were skipped.
    """

    path: str
    parameters: list[Parameter]
    shader: str
    shader_line: int
    model: str | None = None
    specialised: tuple[str, ...] = ()
    warnings: list[str] = field(default_factory=list)
    #: A measured material's data (a MERL table, :class:`explorer.materials.merl.MerlTable`), which makes
    #: its numpy twin (``measured.twin(values)``); None for an analytic file.
    measured: Any = field(default=None, compare=False, repr=False)
    #: The textured view's mapping of a grey texture, from ``# texture: KIND`` (``thickness``: a film's D_inc;
    #: ``bragg``: a Bragg mirror's Lambda and delta); None: no textured view.
    texture: str | None = None

    def parameter(self, name: str) -> Parameter:
        """Return the parameter called `name`.

        Raises
        ------
        UnknownParameterError
            (a MaterialError and a KeyError) listing the valid names.
        """
        for p in self.parameters:
            if p.name == name:
                return p
        from explorer.errors import did_you_mean

        valid = ", ".join(p.name for p in self.parameters) or "(none)"
        hint = did_you_mean(name, [p.name for p in self.parameters])
        raise UnknownParameterError(self.path, None, f"unknown parameter {name!r}{hint}; valid names: {valid}")

    def resolve(
        self, overrides: Mapping[str, str | float | bool | Sequence[float]] = MappingProxyType({})
    ) -> Values:
        """Return every parameter's value: defaults, overridden by `overrides`.

        Parameters
        ----------
        overrides : mapping of str to value
            Values as Python objects or as strings from ``--set name=value``
            (see `Parameter.coerce` for what each type accepts).

        Returns
        -------
        Values
            Name to float, bool or (r, g, b) tuple, in file order (frozen; ints exact integers).

        Raises
        ------
        MaterialError
            For an unknown name (listing the valid ones) or a value that does
            not fit (naming the parameter, the value and the range).
        """
        values: dict[str, Value] = {p.name: p.default for p in self.parameters}
        # An index naming a medium goes last: it selects its medium_NAME whatever number that held before
        # (values read back from a state and a design's n2=chitin, in one mapping).
        names_medium = lambda item: isinstance(item[1], str) and not _NUMBER_RE.match(item[1].strip())  # noqa: E731
        for name, value in sorted(overrides.items(), key=names_medium):
            if isinstance(value, str) and f"medium_{name}" in values and not _NUMBER_RE.match(value.strip()):
                # An index naming a medium (n2=chitin): the material's medium_NAME selects it (explorer.materials.media).
                from explorer.materials.media import medium_values

                try:
                    values.update(medium_values(self, name, value))
                except LocatedError as exc:
                    if exc.path != "--set":  # a medium's file is wrong: its own file and line
                        raise
                    raise MaterialError(self.path, self.parameter(name).line, f"parameter {name!r}: {exc.message}") from None
                continue
            if f"medium_{name}" in values and f"medium_{name}" not in overrides:
                values[f"medium_{name}"] = 0.0  # a number replaces a medium
            p = self.parameter(name)
            try:
                values[name] = p.coerce(value)
            except ValueError as exc:
                # Name the line that declares the parameter: that is where its range is.
                raise MaterialError(self.path, p.line, f"parameter {name!r}: {exc}") from None
        if "medium_nh" in values:  # a host naming a medium must be lossless (explorer.materials.media)
            from explorer.materials.media import host_problem

            problem = host_problem(values, self.parameter("nh").min)
            if problem:
                raise MaterialError(self.path, self.parameter("medium_nh").line, problem)
        return Values(values)

    def typed_values(self, values: Mapping[str, object]) -> Values:
        """The :class:`Values` of ``values`` from elsewhere (a caller's mapping): every ``int`` parameter's value
        rounded by `round_integer`, nothing else checked; a :class:`Values` is returned as it is.

        The GL host and :func:`explorer.materials.models.model_for` read their values through this, so that both
        evaluate the same integers whatever the caller passed (``resolve`` has rounded what it coerced).
        Names the material does not declare are kept as they are.
        """
        if isinstance(values, Values):
            return values
        result = dict(values)
        for p in self.parameters:
            if p.type == "int" and p.name in result:
                result[p.name] = float(round_integer(result[p.name]))
        return Values(result)

    def uniform_declarations(self) -> str:
        """GLSL uniform declarations for the parameters, one per line.

        Returns
        -------
        str
            e.g. ``"uniform float n;\\nuniform bool divide_by_NdotL;\\n"``;
            empty when there are no parameters.
        """
        return "".join(f"uniform {p.glsl_type} {p.name};\n" for p in self.parameters)

    def info(self) -> dict[str, Any]:
        """JSON-friendly summary for UIs and ``--info`` output.

        Returns
        -------
        dict
            ``{"parameters": [{"name", "type", "min", "max", "default"}, ...]}``
            in file order; a color's default is a list of three numbers, a
            bool's min and max are None and its default true/false.
        """
        return {"parameters": [p.info() for p in self.parameters]}


class _Parser:
    """Line-by-line state machine; one instance per file."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.warnings: list[str] = []
        self.parameters: list[Parameter] = []
        self.names: dict[str, int] = {}
        self.model: str | None = None
        self.model_line = 0
        self.texture: str | None = None
        self.specialised: list[tuple[str, int]] = []
        self.header_seen = False
        self.section: str | None = None
        self.section_line = 0
        self.shader_lines: list[str] | None = None
        self.shader_line = 0
        self.shader_begin_line = 0

    def error(self, line: int | None, message: str) -> MaterialError:
        return MaterialError(self.path, line, message)

    def warn(self, line: int, message: str) -> None:
        self.warnings.append(f"{self.path}:{line}: {message}")

    def parse(self, text: str) -> Material:
        lines = _NEWLINE_RE.split(text.removeprefix("\ufeff"))
        if lines and lines[-1] == "":
            lines.pop()  # the final newline does not start another line
        for number, line in enumerate(lines, start=1):
            if self.section == "shader":
                self.shader_text_line(number, line)
            else:
                self.line(number, line)
        if self.section is not None:
            raise self.error(
                self.section_line,
                f"section {self.section!r} is not terminated (missing '::end {self.section}')",
            )
        if not self.header_seen:
            raise self.error(None, "missing 'analytic' header (the file has no content)")
        if self.shader_lines is None:
            raise self.error(None, "no shader section ('::begin shader' ... '::end shader')")
        return Material(
            path=self.path,
            parameters=self.parameters,
            shader="".join(s + "\n" for s in self.shader_lines),
            shader_line=self.shader_line,
            model=self.model,
            specialised=self._check_specialised(),
            warnings=self.warnings,
            texture=self.texture,
        )

    def line(self, number: int, line: str) -> None:
        """Handle a line outside the shader section."""
        stripped = line.strip()
        if not stripped:
            return
        if stripped.startswith("#"):
            self.comment(number, stripped)
            return
        tokens = stripped.split()
        if not self.header_seen:
            self.header(number, tokens)
            return
        if tokens[0] == "::begin":
            self.begin(number, tokens)
        elif tokens[0] == "::end":
            self.end(number, tokens)
        elif self.section == "parameters":
            self.parameter(number, stripped)
        elif self.section is None:
            # BRDF Explorer silently ignores these; say so, they are likely typos.
            self.warn(number, f"ignoring text outside any section: {stripped!r}")
        # else: a line of an unknown section, skipped (warned at ::begin)

    def comment(self, number: int, stripped: str) -> None:
        texture = _TEXTURE_RE.match(stripped)
        if texture is not None:
            self.texture = texture.group(1).lower()
            return
        special = _SPECIALISE_RE.match(stripped)
        if special is not None:
            self.specialised += [(name, number) for name in special.group(1).replace(",", " ").split()]
            return
        match = _MODEL_RE.match(stripped)
        if match is None:
            return
        name = match.group(1)
        if not _MODEL_NAME_RE.match(name):
            self.warn(number, f"ignoring '# model:' comment with invalid model name {name!r}")
        elif self.model is None:
            self.model, self.model_line = name, number
        elif name != self.model:
            self.warn(number, f"ignoring second model {name!r}; using {self.model!r} from line {self.model_line}")

    def _check_specialised(self) -> tuple[str, ...]:
        """``# specialise: NAME``: int parameters the host compiles in as constants."""
        by_name = {p.name: p for p in self.parameters}
        for name, number in self.specialised:
            parameter = by_name.get(name)
            if parameter is None or parameter.type != "int":
                raise self.error(number, f"'# specialise: {name}' needs an int parameter of that name")
        return tuple(dict.fromkeys(name for name, _ in self.specialised))

    def header(self, number: int, tokens: list[str]) -> None:
        kind = tokens[0]
        if kind == "analytic":
            self.header_seen = True
            if len(tokens) > 1:  # BRDF Explorer ignores these too
                self.warn(number, f"ignoring text after 'analytic': {' '.join(tokens[1:])!r}")
        elif kind == "bparam":
            raise self.error(
                number, "this is a BRDF Explorer parameter file ('bparam'); load the material it refers to"
            )
        elif kind.startswith("::"):
            raise self.error(number, f"missing 'analytic' header before {kind!r}")
        elif kind in _OTHER_KINDS:
            raise self.error(
                number, f"unsupported material kind {kind!r}; only 'analytic' materials can be loaded"
            )
        else:  # likely no material at all: its text is not shown (it may be any file, a secret one too)
            raise self.error(number, "not a material file (expected 'analytic' on the first line)")

    def begin(self, number: int, tokens: list[str]) -> None:
        if len(tokens) < 2:
            raise self.error(number, "'::begin' without a section name")
        name = tokens[1]
        if self.section is not None:
            raise self.error(
                number,
                f"'::begin {name}' inside section {self.section!r} opened on line "
                f"{self.section_line}; sections cannot nest",
            )
        self.section, self.section_line = name, number
        if name == "shader":
            if self.shader_lines is not None:  # BRDF Explorer keeps the last one
                self.warn(number, f"second shader section replaces the one on line {self.shader_begin_line}")
            self.shader_lines = []
            self.shader_line = number + 1
            self.shader_begin_line = number
        elif name == "isFunc":
            self.warn(number, "skipping section 'isFunc' (BRDF Explorer's importance sampling; not used here)")
        elif name != "parameters":
            self.warn(number, f"skipping unknown section {name!r}")

    def end(self, number: int, tokens: list[str]) -> None:
        name = tokens[1] if len(tokens) > 1 else ""
        if self.section is None:
            raise self.error(number, f"{' '.join(tokens[:2])!r} without a matching '::begin'")
        if name != self.section:
            raise self.error(
                number,
                f"'::end {name}' does not close section {self.section!r} opened on line {self.section_line}",
            )
        self.section = None

    def shader_text_line(self, number: int, line: str) -> None:
        """Handle a line inside the shader section."""
        tokens = line.split(maxsplit=2)
        if tokens and tokens[0] in ("::begin", "::end"):
            if tokens[0] == "::begin":
                self.begin(number, tokens)  # raises: sections cannot nest
            self.end(number, tokens)
            return
        assert self.shader_lines is not None
        stripped = line.strip()
        if stripped.startswith("#") and not _GLSL_DIRECTIVE_RE.match(line):
            # A comment line: BRDF Explorer drops it, a GLSL compiler would
            # reject it.  Blank it so that line numbers still match the file.
            if _MODEL_RE.match(stripped):
                self.warn(number, "'# model:' inside the shader section is ignored")
            line = ""
        self.shader_lines.append(line)

    def parameter(self, number: int, stripped: str) -> None:
        # BRDF Explorer ignores anything after the last field; we only allow
        # a trailing "# comment" there and insist on the exact field count.
        tokens = stripped.split("#", 1)[0].split()
        kind = tokens[0]
        usage = _PARAMETER_USAGE.get(kind)
        brdf_explorer_file = self.path.lower().endswith(".brdf")
        if usage is None or (kind == "int" and brdf_explorer_file):
            expected = "float, bool or color" if brdf_explorer_file else "float, int, bool or color"
            where = " in BRDF Explorer's .brdf files (int is for .brd files)" if kind == "int" else ""
            raise self.error(number, f"unknown parameter type {kind!r}{where} (expected {expected})")
        expected = len(usage.replace("[", "").replace("]", "").split())
        allowed = (expected - 2, expected) if kind == "color" and not brdf_explorer_file else (expected - 2,) if kind == "color" else (expected,)
        if len(tokens) not in allowed:
            fields = " or ".join(str(n - 1) for n in allowed)
            shown = usage if len(allowed) > 1 else usage.replace(" [MIN MAX]", "")
            raise self.error(
                number, f"{'an' if kind == 'int' else 'a'} {kind} parameter has {fields} fields ({shown}), got {len(tokens) - 1}"
            )
        name = tokens[1]
        self.check_name(number, name)
        if kind == "bool":
            if tokens[2] not in ("0", "1"):
                raise self.error(number, f"bool {name!r}: default must be 0 or 1, got {tokens[2]!r}")
            param = Parameter(name, "bool", None, None, tokens[2] == "1", number)
        else:
            fields = ("red", "green", "blue", "min", "max") if kind == "color" else ("min", "max", "default")
            values: list[float] = []
            for label, token in zip(fields, tokens[2:]):
                value = _parse_number(token)
                if value is None or not math.isfinite(value):
                    raise self.error(number, f"{kind} {name!r}: {label} {token!r} is not a number")
                if kind == "int" and not (value.is_integer() and abs(value) < 2**53):
                    raise self.error(number, f"int {name!r}: {label} {token!r} is not an integer")
                values.append(value)
            if kind != "color":
                lo, hi, default = values
                if lo > hi:
                    raise self.error(number, f"{kind} {name!r}: min {_fmt(lo)} is greater than max {_fmt(hi)}")
                if not lo <= default <= hi:
                    raise self.error(
                        number, f"{kind} {name!r}: default {_fmt(default)} is outside [{_fmt(lo)}, {_fmt(hi)}]"
                    )
                param = Parameter(name, kind, lo, hi, default, number)
            else:
                param = self.color(number, name, values, brdf_explorer_file)
        comment = stripped.split("#", 1)[1] if "#" in stripped else ""
        described = _DESCRIBED_RE.match(comment)
        if described:
            param = dataclasses.replace(param, unit=described.group(1), doc=described.group(2))
        elif comment.strip():
            param = dataclasses.replace(param, doc=comment.strip())
        self.names[name] = number
        self.parameters.append(param)

    def color(self, number: int, name: str, values: list[float], brdf_explorer_file: bool) -> Parameter:
        """A colour line's parameter: its declared range, else :data:`COLOR_RANGE` (see there)."""
        default = (values[0], values[1], values[2])
        if len(values) == 5:
            lo, hi = values[3], values[4]
            if lo > hi:
                raise self.error(number, f"color {name!r}: min {_fmt(lo)} is greater than max {_fmt(hi)}")
        elif brdf_explorer_file:
            lo, hi = min(COLOR_RANGE[0], *default), max(COLOR_RANGE[1], *default)
        else:
            lo, hi = COLOR_RANGE
        if not all(lo <= c <= hi for c in default):
            declared = "" if len(values) == 5 else "; declare another range: color NAME R G B MIN MAX"
            raise self.error(number, f"color {name!r}: default {' '.join(map(_fmt, default))} is outside [{_fmt(lo)}, {_fmt(hi)}]{declared}")
        return Parameter(name, "color", lo, hi, default, number)

    def check_name(self, number: int, name: str) -> None:
        if not _IDENTIFIER_RE.match(name):
            raise self.error(number, f"parameter name {name!r} is not a valid GLSL identifier")
        if name in GLSL_KEYWORDS:
            raise self.error(number, f"parameter name {name!r} is a GLSL keyword")
        if name.startswith("gl_"):
            raise self.error(number, f"parameter name {name!r} uses the reserved prefix 'gl_'")
        if name in self.names:
            raise self.error(number, f"duplicate parameter {name!r} (first defined on line {self.names[name]})")
        if "__" in name:  # reserved by the GLSL spec, though most drivers only warn
            self.warn(number, f"parameter name {name!r} contains '__', which GLSL reserves")


def parse_material(text: str, path: str | os.PathLike[str] = "<string>") -> Material:
    """Parse the text of a material file.

    Parameters
    ----------
    text : str
        The whole file; LF, CRLF or CR line endings.
    path : str or path-like
        Name used in the material and in every message.

    Returns
    -------
    Material

    Raises
    ------
    MaterialError
        With the offending line, for: a missing or non-``analytic`` header,
        an unterminated, unmatched or nested section, a malformed parameter
        (unknown type, ``int`` in a ``.brdf`` file, wrong number of fields,
        non-numeric value, an int's non-integer bound or default, min > max,
        default outside [min, max], bool default not 0/1, duplicate or invalid
        name), or no shader section.
    """
    return _Parser(os.fspath(path)).parse(text)


def load_material(path: str | os.PathLike[str]) -> Material:
    """Read and parse a material file (``.brd`` or BRDF Explorer's ``.brdf``), or a MERL ``.binary`` table.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    Material

    Raises
    ------
    MaterialError
        When the file cannot be read, or does not parse (see `parse_material`).
        Also for a ``.binary`` file that is not a MERL isotropic table, and other binary data (one line
        each: what the file is, what is supported).

    Notes
    -----
    A MERL ``.binary`` table (by suffix, or by its header and size) loads as a measured material without
    parameters (:mod:`explorer.materials.merl`). A Python file of the same stem beside a material file is its
    plugin twin, loaded here (:mod:`explorer.materials.plugins`; its errors are a ``PluginError`` with file and line).
    """
    name = os.fspath(path)
    try:
        with open(name, "rb") as f:
            data = f.read()
    except OSError as exc:
        raise MaterialError(name, None, f"cannot read material file: {exc.strerror or exc}") from None
    from explorer.materials import merl

    try:
        if name.lower().endswith(merl.SUFFIX) or merl.is_merl(data):
            table = merl.MerlTable.from_bytes(data, name)
            return Material(path=name, parameters=[], shader=merl.SHADER, shader_line=1, model=merl.MODEL, measured=table)
        if merl.looks_binary(data):  # no text: say what it is and what is supported, not its garbled first line
            raise merl.not_a_material(name, data)
    except merl.MerlFileError as error:  # a MaterialError for every caller of the loader
        raise MaterialError(error.path, error.line, error.message) from None
    try:
        material = parse_material(data.decode("utf-8-sig"), name)
    except UnicodeDecodeError:
        # Old files may carry Latin-1 comments; BRDF Explorer reads bytes and
        # does not care, so neither do we (but say so).
        material = parse_material(data.decode("latin-1"), name)
        material.warnings.insert(0, f"{name}:1: file is not UTF-8; read as Latin-1")
    from explorer.materials import plugins

    plugins.attach(material)  # a Python file of the same stem beside it: its twin (explorer.materials.plugins)
    return material


def parse_assignment(text: str) -> tuple[str, str]:
    """Split a CLI ``--set name=value`` argument.

    Parameters
    ----------
    text : str
        ``"name=value"``; whitespace around either part is dropped.

    Returns
    -------
    (str, str)
        The name and the value string (to pass to `Material.resolve`).

    Raises
    ------
    MaterialError
        (path ``"--set"``) when there is no ``=``, no name or no value.
    """
    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not name:
        raise MaterialError("--set", None, f"expected name=value, got {text!r}")
    if not value:
        raise MaterialError("--set", None, f"missing value in {text!r}")
    return name, value
