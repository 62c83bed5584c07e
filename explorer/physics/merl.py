"""
Measured isotropic BRDFs in the MERL format (Matusik et al. 2003): the half/difference angles of a pair
of directions, the table's bins and its lookup. Twin of ``shaders/lib/merl.glsl`` (same function names).

A MERL table holds ``f(theta_h, theta_d, phi_d)`` at 90 x 90 x 180 bins (Rusinkiewicz's half/difference
coordinates), each channel scaled by :data:`CHANNEL_SCALES` (red 1/1500, green 1.15/1500, blue
1.66/1500). ``theta_h`` is binned non-linearly, ``index = floor(sqrt(theta_h / 90 deg) 90)``, finer near
the specular peak; ``theta_d`` linearly over [0, 90 deg); ``phi_d`` over [0, 180 deg), a negative
``phi_d`` shifted by 180 deg (the reciprocity symmetry ``f(phi_d) = f(phi_d + pi)`` of an isotropic BRDF).
The lookup is the nearest bin (MERL's ``BRDFRead.cpp``), without interpolation.

Angles come from ``atan2``, not ``acos``: ``acos`` near 1 loses the digits that the ``theta_h`` bins need
(the first bin ends at ``theta_h = 0.011 deg``), in float32 especially.

References
----------
Matusik, Pfister, Brand, McMillan (2003). A Data-Driven Reflectance Model. ACM TOG 22(3), and MERL's
``BRDFRead.cpp`` (the file layout, the indexing and the scale factors).
Rusinkiewicz (1998). A New Change of Variables for Efficient BRDF Representation. EGWR.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

#: Bins in theta_h, theta_d and phi_d (the file header holds these three int32).
THETA_H_BINS, THETA_D_BINS, PHI_D_BINS = 90, 90, 180
#: The file's values times these are linear RGB BRDF values (1/sr).
CHANNEL_SCALES = np.array([1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0])


def merl_half_diff(L: ArrayLike, V: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    ``(theta_h, theta_d, phi_d)`` in radians of light ``L`` and view ``V`` (unit vectors ``(..., 3)`` in
    the surface's local frame, normal ``+z``): ``H = normalize(L + V)``, then ``D`` = ``L`` rotated by
    ``-phi_h`` about ``z`` and by ``-theta_h`` about ``y`` (Rusinkiewicz 1998; MERL's
    ``std_coords_to_half_diff_coords``, ``in`` = ``L``). ``phi_d`` in (-pi, pi].
    """
    L = np.asarray(L, dtype=np.float64)
    H = L + np.asarray(V, dtype=np.float64)
    H = H / np.linalg.norm(H, axis=-1, keepdims=True)
    theta_h = np.arctan2(np.hypot(H[..., 0], H[..., 1]), H[..., 2])
    phi_h = np.arctan2(H[..., 1], H[..., 0])
    c, s = np.cos(phi_h), np.sin(phi_h)
    tx = c * L[..., 0] + s * L[..., 1]  # L rotated by -phi_h about z
    ty = -s * L[..., 0] + c * L[..., 1]
    ch, sh = np.cos(theta_h), np.sin(theta_h)
    dx = tx * ch - L[..., 2] * sh  # then by -theta_h about y
    dz = tx * sh + L[..., 2] * ch
    theta_d = np.arctan2(np.hypot(dx, ty), dz)
    phi_d = np.arctan2(ty, dx)
    return theta_h, theta_d, phi_d


def merl_index(theta_h: ArrayLike, theta_d: ArrayLike, phi_d: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    The bins ``(i_h, i_d, i_phi)`` of half/difference angles (radians), as MERL's ``BRDFRead.cpp``:
    ``i_h = floor(sqrt(theta_h / (pi / 2) 90 x 90))`` (0 for ``theta_h <= 0``), ``i_d = floor(theta_d / (pi / 2) 90)``,
    ``i_phi = floor(phi_d' / pi 180)`` with ``phi_d' = phi_d + pi`` where ``phi_d < 0``; each clamped to its range.
    """
    theta_h = np.asarray(theta_h, dtype=np.float64)
    degrees_h = np.maximum(theta_h, 0.0) / (np.pi / 2.0) * THETA_H_BINS
    i_h = np.clip(np.floor(np.sqrt(degrees_h * THETA_H_BINS)), 0, THETA_H_BINS - 1).astype(np.int64)
    i_d = np.clip(np.floor(np.asarray(theta_d, np.float64) / (np.pi / 2.0) * THETA_D_BINS), 0, THETA_D_BINS - 1).astype(np.int64)
    phi = np.asarray(phi_d, dtype=np.float64)
    phi = np.where(phi < 0.0, phi + np.pi, phi)
    i_phi = np.clip(np.floor(phi / np.pi * PHI_D_BINS), 0, PHI_D_BINS - 1).astype(np.int64)
    return i_h, i_d, i_phi


def merl_bin_centres() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    The angles (radians) at the middle of each bin, the inverse of :func:`merl_index`: ``theta_h`` of bin
    ``i`` at ``((i + 1/2)^2 / 90) / 90 x pi / 2`` (the middle in the square-root variable), ``theta_d`` and
    ``phi_d`` at ``(i + 1/2)`` bin widths.
    """
    theta_h = ((np.arange(THETA_H_BINS) + 0.5) ** 2 / THETA_H_BINS) / THETA_H_BINS * (np.pi / 2.0)
    theta_d = (np.arange(THETA_D_BINS) + 0.5) / THETA_D_BINS * (np.pi / 2.0)
    phi_d = (np.arange(PHI_D_BINS) + 0.5) / PHI_D_BINS * np.pi
    return theta_h, theta_d, phi_d


def merl_directions(theta_h: ArrayLike, theta_d: ArrayLike, phi_d: ArrayLike, phi_h: ArrayLike = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """
    ``(L, V)``, unit ``(..., 3)``, of half/difference angles (the inverse of :func:`merl_half_diff`):
    ``D`` at ``(theta_d, phi_d)`` rotated by ``theta_h`` about ``y`` and ``phi_h`` about ``z`` is ``L``;
    ``V`` is ``L`` reflected about ``H``.
    """
    theta_h, theta_d, phi_d, phi_h = np.broadcast_arrays(*(np.asarray(a, np.float64) for a in (theta_h, theta_d, phi_d, phi_h)))
    d = np.stack([np.sin(theta_d) * np.cos(phi_d), np.sin(theta_d) * np.sin(phi_d), np.cos(theta_d)], axis=-1)
    ch, sh = np.cos(theta_h), np.sin(theta_h)
    x = d[..., 0] * ch + d[..., 2] * sh
    z = -d[..., 0] * sh + d[..., 2] * ch
    c, s = np.cos(phi_h), np.sin(phi_h)
    L = np.stack([c * x - s * d[..., 1], s * x + c * d[..., 1], z], axis=-1)
    H = np.stack([sh * c, sh * s, ch], axis=-1)
    V = 2.0 * np.sum(L * H, axis=-1, keepdims=True) * H - L
    return L, V


def merl_lookup(table: np.ndarray, L: ArrayLike, V: ArrayLike) -> np.ndarray:
    """
    The BRDF of a MERL ``table`` (``(90, 90, 180, 3)`` linear RGB, the scales applied) for local ``L``,
    ``V`` (``(..., 3)``): the nearest bin's value, ``(..., 3)`` float64.
    """
    i_h, i_d, i_phi = merl_index(*merl_half_diff(L, V))
    return np.asarray(table, dtype=np.float64)[i_h, i_d, i_phi]
