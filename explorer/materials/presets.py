"""
Presets: named sets of parameter values for one material file, reproducing the papers' figures.

They live next to the materials, one TOML file per material (``shaders/presets/<material stem>.toml``)::

    material = "thin_film.brd"          # the material, relative to the presets folder's parent

    [figure7]                           # the preset's name
    figure = "Figure 7"                 # what it reproduces
    description = "..."                 # one line
    d = 525                             # parameter values; the others keep their defaults
    eta2 = 1.5

Every value is checked against the material's declared parameters and ranges
(:meth:`explorer.materials.brd.Material.resolve`) when the file is loaded; a bad file is a one-line
:class:`PresetError` naming the file and, where it can be found, the line.
"""

from __future__ import annotations

import os
import re
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from explorer.materials.brd import Material, MaterialError, load_material
from explorer.errors import LocatedError
from explorer.resources import MATERIAL_SUFFIXES, PRESET_DIR

#: Keys of a preset table that are not parameter values.
META_KEYS = ("figure", "description")
#: Optional keys of a preset table that are not parameter values: a specimen's published source.
OPTIONAL_META_KEYS = ("citation",)
_TOML_LINE = re.compile(r"\(at line (\d+), column \d+\)")


class PresetError(LocatedError):
    """A presets file is malformed, or a preset name is unknown."""


@dataclass
class Preset:
    name: str
    material: Material
    figure: str
    description: str
    #: The preset's own values (as written), in file order.
    values: dict[str, object]
    line: int | None = None
    #: Where a specimen's numbers come from (None for the papers' figures).
    citation: str | None = None

    def resolve(self, overrides=None) -> dict:
        """The material's values: defaults, then this preset, then ``overrides`` (e.g. ``--set``)."""
        return self.material.resolve({**self.values, **(overrides or {})})


@dataclass
class PresetFile:
    path: Path
    material: Material
    presets: dict[str, Preset] = field(default_factory=dict)

    def get(self, name: str) -> Preset:
        """The preset called ``name``, or a one-line :class:`PresetError` listing the valid names."""
        if name not in self.presets:
            from explorer.errors import did_you_mean

            valid = ", ".join(self.presets) or "(none)"
            raise PresetError(_display(self.path), None, f"unknown preset {name!r}{did_you_mean(name, self.presets)}; valid names: {valid}")
        return self.presets[name]


def _display(path: Path) -> str:
    try:
        return os.path.relpath(path)
    except ValueError:
        return str(path)


_KEY_LINE = re.compile(r'^"?([^"=\s]+)"?\s*=')


def _line_index(lines: list[str]) -> dict[tuple[str | None, str | None], int]:
    """
    1-based lines of a TOML text's tables and keys, by ``(table, None)`` and ``(table, key)`` (``table`` None:
    the top level), first occurrence each: one pass over the file, however many keys are looked up.
    """
    index: dict[tuple[str | None, str | None], int] = {}
    current: str | None = None
    for number, line in enumerate(lines, start=1):
        stripped = line.strip()
        if stripped.startswith("["):
            current = stripped.split("]")[0].strip("[ ").strip('"')
            index.setdefault((current, None), number)
        elif found := _KEY_LINE.match(stripped):
            index.setdefault((current, found.group(1)), number)
    return index


def _find_line(index: dict, table: str | None, key: str | None = None) -> int | None:
    """1-based line of ``[table]``, or of ``key = ...`` inside it (``table`` None: the top level)."""
    return index.get((table, key))


def _long_integer_line(text: str) -> int | None:
    """1-based line of the first run of digits too long for Python's ``int()``."""
    found = re.search(r"\d{%d,}" % (sys.get_int_max_str_digits() + 1), text)
    return text.count("\n", 0, found.start()) + 1 if found else None


def load_presets(path: str | os.PathLike[str]) -> PresetFile:
    """Read and validate one presets file (see the module docstring)."""
    path = Path(path)
    where = _display(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise PresetError(where, None, "no such presets file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise PresetError(where, None, f"cannot read ({getattr(error, 'strerror', None) or error})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        message = str(error)
        found = _TOML_LINE.search(message)
        line = int(found.group(1)) if found else None
        raise PresetError(where, line, "not valid TOML: " + _TOML_LINE.sub("", message).strip()) from None
    except RecursionError:
        raise PresetError(where, None, "not valid presets: nested too deeply") from None
    except ValueError:  # an integer beyond Python's digit limit (4300): tomllib's int() refuses it
        raise PresetError(where, _long_integer_line(text), "an integer is too long (a parameter value is a number in its range)") from None
    lines = _line_index(text.splitlines())
    material_name = data.get("material")
    if not isinstance(material_name, str):
        raise PresetError(where, _find_line(lines, None, "material"), "needs a top-level material = \"FILE.brd\"")
    if Path(material_name).suffix.lower() not in MATERIAL_SUFFIXES:  # nor is another file read, or shown
        raise PresetError(where, _find_line(lines, None, "material"),
                          f"material must name a {' or '.join(MATERIAL_SUFFIXES)} file, not {material_name[:80]!r}")
    material_path = path.parent.parent / material_name
    if not material_path.is_file():
        material_path = path.parent / material_name
    try:
        material = load_material(material_path)
    except MaterialError as error:
        raise PresetError(where, _find_line(lines, None, "material"), f"material {material_name!r}: {error}") from None
    result = PresetFile(path, material)
    for name, table in data.items():
        if name == "material":
            continue
        line = _find_line(lines, name)
        if not isinstance(table, dict):
            raise PresetError(where, _find_line(lines, None, name), f"{name!r} is not a preset table ([{name}])")
        for key in META_KEYS:
            if not isinstance(table.get(key), str) or not table[key].strip():
                raise PresetError(where, line, f"preset {name!r} needs a {key} = \"...\" line")
        for key in OPTIONAL_META_KEYS:
            if key in table and (not isinstance(table[key], str) or not table[key].strip()):
                raise PresetError(where, _find_line(lines, name, key) or line, f"preset {name!r}: {key} must be a non-empty string")
        values = {k: v for k, v in table.items() if k not in META_KEYS + OPTIONAL_META_KEYS}
        for key, value in values.items():
            key_line = _find_line(lines, name, key) or line
            if isinstance(value, (dict, list)) and not (isinstance(value, list) and len(value) == 3):
                raise PresetError(where, key_line, f"preset {name!r}: {key} must be a number, a boolean or a colour")
            try:
                material.resolve({key: value})
            except MaterialError as error:
                raise PresetError(where, key_line, f"preset {name!r}: {error.message}") from None
        result.presets[name] = Preset(name, material, table["figure"], table["description"], values, line,
                                      table.get("citation"))
    if not result.presets:
        raise PresetError(where, None, "defines no presets")
    return result


def presets_path(material_path: str | os.PathLike[str]) -> Path:
    """Where the presets of a material file live: ``<its folder>/presets/<its stem>.toml``."""
    material_path = Path(material_path)
    return material_path.parent / "presets" / f"{material_path.stem}.toml"


def presets_for(material_path: str | os.PathLike[str]) -> PresetFile:
    """The presets of a material file, or a one-line :class:`PresetError` when it has none."""
    path = presets_path(material_path)
    if not path.is_file():
        raise PresetError(_display(Path(material_path)), None, f"this material has no presets (no {_display(path)})")
    return load_presets(path)


def all_preset_files(directory: Path = PRESET_DIR) -> list[PresetFile]:
    """Every presets file of ``directory``, sorted by name."""
    return [load_presets(p) for p in sorted(directory.glob("*.toml"))]
