"""
Materials from any folder: a material file (``.brd``, or BRDF Explorer's ``.brdf``) with a Python file of
the same stem beside it is a plugin. Loading the material (:func:`explorer.materials.brd.load_material`)
runs the Python file once, whose twin class registers itself with :func:`explorer.materials.twins.twin`;
the material file's ``# model: NAME`` names it (or, without that line, the one twin the file registers).
From there the plugin is a material like the built-ins: ``open``, ``render`` (GL and numpy), ``albedo``,
``info``, ``export`` and ``check`` query the registry, none edits the package (docs/plugins.md).

An error in the Python file (a syntax error, an exception while it runs, a twin that does not register)
is one :class:`PluginError` naming the file and line, never a traceback.
"""

from __future__ import annotations

import hashlib
import importlib.util
import sys
import traceback
from dataclasses import dataclass
from pathlib import Path

from explorer.errors import LocatedError
from explorer.materials import twins

#: The suffix of a material's twin module beside it.
PLUGIN_SUFFIX = ".py"


class PluginError(LocatedError):
    """A plugin's Python file fails to load (one line: the file, the line, what went wrong)."""


@dataclass(frozen=True)
class _Loaded:
    stamp: tuple[int, int]
    names: tuple[str, ...]


#: ``{resolved plugin file: what loading it registered}`` (loaded again when the file changes).
_LOADED: dict[Path, _Loaded] = {}


def plugin_file(material_path) -> Path | None:
    """The Python file beside a material file (same stem, ``.py``), or None."""
    candidate = Path(material_path).with_suffix(PLUGIN_SUFFIX)
    return candidate if candidate.is_file() else None


def _module_name(path: Path) -> str:
    return f"explorer_plugin_{path.stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:10]}"


def _where(error: BaseException, path: Path) -> int | None:
    """The line of ``path`` an exception was raised from (its innermost frame in that file), or None."""
    if isinstance(error, SyntaxError) and error.filename and Path(error.filename).resolve() == path:
        return error.lineno
    line = None
    for frame in traceback.extract_tb(error.__traceback__):
        try:
            if Path(frame.filename).resolve() == path:
                line = frame.lineno
        except OSError:
            continue
    return line


def load_plugin(path) -> tuple[str, ...]:
    """
    Run the plugin file ``path`` (once per version of the file) and return the names of the twins it
    registered. Loading it again after an edit replaces its twins.

    Raises
    ------
    PluginError
        With the file and line: a syntax error, an exception while it runs (a twin that declares wrongly
        included), or no twin registered.
    """
    path = Path(path).resolve()
    try:
        status = path.stat()
    except OSError as error:
        raise PluginError(path, None, f"cannot read the plugin file ({error.strerror})") from None
    stamp = (status.st_mtime_ns, status.st_size)
    loaded = _LOADED.get(path)
    if loaded is not None and loaded.stamp == stamp:
        return loaded.names
    registry = twins.registry()  # the built-ins first: a plugin may not take their names
    if loaded is not None:  # an edited file: its old twins make way for the new ones
        for name in loaded.names:
            registry.pop(name, None)
    before = dict(registry)
    name = _module_name(path)
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise PluginError(path, None, "not a Python file")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and pickling look the module up by name
    try:
        spec.loader.exec_module(module)
    except Exception as error:  # noqa: BLE001  (any error in the user's file: one line with its place)
        sys.modules.pop(name, None)
        for added in [n for n in registry if n not in before]:
            registry.pop(added)
        message = error.msg if isinstance(error, SyntaxError) else str(error)
        raise PluginError(path, _where(error, path), f"{type(error).__name__}: {message}") from None
    names = tuple(n for n, cls in registry.items() if before.get(n) is not cls)
    if not names:
        raise PluginError(path, None, "registers no twin (decorate its class with @explorer.plugins.twin)")
    _LOADED[path] = _Loaded(stamp, names)
    return names


def attach(material) -> None:
    """
    Load the plugin beside ``material`` (a parsed :class:`explorer.materials.brd.Material`), if any, and
    make its ``model`` the plugin's twin: the one ``# model:`` names, or the only one the file registers.
    """
    source = plugin_file(material.path)
    if source is None:
        return
    names = load_plugin(source)
    if material.model is None:
        if len(names) != 1:
            raise PluginError(source, None, f"registers {len(names)} twins ({', '.join(names)}): name one with "
                              f"'# model: NAME' in {Path(material.path).name}")
        material.model = names[0]
    elif material.model not in names:
        raise PluginError(material.path, None, f"'# model: {material.model}' names no twin of {source.name} "
                          f"(it registers {', '.join(names)})")
    twins.TWINS[material.model].material_file = Path(material.path).resolve()
