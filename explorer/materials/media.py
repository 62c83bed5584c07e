"""
Index parameters that name a medium: ``--set n2=chitin`` (and presets, parameter files) on a material that
declares ``int medium_n2 0 K 0`` selects the library's medium number ``k`` (:data:`MEDIA`, 1-based; 0: the
number ``n2``). The index parameter then holds the medium's ``n`` at :data:`SLIDER_WAVELENGTH_NM` (what its
slider shows); the physics reads the medium (:func:`index_value`). A medium from a file (``.csv``/``.toml``,
:func:`explorer.physics.dispersion.load_dispersion`) is numbered after the library for the life of the process
(:func:`medium_number`): ``render --set n2=my_layer.csv`` reads it as the library's media are read.
"""

from __future__ import annotations

from typing import Mapping

from explorer.physics import dispersion

#: The media a ``medium_*`` parameter numbers, 1-based (0: the index parameter's own number).
MEDIA: tuple[str, ...] = tuple(dispersion.LIBRARY)
#: Where an index parameter shows a medium's n.
SLIDER_WAVELENGTH_NM = 550.0


#: Media read from files in this process, numbered after :data:`MEDIA` (``len(MEDIA) + 1`` onwards).
_FILE_MEDIA: list[dispersion.Dispersion] = []


def medium_number(entry: dispersion.Dispersion) -> int:
    """The ``medium_*`` number of ``entry``: its place in :data:`MEDIA`, or after it for a file's medium (registered once)."""
    if entry.name in dispersion.LIBRARY and dispersion.LIBRARY[entry.name] is entry:
        return MEDIA.index(entry.name) + 1
    for number, known in enumerate(_FILE_MEDIA, start=len(MEDIA) + 1):
        if known == entry:
            return number
    _FILE_MEDIA.append(entry)
    return len(MEDIA) + len(_FILE_MEDIA)


def medium_values(material, name: str, text: str) -> dict[str, float]:
    """``{name: n at 550 nm, medium_name: number}`` for ``name=text``; a one-line error for anything else."""
    entry = dispersion.dispersion_named(text)
    parameter = material.parameter(name)
    n = entry.real_at(SLIDER_WAVELENGTH_NM)
    low, high = parameter.min, parameter.max
    return {name: float(min(max(n, low), high)), f"medium_{name}": float(medium_number(entry))}


def index_value(values: Mapping[str, object], name: str) -> float | dispersion.Dispersion:
    """The index ``name`` as the physics reads it: its medium when ``medium_NAME`` selects one, else its number."""
    number = int(round(float(values.get(f"medium_{name}", 0) or 0)))
    if 1 <= number <= len(MEDIA):
        return dispersion.LIBRARY[MEDIA[number - 1]]
    if len(MEDIA) < number <= len(MEDIA) + len(_FILE_MEDIA):
        return _FILE_MEDIA[number - len(MEDIA) - 1]
    return float(values[name])


def medium_labels(values: Mapping[str, object], name: str) -> dict[int, str]:
    """
    A ``medium_*`` parameter's choices by number, for a list of names instead of an integer slider (the app):
    0 the index's own number, then the library, then the current value's file medium where it holds one.
    """
    labels = {0: "(the number)", **{number: medium for number, medium in enumerate(MEDIA, start=1)}}
    number = int(round(float(values.get(name, 0) or 0)))
    if number > len(MEDIA):
        chosen = index_value(values, name[len("medium_"):])
        if isinstance(chosen, dispersion.Dispersion):
            labels[number] = chosen.name
    return labels


def file_media_in(values: Mapping[str, object]) -> list[str]:
    """``NAME=PATH`` for each index of ``values`` whose ``medium_NAME`` selects a medium read from a file."""
    return [f"{key[len('medium_'):]}={index_value(values, key[len('medium_'):]).name}" for key in values
            if key.startswith("medium_") and int(round(float(values[key] or 0))) > len(MEDIA)]


def host_problem(values: Mapping[str, object], minimum: float | None = None) -> str | None:
    """
    Why the host ``medium_nh`` selects cannot be one (an absorbing medium: light comes from a lossless,
    semi-infinite host, where an absorbing one would leave no wave to reflect; or, given the ``nh`` parameter's
    ``minimum``, a medium whose ``n`` drops below it somewhere from 360 to 830 nm), or None.
    """
    value = index_value(values, "nh")
    if isinstance(value, dispersion.Dispersion) and value.absorbing:
        lossless = [name for name in MEDIA if not dispersion.LIBRARY[name].absorbing]
        return (f"parameter 'nh': {value.name} absorbs (k > 0) and the host must be lossless; "
                f"a number or one of {', '.join(lossless)}")
    if isinstance(value, dispersion.Dispersion) and minimum is not None:
        n, at = value.lowest_real()
        if n < minimum:
            return f"parameter 'nh': {value.name} has n = {n:.4g} at {at:g} nm, below the host's minimum {minimum:g}"
    return None


def medium_name(values: Mapping[str, object], name: str) -> str | None:
    """The medium ``medium_NAME`` selects, or None."""
    value = index_value(values, name)
    return value.name if isinstance(value, dispersion.Dispersion) else None
