"""
The designable models: each material's forward model is declared by its twin
(:class:`explorer.materials.twins.DesignModel`, ``Capabilities(design=...)``), and design asks the registry for it.
The forward models themselves live with their materials (the Bragg twins' over
:func:`explorer.physics.bragg.bragg_reflectance_batch`, the film's over its Airy reflectance), a plugin's beside its
material file (docs/plugins.md).
"""

from __future__ import annotations

from dataclasses import replace

from explorer.design.base import DesignError, DesignModel
from explorer.materials.twins import capabilities_of, supporting

#: The public names (re-exported by :mod:`explorer.design`).
__all__ = ["designable", "design_model"]


def designable() -> tuple[str, ...]:
    """The registered twins that declare a forward model for design, sorted (plugins included once loaded)."""
    return supporting("design")


def design_model(name: str | None) -> DesignModel:
    """
    The :class:`DesignModel` the twin of material model ``name`` declares (named ``name``), or a one-line
    :class:`DesignError` when it declares none.
    """
    declared = capabilities_of(name).design if name else None
    if not declared:
        raise DesignError(f"model {name or '(none)'} cannot be designed: its twin declares no forward model "
                          f"(designable: {', '.join(designable())})")
    return declared if declared.name == name else replace(declared, name=name)
