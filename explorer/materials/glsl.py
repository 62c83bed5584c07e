"""The one GLSL preprocessor that assembles every shader program.

`ShaderBuilder` concatenates chunks (a material's shader section, whole
``.glsl`` files), expands ``#include "file"`` once per file (as vispy and
moderngl-window's loader do), and puts ``#line`` directives everywhere the
numbering changes, so that a driver's compile log can be mapped back to the
real file and line by `map_log` and `compile_error_message`.

Line numbering
--------------
Every chunk and included file is a GLSL *source string* with its own number
``S`` (``Program.sources[S]`` is its file name; 0 is the generated preamble).
``#line`` uses the GLSL 3.30 form ``#line L S``: the next line is line ``L``
of source string ``S``.

Mesa (llvmpipe included) forgets the source-string number in every error it
reports after parsing (``0:12(5): error: `foo' undeclared`` even inside
source 3); only syntax and preprocessor errors keep it.  So by default the
line number itself also carries the source: line ``L`` of source ``S`` is
numbered ``S * LINE_STRIDE + L``.  `map_log` decodes both forms, so logs from
drivers that do keep source numbers map the same way.  Pass
``line_stride=0`` to `ShaderBuilder` for plain ``#line L S`` numbering.

Not a full C preprocessor: ``#include`` is expanded even inside ``#if 0``
(it is ignored inside ``/* */`` comments); everything else, ``#define`` and
``#ifdef`` included, passes through to the driver unchanged.

This module never imports GL.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from explorer.errors import LocatedError

__all__ = [
    "LINE_STRIDE",
    "ShaderError",
    "Program",
    "ShaderBuilder",
    "map_log",
    "compile_error",
    "compile_error_message",
]

LINE_STRIDE = 100_000
"""Line numbers of source string ``S`` start at ``S * LINE_STRIDE``."""

PREAMBLE = "<preamble>"
"""Name of source string 0: the ``#version`` and ``#define`` lines."""

_DIRECTIVE_RE = re.compile(r"\s*#\s*([A-Za-z_]\w*)")
_INCLUDE_RE = re.compile(r'\s*#\s*include\s*(?:"([^"]+)"|<([^>]+)>)\s*(?://.*|/\*.*)?\Z')
_IDENTIFIER_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_NEWLINE_RE = re.compile(r"\r\n|\r|\n")


class ShaderError(LocatedError):
    """A shader could not be assembled or compiled (see `explorer.errors.LocatedError`)."""


@dataclass(frozen=True)
class Program:
    """Assembled GLSL source, ready for the driver.

    Attributes
    ----------
    code : str
        The whole shader; ``#version`` is line 1.
    sources : list of str
        Source-string number to file name (0 is `PREAMBLE`).
    files : list of pathlib.Path
        Every file that was read, for reload-on-change watchers.
    line_stride : int
        The numbering used (see the module notes); 0 for plain numbering.
    """

    code: str
    sources: list[str]
    files: list[Path] = field(default_factory=list)
    line_stride: int = LINE_STRIDE

    def locate(self, source: int, line: int) -> tuple[str, int]:
        """Map a (source-string, line) pair as the driver reports it to (file, line)."""
        s, n = _decode(source, line, self.line_stride)
        return (self.sources[s] if 0 <= s < len(self.sources) else f"<source {s}>"), n

    def map_log(self, log: str) -> list[str]:
        """`map_log` for this program."""
        return map_log(log, self.sources, self.line_stride)

    def error_message(self, log: str) -> str:
        """`compile_error_message` for this program."""
        return compile_error_message(log, self.sources, self.line_stride)


def _split_lines(text: str) -> list[str]:
    """Split like universal newlines; a final newline does not add a line."""
    lines = _NEWLINE_RE.split(text.removeprefix("\ufeff"))
    if lines[-1] == "":
        lines.pop()
    return lines


def _ends_in_comment(text: str, in_comment: bool) -> bool:
    """Whether a ``/* */`` comment is still open at the end of `text`."""
    i = 0
    while True:
        if in_comment:
            end = text.find("*/", i)
            if end < 0:
                return True
            in_comment, i = False, end + 2
        else:
            start, line_comment = text.find("/*", i), text.find("//", i)
            if start < 0 or 0 <= line_comment < start:
                return False
            in_comment, i = True, start + 2


@dataclass
class _Chunk:
    name: str
    text: str | None  # None: read `path` at build time
    path: Path | None
    first_line: int


