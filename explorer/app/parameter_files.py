"""
The explorer app's parameter sets, without any GUI: widget kinds, reset, and saving and loading a
material's values as JSON or as Disney BRDF Explorer's ``.bparam`` files.

A ``.bparam`` file is what BRDF Explorer's "Save Params" writes (``BRDFBase::saveParamsFile``)::

    bparam /path/to/material.brdf

    ::begin parameters
    float n 1 1000 250.000000
    bool divide_by_NdotL 1
    color albedo 0.820000 0.670000 0.160000
    ::end parameters

floats (``name min max value``), then bools, then colours. Loading one sets the parameters whose names
the current material has (BRDF Explorer's ``syncParametersIntoBRDF``); the others are reported.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

from explorer.materials.brd import Material, Parameter
from explorer.errors import LocatedError


class ParameterFileError(LocatedError):
    """A parameter-set file (JSON or ``.bparam``) cannot be read, written or applied."""


def widget_kind(parameter: Parameter) -> str:
    """
    The widget of a parameter: ``'int'`` (an integer slider) for the parameters a ``.brd`` file declares
    ``int`` (counts, switches such as ``N``, ``s``, ``method``), ``'float'``, ``'bool'`` or ``'color'``.
    A float whose range and default are whole numbers (BRDF Explorer's ``metallic 0 1 0``) keeps a float
    slider.
    """
    return parameter.type


#: A stack's layer parameters end with their layer's number (``Lambda_2``); the count parameter says how
#: many layers the material draws (``bragg_stack.brd``, ``layered_lobes.brd``).
LAYER_COUNT_PARAMETER = "layers"
_LAYER_SUFFIX = re.compile(r"_(\d+)$")


def inactive_parameters(material: Material, values: Mapping[str, object]) -> set[str]:
    """
    The parameters that change nothing with these values: those of a stack's layers beyond its
    ``layers`` count (their sliders are disabled).
    """
    if not any(p.name == LAYER_COUNT_PARAMETER for p in material.parameters):
        return set()
    count = round(float(values[LAYER_COUNT_PARAMETER]))
    return {p.name for p in material.parameters if (m := _LAYER_SUFFIX.search(p.name)) and int(m.group(1)) > count}


def slider_format(parameter: Parameter) -> str:
    """A printf format showing enough digits for the parameter's range."""
    span = abs((parameter.max or 1.0) - (parameter.min or 0.0))
    return "%.4f" if span <= 1.0 else "%.3f" if span <= 10.0 else "%.2f"


@dataclass
class LoadedValues:
    """
    Values read from a file: those that apply to the material, what was skipped (one line each), and the
    view saved with them (:func:`check_view`), if any.
    """

    values: dict[str, object]
    material: str | None = None
    skipped: list[str] = field(default_factory=list)
    view: dict | None = None


#: What a parameter set may save beside the values: the app's view, so that ``render --params`` shows it.
VIEW_KEYS = ("view", "light", "camera", "exposure", "environment", "env_rotation", "tonemap", "fill")


def check_view(raw, where: str, line: int | None = None) -> dict:
    """
    A saved view, checked: ``view`` (a view's name), ``light`` ``[theta, phi]`` (degrees, theta in
    [0, 180]), ``camera`` ``[yaw, pitch]`` (degrees, pitch in [-89, 89]), ``exposure`` (> 0),
    ``environment`` (a file or a name of :data:`explorer.views.env.ENVIRONMENTS`, or None), ``env_rotation`` (degrees,
    finite), ``tonemap`` (a curve of :data:`explorer.views.tonemap.TONEMAPS`), ``fill`` (the lit view's environment fill, >= 0). Missing keys are absent from the result; unknown ones are errors.
    """
    import math

    from explorer.views.geometry import VIEWS as VIEW_NAMES

    if not isinstance(raw, dict):
        raise ParameterFileError(where, line, 'the view must be an object {"view": NAME, "light": [THETA, PHI], ...}')
    unknown = sorted(set(raw) - set(VIEW_KEYS))
    if unknown:
        raise ParameterFileError(where, line, f"unknown view setting {unknown[0]!r} (known: {', '.join(VIEW_KEYS)})")

    def pair(name, low, high):
        value = raw[name]
        try:
            a, b = (float(v) for v in value)
        except (TypeError, ValueError):
            raise ParameterFileError(where, line, f"view {name!r}: expected two numbers in degrees") from None
        if not (math.isfinite(a) and math.isfinite(b) and low[0] <= a <= low[1] and high[0] <= b <= high[1]):
            raise ParameterFileError(where, line, f"view {name!r}: {a:g}, {b:g} out of [{low[0]:g}, {low[1]:g}] x [{high[0]:g}, {high[1]:g}]")
        return [a, b]

    view: dict = {}
    if "view" in raw:
        if raw["view"] not in VIEW_NAMES:
            raise ParameterFileError(where, line, f"view {raw['view']!r} is not one of {', '.join(VIEW_NAMES)}")
        view["view"] = raw["view"]
    if "light" in raw:
        view["light"] = pair("light", (0.0, 180.0), (-math.inf, math.inf))
    if "camera" in raw:
        view["camera"] = pair("camera", (-math.inf, math.inf), (-89.0, 89.0))
    if "exposure" in raw:
        try:
            exposure = float(raw["exposure"])
        except (TypeError, ValueError):
            exposure = math.nan
        if not (math.isfinite(exposure) and exposure > 0.0):
            raise ParameterFileError(where, line, f"view 'exposure': {raw['exposure']!r} is not a positive number")
        view["exposure"] = exposure
    if raw.get("environment") is not None:
        view["environment"] = str(raw["environment"])
    if raw.get("env_rotation") is not None:
        try:
            rotation = float(raw["env_rotation"])
        except (TypeError, ValueError):
            rotation = math.nan
        if not math.isfinite(rotation):
            raise ParameterFileError(where, line, f"view 'env_rotation': {raw['env_rotation']!r} is not a finite angle in degrees")
        view["env_rotation"] = rotation
    if raw.get("tonemap") is not None:
        from explorer.views.tonemap import TONEMAPS

        if raw["tonemap"] not in TONEMAPS:
            raise ParameterFileError(where, line, f"view 'tonemap': {raw['tonemap']!r} is not one of {', '.join(TONEMAPS)}")
        view["tonemap"] = raw["tonemap"]
    if raw.get("fill") is not None:
        try:
            fill = float(raw["fill"])
        except (TypeError, ValueError):
            fill = math.nan
        if not (math.isfinite(fill) and fill >= 0.0):
            raise ParameterFileError(where, line, f"view 'fill': {raw['fill']!r} is not a radiance >= 0")
        view["fill"] = fill
    return view


def _display(path: os.PathLike[str] | str) -> str:
    """A parameter file's path as the user typed it (an absolute one stays absolute)."""
    return os.fspath(path)


def named_material(path: os.PathLike[str] | str) -> str | None:
    """The material a parameter set names (JSON ``"material"``, a ``.bparam``'s first line), or None."""
    where = _display(path)
    text = _read_text(path, where)
    if str(path).lower().endswith(".bparam"):
        return parse_bparam(text, where)[0]
    try:
        document = json.loads(text)
    except (json.JSONDecodeError, RecursionError):
        raise ParameterFileError(where, None, "not valid JSON") from None
    material = document.get("material") if isinstance(document, dict) else None
    return material if isinstance(material, str) and material else None


def _json_value(value):
    return list(value) if isinstance(value, tuple) else value


def save_json(path: os.PathLike[str] | str, material: Material, values: Mapping[str, object], view: Mapping | None = None) -> None:
    """Write ``{"material": path, "values": {...}, "view": {...}}`` (colours as lists; the view when given)."""
    document = {
        "format": "bragg-explorer parameters",
        "material": str(Path(material.path).resolve()),
        "values": {p.name: _json_value(values[p.name]) for p in material.parameters},
    }
    if view:
        document["view"] = {k: v for k, v in view.items() if v is not None}
    _write_text(path, json.dumps(document, indent=2) + "\n")


def save_bparam(path: os.PathLike[str] | str, material: Material, values: Mapping[str, object], view: Mapping | None = None) -> None:
    """
    Write BRDF Explorer's ``.bparam`` (``%f`` numbers, floats then bools then colours, as it does), naming
    the material's file (for a material opened from an exported ``.brdf``, that ``.brdf``), and the view in
    a ``::begin view`` section of ``KEY VALUE...`` lines (BRDF Explorer skips sections it does not know).
    """
    from explorer.materials.export_brdf import bparam_text

    lines = [bparam_text(str(Path(material.path).resolve()), material.parameters, values).rstrip("\n")]
    if view:
        lines += ["", "::begin view"]
        for key in VIEW_KEYS:
            value = view.get(key)
            if value is not None:
                lines.append(f"{key} {' '.join(repr(float(v)) for v in value) if isinstance(value, (list, tuple)) else value}")
        lines.append("::end view")
    _write_text(path, "\n".join(lines) + "\n")


def _write_text(path: os.PathLike[str] | str, text: str) -> None:
    from explorer.files import OutputError, write_text_atomic

    try:
        write_text_atomic(path, text)
    except OutputError as error:  # its message names the path already
        raise ParameterFileError(_display(path), None, str(error).split(": ", 1)[-1]) from None


def _apply(material: Material, raw: Mapping[str, object], where: str, lines: Mapping[str, int]) -> LoadedValues:
    """Coerce ``raw`` into ``material``'s parameters; unknown names are skipped, bad values are errors."""
    known = {p.name: p for p in material.parameters}
    result = LoadedValues({})
    for name, value in raw.items():
        if name not in known:
            result.skipped.append(f"{name} (not a parameter of {_display(material.path)})")
            continue
        try:
            result.values[name] = known[name].coerce(value)
        except ValueError as error:
            raise ParameterFileError(where, lines.get(name), f"parameter {name!r}: {error}") from None
    return result


def _json_int(digits: str) -> int | float:
    """
    A JSON integer: an ``int``, or beyond Python's digit limit for ``int()`` (4300) a float, infinite: the
    parameter's range then refuses it naming the key, as it does an int too large for a float (``1e400``).
    """
    return int(digits) if len(digits) <= 1000 else float(digits)


def load_json(path: os.PathLike[str] | str, material: Material) -> LoadedValues:
    """Read values saved by :func:`save_json` and check them against ``material``."""
    where = _display(path)
    try:
        document = json.loads(Path(path).read_text(encoding="utf-8"), parse_int=_json_int)
    except OSError as error:
        raise ParameterFileError(where, None, f"cannot read ({error.strerror or error})") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ParameterFileError(where, getattr(error, "lineno", None), f"not valid JSON ({getattr(error, 'msg', error)})") from None
    except RecursionError:
        raise ParameterFileError(where, None, "not a parameter set: nested too deeply") from None
    raw = document.get("values") if isinstance(document, dict) else None
    if not isinstance(raw, dict):
        raise ParameterFileError(where, None, 'expected an object with "values": {NAME: VALUE, ...}')
    result = _apply(material, raw, where, {})
    result.material = document.get("material") if isinstance(document.get("material"), str) else None
    if "view" in document:
        result.view = check_view(document["view"], where)
    return result


def parse_bparam(text: str, where: str) -> tuple[str | None, dict[str, object], dict[str, int]]:
    """``(material file, {name: value}, {name: line})`` of a ``.bparam`` text (values as strings/tuples)."""
    material_file: str | None = None
    raw: dict[str, object] = {}
    lines: dict[str, int] = {}
    section = None
    first = True
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        tokens = stripped.split()
        if first:
            first = False
            if tokens[0] != "bparam":  # the line itself is not shown: the file may be anything
                raise ParameterFileError(where, number, "not a .bparam file (expected 'bparam MATERIAL' on the first line)")
            material_file = stripped[len("bparam"):].strip() or None
            continue
        if tokens[0] == "::begin":
            section = tokens[1] if len(tokens) > 1 else ""
            continue
        if tokens[0] == "::end":
            section = None
            continue
        if section != "parameters":
            continue
        kind, name, numbers = tokens[0], tokens[1] if len(tokens) > 1 else "", tokens[2:]
        expected = {"float": 3, "bool": 1, "color": 3}.get(kind)
        if expected is None or len(numbers) != expected:
            raise ParameterFileError(where, number, f"expected 'float NAME MIN MAX VALUE', 'bool NAME 0|1' or 'color NAME R G B', got {stripped!r}")
        raw[name] = numbers[2] if kind == "float" else numbers[0] if kind == "bool" else ",".join(numbers)
        lines[name] = number
    if first:
        raise ParameterFileError(where, None, "empty file (expected 'bparam MATERIAL')")
    return material_file, raw, lines


def _read_text(path: os.PathLike[str] | str, where: str) -> str:
    """A parameter file's text, or :class:`ParameterFileError` (unreadable, not text)."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as error:
        raise ParameterFileError(where, None, f"cannot read ({error.strerror or error})") from None
    except UnicodeDecodeError:
        raise ParameterFileError(where, None, "not a text file") from None


def load_bparam(path: os.PathLike[str] | str, material: Material) -> LoadedValues:
    """Read a BRDF Explorer ``.bparam`` file and apply the parameters ``material`` has."""
    where = _display(path)
    text = _read_text(path, where)
    material_file, raw, lines = parse_bparam(text, where)
    result = _apply(material, raw, where, lines)
    result.material = material_file
    result.view = parse_bparam_view(text, where)
    return result


def parse_bparam_view(text: str, where: str) -> dict | None:
    """The ``::begin view`` section of a ``.bparam`` text (:func:`save_bparam`), checked; None without one."""
    raw: dict = {}
    section, first_line = None, None
    for number, line in enumerate(text.splitlines(), start=1):
        tokens = line.split()
        if not tokens or tokens[0].startswith("#"):
            continue
        if tokens[0] in ("::begin", "::end"):
            section = tokens[1] if tokens[0] == "::begin" and len(tokens) > 1 else None
            first_line = first_line or (number if section == "view" else None)
            continue
        if section != "view":
            continue
        key, rest = tokens[0], tokens[1:]
        if key in ("light", "camera"):
            raw[key] = rest
        elif key in ("view", "environment"):
            raw[key] = line.strip()[len(key):].strip()
        else:
            raw[key] = rest[0] if len(rest) == 1 else rest
    return check_view(raw, where, first_line) if first_line is not None else None


def save_values(path: os.PathLike[str] | str, material: Material, values: Mapping[str, object], view: Mapping | None = None) -> None:
    """Save as ``.bparam`` when the name ends so, as JSON otherwise; ``view``: the app's view beside the values."""
    (save_bparam if str(path).lower().endswith(".bparam") else save_json)(path, material, values, view)


def load_values(path: os.PathLike[str] | str, material: Material) -> LoadedValues:
    """Load a ``.bparam`` or a JSON parameter set for ``material``."""
    return (load_bparam if str(path).lower().endswith(".bparam") else load_json)(path, material)


def load_view(path: os.PathLike[str] | str) -> dict | None:
    """The view saved in a parameter set (JSON ``"view"``, ``.bparam``'s ``::begin view``), checked; None without one."""
    where = _display(path)
    text = _read_text(path, where)
    if str(path).lower().endswith(".bparam"):
        return parse_bparam_view(text, where)
    try:
        document = json.loads(text, parse_int=_json_int)
    except (json.JSONDecodeError, RecursionError):
        return None  # load_json reports what is wrong with the file
    return check_view(document["view"], where) if isinstance(document, dict) and "view" in document else None
