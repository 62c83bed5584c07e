"""
Tone mapping (:mod:`explorer.views.tonemap`) and its GLSL twin in the app's display pass
(``shaders/lib/tonemap.glsl`` through :class:`explorer.gpu.display.DisplayPass`); what ``render --tonemap``
writes; the gamut overlay judged on the linear values before the curve.
"""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from conftest import run_cli
from explorer.physics.colorimetry import encode_srgb8
from explorer.views.tonemap import TONEMAPS, agx, aces, default_tonemap, tonemap

#: 8-bit levels the GL display may differ from numpy's encode (float32 log2/pow against float64).
DISPLAY_LEVELS = 1


def _pattern(width: int = 64, height: int = 16) -> np.ndarray:
    """Linear RGB from 0 to ~32 across (2^-8 .. 2^5), greys and vivid colours down, one out-of-gamut row with a negative channel."""
    level = 2.0 ** np.linspace(-8.0, 5.0, width)
    hues = np.array([[1, 1, 1], [1, 0.2, 0.05], [0.05, 1, 0.2], [0.1, 0.3, 1], [1.2, -0.15, 0.4], [-0.1, 0.8, 1.1]])
    rows = hues[np.arange(height) % len(hues)]
    return (rows[:, None, :] * level[None, :, None]).astype(np.float32)


def test_curves_are_monotone_bounded_and_keep_grey_neutral():
    """Each curve maps [0, inf) into [0, 1], increasing, black to black, grey to grey; AgX keeps 0.18 near 0.18."""
    x = 2.0 ** np.linspace(-10, 8, 200)
    for curve in ("agx", "aces"):
        y = tonemap(np.repeat(x[:, None], 3, axis=1), curve)
        assert np.all((y >= 0) & (y <= 1)) and np.all(np.diff(y[:, 1]) >= -1e-12), curve
        # Grey stays grey (the published AgX matrices' rows sum to 1 within 5e-5: a tint far below 8 bits).
        assert np.allclose(y[:, 0], y[:, 1], rtol=1e-3) and np.allclose(y[:, 1], y[:, 2], rtol=1e-3), curve
        assert tonemap(np.zeros(3), curve).max() == 0.0
    assert 0.15 < agx(np.full(3, 0.18))[0] < 0.25
    assert agx(np.full(3, 16.0))[0] > 0.99 and aces(np.full(3, 16.0))[0] == 1.0
    assert np.array_equal(tonemap(np.array([2.0, -1.0, 0.5]), "none"), [1.0, 0.0, 0.5])
    with pytest.raises(ValueError):
        tonemap(np.zeros(3), "filmic-ish")


def test_agx_keeps_an_overexposed_vivid_colour_readable():
    """
    An orange-red at 4x white, (1, 0.3, 0.05)·4: clamping shows (1, 1, 0.2), a yellow (its hue lost); AgX keeps
    red the largest channel and orders the channels as the linear colour does.
    """
    colour = 4.0 * np.array([1.0, 0.3, 0.05])
    clamped, mapped = tonemap(colour, "none"), agx(colour)
    assert clamped[0] == clamped[1]  # red and green both clipped: the hue is gone
    assert mapped[0] > mapped[1] > mapped[2] and mapped[0] < 1.0


def test_default_curve_per_view():
    """AgX for the radiance views, none for the colour views and plots (a strip PNG stays its colours)."""
    assert [default_tonemap(v) for v in ("lit", "env", "textured")] == ["agx"] * 3
    assert [default_tonemap(v) for v in ("gradient", "sphere", "slice", "scatter", "albedo")] == ["none"] * 5


class _Image:
    """A float image as the display pass reads a view: its full framebuffer, no preview, every row refined."""

    preview = None
    has_preview = False
    generation = 0

    def __init__(self, renderer, image: np.ndarray):
        height, width = image.shape[:2]
        self.size = (width, height)
        self.refined_rows = height
        self.full = renderer.resources.framebuffer(width, height, origin="test")
        rgba = np.concatenate([image, np.ones((height, width, 1), np.float32)], axis=-1)
        self.full.color_attachments[0].write(np.ascontiguousarray(rgba[::-1], dtype=np.float32).tobytes())