class ShaderBuilder:
    """Assemble one GLSL shader from chunks and files with ``#include``.

    Parameters
    ----------
    include_dirs : sequence of path-like
        Searched in order for ``#include`` targets, after the including
        file's own directory.
    version : str
        Written as ``#version {version}`` on line 1.
    max_depth : int
        Deepest allowed ``#include`` nesting.
    line_stride : int
        See the module notes; 0 gives plain ``#line L S`` numbering.

    Examples
    --------
    >>> b = ShaderBuilder(["shaders/lib"])                  # doctest: +SKIP
    >>> b.add_source(material.uniform_declarations(), "<uniforms>")
    >>> b.add_source(material.shader, material.path, material.shader_line)
    >>> b.add_file("shaders/views/sphere.glsl")
    >>> program = b.build()
    """

    def __init__(
        self,
        include_dirs: Sequence[str | os.PathLike[str]] = (),
        version: str = "330 core",
        max_depth: int = 16,
        line_stride: int = LINE_STRIDE,
        generated: Mapping[str, Callable[[], str]] | None = None,
    ) -> None:
        if "\n" in version or "\r" in version:
            raise ValueError("version must be one line")
        self.include_dirs = [Path(d) for d in include_dirs]
        if generated is None:  # the library's shared constants (explorer.materials.shader_constants)
            from explorer.materials.shader_constants import GENERATED as generated
        self.generated = dict(generated)
        self.version = version
        self.max_depth = max_depth
        self.line_stride = line_stride
        self._chunks: list[_Chunk] = []
        self._defines: dict[str, str] = {}

    def define(self, name: str, value: str | int | float | bool = "") -> None:
        """Add ``#define name value`` right after ``#version``.

        Parameters
        ----------
        name : str
            A GLSL identifier.
        value : str or int or float or bool
            Written as is (bools as 1/0).  Defining a name again replaces it.
        """
        if not _IDENTIFIER_RE.match(name):
            raise ValueError(f"not a valid macro name: {name!r}")
        text = str(int(value)) if isinstance(value, bool) else str(value)
        if "\n" in text or "\r" in text:
            raise ValueError(f"macro {name} value must be one line")
        self._defines[name] = text

    def add_source(self, text: str, name: str, first_line: int = 1) -> None:
        """Append a chunk of GLSL text.

        Parameters
        ----------
        text : str
            The GLSL.
        name : str
            The file it comes from (messages name it; relative ``#include``\\ s
            are looked up next to it), or a ``<label>`` for generated text.
        first_line : int
            The line of `name` that the chunk's first line is.
        """
        self._chunks.append(_Chunk(name, text, None, first_line))

    def add_file(self, path: str | os.PathLike[str]) -> None:
        """Append a whole GLSL file (read when `build` runs)."""
        self._chunks.append(_Chunk(os.fspath(path), None, Path(path), 1))

    def build(self) -> Program:
        """Assemble the program.

        Returns
        -------
        Program

        Raises
        ------
        ShaderError
            For a missing or unreadable file, a missing include (naming the
            includer's file and line and the directories searched), a
            malformed ``#include``, or nesting deeper than ``max_depth``.
        """
        return _Assembly(self).run()


