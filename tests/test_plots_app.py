"""The app's Plots window (explorer/app/panels/plots.py) in a scripted session under Xvfb: the registry's plots chosen in its combo."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import BRAGG_MATERIAL
from test_app import run_session


def test_plots_window_shows_the_chosen_plot(x_display, tmp_path, bragg_material):
    """theta_h chosen in the combo: the window's curve is the numpy twin's at the app's values (light irrelevant)."""
    from explorer.materials.models import model_for
    from explorer.views.geometry import light_direction
    from explorer.views.plots import PlotSettings, cos_light, plot_numpy, plotted

    actions = [{"wait": 2}, {"wait_complete": True}, {"focus": "Plots"}, {"wait": 3}, {"click": "plot_combo"}, {"wait": 2},
               {"click": "plot:theta_h"}, {"wait": 3}, {"wait_for": "plots"}, {"quit": True}]
    _, report = run_session(x_display, BRAGG_MATERIAL, actions, tmp_path)
    assert "clicked plot:theta_h" in report["script_log"], report["script_log"]
    plots = report["plots"]
    assert plots is not None and plots["view"] == "theta_h", plots and plots["view"]
    settings = PlotSettings(**plots["settings"])
    width, height = plots["size"]
    model = model_for(bragg_material, bragg_material.resolve(report["values"]))
    direction = light_direction(tuple(plots["light"]))
    expected = plotted(plot_numpy(model, "theta_h", width, height, direction, settings),
                       settings, cos_light("theta_h", width, height, direction, settings))
    shown = np.asarray(plots["values"])
    assert shown.shape == expected.shape
    np.testing.assert_allclose(shown, expected, rtol=2e-3, atol=1e-5)


def test_texture_window_shows_the_textured_mirror(x_display, tmp_path, gl_renderer, bragg_material):
    """
    The Texture window on the default mirror, mapping delta chosen: its image is the headless textured render
    (at the improved method: the tabulated one's textured tables take seconds to build).
    """
    from explorer.views.surface_texture import BraggTexture

    actions = [{"set": {"method": 4}}, {"wait": 2}, {"wait_complete": True}, {"focus": "Texture"}, {"wait": 3}, {"click": "mapping_combo"}, {"wait": 2},
               {"click": "mapping:delta"}, {"wait": 3}, {"wait_for": "texture_view"}, {"quit": True}]
    _, report = run_session(x_display, BRAGG_MATERIAL, actions, tmp_path)
    assert "clicked mapping:delta" in report["script_log"], report["script_log"]
    shown = report["texture_view"]
    assert shown is not None and shown["mapping"] == "delta" and shown["values"]["method"] == 4, shown
    values = bragg_material.resolve(shown["values"])
    width, height = shown["size"]
    texture = BraggTexture.from_file(shown["path"], "delta")
    theta = np.degrees(np.arccos(np.clip(shown["light"][2], -1.0, 1.0)))
    phi = np.degrees(np.arctan2(shown["light"][1], shown["light"][0]))
    image = gl_renderer.render(bragg_material, values, "textured", width, height, light=(theta, phi),
                               **texture.gl_arguments(bragg_material, values, width, height))
    np.testing.assert_allclose(shown["mean_rgb"], image.reshape(-1, 3).mean(axis=0), rtol=1e-3, atol=1e-5)


@pytest.mark.slow
def test_texture_window_shows_drafts_while_dragging(x_display, tmp_path, gl_renderer, bragg_material):
    """
    The tabulated mirror's textured view while Lambda is dragged: frames show draft (cos theta, T) tables and the
    view follows the slider; on release it shows the exact table's image (the headless render's), not a draft.
    """
    from explorer.views.surface_texture import BraggTexture

    actions = [{"view_size": 128}, {"set": {"method": 3}}, {"wait": 2}, {"focus": "Texture"}, {"wait": 3},
               {"wait_for": "texture_view"}, {"mark": "drag"}, {"drag": "param:Lambda", "from": 0.3, "to": 0.6, "frames": 40,
                                                                 "hold": 600, "hold_until_draft": "textured"},
               {"mark": None}, {"wait": 3}, {"wait_for": "texture_view"}, {"quit": True}]
    for attempt in range(2):  # a drag whose press landed before the panel settled moves nothing: once more
        _, report = run_session(x_display, BRAGG_MATERIAL, actions, tmp_path)
        drag = [f["main"]["views"]["textured"] for f in report["frames"] if f["mark"] == "drag" and f["dragging"]]
        if len({v["generation"] for v in drag}) >= 2:
            break
    assert not [line for line in report["script_log"] if "timed out" in line], report["script_log"]
    assert len(drag) >= 20 and any(v["draft"] for v in drag), drag[-3:]
    assert len({v["generation"] for v in drag}) >= 2, drag[-3:]  # the view followed the slider
    assert not report["frames"][-1]["main"]["views"]["textured"]["draft"]
    shown = report["texture_view"]
    assert shown["draft"] is False and shown["values"]["method"] == 3 and shown["size"] == [128, 128], shown
    assert shown["values"]["Lambda"] == report["values"]["Lambda"]  # the released value, not one from the drag
    values = bragg_material.resolve(shown["values"])
    texture = BraggTexture.from_file(shown["path"], shown["mapping"])
    theta = np.degrees(np.arccos(np.clip(shown["light"][2], -1.0, 1.0)))
    phi = np.degrees(np.arctan2(shown["light"][1], shown["light"][0]))
    image = gl_renderer.render(bragg_material, values, "textured", 128, 128, light=(theta, phi),
                               **texture.gl_arguments(bragg_material, values, 128, 128))
    np.testing.assert_allclose(shown["mean_rgb"], image.reshape(-1, 3).mean(axis=0), rtol=1e-3, atol=1e-5)


def test_textured_draft_table_is_near_the_exact_one(bragg_material):
    """The draft table (few T rows, the draft rule) has the exact table's columns and stays near it on average."""
    from explorer.materials.models import model_for
    from explorer.physics import bragg
    from explorer.views.surface_texture import TEXTURED_DRAFT_ROWS, textured_draft_table

    mirror = model_for(bragg_material, bragg_material.resolve({"method": 3, "Lambda": 431.0})).mirror
    exact = bragg.textured_rgb_table(mirror, "lambda")
    draft = textured_draft_table(mirror, "lambda")
    assert draft.shape == (TEXTURED_DRAFT_ROWS, exact.shape[1], 3)
    C, T = np.meshgrid(np.linspace(0.0, 1.0, 97), np.linspace(0.0, 1.0, 65))
    error = np.abs(bragg.textured_tabulated_rgb(draft, C, T) - bragg.textured_tabulated_rgb(exact, C, T))
    assert error.mean() < 0.05 and np.percentile(error, 50) < 0.05, (error.mean(), error.max())
    # No T dependence: two equal rows, as in the exact table.
    flat = textured_draft_table(mirror, "none")
    assert flat.shape[0] == 2 and np.array_equal(flat[0], flat[1])
