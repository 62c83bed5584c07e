"""
Directional albedo: ``a(theta_i) = int f(i, o) cos theta_o d omega_o`` over the outgoing hemisphere,
plus the weight of a material's Dirac reflection where it has one, per incidence angle ``theta_i`` in
the outer medium (the light in the ``xz`` plane, ``phi_i = 0``), linear sRGB in the colour convention of
``render`` (:mod:`explorer.physics.colorimetry`: a white reflector is (1, 1, 1)).

Three engines:

- ``numpy``: the material's numpy twin (:mod:`explorer.materials.models`) on a deterministic quadrature
  over the half vector ``h`` (``d omega_o = 4 (o.h) d omega_h``, Walter et al. 2007, Eq. 14), Gauss-Legendre
  in ``theta_h`` on cells graded geometrically toward the normal (a GGX lobe of ``alpha`` spans
  ``theta_h ~ alpha``, Eq. 18) and the midpoint rule in ``phi_h``;
- ``gl``: the material's GLSL ``BRDF`` drawn by the GPU in the ``scatter`` view (the hemisphere of ``o``
  on a disc, ``BRDF cos theta_o`` per pixel), summed with each pixel's solid angle; any material of the
  format, BRDF Explorer's ``.brdf`` files included;
- ``position-free``: the Monte Carlo reference of Section 4.2 for layered Bragg structures
  (:mod:`explorer.physics.position_free`), with its standard error.

A smooth mirror (a twin that declares ``dirac``: its ``BRDF`` is its reflectance at the half vector, a Dirac's
weight) has for albedo its specular reflectance ``reflectance(cos theta)``. (A Fresnel-weighted Lambertian,
``F / pi``, is integrated like any BRDF.) A twin's ``mirror_reflection`` (the coating of a layered Bragg
stack: Eq. 34's ``f_r,0``) adds its Dirac reflection.

References
----------
Fourneau, Pacanowski, Barla (2024), Eq. 34 and Section 4.2; Walter, Marschner, Li, Torrance (2007),
Microfacet models for refraction through rough surfaces, Eq. 14.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from explorer.materials.twins import capabilities_of, supporting

#: Cell edges in theta_h (radians), graded toward the normal: lobes down to alpha ~ 1e-3 span cells.
THETA_H_EDGES = np.array([0.0, 1e-3, 3e-3, 0.01, 0.02, 0.035, 0.06, 0.1, 0.15, 0.22, 0.32, 0.45, 0.6, 0.8, 1.05, 1.3, 0.5 * np.pi])
#: Gauss-Legendre nodes per theta_h cell, and azimuths (midpoint rule) of the numpy quadrature.
THETA_H_NODES = 8
PHI_H_NODES = 128
#: The gl engine's scatter image (pixels per side): a pixel spans 0.35 degree of theta_o.
GL_SIZE = 512
#: Directions per block of the numpy quadrature (memory: the bragg_stack twin holds 471 wavelengths each).
BLOCK = 4096


def check_theta(theta_deg) -> np.ndarray:
    """Incidence angles in degrees, each in [0, 90); a one-line ``ValueError`` otherwise."""
    theta = np.atleast_1d(np.asarray(theta_deg, dtype=np.float64))
    bad = ~(np.isfinite(theta) & (theta >= 0.0) & (theta < 90.0))
    if theta.size == 0 or bad.any():
        raise ValueError(f"incidence angles must be in [0, 90) degrees, got {theta[bad][0] if bad.any() else 'none'}")
    return theta


def theta_h_nodes() -> tuple[np.ndarray, np.ndarray]:
    """The quadrature's ``theta_h`` nodes and weights (radians): Gauss-Legendre on each cell of :data:`THETA_H_EDGES`."""
    x, w = np.polynomial.legendre.leggauss(THETA_H_NODES)
    a, b = THETA_H_EDGES[:-1, None], THETA_H_EDGES[1:, None]
    return (0.5 * (b - a) * x + 0.5 * (a + b)).ravel(), (0.5 * (b - a) * w).ravel()


