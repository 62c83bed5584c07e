"""
The numpy twins of the materials: what a twin provides, and the registry they add themselves to.

A twin (``# model: NAME`` in a material file) computes in float64 what the material's shader computes
in float32; the GL-vs-numpy harness (tests/twins.py) compares them view by view. Each twin class
declares itself with :func:`twin`; :data:`TWINS` is the one list, from which
:func:`explorer.materials.models.model_for` and the table cache (:mod:`explorer.gpu.tables`) read.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class Twin(Protocol):
    """What every numpy twin provides (unit direction arrays ``(..., 3)``, colours ``(..., 3)`` linear sRGB)."""

    #: The ``# model:`` name of the material files it twins.
    name: str

    def __init__(self, values: Mapping[str, object]) -> None: ...

    def reflectance(self, cos_theta) -> np.ndarray:
        """The colour views' ``reflectance(cos_theta)``."""

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        """The shader's ``BRDF(L, V, N, X, Y)``."""

    def textures(self) -> dict[str, np.ndarray]:
        """The tables the shader samples, by uniform name (host-built)."""


#: ``{name: twin class}``: every registered twin (filled as their modules are imported).
TWINS: dict[str, type] = {}


def twin(cls: type) -> type:
    """Class decorator: register a twin under its ``name`` (one name, one class)."""
    name = getattr(cls, "name", None)
    if not isinstance(name, str) or not name:
        raise TypeError(f"{cls.__name__}: a twin needs a class attribute 'name'")
    if name in TWINS and TWINS[name] is not cls:
        raise ValueError(f"twin {name!r} registered twice ({TWINS[name].__name__}, {cls.__name__})")
    missing = [m for m in ("reflectance", "brdf", "textures") if not callable(getattr(cls, m, None))]
    if missing:
        raise TypeError(f"{cls.__name__}: a twin needs {', '.join(missing)}")
    TWINS[name] = cls
    return cls
