"""
How every command takes a material and its values: ``MATERIAL`` (a file or a built-in's name), then its
defaults under ``--preset``, under ``--params``, under ``--set``. One place for ``render``, ``albedo``,
``export`` and the others, imported by each command module (none imports :mod:`explorer.cli.commands`).
"""

from __future__ import annotations

from pathlib import Path

import click

from explorer.materials.brd import Material, load_material, parse_assignment
from explorer.resources import material_path

PROG = "bragg-explorer"


def command_prefix() -> str:
    """How to run a command as printed: ``bragg-explorer`` where the console script is on PATH (an installed
    package), else ``python3 -m explorer`` (a checkout, as the README runs it)."""
    import shutil

    return PROG if shutil.which(PROG) else "python3 -m explorer"


class SuggestingChoice(click.Choice):
    """A :class:`click.Choice` whose refusal names the closest choice (difflib): ``(did you mean 'sphere'?)``."""

    def convert(self, value, param, ctx):
        try:
            return super().convert(value, param, ctx)
        except click.BadParameter as error:
            from explorer.errors import did_you_mean

            hint = did_you_mean(value, self.choices)
            if hint:
                error.message = f"{error.message.rstrip('.')}{hint}"
            raise


def warn(message: str) -> None:
    """A one-line warning on stderr."""
    click.echo(f"{PROG}: warning: {message}", err=True)


def load(path: str | Path) -> Material:
    """A material file, or a built-in material by name (:func:`explorer.resources.material_path`), its warnings on stderr."""
    material = load_material(material_path(path))
    for warning in material.warnings:
        warn(warning)
    return material


def load_mirror(path: str | Path, command: str) -> Material:
    """
    :func:`load`, for a command that takes a Bragg mirror (``spectrum``, ``design --target-spectrum``): a material whose
    twin declares ``bragg_spectrum`` (a rough layer's spectrum is its smooth mirror's), else one line that starts with
    ``command`` (``"spectrum takes"``) and names the materials that do.
    """
    from explorer.errors import LocatedError
    from explorer.materials.twins import capabilities_of, names_with

    loaded = load(path)
    if not capabilities_of(loaded).bragg_spectrum:
        mirrors = ", ".join(names_with(lambda c: c.bragg_spectrum))
        raise LocatedError(loaded.path, None, f"{command} a Bragg mirror ({mirrors}), not model {loaded.model}")
    return loaded


def resolve_values(loaded: Material, preset: str | None, params_file: str | None, assignments, opening: dict | None = None) -> dict:
    """
    The material's values: its defaults, under ``opening`` (default: the app's opening values,
    :func:`explorer.materials.methods.opening_values`, as every command opens a material), under
    ``--preset``, under ``--params``, under ``--set``.
    """
    if opening is None:
        from explorer.materials.methods import opening_values

        opening = opening_values(loaded)
    overrides = dict(parse_assignment(a) for a in assignments) if assignments else {}
    if params_file is not None:
        from explorer.app.parameter_files import load_values

        loaded_values = load_values(params_file, loaded)
        for skipped in loaded_values.skipped:
            warn(f"{params_file}: skipped {skipped}")
        overrides = {**loaded_values.values, **overrides}
    if preset is not None:
        from explorer.materials.presets import presets_for

        overrides = {**presets_for(loaded.path).get(preset).values, **overrides}
    return loaded.resolve({**(opening or {}), **overrides})
