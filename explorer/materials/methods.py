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
    return member


class _Method(enum.IntEnum):
    """A method: its integer value, a label, and what it needs (members are ``(value, label, options)``)."""

    def __new__(cls, value, label, options):  # the subclasses' members, through Enum's __new_member__
        return _member(cls, value, label, options)

    @classmethod
    def glsl_prefix(cls) -> str:
        raise NotImplementedError


class BraggMethod(_Method):
    """The Bragg materials' methods (``bragg_mirror.brd``, ``bragg_layer.brd``)."""

    REFERENCE = (0, "reference", dict(approximate=False, source="Fourneau et al. 2024, Eqs. 2, 9, 10 (the 1-nm sum)"))
    BASIC = (1, "basic", dict(source="Fourneau et al. 2024, Eqs. 11-16, Appendix B"))
    SUBDIVIDED = (2, "subdivided", dict(source="Fourneau et al. 2024, Section 3.2 (quality s)"))
    TABULATED = (3, "tabulated", dict(table=True, approximate=False, source="ours: the converged spectral colour over cos theta"))
    IMPROVED = (4, "improved", dict(source="ours: fringe-averaged, graded boxes"))

    @classmethod
    def glsl_prefix(cls) -> str:
        return "BRAGG_"


class ThinFilmMethod(_Method):
    """The thin film's methods (``thin_film.brd``; Belcour & Barla 2017)."""

    REFERENCE = (0, "reference", dict(approximate=False, source="Belcour & Barla 2017, Eq. 4 (the 1-nm sum)"))
    FOURIER_1 = (1, "Fourier m=1", dict(source="Belcour & Barla 2017, Eq. 10, m = 1, with its remainder"))
    FOURIER_2 = (2, "Fourier m=2", dict(source="Belcour & Barla 2017, Eq. 10, m = 2, with its remainder"))
    FOURIER_3 = (3, "Fourier m=3", dict(source="Belcour & Barla 2017, Eq. 10, m = 3, with its remainder"))
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
    The overrides a material opens with, in the app and in ``render`` alike: the default material
    (``bragg_mirror.brd``) on its fastest exact method, the tabulated one (its file's default is the
    reference, 1-nm sum); ``{}`` for every other material.
    """
    from pathlib import Path

    from explorer.resources import DEFAULT_MATERIAL

    path = getattr(material, "path", None)
    if path is None or not any(p.name == "method" for p in material.parameters):
        return {}
    try:
        same = Path(path).resolve() == DEFAULT_MATERIAL.resolve()
    except OSError:
        same = False
    return {"method": int(BraggMethod.TABULATED)} if same else {}
