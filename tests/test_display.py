"""
The app's display pass (:class:`explorer.gpu.display.DisplayPass`): linear float views to the 8-bit sRGB
textures ImGui shows, against :func:`explorer.physics.colorimetry.encode_srgb8` of the same images.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT

SIZE = 96


def _texture_pixels(texture) -> np.ndarray:
    """An RGBA8 texture's RGB, rows from the top, as ints."""
    width, height = texture.size
    return np.frombuffer(texture.read(), np.uint8).reshape(height, width, 4)[::-1, :, :3].astype(int)


def _bilinear(image: np.ndarray, width: int, height: int) -> np.ndarray:
    """``image`` (rows from the top) sampled at the texel centres of a ``width`` x ``height`` grid, as GL's LINEAR, clamped."""
    h, w = image.shape[:2]
    x = np.clip((np.arange(width) + 0.5) / width * w - 0.5, 0, w - 1)
    y = np.clip((np.arange(height) + 0.5) / height * h - 0.5, 0, h - 1)
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    x1, y1 = np.minimum(x0 + 1, w - 1), np.minimum(y0 + 1, h - 1)
    fx, fy = (x - x0)[None, :, None], (y - y0)[:, None, None]
    top = image[y0][:, x0] * (1 - fx) + image[y0][:, x1] * fx
    bottom = image[y1][:, x0] * (1 - fx) + image[y1][:, x1] * fx
    return top * (1 - fy) + bottom * fy


@pytest.mark.gl
def test_display_of_a_preview_and_of_the_full_image(gl_renderer):
    """
    While a slider moves a view shows its preview only: the display encodes it at the preview's size and
    stretches it (bilinear, within 2 of 255 of stretching the encoded preview); once the view is complete,
    each pixel is the 8-bit sRGB of the full image (within 1).
    """
    from explorer.gpu.display import DisplayPass
    from explorer.gpu.progressive import CostModel, ProgressiveView
    from explorer.materials.brd import load_material
    from explorer.physics.colorimetry import encode_srgb8

    material = load_material(REPO_ROOT / "shaders" / "bragg_mirror.brd")
    values = material.resolve({"method": 1})
    costs = CostModel()
    view = ProgressiveView(gl_renderer, costs)
    view.request(material, values, "sphere", (SIZE, SIZE), dragging=True)
    costs.update(view._program(), SIZE * SIZE, 100.0)  # pretend the full image costs 100 ms: a preview first
    view.work(10.0)
    assert view.has_preview and not view.complete and view.preview_size[0] < SIZE
    display = DisplayPass(gl_renderer)
    width, height = view.preview_size
    preview = np.frombuffer(view.preview.read(components=4, dtype="f4"), np.float32).reshape(height, width, 4)[::-1, :, :3]
    shown = _texture_pixels(display.draw("main", view))
    expected = _bilinear(encode_srgb8(preview).astype(float), SIZE, SIZE)
    assert np.abs(shown - expected).max() <= 2
    assert shown.std() > 10  # an image, not a flat colour

    view.request(material, values, "sphere", (SIZE, SIZE), dragging=False)
    while not view.complete:
        view.work(1e3)
    shown = _texture_pixels(display.draw("main", view))
    assert np.abs(shown - encode_srgb8(view.read()).astype(int)).max() <= 1
