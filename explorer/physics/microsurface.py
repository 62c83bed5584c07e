"""
Multiple scattering on the microsurface of a rough Bragg layer: the random walk of Heitz, Hanika, d'Eon &
Dachsbacher (2016) on a Smith microsurface (GGX slopes, uncorrelated heights), whose facets are Bragg
mirrors that reflect with Yeh's ``R_lambda(theta_d)`` or let the light through ballistically with
``T = 1 - R`` (Fourneau et al. 2024, Section 4.2.1). Numpy only; used by
:class:`explorer.physics.position_free.PositionFree` (``microsurface="walk"``).

The walk (Heitz et al. 2016, Section 5 and their published ``MicrosurfaceConductor`` /
``MicrosurfaceDielectric`` code): a ray at height ``h`` travelling along ``w``

- away from the microsurface (``w.z > 0`` on its side) leaves it with Smith's height-dependent masking
  ``G1(w, h) = C1(h)^Lambda(w)``, else meets it higher up, at ``C1(h') = C1(h) V^(-1/Lambda(w))``
  (``V`` uniform in ``[G1, 1]``);
- toward it (``w.z < 0``) always meets it, at ``C1(h') = C1(h) V^(1/(1 + Lambda(|w|)))``;
- at a hit, a facet normal is drawn from the normals visible from ``-w`` (Heitz 2018; valid for ``-w``
  below the horizon too, as the walk needs), and the facet reflects about it or, with ``T``, lets the ray
  cross without changing its direction. A crossing ray is below the microsurface, which it sees
  upside down: heights and the normal flipped, ``C1 -> 1 - C1`` (the height distribution is symmetric).

Only ``C1(h)`` enters (Smith's uncorrelated heights make the height distribution irrelevant), so the walk
keeps ``u = C1(h)`` in ``[0, 1]``. A ray entering from above starts at ``u = 1``, from below at ``u = 0``.
It ends when it leaves the microsurface, upward (reflected by the layer) or downward (transmitted).
With ``R = 1`` the walk is the conductor of Heitz et al.: it loses no energy (the white furnace).

Single scattering (Eq. 17 and Eq. 28) is the walk's first event with the separable Smith ``G1(i) G1(o)``
instead of the walk's height-correlated masking; the light beyond it (Eq. 30's ``A``, and the part
``1 - G1(o)`` of each reflection) is what the single-scattering model loses.

References
----------
Heitz, Hanika, d'Eon, Dachsbacher (2016). Multiple-scattering microfacet BSDFs with the Smith model.
ACM TOG 35(4) (SIGGRAPH 2016). Section 5 (the random walk), Eqs. for ``G1(w, h)`` and height sampling.
Heitz (2018). Sampling the GGX distribution of visible normals. JCGT 7(4).
Fourneau, Pacanowski, Barla (2024). Computer Graphics Forum 43(2). Sections 4.1-4.2 (Eqs. 17-19, 28-30).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from explorer.physics import microfacet

#: A walk's hard stop on facet events; paths still on the microsurface then are dropped. Reflecting facets
#: need few (alpha = 1, R = 1: 99.9 % within 7); crossing ones zigzag through the layer, ~1 / |cos theta|
#: times at grazing angles (alpha = 1, T = 1, isotropic directions: 0.4 % of the paths reach 256 events).
MAX_WALK_EVENTS = 256


def smith_lambda(cos_theta: np.ndarray, alpha: float) -> np.ndarray:
    """
    Smith's ``Lambda`` for GGX at a direction above the surface (``cos_theta > 0``):
    ``(sqrt(1 + alpha^2 tan^2 theta) - 1) / 2``, so that ``G1 = 1 / (1 + Lambda)`` (Eq. 19).
    Evaluated as ``(sqrt(c^2 + alpha^2 s^2) - c) / (2 c)``; infinite at the horizon.
    """
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    root = np.sqrt(c * c + alpha * alpha * (1.0 - c * c))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(c > 0.0, (root - c) / (2.0 * np.where(c > 0.0, c, 1.0)), np.inf)


def walk(
    direction: np.ndarray, beta: np.ndarray, pi: np.ndarray, alpha: float,
    reflectance: Callable[[np.ndarray, np.ndarray], np.ndarray], rng: np.random.Generator,
    max_events: int = MAX_WALK_EVENTS, record: Callable[[np.ndarray, np.ndarray, np.ndarray], None] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """
    Walk ``n`` paths through one rough Bragg layer until they leave it.

    Parameters
    ----------
    direction : ndarray, shape (n, 3)
        Propagation directions (the layer's frame, ``n = +z``); ``z < 0`` enters from above, ``z > 0``
        from below.
    beta, pi : ndarray, shape (n, K)
        Each wavelength's throughput and the probability its own choices give the path (spectral MIS,
        as in :meth:`explorer.physics.position_free.PositionFree.trace`): the first wavelength (the hero)
        decides between reflection and crossing.
    alpha : float
        The layer's GGX roughness.
    reflectance : callable
        ``reflectance(cos_theta_d, rows)``: Yeh's ``R_lambda`` at the facet angle for the paths ``rows``,
        shape ``(len(rows), K)``.
    rng : numpy.random.Generator
    max_events : int
        Facet events at most per path.
    record : callable, optional
        ``record(rows, cos_theta_d, reflect)`` at every facet event: which paths, their facet angles, whether
        each reflected (for reweighting the paths to other reflectances: the path's geometry depends on the
        choices only).

    Returns
    -------
    direction, beta, pi : ndarray
        At exit.
    up : ndarray of bool, shape (n,)
        Left upward (reflected by the layer); ``False``: downward (transmitted).
    alive : ndarray of bool, shape (n,)
        ``False`` for paths dropped at ``max_events``.
    events : ndarray of int, shape (n,)
        Facet events per path, reflections and crossings (1: single scattering).
    reflections : ndarray of int, shape (n,)
        Of them, reflections: the scattering order (a path reflected once that crossed occluders on its way
        out is still first order).
    """
    alpha = float(microfacet.check_alpha(alpha))
    d = np.array(direction, dtype=np.float64)
    beta = np.array(beta, dtype=np.float64)
    pi = np.array(pi, dtype=np.float64)
    n = d.shape[0]
    above = d[:, 2] < 0.0  # the side of the microsurface the ray is on
    u = np.where(above, 1.0, 0.0)  # C1(h) in the layer's frame
    up = np.zeros(n, dtype=bool)
    alive = np.ones(n, dtype=bool)
    events = np.zeros(n, dtype=np.int64)
    reflections = np.zeros(n, dtype=np.int64)
    active = np.arange(n)
    for _ in range(max_events + 1):
        if active.size == 0:
            break
        side = np.where(above[active], 1.0, -1.0)
        w = d[active] * np.stack([np.ones_like(side), np.ones_like(side), side], axis=-1)  # the side's own frame
        ul = np.where(above[active], u[active], 1.0 - u[active])
        lam = smith_lambda(np.abs(w[:, 2]), alpha)
        V = 1.0 - rng.random(active.size)  # in (0, 1]
        away = w[:, 2] > 0.0
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            leave = away & (V <= np.where(away, ul ** lam, 0.0))
            # The next hit's height: higher up going away, lower going toward the microsurface.
            u_next = np.where(away, ul * V ** (-1.0 / np.where(lam > 0.0, lam, 1.0)), ul * V ** (1.0 / (1.0 + lam)))
        u_next = np.clip(np.nan_to_num(u_next, nan=0.0), 0.0, 1.0)
        gone = active[leave]
        up[gone] = (d[gone, 2] > 0.0)
        over = ~leave & (events[active] >= max_events)
        alive[active[over]] = False
        hit = ~leave & ~over
        rows = active[hit]
        active = rows
        if rows.size == 0:
            break
        events[rows] += 1
        w, ul = w[hit], u_next[hit]
        wi = -w  # toward where the ray comes from, in the side's frame
        m = microfacet.sample_ggx_visible_normal(wi, alpha, rng.random(rows.size), rng.random(rows.size))
        cos_d = np.clip(np.sum(wi * m, axis=-1), 0.0, 1.0)
        R = np.clip(reflectance(cos_d, rows), 0.0, 1.0)
        reflect = rng.random(rows.size) < R[:, 0]
        if record is not None:
            record(rows, cos_d, reflect)
        reflections[rows] += reflect
        # Reflection: about m, on the same side; crossing: the same direction, on the other side.
        beta[rows] *= np.where(reflect[:, None], R, 1.0 - R)
        pi[rows] *= np.where(reflect[:, None], R, 1.0 - R)
        w_new = np.where(reflect[:, None], 2.0 * cos_d[:, None] * m - wi, w)
        side = np.where(above[rows], 1.0, -1.0)
        d[rows] = w_new * np.stack([np.ones_like(side), np.ones_like(side), side], axis=-1)
        u[rows] = np.where(above[rows], ul, 1.0 - ul)
        above[rows] = np.where(reflect, above[rows], ~above[rows])
    return d, beta, pi, up, alive, events, reflections
