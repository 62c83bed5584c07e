"""
The views, in numpy: the twin of every image the GL renderer makes (``shaders/views/*.glsl``).

Pixel positions are computed in float32, as the fragment shader computes them, so that both sides
evaluate the material at the same angle; the physics then runs in float64.
"""

from __future__ import annotations

import numpy as np

VIEWS = ("gradient", "sphere")
DEFAULT_SIZES = {"gradient": (256, 32), "sphere": (256, 256)}


def view_cos_theta(view: str, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """
    Cosine of the incidence angle at each pixel (rows from the top) and the mask of pixels that
    show the material.

    ``gradient``: column i at theta = 90 deg (i + 0.5) / W, every row the same.
    ``sphere``: orthographic unit sphere, pixel (i, j) at x = 2 (i + 0.5) / W - 1,
    y = 1 - 2 (j + 0.5) / H, cos theta = sqrt(1 - x^2 - y^2) inside the disc.
    """
    f32 = np.float32
    i = np.arange(width, dtype=f32) + f32(0.5)
    j = np.arange(height, dtype=f32) + f32(0.5)
    if view == "gradient":
        theta = f32(np.pi / 2) * (i / f32(width))
        cos_theta = np.broadcast_to(np.cos(theta), (height, width))
        return cos_theta.astype(np.float64), np.ones((height, width), dtype=bool)
    if view == "sphere":
        x = f32(2.0) * i / f32(width) - f32(1.0)
        y = f32(1.0) - f32(2.0) * j / f32(height)
        r2 = x[None, :] ** 2 + y[:, None] ** 2
        inside = r2 < f32(1.0)
        cos_theta = np.sqrt(np.maximum(f32(1.0) - r2, f32(0.0)))
        return cos_theta.astype(np.float64), inside
    raise ValueError(f"unknown view {view!r} (views: {', '.join(VIEWS)})")


def rim_distance(view: str, width: int, height: int) -> np.ndarray:
    """|r^2 - 1| per pixel for the sphere (inf elsewhere): tests skip the float32 rim."""
    if view != "sphere":
        return np.full((height, width), np.inf)
    x = 2.0 * (np.arange(width) + 0.5) / width - 1.0
    y = 1.0 - 2.0 * (np.arange(height) + 0.5) / height
    return np.abs(x[None, :] ** 2 + y[:, None] ** 2 - 1.0)


def render_numpy(model, view: str, width: int, height: int) -> np.ndarray:
    """The view of a material's numpy twin: ``(height, width, 3)`` float32 linear RGB, unclamped."""
    cos_theta, inside = view_cos_theta(view, width, height)
    image = np.zeros((height, width, 3), dtype=np.float32)
    if view == "gradient":
        # Every row is the same.
        image[:] = model.reflectance(cos_theta[0])[None, :, :]
    else:
        image[inside] = model.reflectance(cos_theta[inside])
    return image
