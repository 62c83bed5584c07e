"""
The numpy twins of the materials: what a twin provides, what it declares, and the registry they add
themselves to.

A twin (``# model: NAME`` in a material file) computes in float64 what the material's shader computes
in float32; the GL-vs-numpy harness (:mod:`explorer.views.twin_check`, ``bragg-explorer check``) compares
them view by view. Each twin class declares itself with :func:`twin`, and declares with its
:class:`Capabilities` everything the rest of the code would otherwise look up by the material's name:
its methods, whether it is a Dirac reflector or has a Bragg spectrum, its engines, its exports and, for inverse
design, its forward model (:class:`DesignModel`).
:data:`TWINS` is the one registry: the app, the CLI, the exports, Mitsuba, design, albedo and the
accuracy badge query it (:func:`capabilities_of`, :func:`names_with`), in the spirit of Mitsuba 3's
plugins. The built-in twins register when :func:`registry` first runs; a plugin's on loading its file
(:mod:`explorer.materials.plugins`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from typing import Protocol, runtime_checkable

import numpy as np

#: The albedo engines (``albedo --engine``): the numpy twin's quadrature, the GLSL scatter view, the
#: position-free Monte Carlo reference of layered Bragg structures.
ALBEDO_ENGINES = ("numpy", "gl", "position-free")
#: The export targets a twin may declare (``export --to``).
EXPORT_TARGETS = ("mitsuba", "brdf", "table", "materialx", "gltf")


@dataclass(frozen=True, kw_only=True)
class DesignModel:
    """
    What inverse design (:mod:`explorer.design`, ``bragg-explorer design``) reads of a material, declared by its
    twin (``Capabilities(design=DesignModel(...))``): its structural parameters (the others, such as ``method``
    or a roughness, do not change the specular colour) and its forward models, the coarse batch model the search
    screens and refines on and the converged one it polishes and reports. Colours are linear sRGB.
    """

    #: The parameters design may fit (names of the material file's parameters).
    parameters: tuple[str, ...]
    #: Those it walks on a log scale, and those it rounds to integers (a count).
    log_parameters: tuple[str, ...] = ()
    integer_parameters: tuple[str, ...] = ()
    #: ``batch(values: dict of (B,) arrays, cos_theta (A,), step=COARSE_STEP, smooth=None) -> (B, A, 3)``, coarse
    #: (:data:`explorer.physics.colorimetry.COARSE_STEP`; integer parameters may be fractional).
    batch: Callable
    #: ``converged(values: dict of floats, cos_theta (A,), final: bool) -> (A, 3)``: the reference when ``final``.
    converged: Callable
    #: Optional ``gradient(values, cos_theta (A,), step=COARSE_STEP) -> (rgb (B, A, 3), {name: d rgb / d name})`` of the
    #: batch model, or None for rows it does not cover (the caller then differences the batch).
    gradient: Callable | None = None
    #: Optional ``converged_many(values: dict of (B,) arrays, cos_theta (A,)) -> (B, A, 3)``: the final ``converged``
    #: colours of many structures at once (:meth:`converged_rows` loops over ``converged`` without it).
    converged_many: Callable | None = None
    #: A parameter whose value below ``host_threshold`` means "no separate host" (a branch, not a slope).
    host_parameter: str | None = None
    host_threshold: float = 1.0
    #: The length that scales the structure (scanned on every value: :meth:`explorer.design.search._Problem.scale_scan`;
    #: needs ``spectra``).
    scale_parameter: str | None = None
    #: Search a mirror by its optical period and thickness share instead of ``Lambda`` and ``delta``.
    optical: bool = False
    #: ``spectra(values, cos_theta (A,), wavelengths (W,), smooth_relative) -> (B, A, W)`` for the scale scan.
    spectra: Callable | None = None
    #: The scan's spectra only approximate the batch model (a medium's index at one wavelength): the scanned
    #: shapes are ranked again on the screening model before the starts are chosen.
    rescreen: bool = False
    #: Free by default when painting an image: the structure's lengths and count (its indices are materials,
    #: fixed at the file's values unless named free).
    paint_free: tuple[str, ...] = ()
    #: Parameters the search holds at 0 (an effect off: a layer's absorption, the disorder) unless the caller fixes
    #: them at another value or frees them by name (:func:`explorer.design.design`'s ``free``).
    held: tuple[str, ...] = ()
    #: The ``# model:`` name it designs: set by :func:`explorer.design.design_model` from the registry.
    name: str | None = None

    def converged_rows(self, values: dict, cos_theta) -> np.ndarray:
        """The final converged colours ``(B, A, 3)`` of structures ``values`` (arrays ``(B,)``)."""
        cos_theta = np.asarray(cos_theta, dtype=np.float64)
        if self.converged_many is not None:
            return np.asarray(self.converged_many(values, cos_theta)).reshape(-1, cos_theta.size, 3)
        rows = np.asarray(next(iter(values.values()))).shape[0]
        return np.array([self.converged({k: float(v[i]) for k, v in values.items()}, cos_theta, final=True)
                         for i in range(rows)]).reshape(rows, cos_theta.size, 3)

    def __post_init__(self):
        named = (*self.log_parameters, *self.integer_parameters, *self.paint_free, *self.held,
                 *(p for p in (self.host_parameter, self.scale_parameter) if p is not None))
        stray = [p for p in named if p not in self.parameters]
        if stray:
            raise ValueError(f"design names {stray[0]!r}, not one of its parameters ({', '.join(self.parameters)})")
        if not callable(self.batch) or not callable(self.converged):
            raise TypeError("design needs its forward models: batch(values, cos_theta, ...) and converged(values, cos_theta, final)")
        if self.scale_parameter is not None and not callable(self.spectra):
            raise TypeError(f"design scans {self.scale_parameter!r}: it needs spectra(values, cos_theta, wavelengths, smooth)")


@dataclass(frozen=True, kw_only=True)
class StructureMaps:
    """
    Structure maps (``design --out-maps``) drawn on a material, declared by its twin (``Capabilities(maps=...)``):
    each texel its own structure, the parameters ``fields`` from their maps or the material's values, packed in order
    (:func:`explorer.physics.structure_maps.structure_table`). The shader's ``textured_reflectance`` reads them under
    ``texture_mapping == TEXTURE_MAPS`` (lib/structure_maps.glsl), the twin's ``textured_brdf`` with
    ``mapping="maps"`` and ``structures`` (the table).
    """

    #: The parameters a texel holds, in the table's order (at most :data:`explorer.physics.structure_maps.MAX_STRUCTURE_FIELDS`).
    fields: tuple[str, ...]
    #: Those rounded per texel (a count).
    integer_fields: tuple[str, ...] = ()
    #: ``{method: method}``: a method that needs a table of the whole material (built per material, not per texel)
    #: and the method each texel shows instead.
    stand_ins: Mapping[int, int] = ()

    def __post_init__(self):
        from explorer.physics.structure_maps import MAX_STRUCTURE_FIELDS

        if not 0 < len(self.fields) <= MAX_STRUCTURE_FIELDS:
            raise ValueError(f"structure maps hold 1 to {MAX_STRUCTURE_FIELDS} fields, not {len(self.fields)}")
        stray = [p for p in self.integer_fields if p not in self.fields]
        if stray:
            raise ValueError(f"structure maps round {stray[0]!r}, not one of their fields ({', '.join(self.fields)})")
        object.__setattr__(self, "stand_ins", dict(self.stand_ins))

    def table(self, values: Mapping[str, float], maps: Mapping[str, np.ndarray]) -> np.ndarray:
        """The shader's table of ``maps`` over ``values`` (:func:`explorer.physics.structure_maps.structure_table`)."""
        from explorer.physics.structure_maps import structure_table

        return structure_table(self.fields, values, maps, self.integer_fields)

    def texel_method(self, method: int) -> int:
        """The method each texel shows for the material's ``method``."""
        return int(self.stand_ins.get(int(method), method))


