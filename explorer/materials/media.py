"""
Index parameters that name a medium: ``--set n2=chitin`` (and presets, parameter files) on a material that
declares ``int medium_n2 0 K 0`` selects the library's medium number ``k`` (:data:`MEDIA`, 1-based; 0: the
number ``n2``). The index parameter then holds the medium's ``n`` at :data:`SLIDER_WAVELENGTH_NM` (what its
slider shows); the physics reads the medium (:func:`index_value`). A medium from a file (``.csv``/``.toml``)
is for ``spectrum`` and ``design --target-spectrum``, which take it by path.
"""

from __future__ import annotations

from typing import Mapping

from explorer.errors import LocatedError
from explorer.physics import dispersion

#: The media a ``medium_*`` parameter numbers, 1-based (0: the index parameter's own number).
MEDIA: tuple[str, ...] = tuple(dispersion.LIBRARY)
#: Where an index parameter shows a medium's n.
SLIDER_WAVELENGTH_NM = 550.0


def medium_values(material, name: str, text: str) -> dict[str, float]:
    """``{name: n at 550 nm, medium_name: number}`` for ``name=text``; a one-line error for anything else."""
    entry = dispersion.dispersion_named(text, origin=material.path)
    if entry.name not in dispersion.LIBRARY:
        raise LocatedError(material.path, None, f"{name}={text!r}: a medium from a file is for the spectrum and design commands; "
                                                f"here one of {', '.join(MEDIA)}")
    parameter = material.parameter(name)
    n = entry.real_at(SLIDER_WAVELENGTH_NM)
    low, high = parameter.min, parameter.max
    return {name: float(min(max(n, low), high)), f"medium_{name}": float(MEDIA.index(entry.name) + 1)}


def index_value(values: Mapping[str, object], name: str) -> float | dispersion.Dispersion:
    """The index ``name`` as the physics reads it: its medium when ``medium_NAME`` selects one, else its number."""
    number = int(round(float(values.get(f"medium_{name}", 0) or 0)))
    if 1 <= number <= len(MEDIA):
        return dispersion.LIBRARY[MEDIA[number - 1]]
    return float(values[name])


def host_problem(values: Mapping[str, object]) -> str | None:
    """
    Why the host ``medium_nh`` selects cannot be one (an absorbing medium: light comes from a lossless,
    semi-infinite host, where an absorbing one would leave no wave to reflect), or None.
    """
    value = index_value(values, "nh")
    if isinstance(value, dispersion.Dispersion) and value.absorbing:
        lossless = [name for name in MEDIA if not dispersion.LIBRARY[name].absorbing]
        return (f"parameter 'nh': {value.name} absorbs (k > 0) and the host must be lossless; "
                f"a number or one of {', '.join(lossless)}")
    return None


def medium_name(values: Mapping[str, object], name: str) -> str | None:
    """The medium ``medium_NAME`` selects, or None."""
    value = index_value(values, name)
    return value.name if isinstance(value, dispersion.Dispersion) else None
