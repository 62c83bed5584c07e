"""
Where every file the package reads comes from: the shipped data, the user cache, the built-in materials.

The repository keeps ``shaders/`` and ``luts/`` at its top level; the wheel ships them inside the package
(``explorer/shaders``, ``explorer/luts``, see ``pyproject.toml``). :data:`SHADER_DIR` and :data:`LUT_DIR`
are the package's copies when they exist (an installed package, found through :mod:`importlib.resources`)
and the checkout's otherwise (running from source, or an editable install).

The shipped data is read-only: what the package regenerates at run time (a stale table) goes to the user
cache, :func:`cache_dir`, never into the installation.

Standard library only: :mod:`explorer.dev.bootstrap` imports this before any dependency is installed.
"""

from __future__ import annotations

import importlib.resources
import os
from pathlib import Path

from explorer.errors import LocatedError

#: The distribution's name: the console script, the cache folder.
APP_NAME = "bragg-explorer"
#: The material files' suffixes (ours, Disney BRDF Explorer's).
MATERIAL_SUFFIXES = (".brd", ".brdf")


def _shipped(name: str) -> Path:
    """The data folder ``name`` inside the installed package, or the source checkout's top-level one."""
    packaged = importlib.resources.files(__package__) / name
    if isinstance(packaged, Path) and packaged.is_dir():
        return packaged.resolve()
    return SOURCE_ROOT / name


#: The folder that holds the package: a source checkout's root, or an installation's site-packages.
SOURCE_ROOT = Path(__file__).resolve().parent.parent
#: The repository root when running from a source checkout (``pyproject.toml`` and ``shaders/`` next to
#: ``explorer/``); None in an installed package.
CHECKOUT_ROOT: Path | None = (
    SOURCE_ROOT if (SOURCE_ROOT / "pyproject.toml").is_file() and (SOURCE_ROOT / "shaders").is_dir() else None
)
SHADER_DIR = _shipped("shaders")
LUT_DIR = _shipped("luts")
PRESET_DIR = SHADER_DIR / "presets"
DEFAULT_MATERIAL = SHADER_DIR / "bragg_mirror.brd"
DEFAULT_TEXTURE = SHADER_DIR / "textures" / "thickness_noise.png"
DEFAULT_ENVIRONMENT = SHADER_DIR / "environments" / "default.hdr"


def package_version() -> str:
    """A source checkout's ``pyproject.toml`` version, else the installed distribution's (``unknown`` without either)."""
    import re
    from importlib import metadata

    if CHECKOUT_ROOT is not None:  # a checkout run through PYTHONPATH may have no (or another) installed copy
        match = re.search(r'^version\s*=\s*"([^"]+)"', (CHECKOUT_ROOT / "pyproject.toml").read_text(encoding="utf-8"), re.M)
        if match:
            return match.group(1)
    try:
        return metadata.version(APP_NAME)
    except metadata.PackageNotFoundError:
        return "unknown"


def require_checkout(command: str) -> None:
    """
    Exit with one line unless running from a source checkout: ``command`` rewrites shipped files, which in
    an installed package would mean writing into the installation.
    """
    if CHECKOUT_ROOT is None:
        raise SystemExit(f"{command} rewrites the files a source checkout ships; this is an installed package "
                         f"({SOURCE_ROOT}), which is never written")


def cache_dir() -> Path:
    """
    The user cache, ``$XDG_CACHE_HOME/bragg-explorer`` (``~/.cache/bragg-explorer`` when unset or not
    absolute, as the XDG base directory specification says). Read at each call: tests point it elsewhere.
    """
    base = os.environ.get("XDG_CACHE_HOME", "")
    root = Path(base) if base and os.path.isabs(base) else Path.home() / ".cache"
    return root / APP_NAME


class UnknownMaterial(LocatedError):
    """A material argument is neither a file nor a built-in material."""


def builtin_materials() -> dict[str, Path]:
    """The materials shipped with the package, ``{name: path}`` by name (``bragg_mirror``, ...)."""
    return {path.stem: path for path in sorted(SHADER_DIR.glob("*.brd"))}


def is_bare_name(text: str) -> bool:
    """``text`` names no folder (``bragg_mirror``, ``thin_film.brd``): it may be a built-in's name."""
    return bool(text) and os.sep not in text and (os.altsep is None or os.altsep not in text) and text not in (".", "..")


def material_path(text: str | os.PathLike[str]) -> Path:
    """
    The material file an argument names: a file when one exists (or the argument has a folder), else the
    built-in material of that name (``bragg_mirror`` or ``bragg_mirror.brd``).

    Raises
    ------
    UnknownMaterial
        A bare name that is neither a file nor a built-in: one line listing the built-ins.
    """
    text = os.fspath(text)
    path = Path(text)
    from explorer.errors import show_path_as

    if path.exists() or not is_bare_name(text):
        show_path_as(path, text)  # as typed, even where a built-in was named by name before
        return path  # an unreadable or malformed file is the material loader's error, with its line
    builtins = builtin_materials()
    stem = path.stem if path.suffix in MATERIAL_SUFFIXES else path.name
    if stem in builtins and path.suffix in ("", ".brd"):
        show_path_as(builtins[stem], text)  # its errors name it as typed, not by its installed path
        return builtins[stem]
    from explorer.errors import did_you_mean

    names = ", ".join(builtins) or "(none installed)"
    raise UnknownMaterial(text, None, f"no such file, nor a built-in material{did_you_mean(stem, builtins)}; built-in materials: {names}")


def display_path(path: str | os.PathLike[str]) -> str:
    """
    How to show a material's path: relative to the working directory when it lies below it, the bare
    name of a built-in material otherwise (what ``render NAME`` accepts), else absolute.
    """
    path = Path(path)
    try:
        relative = os.path.relpath(path)
    except ValueError:  # another drive
        relative = str(path)
    if not relative.startswith(os.pardir):
        return relative
    resolved = path.resolve()
    if resolved.parent == SHADER_DIR and builtin_materials().get(resolved.stem) == resolved:
        return resolved.stem
    return str(resolved)
