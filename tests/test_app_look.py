"""
Scripted Xvfb sessions at 1280x800, the size a laptop gives: the Help window opaque over the Slice plot,
Strips in the methods' order, nothing cut in the Spectrum, Design and Inverse windows, the Spectrum's legend
outside its plot, a smooth mirror's Polar and Slice saying reflectance; Polar's log scale per material, F12
on the Compare window, the Compare and Scatter images fitted to their windows, the Texture tab's words.
"""

from __future__ import annotations

import numpy as np
from PIL import Image

from conftest import BRAGG_MATERIAL, REPO_ROOT
from test_app import run_session

from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.views.tonemap import display_srgb8

LAPTOP = ("--window-size", "1280x800")
LAYER = REPO_ROOT / "shaders" / "bragg_layer.brd"
GGX = REPO_ROOT / "shaders" / "ggx_schlick.brd"


def _inside(rect, window, what: str) -> None:
    """An item's rectangle ends within its window's (not cut by the window's right or bottom edge)."""
    assert rect[2] <= window[2] + 0.5 and rect[0] >= window[0] - 0.5, f"{what}: {rect} beyond its window {window}"


def test_help_strips_and_controls_at_1280x800(x_display, tmp_path):
    covered, shown = tmp_path / "slice.png", tmp_path / "help.png"
    actions = [
        {"wait": 3}, {"wait_complete": True}, {"focus": "Strips"}, {"wait": 3},
        {"focus": "Slice"}, {"wait": 3}, {"wait_complete": True}, {"wait": 30}, {"window_screenshot": str(covered)},
        {"click": "menu_help"}, {"click": "menu_controls"}, {"wait": 4}, {"window_screenshot": str(shown)},
        {"focus": "Polar"}, {"wait": 20}, {"focus": "Spectrum"}, {"wait": 3}, {"focus": "Design"}, {"wait": 3},
        {"focus": "Inverse"}, {"wait": 3}, {"quit": True},
    ]
    _, report = run_session(x_display, BRAGG_MATERIAL, actions, tmp_path, *LAPTOP)
    rects = {name: tuple(rect) for name, rect in report["rects"].items()}
    # Strips: one row per method, in the order of their numbers (as the method combo lists them).
    assert report["strip_rows"] == [f"{int(m)} {m.label}" for m in sorted(BraggMethod, key=int)], report["strip_rows"]
    # Help over the Slice plot: where the plot showed colours, the window shows its own grey, not the plot.
    x0, y0, x1, y1 = (int(round(v)) for v in rects["controls_window"])
    before = np.asarray(Image.open(covered).convert("RGB")).astype(int)[y0 + 24:y1 - 2, x0 + 2:x1 - 2]
    after = np.asarray(Image.open(shown).convert("RGB")).astype(int)[y0 + 24:y1 - 2, x0 + 2:x1 - 2]
    colourful = before.max(-1) - before.min(-1) > 40
    assert colourful.sum() > 200, "the Slice plot is not under the Help window: nothing to hide"
    grey = after.max(-1) - after.min(-1) <= 6
    assert grey[colourful].mean() > 0.99, f"{(~grey[colourful]).mean():.1%} of the plot shows through the Help window"
    # A smooth mirror's Slice and Polar say what they plot: its reflectance, not a BRDF per steradian.
    assert report["slice"]["quantity"].startswith("reflectance R(theta_d)"), report["slice"]
    assert report["polar"]["quantity"] == "reflectance R(theta_d)", report["polar"]
    # Nothing cut at 1280x800: each control ends inside its window; the legend sits outside the Spectrum's plot.
    for name in ("landmarks", "boxes", "envelope"):
        _inside(rects[f"spectrum_show:{name}"], rects["window:Spectrum"], name)
    for name in ("design:air", "design:from_current", "design:load_strip", "design:run"):
        _inside(rects[name], rects["window:Design"], name)
    for name in ("inverse:apply", "inverse:keep_b", "inverse:compare", "inverse:R_colour_1", "inverse:conductor_1"):
        _inside(rects[name], rects["window:Inverse"], name)
    assert report["spectrum_legend"] == "right of the plot, outside its area"