class _Assembly:
    """The state of one `ShaderBuilder.build` call."""

    def __init__(self, builder: ShaderBuilder) -> None:
        self.builder = builder
        self.out: list[str] = [f"#version {builder.version}"]
        self.out += [f"#define {k} {v}".rstrip() for k, v in builder._defines.items()]
        self.sources: list[str] = [PREAMBLE]
        self.included: set[Path] = set()
        self.files: list[Path] = []

    def run(self) -> Program:
        for chunk in self.builder._chunks:
            if chunk.path is None:
                assert chunk.text is not None
                base = None if chunk.name.startswith("<") else Path(chunk.name).parent
                self.emit(_split_lines(chunk.text), chunk.name, chunk.first_line, base, 0)
            elif self.claim(chunk.path):
                lines = self.read(chunk.path, chunk.name, None, None)
                self.emit(lines, chunk.name, 1, chunk.path.parent, 0)
        return Program("\n".join(self.out) + "\n", self.sources, self.files, self.builder.line_stride)

    def claim(self, path: Path) -> bool:
        """Mark a file as included; False when it already was (once per program)."""
        key = path.resolve()
        if key in self.included:
            return False
        self.included.add(key)
        return True

    def read(self, path: Path, name: str, includer: str | None, line: int | None) -> list[str]:
        try:
            # utf-8-sig: a BOM would be a syntax error for the driver.
            text = path.read_text(encoding="utf-8-sig")
        except (OSError, UnicodeDecodeError) as exc:
            reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            if includer is None:
                raise ShaderError(name, None, f"cannot read shader file: {reason}") from None
            raise ShaderError(includer, line, f"cannot read included file {name!r}: {reason}") from None
        self.files.append(path)
        return _split_lines(text)

    def source_number(self, name: str) -> int:
        if name not in self.sources:
            self.sources.append(name)
        return self.sources.index(name)

    def line_directive(self, line: int, source: int) -> str:
        return f"#line {source * self.builder.line_stride + line} {source}"

    def emit(self, lines: list[str], name: str, first_line: int, base: Path | None, depth: int) -> None:
        """Append `lines` (of file `name`, starting at `first_line`), expanding includes."""
        stride = self.builder.line_stride
        if stride and first_line + len(lines) > stride:
            raise ShaderError(name, None, f"too long for line numbering ({stride} lines at most)")
        source = self.source_number(name)
        self.out.append(self.line_directive(first_line, source))
        in_comment = False
        for number, text in enumerate(lines, start=first_line):
            directive = None if in_comment else _DIRECTIVE_RE.match(text)
            keyword = directive.group(1) if directive else None
            if keyword == "version":
                self.out.append("")  # only the preamble's #version counts
            elif keyword == "include":
                self.include(text, name, number, base, depth)
            else:
                self.out.append(text)
            in_comment = _ends_in_comment(text, in_comment)

    def include(self, text: str, name: str, number: int, base: Path | None, depth: int) -> None:
        match = _INCLUDE_RE.match(text)
        if match is None:
            raise ShaderError(name, number, 'malformed #include; expected #include "file" or #include <file>')
        target = match.group(1) or match.group(2)
        if target in self.builder.generated:  # written from Python, not read: once per program
            key = Path("<generated>") / target
            if key in self.included:
                self.out.append("")
                return
            self.included.add(key)
            self.emit(_split_lines(self.builder.generated[target]()), f"<{target}>", 1, None, depth + 1)
            self.out.append(self.line_directive(number + 1, self.source_number(name)))
            return
        path = self.resolve(target, name, number, base)
        if not self.claim(path):
            self.out.append("")  # already included (or a cycle): keep the line count
            return
        if depth + 1 > self.builder.max_depth:
            raise ShaderError(
                name, number, f"#include {target!r} nests deeper than {self.builder.max_depth} levels"
            )
        display = os.path.normpath(path)
        lines = self.read(path, display, name, number)
        self.emit(lines, display, 1, path.parent, depth + 1)
        # Back in the includer: the next line is the one after the #include.
        self.out.append(self.line_directive(number + 1, self.source_number(name)))

    def resolve(self, target: str, name: str, number: int, base: Path | None) -> Path:
        """
        The file ``#include target`` names, confined: relative, without ``..``, found inside the including
        file's folder or an include folder, and resolving (symbolic links followed) inside that folder.
        Anything else is a :class:`ShaderError` naming the include, and nothing outside is read.
        """
        dirs = ([base] if base is not None else []) + self.builder.include_dirs
        parts = re.split(r"[\\/]", target)
        if os.path.isabs(target) or target.startswith(("/", "\\")) or re.match(r"[A-Za-z]:", target) or ".." in parts:
            raise ShaderError(name, number, f"#include {target!r} leaves the material's folder and the shader library "
                                            "(includes are relative, without '..')")
        for folder in dirs:
            candidate = folder / target
            if candidate.is_file():
                if not candidate.resolve().is_relative_to(folder.resolve()):
                    raise ShaderError(name, number, f"#include {target!r} resolves outside {os.path.normpath(folder)} (a link)")
                return candidate
        searched = ", ".join(os.path.normpath(d) for d in dirs) or "(no directories)"
        raise ShaderError(name, number, f"cannot find include {target!r}; searched: {searched}")


# --- compile logs ----------------------------------------------------------

