"""
The public API of material plugins (docs/plugins.md): what a twin module beside a ``.brd`` file imports.

A material is a plugin: a material file (``NAME.brd``, or BRDF Explorer's ``NAME.brdf``) and, beside it, a
Python file ``NAME.py`` whose class, decorated with :func:`twin`, computes in numpy what the shader computes
in GLSL and declares with :class:`Capabilities` what the material can do. Every command loads it from any
folder (``render``, ``albedo``, ``info``, ``export``, ``check``, ``open``); ``bragg-explorer check NAME.brd``
compares both versions view by view. The built-in materials are plugins of the same kind
(``explorer/materials/models.py`` and its neighbours).

- :func:`twin`: the class decorator that registers a twin under its ``name`` (its material's ``# model:``).
- :class:`Twin`: the protocol a twin follows (``reflectance``, ``brdf``, ``textures``; optional hooks in
  docs/plugins.md).
- :class:`Capabilities`: the declaration (methods, Dirac reflector, Bragg spectrum, engines, exports, design),
  with :data:`ALBEDO_ENGINES` and :data:`EXPORT_TARGETS`; :class:`DesignModel`: design's forward model and
  parameters, which a designable twin declares (``Capabilities(design=DesignModel(...))``); :class:`StructureMaps`:
  the parameters a texel of a map folder holds (``Capabilities(maps=StructureMaps(...))``).
- :class:`Method`: the base of a ``method`` parameter's enumeration; :class:`Values`: the typed, frozen
  values a twin receives; :func:`round_integer`: the one rounding rule of ``int`` parameters.
"""

from explorer.materials.brd import Values, round_integer
from explorer.materials.methods import Method
from explorer.materials.plugins import PluginError
from explorer.materials.twins import ALBEDO_ENGINES, EXPORT_TARGETS, Capabilities, DesignModel, StructureMaps, Twin, twin

__all__ = ["twin", "Twin", "Capabilities", "DesignModel", "StructureMaps", "ALBEDO_ENGINES", "EXPORT_TARGETS", "Method", "Values",
           "round_integer", "PluginError"]