def _shown(texture) -> np.ndarray:
    width, height = texture.size
    return np.frombuffer(texture.read(), np.uint8).reshape(height, width, 4)[::-1, :, :3].astype(int)


@pytest.mark.gl
def test_display_pass_tonemap_twins_numpy(gl_renderer):
    """The display pass's GLSL curves equal numpy's to 1 level in 8 bits, at two exposures, over 13 stops of greys and colours."""
    from explorer.gpu.display import DisplayPass

    image = _pattern()
    view = _Image(gl_renderer, image)
    display = DisplayPass(gl_renderer)
    for curve in TONEMAPS:
        for exposure in (1.0, 0.25):
            shown = _shown(display.draw(f"t{curve}{exposure}", view, exposure=exposure, tonemap=curve))
            expected = encode_srgb8(tonemap(image.astype(np.float64) * exposure, curve)).astype(int)
            assert np.abs(shown - expected).max() <= DISPLAY_LEVELS, (curve, exposure)


@pytest.mark.gl
def test_gamut_overlay_judges_linear_values_before_the_curve(gl_renderer):
    """Under AgX every shown colour is in [0, 1], yet the overlay still hatches exactly the pixels outside sRGB before it."""
    from explorer.gpu.display import DisplayPass
    from explorer.physics.colorimetry import out_of_gamut

    image = _pattern()
    view = _Image(gl_renderer, image)
    display = DisplayPass(gl_renderer)
    plain = _shown(display.draw("plain", view, tonemap="agx"))
    hatched = _shown(display.draw("hatched", view, tonemap="agx", gamut=True))
    outside = out_of_gamut(image)
    assert outside.any() and (~outside).any()
    differs = np.any(hatched != plain, axis=-1)
    # Inside sRGB nothing changes; outside, the hatching (magenta, or the colour halved) changes almost every pixel.
    assert not differs[~outside].any()
    assert differs[outside].mean() > 0.9


@pytest.mark.slow
def test_render_tonemap_png_and_linear_outputs(tmp_path):
    """
    ``render --tonemap``: the lit view's PNG is AgX of the exposed image by default (the .npy written beside it,
    linear and untouched), ``none`` clamps; a colour view (gradient) is not tone mapped by default.
    """
    npy, png, plain = tmp_path / "lit.npy", tmp_path / "lit.png", tmp_path / "plain.png"
    # The light alone (--fill 0): the tone map does not depend on the fill, whose table costs ~9 s of CPU a render.
    common = ("render", "bragg_layer", "--view", "lit", "--size", "32", "--set", "method=4", "--engine", "numpy", "--fill", "0")
    assert run_cli(*common, "--out", str(npy)).returncode == 0
    assert run_cli(*common, "--exposure", "2", "--out", str(png)).returncode == 0
    assert run_cli(*common, "--exposure", "2", "--tonemap", "none", "--out", str(plain)).returncode == 0
    linear = np.load(npy)
    assert np.isfinite(linear).all() and (2.0 * linear).max() > 1.0  # a highlight that AgX and the clamp show apart
    shown = np.asarray(Image.open(png).convert("RGB")).astype(int)
    assert np.abs(shown - encode_srgb8(agx(2.0 * linear.astype(np.float64))).astype(int)).max() <= 1
    assert np.abs(np.asarray(Image.open(plain).convert("RGB")).astype(int) - encode_srgb8(2.0 * linear).astype(int)).max() <= 1
    strip_npy, strip_png = tmp_path / "strip.npy", tmp_path / "strip.png"
    strip = ("render", "bragg_mirror", "--view", "gradient", "--size", "32x4", "--set", "method=4", "--engine", "numpy")
    assert run_cli(*strip, "--out", str(strip_npy)).returncode == 0 and run_cli(*strip, "--out", str(strip_png)).returncode == 0
    assert np.abs(np.asarray(Image.open(strip_png).convert("RGB")).astype(int) - encode_srgb8(np.load(strip_npy)).astype(int)).max() <= 1
    bad = run_cli(*strip, "--tonemap", "filmic", "--out", str(strip_png))
    assert bad.returncode != 0 and "Traceback" not in bad.stderr
