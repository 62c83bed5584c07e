"""
The Sphere window's env mode and models in scripted sessions under Xvfb (see tests/test_app.py): the
environment chosen from its combo, the probe turned, a mesh chosen by "Switch model", the sample counter
that ends "converged", and the screenshot equal to the headless render of the same samples; a mesh in the
lit mode; a MERL file opened.
"""

from __future__ import annotations

import numpy as np

from conftest import REPO_ROOT
from test_app import lit_fill, run_session

from explorer.materials.brd import load_material

GGX = REPO_ROOT / "shaders" / "ggx_schlick.brd"
SIZE = 128


def test_env_choice_rotation_model_and_converged_counter(x_display, tmp_path, gl_renderer):
    from explorer.gpu.env import render_env
    from explorer.views.env import ENVIRONMENTS
    from explorer.views.mesh import torus

    shot = tmp_path / "env.png"
    actions = [
        {"wait": 2}, {"view_size": SIZE}, {"click": "mode:env"}, {"wait": 2},
        {"click": "environment_combo"}, {"click": "environment:studio"}, {"wait": 1},
        {"click": "model_combo"}, {"click": "model:torus"}, {"click": "env_background"}, {"wait": 1},
        {"drag": "env_rotation", "from": 0.33, "to": 0.5, "frames": 6}, {"wait": 2},
        {"wait_converged": True}, {"wait": 3}, {"screenshot": str(shot)}, {"quit": True},
    ]
    _, report = run_session(x_display, GGX, actions, tmp_path)
    log = report["script_log"]
    assert "clicked environment:studio" in log and "clicked model:torus" in log and "dragged env_rotation" in log, log
    env = report["env"]
    assert env["environment"] == "studio" and env["model"] == "torus" and env["background"] is True
    assert 10.0 < env["rotation"] < 180.0, env  # the slider moved right of 0 (its rectangle holds the label too)
    assert env["converged"] and env["samples"] >= env["target"] == 256, env
    assert any(entry.startswith("converged at") for entry in log), log
    info = report["screenshot_info"][str(shot)]
    # Converged: no sample was added after the counter reached its target (the screenshot waited 3 frames).
    assert info["samples"] == env["samples"]
    material = load_material(GGX)
    values = material.resolve(info["values"])
    environment = ENVIRONMENTS["studio"]().rotated(env["rotation"])
    headless = render_env(material, values, SIZE, SIZE, spp=info["samples"], renderer=gl_renderer, environment=environment,
                          mesh=torus(), background=True)
    np.testing.assert_allclose(np.load(shot.with_suffix(".npy")), headless, rtol=1e-3, atol=2e-3)


def test_lit_mesh_and_a_merl_file_in_the_app(x_display, tmp_path, gl_renderer):
    from explorer.gpu.mesh import render_mesh
    from explorer.materials.merl import tabulate, write_merl
    from explorer.views.mesh import teapot

    merl = write_merl(tmp_path / "lambert.binary", tabulate(lambda L, V: np.full(L.shape, 0.2)))
    shot = tmp_path / "lit.png"
    actions = [
        {"wait": 2}, {"view_size": SIZE}, {"click": "mode:lit"}, {"click": "model_combo"}, {"click": "model:teapot"},
        {"wait": 2}, {"wait_complete": True}, {"screenshot": str(shot)}, {"quit": True},
    ]
    _, report = run_session(x_display, merl, actions, tmp_path)
    assert report["error"] == "" and report["env"]["model"] == "teapot", report["script_log"]
    material = load_material(merl)
    headless = render_mesh(gl_renderer, material, {}, "lit", teapot(), SIZE, SIZE, uniforms=lit_fill(material))
    image = np.load(shot.with_suffix(".npy"))
    np.testing.assert_allclose(image, headless, rtol=1e-4, atol=1e-5)
    assert image.max() > 0.1 and (image == 0).all(axis=-1).mean() > 0.3  # a lit teapot on black


def test_a_smooth_mirror_in_the_lit_mode_reflects_the_chosen_environment(x_display, tmp_path, gl_renderer):
    """bragg_mirror in the lit mode: the environment combo and probe turn are offered, and the image is the headless lit mirror."""
    shot = tmp_path / "mirror.png"
    actions = [
        {"wait": 2}, {"view_size": SIZE}, {"click": "mode:lit"}, {"wait": 1},
        {"click": "environment_combo"}, {"click": "environment:studio"}, {"wait": 1},
        {"drag": "env_rotation", "from": 0.33, "to": 0.5, "frames": 4}, {"wait": 2},
        {"wait_complete": True}, {"screenshot": str(shot)}, {"quit": True},
    ]
    _, report = run_session(x_display, REPO_ROOT / "shaders" / "bragg_mirror.brd", actions, tmp_path)
    log = report["script_log"]
    assert report["error"] == "" and "clicked environment:studio" in log and "dragged env_rotation" in log, log
    env = report["env"]
    assert env["environment"] == "studio" and 10.0 < env["rotation"] < 180.0, env
    info = report["screenshot_info"][str(shot)]
    assert info["view"] == "lit"
    from explorer.views.env import ENVIRONMENTS

    material = load_material(REPO_ROOT / "shaders" / "bragg_mirror.brd")
    headless = gl_renderer.render(material, material.resolve(info["values"]), "lit", SIZE, SIZE,
                                  environment=ENVIRONMENTS["studio"]().rotated(env["rotation"]))
    np.testing.assert_allclose(np.load(shot.with_suffix(".npy")), headless, rtol=1e-4, atol=1e-5)
    default = gl_renderer.render(material, material.resolve(info["values"]), "lit", SIZE, SIZE)
    assert np.abs(headless - default).max() > 0.1  # the studio, not the sky