@dataclass(frozen=True, kw_only=True)
class Capabilities:
    """
    What a material can do, declared by its twin class (every field, no default: a built-in states each).

    ``methods``: the enumeration of its ``int method`` parameter (an :class:`explorer.materials.methods.Method`
    subclass) or None; ``dirac``: its ``BRDF`` is a smooth mirror's reflectance at the half vector (a Dirac's
    weight: its albedo is ``reflectance``, Mitsuba samples it as a delta); ``bragg_spectrum``: its values
    describe one Bragg mirror (``n1, n2, Lambda, delta, N, nh``: the spectrum window, the method strips, the
    accuracy badge); ``numpy``: ``render --engine numpy`` draws its twin; ``albedo``: the engines of
    :data:`ALBEDO_ENGINES` it supports; ``exports``: the targets of :data:`EXPORT_TARGETS` it supports
    (``mitsuba`` needs the twin's ``spectral_brdf`` and ``sampling_lobes``, or ``dirac`` and
    ``spectral_reflectance``); ``design``: its :class:`DesignModel` (``design`` fits its parameters on that
    forward model), or None: not designable.
    """

    methods: type | None
    dirac: bool
    bragg_spectrum: bool
    numpy: bool
    albedo: tuple[str, ...]
    exports: tuple[str, ...]
    design: DesignModel | None
    maps: StructureMaps | None = None

    def __post_init__(self):
        if not (self.maps is None or isinstance(self.maps, StructureMaps)):
            raise TypeError("maps must be a StructureMaps(...) (the parameters a texel holds), or None")
        if not (self.design is None or self.design is False or isinstance(self.design, DesignModel)):
            raise TypeError("design must be a DesignModel(...) (its parameters and forward model), or None")
        unknown = [e for e in self.albedo if e not in ALBEDO_ENGINES] + [e for e in self.exports if e not in EXPORT_TARGETS]
        if unknown:
            raise ValueError(f"unknown engine or export {unknown[0]!r} (albedo engines: {', '.join(ALBEDO_ENGINES)}; "
                             f"exports: {', '.join(EXPORT_TARGETS)})")

    def summary(self) -> str:
        """One line for ``info``: the engines, the exports, design, and what kind of reflector it is."""
        if not self.numpy:
            return f"GL only (no numpy twin); albedo {', '.join(self.albedo)}"
        kinds = [k for k, on in (("a Dirac reflector", self.dirac), ("a Bragg spectrum", self.bragg_spectrum)) if on]
        parts = ["render gl, numpy", f"albedo {', '.join(self.albedo)}", f"export {', '.join(self.exports) or 'none'}",
                 f"design {'yes' if self.design else 'no'}", f"maps {', '.join(self.maps.fields) if self.maps else 'no'}"]
        return "; ".join(parts + kinds)

    def as_json(self) -> dict:
        """The declaration as JSON (``info --json``): ``methods`` as the enumeration's member names."""
        document = {f.name: getattr(self, f.name) for f in fields(self)}
        document["methods"] = None if self.methods is None else [m.name for m in self.methods]
        document["design"] = bool(self.design)
        document["maps"] = None if self.maps is None else list(self.maps.fields)
        document.update(albedo=list(self.albedo), exports=list(self.exports))
        return document

    def supports(self, what: str) -> bool:
        """Whether ``what`` (an albedo engine, an export target, ``numpy`` or ``design``) is declared."""
        if what in ("numpy", "design"):
            return bool(getattr(self, what))
        return what in self.albedo or what in self.exports