def half_vector_quadrature(theta_i: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Outgoing directions ``o`` and weights ``w`` such that ``sum w g(o) ~ int g(o) d omega_o`` over the upper
    hemisphere, for incidence ``i = (sin theta_i, 0, cos theta_i)``: nodes in the half vector ``h``
    (Gauss-Legendre over :data:`THETA_H_EDGES`, midpoint in ``phi_h``), ``o = 2 (i.h) h - i``, weight
    ``4 (i.h) sin theta_h d theta_h d phi_h`` (the Jacobian of the reflection); ``h`` whose ``o`` falls
    below the horizon are dropped.
    """
    theta_h, d_theta = theta_h_nodes()
    phi_h = (np.arange(PHI_H_NODES) + 0.5) * (2.0 * np.pi / PHI_H_NODES)
    T, P = np.meshgrid(theta_h, phi_h, indexing="ij")
    h = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1).reshape(-1, 3)
    weight = (4.0 * np.sin(T) * d_theta[:, None] * (2.0 * np.pi / PHI_H_NODES)).ravel()
    i = np.array([np.sin(theta_i), 0.0, np.cos(theta_i)])
    i_dot_h = h @ i
    o = 2.0 * i_dot_h[:, None] * h - i
    keep = (i_dot_h > 0.0) & (o[:, 2] > 0.0)
    return o[keep], (weight * i_dot_h)[keep]


def _dirac(model, cos_theta: np.ndarray) -> np.ndarray:
    """The weight of a model's Dirac reflection (``mirror_reflection``) at incidence ``cos_theta``: (n, 3)."""
    mirror = getattr(model, "mirror_reflection", None)
    if mirror is None:
        return np.zeros((cos_theta.size, 3))
    s = np.sqrt(np.maximum(1.0 - cos_theta**2, 0.0))
    V = np.stack([s, np.zeros_like(s), cos_theta], axis=-1)
    return np.asarray(mirror(V, np.broadcast_to([0.0, 0.0, 1.0], V.shape)), dtype=np.float64).reshape(-1, 3)


def albedo_numpy(model, theta_deg, progress: Callable[[int, int], None] | None = None) -> np.ndarray:
    """
    The directional albedo of a numpy twin (:mod:`explorer.materials.models`) at ``theta_deg``: (n, 3).

    A Dirac reflector (its twin declares ``dirac``) gives ``reflectance(cos theta)``; others ``brdf`` under the views'
    rule (:func:`explorer.views.geometry.view_brdf`) on :func:`half_vector_quadrature`, plus their
    ``mirror_reflection`` where they have one.
    """
    from explorer.views.geometry import view_brdf

    theta = np.radians(check_theta(theta_deg))
    if capabilities_of(model).dirac:
        return np.asarray(model.reflectance(np.cos(theta)), dtype=np.float64).reshape(-1, 3)
    if not callable(getattr(model, "brdf", None)):
        raise ValueError(f"{type(model).__name__} has no brdf(): no albedo")
    result = _dirac(model, np.cos(theta))
    N, X, Y = (np.array(v, dtype=np.float64) for v in ([0, 0, 1], [1, 0, 0], [0, 1, 0]))
    for k, t in enumerate(theta):
        o, w = half_vector_quadrature(t)
        L = np.array([np.sin(t), 0.0, np.cos(t)])
        for start in range(0, o.shape[0], BLOCK):
            V = o[start:start + BLOCK]
            frame = [np.broadcast_to(a, V.shape) for a in (L, V, N, X, Y)]
            f = view_brdf(model.brdf, *frame)
            result[k] += np.sum(f * (V[:, 2] * w[start:start + BLOCK])[:, None], axis=0)
        if progress is not None:
            progress(k + 1, theta.size)
    return result


def sum_albedo_terms(terms: np.ndarray, columns: int) -> np.ndarray:
    """
    The albedo of ``columns`` incidence angles from the albedo view's terms (``shaders/views/albedo.glsl``:
    rows from the top, ``columns`` blocks of one row per ``theta_h`` node, a column per azimuth), summed
    in float64: ``(columns, 3)``.
    """
    terms = np.asarray(terms, dtype=np.float64)
    return terms.reshape(columns, -1, terms.shape[-1])[..., :3].sum(axis=1)


def scatter_solid_angles(width: int, height: int) -> np.ndarray:
    """
    Each pixel's solid angle (sr) in the scatter view's disc (:func:`explorer.views.geometry.brdf_view_geometry`:
    ``theta_o = (pi / 2) r``): ``d omega = sin theta_o d theta_o d phi = (pi / 2) (sin theta_o / r) dx dy``,
    0 outside the disc.
    """
    x = 2.0 * (np.arange(width) + 0.5) / width - 1.0
    y = 1.0 - 2.0 * (np.arange(height) + 0.5) / height
    r = np.hypot(x[None, :], y[:, None])
    sinc = np.where(r > 0.0, np.sin(0.5 * np.pi * r) / np.maximum(r, 1e-300), 0.5 * np.pi)
    return np.where(r < 1.0, 0.5 * np.pi * sinc * (2.0 / width) * (2.0 / height), 0.0)


def albedo_gl(material, values, theta_deg, renderer, size: int = GL_SIZE, model=None,
              progress: Callable[[int, int], None] | None = None) -> np.ndarray:
    """
    The directional albedo by the GPU: ``BRDF cos theta_o`` in the scatter view (light at ``(theta, 0)``)
    summed with :func:`scatter_solid_angles`; a Dirac reflector (its twin declares ``dirac``) gives its reflectance
    at the mirror pixel's angle instead (the gradient view, interpolated). ``model`` (its numpy twin, when
    it has one) adds its ``mirror_reflection``. ``renderer``: an :class:`explorer.gpu.Renderer` (views
    come below gpu: the caller makes it). (n, 3).
    """
    theta = check_theta(theta_deg)
    if capabilities_of(material).dirac:
        # The gradient's column k shows reflectance at theta = 90 (k + 0.5) / W degrees.
        width = 8192
        row = renderer.render(material, values, "gradient", width, 1)[0].astype(np.float64)
        columns = 90.0 * (np.arange(width) + 0.5) / width
        return np.stack([np.interp(theta, columns, row[:, c]) for c in range(3)], axis=-1)
    weights = scatter_solid_angles(size, size)
    result = np.zeros((theta.size, 3))
    for k, t in enumerate(theta):
        image = renderer.render(material, values, "scatter", size, size, light=(float(t), 0.0)).astype(np.float64)
        result[k] = np.einsum("hwc,hw->c", image, weights)
        if progress is not None:
            progress(k + 1, theta.size)
    if model is not None:
        result += _dirac(model, np.cos(np.radians(theta)))
    return result


def gl_size_for(model) -> int:
    """
    The gl engine's scatter image size: :data:`GL_SIZE`, doubled for lobes narrower than ``alpha = 0.05``
    (a pixel must stay well under the lobe: at 512, ``alpha = 0.025`` is off by ~1e-2, at 1024 by 1e-5),
    and again below 0.0125. ``model`` is the numpy twin (its ``alpha`` or its stack's), or None.
    """
    alphas = [getattr(model, "alpha", None)]
    alphas += [getattr(layer, "alpha", None) for layer in getattr(getattr(model, "stack", None), "layers", ())]
    alphas = [float(a) for a in alphas if a is not None]
    alpha = min(alphas) if alphas else 1.0
    return GL_SIZE * (1 if alpha >= 0.05 else 2 if alpha >= 0.0125 else 4)


def position_free_stack(model):
    """The :class:`explorer.physics.layered.LayeredBragg` of a numpy twin the position-free engine simulates."""
    if not capabilities_of(model).supports("position-free"):
        raise ValueError(f"the position-free engine simulates layered Bragg structures ({', '.join(supporting('position-free'))}), "
                         f"not {getattr(model, 'name', type(model).__name__)}")
    return model.stack


def albedo_position_free(model, theta_deg, samples: int = 20000, seed: int = 0,
                         progress: Callable[[int, int], None] | None = None, microsurface: str = "single"):
    """
    The position-free directional albedo (:meth:`explorer.physics.position_free.PositionFree.albedo`) of a
    twin that supports it (a layered Bragg stack's): a :class:`explorer.physics.position_free.PositionFreeResult`.
    ``microsurface``: ``single`` (Eq. 17's single scattering per layer) or ``walk`` (every bounce among a
    layer's facets).
    """
    from explorer.physics.position_free import PositionFree

    stack = position_free_stack(model)
    return PositionFree(stack, getattr(model, "tables", None), microsurface).albedo(check_theta(theta_deg), samples, seed, progress)
