"""The app's Plots window (explorer/app/panels/plots.py) in a scripted session under Xvfb: the registry's plots chosen in its combo."""

from __future__ import annotations

import numpy as np

from conftest import BRAGG_MATERIAL
from test_app import run_session, x_display  # noqa: F401  (the session's Xvfb fixture)


def test_plots_window_shows_the_chosen_plot(x_display, tmp_path, bragg_material):  # noqa: F811
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


def test_texture_window_shows_the_textured_mirror(x_display, tmp_path, gl_renderer, bragg_material):  # noqa: F811
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
