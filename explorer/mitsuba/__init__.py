"""
The explorer's materials in Mitsuba 3: BSDF plugins (:mod:`explorer.mitsuba.bsdfs`), the env view's scene
(:mod:`explorer.mitsuba.scene`) and a safe choice of variant (:mod:`explorer.mitsuba.variants`).

Usage::

    import mitsuba as mi
    from explorer import mitsuba as em
    em.register("llvm_ad_rgb")          # sets the variant, registers bragg_mirror, bragg_layer, ...
    bsdf = mi.load_dict({"type": "bragg_layer", "Lambda": 600.0, "alpha": 0.2})

Needs the optional extra: ``pip install '.[mitsuba]'``.
"""

from __future__ import annotations

from explorer.mitsuba.variants import VARIANTS, MitsubaError, choose_variant

__all__ = ["register", "load_file", "choose_variant", "VARIANTS", "MitsubaError", "BSDF_NAMES"]

BSDF_NAMES = ("bragg_mirror", "bragg_layer", "bragg_stack", "thin_film", "layered_lobes")
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


def load_file(path, variant: str | None = None, **parameters):
    """Load a scene written by ``export --to mitsuba`` (or any scene using our BSDFs) after :func:`register`."""
    mi = register(variant)
    return mi.load_file(str(path), **parameters)
