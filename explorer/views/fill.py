"""
The lit view's environment fill: beside its point light (unit irradiance), a uniform white environment of
radiance ``fill``, so that a material shows its colour where the light's highlight is not (the paper's
Figure 1 renders are lit by environments; one point light on black shows a white dot).

Under a uniform environment of radiance ``L`` a surface sends ``L a(theta_v)`` toward the eye, ``a`` the
directional albedo (reciprocity: the albedo for the light at the view's angle), exactly. The fill adds
``fill x a(theta_v)`` per pixel, ``a`` from a table of :data:`FILL_ANGLES` incidence angles (linear in the
angle between them, clamped at the ends) on a coarse version of the albedo view's half-vector quadrature
(:func:`explorer.views.albedo.half_vector_quadrature`: :data:`FILL_THETA_H_NODES` Gauss-Legendre nodes per
cell of :data:`explorer.views.albedo.THETA_H_EDGES`, :data:`FILL_PHI_NODES` azimuths). The GL lit view gets
the table from the albedo view (``shaders/views/albedo.glsl``) drawn with these nodes; its numpy twin sums
the same nodes (:func:`fill_albedo_numpy`). Coarse: a table costs 16 x 32 x 32 BRDF evaluations, so that a
slider stays interactive; a lobe narrower than the cells is integrated roughly (a fill, not a measurement:
``albedo`` gives the converged numbers).

A smooth mirror (``mirror_only``) has no fill: its lit view already reflects an environment.
"""

from __future__ import annotations

import numpy as np

#: Incidence angles of the table: theta_k = 90 (k + 0.5) / FILL_ANGLES degrees (the albedo view's columns).
FILL_ANGLES = 16
#: Gauss-Legendre nodes per theta_h cell and azimuths of the fill's quadrature.
FILL_THETA_H_NODES = 2
FILL_PHI_NODES = 32
#: The fill's radiance by default (the point light's irradiance is 1; this environment's is pi x 0.15 ~ 0.47).
DEFAULT_FILL = 0.15


def fill_angles() -> np.ndarray:
    """The table's incidence angles in degrees."""
    return 90.0 * (np.arange(FILL_ANGLES) + 0.5) / FILL_ANGLES


def fill_theta_h_nodes() -> tuple[np.ndarray, np.ndarray]:
    """The fill quadrature's ``theta_h`` nodes and weights (radians) over :data:`explorer.views.albedo.THETA_H_EDGES`."""
    from explorer.views.albedo import THETA_H_EDGES

    x, w = np.polynomial.legendre.leggauss(FILL_THETA_H_NODES)
    a, b = THETA_H_EDGES[:-1, None], THETA_H_EDGES[1:, None]
    return (0.5 * (b - a) * x + 0.5 * (a + b)).ravel(), (0.5 * (b - a) * w).ravel()


def fill_uniforms() -> dict[str, object]:
    """The albedo view's uniforms (``shaders/views/albedo.glsl``) for the fill's quadrature."""
    from explorer.views.plots import ALBEDO_MAX_NODES

    theta_h, d_theta = fill_theta_h_nodes()
    padded = [np.zeros(ALBEDO_MAX_NODES) for _ in range(2)]
    padded[0][:theta_h.size], padded[1][:theta_h.size] = theta_h, d_theta
    return {"albedo_nodes": int(theta_h.size), "albedo_theta_h": tuple(float(t) for t in padded[0]),
            "albedo_d_theta": tuple(float(w) for w in padded[1]), "albedo_phi_nodes": FILL_PHI_NODES}


def has_fill(model_or_material) -> bool:
    """Whether the lit view fills: every material but a smooth mirror (which reflects the environment)."""
    from explorer.views.mirror import is_mirror_only

    if hasattr(model_or_material, "shader"):  # a Material
        return not is_mirror_only(model_or_material)
    return not getattr(model_or_material, "mirror_only", False)


def fill_albedo_numpy(model) -> np.ndarray:
    """
    The fill's table, ``(FILL_ANGLES, 3)``: the numpy twin's directional albedo at :func:`fill_angles` on the fill's
    quadrature, as the albedo view sums it (the BRDF under the views' rule, plus a Dirac's ``mirror_reflection``).
    """
    from explorer.views.albedo import BLOCK, _dirac
    from explorer.views.geometry import view_brdf

    theta = np.radians(fill_angles())
    theta_h, d_theta = fill_theta_h_nodes()
    phi_h = (np.arange(FILL_PHI_NODES) + 0.5) * (2.0 * np.pi / FILL_PHI_NODES)
    T, P = np.meshgrid(theta_h, phi_h, indexing="ij")
    h = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1).reshape(-1, 3)
    weight = (4.0 * np.sin(T) * d_theta[:, None] * (2.0 * np.pi / FILL_PHI_NODES)).ravel()
    result = _dirac(model, np.cos(theta))
    N, X, Y = (np.array(v, dtype=np.float64) for v in ([0, 0, 1], [1, 0, 0], [0, 1, 0]))
    for k, t in enumerate(theta):
        i = np.array([np.sin(t), 0.0, np.cos(t)])
        i_dot_h = h @ i
        o = 2.0 * i_dot_h[:, None] * h - i
        keep = (i_dot_h > 0.0) & (o[:, 2] > 0.0)
        o, w = o[keep], (weight * i_dot_h)[keep]
        for start in range(0, o.shape[0], BLOCK):
            V = o[start:start + BLOCK]
            frame = [np.broadcast_to(a, V.shape) for a in (i, V, N, X, Y)]
            f = view_brdf(model.brdf, *frame)
            result[k] += np.sum(f * (V[:, 2] * w[start:start + BLOCK])[:, None], axis=0)
    return result


def fill_radiance(table: np.ndarray, cos_view: np.ndarray, fill: float) -> np.ndarray:
    """``fill x a(theta_v)`` per pixel, ``(n, 3)``: the table interpolated as ``lit.glsl``'s ``fill_radiance`` does."""
    theta = np.degrees(np.arccos(np.clip(np.asarray(cos_view, dtype=np.float64), 0.0, 1.0)))
    table = np.asarray(table, dtype=np.float64)
    return fill * np.stack([np.interp(theta, fill_angles(), table[:, c]) for c in range(3)], axis=-1)