#: The names of the fields a twin declares (the registry test checks every shipped twin sets each).
CAPABILITY_FIELDS = tuple(f.name for f in fields(Capabilities))
#: What a material without a twin can do: the GLSL engines only (any file of the format renders in GL).
NO_TWIN = Capabilities(methods=None, dirac=False, bragg_spectrum=False, numpy=False, albedo=("gl",), exports=(),
                       design=None)
#: What a twin that declares nothing can do (a test's twin, a measured table): its numpy engine and albedo.
UNDECLARED = Capabilities(methods=None, dirac=False, bragg_spectrum=False, numpy=True, albedo=("numpy", "gl"),
                          exports=(), design=None)


@runtime_checkable
class Twin(Protocol):
    """What every numpy twin provides (unit direction arrays ``(..., 3)``, colours ``(..., 3)`` linear sRGB)."""

    #: The ``# model:`` name of the material files it twins.
    name: str
    #: What the material can do (:class:`Capabilities`).
    capabilities: Capabilities

    def __init__(self, values: Mapping[str, object]) -> None: ...

    def reflectance(self, cos_theta) -> np.ndarray:
        """The colour views' ``reflectance(cos_theta)``."""

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        """The shader's ``BRDF(L, V, N, X, Y)``."""

    def textures(self) -> dict[str, np.ndarray]:
        """The tables the shader samples, by uniform name (host-built)."""