# Mesa:         0:12(3): error: `foo' undeclared
_MESA_RE = re.compile(r"\s*(\d+):(\d+)\((\d+)\)\s*:\s*(.*)\Z")
# NVIDIA:       0(12) : error C1008: undefined variable "foo"
_NVIDIA_RE = re.compile(r"\s*(\d+)\((\d+)\)\s*:\s*(.*)\Z")
# AMD, Intel, Apple:  ERROR: 0:12: 'foo' : undeclared identifier
_AMD_RE = re.compile(r"\s*(ERROR|WARNING|INFO|NOTE)\s*:\s*(\d+):(\d+)\s*:\s*(.*)\Z", re.IGNORECASE)
# The severity at the start of Mesa's and NVIDIA's message text:
# "error: ...", "preprocessor error: ...", "error C1008: ...", "warning C7011: ..."
_SEVERITY_RE = re.compile(r"((?:[A-Za-z]+\s+)?(error|warning|info|note)\b[^:]*):\s*(.*)\Z", re.IGNORECASE)


@dataclass(frozen=True)
class _Entry:
    source: int
    line: int
    column: int | None
    severity: str | None  # error, warning, info, note; None when unknown
    label: str | None  # the severity as written, e.g. "error C1008"
    message: str


def _parse_entry(text: str) -> _Entry | None:
    """Parse one log line in any of the known formats; None if it is not one."""
    if m := _MESA_RE.match(text):
        source, line, column, rest = int(m[1]), int(m[2]), int(m[3]), m[4]
    elif m := _NVIDIA_RE.match(text):
        source, line, column, rest = int(m[1]), int(m[2]), None, m[3]
    elif m := _AMD_RE.match(text):
        severity = m[1].lower()
        return _Entry(int(m[2]), int(m[3]), None, severity, severity, m[4].strip())
    else:
        return None
    if s := _SEVERITY_RE.match(rest):
        return _Entry(source, line, column, s[2].lower(), s[1].strip(), s[3].strip())
    return _Entry(source, line, column, None, None, rest.strip())


def _decode(source: int, line: int, stride: int) -> tuple[int, int]:
    """Undo the ``S * stride + L`` numbering; trust it over the reported source."""
    if stride and line >= stride:
        return divmod(line, stride)
    return source, line


def _locate(entry: _Entry, sources: Sequence[str], stride: int) -> tuple[str, int] | None:
    s, n = _decode(entry.source, entry.line, stride)
    return (sources[s], n) if 0 <= s < len(sources) else None


def map_log(log: str, sources: Sequence[str], line_stride: int = LINE_STRIDE) -> list[str]:
    """Rewrite a driver's compile log so that each message names ``file:line``.

    Parameters
    ----------
    log : str
        The info log (or an exception text that contains it).
    sources : sequence of str
        ``Program.sources``.
    line_stride : int
        ``Program.line_stride`` (the default suits both numberings unless a
        file has that many lines).

    Returns
    -------
    list of str
        One per log line.  Recognised messages (Mesa ``0:12(3): error: ...``,
        NVIDIA ``0(12) : error C1008: ...``, AMD/Intel ``ERROR: 0:12: ...``)
        become ``file:12[:3]: error: ...``; other lines pass through.
    """
    mapped = []
    for text in log.splitlines():
        entry = _parse_entry(text)
        where = _locate(entry, sources, line_stride) if entry else None
        if entry is None or where is None:
            mapped.append(text)
            continue
        loc = f"{where[0]}:{where[1]}" + (f":{entry.column}" if entry.column is not None else "")
        mapped.append(f"{loc}: {entry.label}: {entry.message}" if entry.label else f"{loc}: {entry.message}")
    return mapped


def compile_error(log: str, sources: Sequence[str], line_stride: int = LINE_STRIDE) -> ShaderError:
    """The first error of a compile log as a `ShaderError` (file, line, message).

    When no line of the log has a location, the error names ``<shader>``
    and carries the first line that mentions an error (or the first line).
    """
    entries = [e for e in map(_parse_entry, log.splitlines()) if e is not None]
    errors = [e for e in entries if e.severity == "error"] or [e for e in entries if e.severity is None]
    if errors:
        first = errors[0]
        where = _locate(first, sources, line_stride)
        if where is None:
            s, n = _decode(first.source, first.line, line_stride)
            where = (f"<source {s}>", n)
        return ShaderError(where[0], where[1], first.message)
    lines = [t.strip() for t in log.splitlines() if t.strip()]
    wordy = [t for t in lines if "error" in t.lower()]
    return ShaderError("<shader>", None, (wordy or lines or ["compilation failed (empty log)"])[0])


def compile_error_message(log: str, sources: Sequence[str], line_stride: int = LINE_STRIDE) -> str:
    """The first error of a compile log as one line, ``"{file}:{line}: {message}"``."""
    return str(compile_error(log, sources, line_stride))
