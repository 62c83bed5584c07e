"""
``export MATERIAL --to table out.exr``: a homogeneous material baked into an RGB table any engine can sample.

Layout (docs/export.md): a float32 RGB OpenEXR, linear sRGB in the explorer's colour convention.

- Columns ``j = 0 .. W - 1``: ``cos theta = j / (W - 1)`` (the view's angle to the normal), W = :data:`COLUMNS`.
- A material with no roughness parameter (``bragg_mirror``): one row, its reflectance ``R(cos theta)``.
- A rough one (a parameter ``alpha`` or ``alpha_k``): rows ``i = 0 .. H - 1`` at roughness
  ``alpha = i / (H - 1)`` (every ``alpha`` parameter set to it), H = :data:`ROWS`; each texel is the
  directional albedo ``int f(l, v) cos theta_l d omega_l`` for ``v`` at that ``cos theta``: the split-sum
  "environment BRDF" of real-time engines, in colour. Row 0 is the smooth limit ``R(cos theta)`` (the
  material's ``reflectance``), where GGX with ``alpha -> 0`` is a Dirac.

The albedo is a stratified estimate (:data:`STRATA`\\ ² samples per texel) of one-sample MIS over the GGX
visible normals (Heitz 2018) and a cosine lobe, the estimator of the env view; unbiased for any material.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from explorer.errors import LocatedError
from explorer.physics import microfacet

COLUMNS = 64
ROWS = 32
STRATA = 16
#: The cosine lobe's share of the samples (the base's diffuse light).
COSINE_SHARE = 0.25


class TableExportError(LocatedError):
    """A table that cannot be made for this material (one line)."""


def roughness_names(material) -> list[str]:
    return [p.name for p in material.parameters if p.name == "alpha" or p.name.startswith("alpha_")]


#: Texels (columns) whose samples go to the material's BRDF in one call: the per-call cost (a lobe sum's
#: setup) is paid 16 times per row, not 64; more columns a call slow a spectral stack down (its arrays outgrow the caches).
COLUMNS_PER_CALL = 4


def _albedo(model, cos_v: np.ndarray, alpha: float) -> np.ndarray:
    """Directional albedo (RGB) at each ``cos_v``, by a stratified MIS estimate."""
    alpha_s = max(alpha, 1e-3)
    k = np.arange(STRATA)
    u1, u2 = np.meshgrid((k + 0.5) / STRATA, (k + 0.5) / STRATA)
    u1, u2 = u1.ravel(), u2.ravel()
    samples = u1.size
    e = np.eye(3)
    out = np.zeros((cos_v.size, 3))
    r, phi = np.sqrt(u1), 2.0 * np.pi * u2
    l_cos_one = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1.0 - u1))], axis=-1)
    for first in range(0, cos_v.size, COLUMNS_PER_CALL):
        cos = np.clip(cos_v[first:first + COLUMNS_PER_CALL], 1e-3, 1.0)
        count = cos.size
        v = np.stack([np.sqrt(1.0 - cos * cos), np.zeros_like(cos), cos], axis=-1)
        vv = np.repeat(v, samples, axis=0)  # (count * samples, 3): texel c's samples in rows c S .. (c + 1) S
        m = microfacet.sample_ggx_visible_normal(vv, alpha_s, np.tile(u1, count), np.tile(u2, count))
        l_ggx = 2.0 * np.sum(vv * m, axis=-1, keepdims=True) * m - vv
        l_cos = np.tile(l_cos_one, (count, 1))
        texel = np.repeat(np.arange(count), samples)
        for l, share in ((l_ggx, 1.0 - COSINE_SHARE), (l_cos, COSINE_SHARE)):
            pdf = (1.0 - COSINE_SHARE) * microfacet.ggx_reflection_pdf(l, vv, alpha_s) + COSINE_SHARE * np.maximum(l[:, 2], 0.0) / np.pi
            ok = (l[:, 2] > 0.0) & (pdf > 0.0)
            with np.errstate(all="ignore"):
                f = model.brdf(l[ok], vv[ok], e[2], e[0], e[1])
            f = np.where(np.isfinite(f), f, 0.0)
            contribution = share * f * (l[ok, 2] / pdf[ok])[:, None] / samples
            np.add.at(out, first + texel[ok], contribution)
    return out


#: Nodes in cos theta of the dense copy of a material's ``reflectance`` its rough rows read (the BRDF's Fresnel
#: factor at theta_d, where the model takes it from ``reflectance``): computed once for all rows, read linearly.
#: A film's or a tabulated mirror's colour varies over a few fringes across cos theta at most; 4097 nodes keep
#: the linear reading within ~1e-6 of it, and a spectral method costs 4097 sums instead of ~10^6.
DENSE_NODES = 4097


def _dense_reflectance(base) -> Callable[[np.ndarray], np.ndarray]:
    """``reflectance(cos_theta)`` of ``base`` read linearly from :data:`DENSE_NODES` nodes (the same method's values)."""
    nodes = np.linspace(0.0, 1.0, DENSE_NODES)
    table = np.asarray(base.reflectance(nodes), dtype=np.float64)

    def reflectance(cos_theta):
        c = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
        return np.stack([np.interp(c, nodes, table[:, k]) for k in range(3)], axis=-1)

    return reflectance


def table_values(material, values) -> dict:
    """
    The values a table is baked at: ``values``, a Bragg material on its tabulated method whatever the file's
    (the converged colours, within 0.01 of the 1-nm sum and many times faster: a table bakes ~10^6 BRDF
    samples, each a 471-wavelength sum at method 0).
    """
    from explorer.materials.methods import BraggMethod, methods_for

    values = dict(values)
    if "method" in values and methods_for(material) is BraggMethod:
        values["method"] = int(BraggMethod.TABULATED)
    return values


def material_table(material, values, progress: Callable[[int, int], None] | None = None) -> np.ndarray:
    """
    The table (``(rows, COLUMNS, 3)`` float32) described in the module's docstring, at :func:`table_values`;
    ``progress(done, total)`` after each row.
    """
    from explorer.materials.models import model_for

    values = table_values(material, values)
    names = roughness_names(material)
    cos = np.linspace(0.0, 1.0, COLUMNS)
    base = model_for(material, values)
    if base is None or not callable(getattr(base, "reflectance", None)):
        raise TableExportError(material.path, None, "this material has no numpy twin to bake (no known '# model:' line)")
    smooth = np.asarray(base.reflectance(cos), dtype=np.float64)
    total = ROWS if names else 1
    if progress is not None:
        progress(1, total)
    if not names:
        return smooth[None].astype(np.float32)
    rows = [smooth]
    dense = _dense_reflectance(base)  # the roughness changes the lobe, not the smooth colour: built once
    for k, alpha in enumerate(np.linspace(0.0, 1.0, ROWS)[1:], start=2):
        model = model_for(material, {**values, **{n: float(alpha) for n in names}})
        model.reflectance = dense
        rows.append(_albedo(model, cos, float(alpha)))
        if progress is not None:
            progress(k, total)
    return np.asarray(rows, dtype=np.float32)
