"""
Issue 18's rough edges of the app, in one scripted session under Xvfb (see test_app.py): the first screen
shows the Spectrum window, ``method`` is a combo of the methods' names, a stack's sliders beyond ``layers``
are disabled, Help shows About and the keyboard and mouse reference, and a parameter set saved with the
view makes ``render --params`` draw what the app showed. GUI-free parts are tested directly.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from conftest import BRAGG_MATERIAL, REPO_ROOT, one_line_error, run_cli, run_cli_process
from test_app import run_session

from explorer.app.parameter_files import ParameterFileError, inactive_parameters, load_values, load_view, save_values
from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.physics.colorimetry import encode_srgb8

STACK = REPO_ROOT / "shaders" / "bragg_stack.brd"


@pytest.mark.slow
def test_app_first_screen_method_combo_help_and_saved_view(x_display, tmp_path):
    """One session: first screen, method combo, Help, a lit view orbited and saved; render --params redraws it."""
    shot, saved = tmp_path / "lit.png", tmp_path / "view.json"
    actions = [
        {"wait": 4}, {"click": "param:method"}, {"wait": 1}, {"click": f"method:{int(BraggMethod.IMPROVED)}"}, {"wait": 1},
        {"click": "menu_help"}, {"wait": 1}, {"click": "menu_about"}, {"wait": 2},
        {"click": "menu_help"}, {"wait": 1}, {"click": "menu_controls"}, {"wait": 2},
        {"view_size": 128}, {"click": "mode:lit"}, {"wait": 2},
        {"drag": "sphere_image", "from": 0.5, "to": 0.6, "frames": 4}, {"wait": 1},
        {"wheel": "param:n1", "y": -30}, {"wait": 2},  # the exposure below the material's many parameters: scrolled into view
        {"drag": "exposure", "from": 0.5, "to": 0.7, "frames": 3}, {"wait": 2},
        {"focus": "Files"}, {"wait": 2}, {"file_path": str(saved)}, {"click": "save_parameters"}, {"wait": 1},
        {"wait_complete": True}, {"screenshot": str(shot)}, {"quit": True},
    ]
    _, report = run_session(x_display, BRAGG_MATERIAL, actions, tmp_path)
    log = report["script_log"]
    assert "clicked menu_about" in log and "clicked menu_controls" in log and "clicked save_parameters" in log, log
    # The first screen: Spectrum in front of its dock (not Inverse or Design, docked there too).
    assert "Spectrum" in report["first_screen"] and "Inverse" not in report["first_screen"], report["first_screen"]
    # The method combo, by name: its items are the enumeration's.
    assert report["values"]["method"] == int(BraggMethod.IMPROVED)
    assert {f"method:{int(m)}" for m in BraggMethod} <= set(report["items"])
    assert {"about_text", "controls_table"} <= set(report["items"])
    # The saved view: what render --params draws is the app's screenshot.
    document = json.loads(saved.read_text())
    view = document["view"]
    assert view["view"] == "lit" and abs(view["camera"][0]) > 1.0 and view["exposure"] > 1.2, view
    assert view["exposure"] == pytest.approx(report["exposure"]) and view["camera"] == pytest.approx(report["camera"])
    rendered = tmp_path / "rendered.png"
    run = run_cli_process("render", BRAGG_MATERIAL, "--params", saved, "--size", "128", "--out", rendered)
    assert run.returncode == 0, run.stderr
    assert "lit" in run.stdout and "method 4 improved" in run.stdout, run.stdout
    app_png = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    cli_png = np.asarray(Image.open(rendered).convert("RGB")).astype(int)
    assert app_png.shape == cli_png.shape == (128, 128, 3)
    assert np.abs(app_png - cli_png).max() <= 2
    linear = np.load(shot.with_suffix(".npy"))  # without the exposure: the saved exposure made the difference
    assert np.abs(cli_png - encode_srgb8(linear).astype(int)).max() > 10


def test_stack_layers_beyond_the_count_are_inactive():
    material = load_material(STACK)
    for layers in (1, 2, 3):
        values = material.resolve({"layers": layers})
        inactive = inactive_parameters(material, values)
        layered = {p.name for p in material.parameters if p.name.rsplit("_", 1)[-1].isdigit()}
        assert inactive == {name for name in layered if int(name.rsplit("_", 1)[1]) > layers}
    assert inactive_parameters(load_material(BRAGG_MATERIAL), load_material(BRAGG_MATERIAL).resolve({})) == set()


def test_saved_view_round_trip_and_errors(tmp_path, bragg_material):
    """JSON and .bparam keep the view; a bad view is a one-line error naming the file (and .bparam's line)."""
    values = bragg_material.resolve({"Lambda": 612.0})
    view = {"view": "lit", "light": [30.0, 20.0], "camera": [15.0, -10.0], "exposure": 2.5, "environment": None}
    for name in ("v.json", "v.bparam"):
        save_values(tmp_path / name, bragg_material, values, view)
        loaded = load_values(tmp_path / name, bragg_material)
        assert loaded.values == pytest.approx(values)
        assert loaded.view == {k: v for k, v in view.items() if v is not None} == load_view(tmp_path / name)
    assert "::begin view" in (tmp_path / "v.bparam").read_text()
    save_values(tmp_path / "plain.json", bragg_material, values)
    assert load_view(tmp_path / "plain.json") is None
    bad = tmp_path / "bad.bparam"
    bad.write_text((tmp_path / "v.bparam").read_text().replace("camera 15.0 -10.0", "camera 15.0 -95.0"))
    with pytest.raises(ParameterFileError, match=r"bad.bparam:\d+: view 'camera'"):
        load_view(bad)
    document = json.loads((tmp_path / "v.json").read_text())
    document["view"]["view"] = "hologram"
    (tmp_path / "bad.json").write_text(json.dumps(document))
    line = one_line_error(run_cli("render", BRAGG_MATERIAL, "--params", tmp_path / "bad.json", "--out", tmp_path / "x.png"))
    assert "bad.json" in line and "hologram" in line


def test_render_params_view_options_and_command_line_precedence(tmp_path, bragg_material):
    """The saved view sets render's view, light and exposure; the command line's own options win."""
    from explorer.cli.commands import cli, saved_view

    save_values(tmp_path / "v.json", bragg_material, bragg_material.resolve({}),
                {"view": "lit", "light": [30.0, 20.0], "camera": [0.0, 0.0], "exposure": 2.0})
    context = cli.make_context("bragg-explorer", ["render", "x", "--out", "x.png"], resilient_parsing=True)
    command = cli.get_command(context, "render")
    sub = command.make_context("render", ["x", "--out", "x.png"])
    assert saved_view(str(tmp_path / "v.json"), sub) == {"view": "lit", "exposure": "2.0", "light": pytest.approx((30.0, 20.0), abs=1e-4)}
    sub = command.make_context("render", ["x", "--out", "x.png", "--view", "sphere", "--exposure", "1", "--light", "10,0"])
    assert saved_view(str(tmp_path / "v.json"), sub) == {}
