"""Setting Mitsuba's variant and registering the explorer's BSDFs for it (:func:`register`)."""

from __future__ import annotations

from explorer.mitsuba.variants import choose_variant

_REGISTERED: set[str] = set()


def register(variant: str | None = None):
    """
    Set Mitsuba's ``variant`` (default: :func:`explorer.mitsuba.variants.choose_variant`, LLVM probed in a
    subprocess) and register the explorer's BSDFs for it. Returns the ``mitsuba`` module.

    The kernels call back into numpy (the explorer's physics and tables), so the JIT variants run with
    Dr.Jit's symbolic loops and calls off (wavefront mode).
    """
    import drjit as dr
    import mitsuba as mi

    variant = variant or choose_variant()
    mi.set_variant(variant)
    if dr.is_jit_v(mi.Float):
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        dr.set_flag(dr.JitFlag.SymbolicCalls, False)
    if variant not in _REGISTERED:
        from explorer.mitsuba.bsdfs import define_bsdfs

        for name, cls in define_bsdfs(mi, dr).items():
            mi.register_bsdf(name, lambda props, cls=cls: cls(props))
        _REGISTERED.add(variant)
    return mi
