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

__all__ = ["register", "load_file", "render_file", "choose_variant", "VARIANTS", "MitsubaError", "plugin_names"]

from explorer.mitsuba.bsdfs import plugin_names  # noqa: E402  (numpy only: mitsuba is imported by register)
from explorer.mitsuba.registry import register  # noqa: E402
def load_file(path, variant: str | None = None, **parameters):
    """
    Load a scene written by ``export --to mitsuba`` (or any scene that uses our BSDFs) after
    :func:`register`. In the spectral variants its film records XYZ (``pixel_format="xyz"``) unless
    ``parameters`` say otherwise: :func:`render_file` converts it to the explorer's RGB.
    """
    from explorer.mitsuba.variants import is_spectral

    mi = register(variant)
    if is_spectral(mi.variant()):
        parameters.setdefault("pixel_format", "xyz")
    return mi.load_file(str(path), **parameters)


def render_file(path, variant: str | None = None, spp: int | None = None, seed: int = 0):
    """Render an exported scene: ``(H, W, 3)`` float32 linear sRGB in the explorer's colour convention."""
    import numpy as np

    from explorer.mitsuba.scene import render_in_passes, xyz_to_explorer_rgb
    from explorer.mitsuba.variants import is_spectral

    scene = load_file(path, variant)
    import mitsuba as mi

    image = render_in_passes(mi, scene, spp, seed)
    if is_spectral(mi.variant()):
        image = xyz_to_explorer_rgb(image)
    return image.astype(np.float32)
