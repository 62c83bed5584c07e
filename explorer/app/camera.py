"""
The orbit camera of the sphere views: the light turned into view space, and the mouse on the sphere
(left-drag orbits, right-drag places the light, the wheel zooms).
"""

from __future__ import annotations

import numpy as np

from explorer.views.geometry import light_direction
from explorer.app.state import AppState


def light_vector(light, camera) -> tuple[float, float, float]:
    """The light ``(theta, phi)`` in view space: the world light turned by the inverse of the orbit camera (pyrr)."""
    from pyrr import Matrix33

    yaw, pitch = np.radians(camera)
    if yaw == 0.0 and pitch == 0.0:
        return tuple(float(c) for c in light_direction(tuple(light)))  # bit for bit the headless light
    direction = light_direction(tuple(light)).astype(np.float64)
    rotation = Matrix33.from_x_rotation(pitch) @ Matrix33.from_y_rotation(yaw)
    turned = np.asarray(rotation) @ direction
    return tuple(float(c) for c in (turned / np.linalg.norm(turned)).astype(np.float32))


def sphere_mouse(state: AppState, imgui, label: str) -> None:
    """The mouse on the sphere image just drawn (``label``'s rectangle): orbit, light, zoom."""
    io = imgui.get_io()
    hovered = imgui.is_item_hovered()
    if hovered and imgui.is_mouse_clicked(0):
        state.orbit_drag = True
    if not imgui.is_mouse_down(0):
        state.orbit_drag = False
    if state.orbit_drag:
        delta = io.mouse_delta
        state.camera[0] = float((state.camera[0] + 0.4 * delta.x + 180.0) % 360.0 - 180.0)
        state.camera[1] = float(np.clip(state.camera[1] + 0.4 * delta.y, -89.0, 89.0))
    if hovered and imgui.is_mouse_down(1):
        x0, y0, x1, y1 = state.rects[label]
        x = (2.0 * (io.mouse_pos.x - x0) / max(x1 - x0, 1) - 1.0) / state.zoom
        y = (1.0 - 2.0 * (io.mouse_pos.y - y0) / max(y1 - y0, 1)) / state.zoom
        r = min(np.hypot(x, y), 1.0)
        state.light = [float(np.degrees(np.arcsin(r))), float(np.degrees(np.arctan2(y, x)))]
    if hovered and io.mouse_wheel:
        state.zoom = float(np.clip(state.zoom * (1.1 ** io.mouse_wheel), 1.0, 8.0))