def test_polar_log_compare_f12_and_fitted_images(x_display, tmp_path, gl_renderer):
    actions = [
        {"set": {"method": int(BraggMethod.TABULATED)}},  # exact and fast: the session stays short on a shared machine
        {"wait": 3}, {"focus": "Polar"}, {"wait": 20}, {"click": "polar_log:0"}, {"click": "polar_log:1"}, {"wait": 20},
        {"focus": "Texture"}, {"wait": 3}, {"focus": "Scatter"}, {"wait": 3},
        {"focus": "Compare"}, {"wait": 2}, {"click": "compare_on"}, {"click": "compare_materials"}, {"wait": 3},
        {"wait_complete": True, "timeout": 2400}, {"key": "F12"}, {"quit": True},
    ]
    _, report = run_session(x_display, LAYER, actions, tmp_path, GGX, *LAPTOP, timeout=480)
    log = report["script_log"]
    assert "clicked polar_log:1" in log and "pressed F12" in log, log
    # Polar, each material on its log scale: the GGX lobe is no speck beside the Bragg layer's.
    curves = report["polar"]["curves"]
    assert curves["bragg_layer.brd"]["log"] and curves["ggx_schlick.brd"]["log"], curves
    assert curves["ggx_schlick.brd"]["peak"] >= 0.3 * curves["bragg_layer.brd"]["peak"], curves
    x_min, x_max, y_min, y_max = report["polar"]["limits"]  # every point inside: the peak's reach fits
    peak = max(c["peak"] for c in curves.values())
    assert x_max - x_min >= peak and y_max >= 0.9 * peak, report["polar"]
    # Compare fills its window (it stayed 256 px in a larger one), and so does Scatter.
    size = report["compare_size"]
    assert size[0] == size[1] >= 384, size
    scatter = report["rects"]["scatter_image"]
    assert scatter[2] - scatter[0] >= 384, scatter
    # F12 with Compare in front saves Compare's image: the layer | the GGX, each half its headless render (both have a
    # reflectance: the sphere mode's white furnace, as the Sphere window shows them).
    assert report["active_view"] == "compare" and report["mode"] == "sphere"
    shot = tmp_path / "screenshots" / "bragg_layer_compare_1.npy"
    assert shot.exists(), sorted(p.name for p in (tmp_path / "screenshots").iterdir())
    assert report["screenshot_info"][str(shot.with_suffix(".png").relative_to(tmp_path))]["view"] == "compare"
    values = {entry["path"]: entry["values"] for entry in report["materials"]}
    side = size[0]
    layer, ggx = load_material(LAYER), load_material(GGX)
    a = gl_renderer.render(layer, layer.resolve(values[str(LAYER)]), "sphere", side, side)
    b = gl_renderer.render(ggx, ggx.resolve(values[str(GGX)]), "sphere", side, side)
    linear = np.load(shot)
    np.testing.assert_allclose(linear[:, : side // 2], a[:, : side // 2], rtol=1e-3, atol=2e-3)
    np.testing.assert_allclose(linear[:, side // 2:], b[:, side // 2:], rtol=1e-3, atol=2e-3)
    assert np.abs(a - b).max() > 0.1  # two different images: the halves tell them apart
    png = np.asarray(Image.open(shot.with_suffix(".png")).convert("RGB")).astype(int)  # as shown: colours, no tone map
    assert np.abs(png - display_srgb8(linear, 1.0, "none").astype(int)).max() <= 1
    # The Texture tab says in words why it has nothing to show for this material.
    message = report["texture_view"]["message"]
    assert "looks the same all over its surface" in message and "# texture" not in message, message
