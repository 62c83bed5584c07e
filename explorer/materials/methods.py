"""
The materials' ``method`` parameter, declared once: which number is which computation.

Each enumeration names a material family's methods (the integer a ``.brd`` file's ``int method``
parameter holds) with a label and the properties the host and the app need (whether the host builds a
table for it, whether it is an approximation, which paper it follows). Everything else derives from
here: the numpy twins' dispatch (:mod:`explorer.materials.models`, :mod:`explorer.materials.thinfilm_model`),
the app's names and strips, the benchmarks, and the GLSL ``#define``s that every program receives at
assembly (:func:`glsl_defines`: ``BRAGG_TABULATED``, ``THIN_FILM_NAIVE``, …), which the ``.brd`` files
compare ``method`` with. No other place spells a method's number.
"""

from __future__ import annotations

import enum


def _member(cls, value: int, label: str, options: dict):
    """An enumeration member: its integer value, a label, and what it needs (the keywords below)."""
    member = int.__new__(cls, value)
    member._value_ = value
    member.label = label
    member.needs_table = bool(options.get("table", False))  # the host builds a table for it
    member.approximate = bool(options.get("approximate", True))  # an approximation (else exact colours)
    member.source = str(options.get("source", ""))  # the paper and equations it follows
    member.preferred = bool(options.get("preferred", False))  # the family's best colours at a table lookup (design's render line)
    return member


class _Method(enum.IntEnum):
    """A method: its integer value, a label, and what it needs (members are ``(value, label, options)``)."""

    def __new__(cls, value, label, options):  # the subclasses' members, through Enum's __new_member__
        return _member(cls, value, label, options)

    @classmethod
    def preferred_member(cls):
        """The member declared ``preferred`` (the best colours at a table lookup), or None."""
        return next((m for m in cls if m.preferred), None)

    @classmethod
    def glsl_prefix(cls) -> str:
        """The prefix of its members' ``#define`` names (``BRAGG_`` …): by default the class name's, upper case."""
        return cls.__name__.upper().removesuffix("METHOD") + "_"


class BraggMethod(_Method):
    """The Bragg materials' methods (``bragg_mirror.brd``, ``bragg_layer.brd``)."""

    REFERENCE = (0, "reference", dict(approximate=False, source="Fourneau et al. 2024, Eqs. 2, 9, 10 (the 1-nm sum)"))
    BASIC = (1, "basic", dict(source="Fourneau et al. 2024, Eqs. 11-16, Appendix B"))
    SUBDIVIDED = (2, "subdivided", dict(source="Fourneau et al. 2024, Section 3.2 (quality s)"))
    TABULATED = (3, "tabulated", dict(table=True, approximate=False, preferred=True, source="ours: the converged spectral colour over cos theta"))
    IMPROVED = (4, "improved", dict(source="ours: fringe-averaged, graded boxes"))

    @classmethod
    def glsl_prefix(cls) -> str:
        return "BRAGG_"


class ThinFilmMethod(_Method):
    """The thin film's methods (``thin_film.brd``; Belcour & Barla 2017)."""

    REFERENCE = (0, "reference", dict(approximate=False, source="Belcour & Barla 2017, Eq. 4 (the 1-nm sum)"))
    FOURIER_1 = (1, "Fourier m=1", dict(source="Belcour & Barla 2017, Eq. 10, m = 1, with its remainder"))
    FOURIER_2 = (2, "Fourier m=2", dict(source="Belcour & Barla 2017, Eq. 10, m = 2, with its remainder"))
    FOURIER_3 = (3, "Fourier m=3", dict(preferred=True, source="Belcour & Barla 2017, Eq. 10, m = 3, with its remainder"))
    GAUSSIAN = (4, "Gaussian fits", dict(source="Belcour & Barla 2017, Eq. 10, m = 3, Gaussian XYZ fits"))
    NAIVE = (5, "naive RGB", dict(source="Belcour & Barla 2017, Section 4 (one wavelength per channel)"))

    @classmethod
    def glsl_prefix(cls) -> str:
        return "THIN_FILM_"

    @property
    def m_max(self) -> int:
        """The harmonics Eq. 10 sums explicitly (0 for the methods that do not use it)."""
        return {ThinFilmMethod.FOURIER_1: 1, ThinFilmMethod.FOURIER_2: 2, ThinFilmMethod.FOURIER_3: 3,
                ThinFilmMethod.GAUSSIAN: 3}.get(self, 0)


#: The base of every method enumeration: a plugin's own methods subclass it (members ``(value, label, options)``).
Method = _Method


def methods_for(model) -> type[_Method] | None:
    """The enumeration of a material's (or a ``# model:`` name's) ``method`` parameter, or None: its twin's declaration."""
    from explorer.materials.twins import capabilities_of

    return capabilities_of(model).methods


def glsl_defines() -> dict[str, int]:
    """``{"BRAGG_REFERENCE": 0, …}`` for every registered twin's methods: ``#define``d in every program at assembly."""
    from explorer.materials.twins import registry

    enumerations = dict.fromkeys(m for cls in registry().values()
                                 if (m := getattr(getattr(cls, "capabilities", None), "methods", None)) is not None)
    return {f"{enumeration.glsl_prefix()}{m.name}": int(m) for enumeration in enumerations for m in enumeration}


def method_labels(material) -> dict[int, str]:
    """
    ``{value: "value label"}`` of a material's ``method`` parameter over its declared range ({} without
    one): what the app's combo and ``info`` show (a value the enumeration does not name is ``"value"``).
    """
    parameter = next((p for p in material.parameters if p.name == "method"), None)
    if parameter is None or parameter.min is None:
        return {}
    methods = methods_for(material.model)
    known = {int(m): m.label for m in methods} if methods else {}
    return {m: f"{m} {known[m]}" if m in known else str(m) for m in range(int(parameter.min), int(parameter.max) + 1)}


def opening_values(material) -> dict[str, int]:
    """
    The overrides a material opens with, in the app, ``render``, ``export`` and ``albedo`` alike: every
    Bragg material (a ``# model:`` whose methods are :class:`BraggMethod`, built-in or a copy, whatever its
    name) on the tabulated method, exact and fast; the built-in files declare it as their default, and an
    older copy that declares the 1-nm reference opens on it too. The reference stays a choice
    (``--set method=0``). ``{}`` for every other material.
    """
    parameter = next((p for p in getattr(material, "parameters", ()) if p.name == "method"), None)
    if parameter is None or methods_for(getattr(material, "model", None)) is not BraggMethod:
        return {}
    tabulated = int(BraggMethod.TABULATED)
    if parameter.min is not None and not (parameter.min <= tabulated <= parameter.max):
        return {}
    return {"method": tabulated}