#: ``{name: twin class}``: every registered twin (the built-ins by :func:`registry`, plugins as they load).
TWINS: dict[str, type] = {}
#: The modules whose twins ship with the package (imported by :func:`registry`, each registers its own).
BUILTIN_MODULES = ("explorer.materials.models", "explorer.materials.thinfilm_model", "explorer.materials.lobes_model")


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
    capabilities = getattr(cls, "capabilities", None)
    if capabilities is not None and not isinstance(capabilities, Capabilities):
        raise TypeError(f"{cls.__name__}: 'capabilities' must be a Capabilities(...)")
    if capabilities is not None and "mitsuba" in capabilities.exports:
        hooks = ("spectral_reflectance",) if capabilities.dirac else ("spectral_brdf", "sampling_lobes")
        lacking = [h for h in hooks if not callable(getattr(cls, h, None))]
        if lacking:
            raise TypeError(f"{cls.__name__}: a Mitsuba export needs {', '.join(lacking)}")
    TWINS[name] = cls
    for listener in tuple(_LISTENERS):
        listener(cls)
    return cls


#: What runs on each registration (:func:`on_register`): a consumer above the registry that keeps its own table of
#: plugins (Mitsuba's BSDFs, once :func:`explorer.mitsuba.register` has run) hears of a twin registered later.
_LISTENERS: list[Callable[[type], None]] = []


def on_register(listener: Callable[[type], None]) -> None:
    """Call ``listener(cls)`` for every twin registered from now on (once per listener)."""
    if listener not in _LISTENERS:
        _LISTENERS.append(listener)


def registry() -> dict[str, type]:
    """:data:`TWINS`, the built-in twins registered (their modules imported) on first use."""
    import importlib

    for module in BUILTIN_MODULES:
        importlib.import_module(module)
    return TWINS


def twin_class(material_or_model) -> type | None:
    """The twin class of a material (or of a ``# model:`` name); None when it names none."""
    name = material_or_model if isinstance(material_or_model, str) or material_or_model is None \
        else getattr(material_or_model, "model", None)
    return registry().get(name or "")


def capabilities_of(material_or_model) -> Capabilities:
    """
    What a material (or a ``# model:`` name, or a twin instance) can do: its twin's declaration,
    :data:`UNDECLARED` for a twin that declares none (a measured table's), :data:`NO_TWIN` without a twin.
    """
    if material_or_model is not None and not isinstance(material_or_model, str) and hasattr(material_or_model, "brdf"):
        return getattr(material_or_model, "capabilities", None) or UNDECLARED  # a twin instance
    measured = getattr(material_or_model, "measured", None)
    if measured is not None:
        return getattr(measured, "capabilities", None) or UNDECLARED
    cls = twin_class(material_or_model)
    if cls is None:
        return NO_TWIN
    return getattr(cls, "capabilities", None) or UNDECLARED


def names_with(predicate: Callable[[Capabilities], bool]) -> tuple[str, ...]:
    """The registered twins' names whose capabilities satisfy ``predicate``, sorted."""
    return tuple(sorted(name for name, cls in registry().items() if predicate(getattr(cls, "capabilities", None) or UNDECLARED)))


def supporting(what: str) -> tuple[str, ...]:
    """The registered twins that support ``what`` (:meth:`Capabilities.supports`), sorted: for messages."""
    return names_with(lambda c: c.supports(what))


def shipped_file(cls: type):
    """
    The shipped material file (``shaders/NAME.brd``) of a built-in twin class: how a study script names the
    material it studies, by the plugin's own declaration rather than by a string.
    """
    from explorer.resources import material_path

    return material_path(cls.name)
