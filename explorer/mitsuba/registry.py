"""
Setting Mitsuba's variant and registering the explorer's BSDFs for it (:func:`register`): every twin that declares
a Mitsuba export, including a plugin loaded later (the registry tells :func:`_registered_late`).
"""

from __future__ import annotations

from explorer.mitsuba.variants import choose_variant

#: ``{variant: {plugin name: its twin class when registered}}``: what Mitsuba holds, per variant.
_REGISTERED: dict[str, dict[str, type]] = {}


def register(variant: str | None = None):
    """
    Set Mitsuba's ``variant`` (default: :func:`explorer.mitsuba.variants.choose_variant`, LLVM probed in a
    subprocess) and register the explorer's BSDFs for it. Returns the ``mitsuba`` module.

    A twin registered afterwards (a plugin loaded from its folder) reaches every variant registered so far at once.
    The kernels call back into numpy (the explorer's physics and tables), so the JIT variants run with
    Dr.Jit's symbolic loops and calls off (wavefront mode).
    """
    import drjit as dr
    import mitsuba as mi

    from explorer.materials.twins import on_register, registry
    from explorer.mitsuba.bsdfs import plugin_names

    variant = variant or choose_variant()
    mi.set_variant(variant)
    if dr.is_jit_v(mi.Float):
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        dr.set_flag(dr.JitFlag.SymbolicCalls, False)
    held = _REGISTERED.setdefault(variant, {})
    _define(mi, dr, [name for name in plugin_names() if held.get(name) is not registry()[name]], held)
    on_register(_registered_late)
    return mi


def _define(mi, dr, names, held: dict[str, type]) -> None:
    """Register ``names``' BSDFs with Mitsuba for its active variant."""
    from explorer.materials.twins import registry
    from explorer.mitsuba.bsdfs import define_bsdfs

    for name, cls in define_bsdfs(mi, dr, names).items():
        mi.register_bsdf(name, lambda props, cls=cls: cls(props))
        held[name] = registry()[name]


def _registered_late(cls: type) -> None:
    """A twin registered after :func:`register`: its BSDF in every variant registered so far (the active one kept)."""
    capabilities = getattr(cls, "capabilities", None)
    if capabilities is None or "mitsuba" not in capabilities.exports or not _REGISTERED:
        return
    import drjit as dr
    import mitsuba as mi

    active = mi.variant()
    try:
        for variant, held in _REGISTERED.items():
            mi.set_variant(variant)
            _define(mi, dr, [cls.name], held)
    finally:
        if active is not None:
            mi.set_variant(active)
