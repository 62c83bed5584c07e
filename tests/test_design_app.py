"""
The Design window in a scripted session under Xvfb: its default targets designed on the worker thread while
the window keeps drawing, the result applied to the mirror, and the reachable chromaticities plotted.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import BRAGG_MATERIAL
from test_app import run_session

from explorer.design import forward_rgb


@pytest.mark.slow
def test_design_panel_runs_in_the_background_and_applies(x_display, tmp_path):
    window = tmp_path / "design.png"
    actions = [{"wait": 2}, {"view_size": 128}, {"focus": "Design"}, {"wait": 3}, {"click": "design:run"}, {"mark": "designing"},
               {"wait_for": "design", "timeout": 4000}, {"mark": None}, {"wait": 5}, {"window_screenshot": str(window)},
               {"quit": True}]
    _, report = run_session(x_display, BRAGG_MATERIAL, actions, tmp_path)
    log = report["script_log"]
    assert "clicked design:run" in log and not any("timed out" in line for line in log), log
    design = report["design"]
    assert design is not None and not design["running"] and "set" in design, design
    # The material's structure before the design joined its first pass (the default).
    assert len(design["guesses"]) == 1 and set(design["guesses"][0]) == set(design["set"]), design["guesses"]
    # The designed structure is the mirror's values now.
    for name, value in design["set"].items():
        assert report["values"][name] == value
    # Its reported colours are the converged ones of that structure.
    theta = [t["theta_deg"] for t in design["targets"]]
    np.testing.assert_allclose(forward_rgb("bragg_mirror", design["set"], theta),
                               [t["achieved_rgb"] for t in design["targets"]], atol=1e-9)
    # The window kept drawing while the worker searched: many frames, none frozen for the whole design.
    frames = [f["ms"] for f in report["frames"] if f["mark"] == "designing"]
    assert len(frames) >= 10, len(frames)
    assert max(frames) < 0.5 * design["wall_seconds"] * 1e3, (max(frames), design["wall_seconds"])
    assert window.is_file()


@pytest.mark.slow
def test_a_strip_typed_into_the_panel_is_designed_with_its_linear_colours(x_display, tmp_path):
    # A render-style .npy strip of a vivid mirror (a negative red: outside sRGB): its colours are the
    # targets as they are, not the pickers' sRGB clipping of them.
    from explorer.design import targets_from_strip

    truth = {"n1": 1.38, "n2": 1.6, "Lambda": 175.0, "delta": 0.5, "N": 15, "nh": 1.0}
    theta = 90.0 * (np.arange(32) + 0.5) / 32
    strip = np.repeat(forward_rgb("bragg_mirror", truth, theta)[None], 3, axis=0)
    np.save(tmp_path / "strip.npy", strip)
    expected = targets_from_strip(strip, 0.0, 90.0)
    assert min(min(t.rgb) for t in expected) < -0.05
    actions = [{"wait": 2}, {"focus": "Design"}, {"wait": 2}, {"type": "design:strip_path", "text": str(tmp_path / "strip.npy")},
               {"wait": 2}, {"click": "design:run"}, {"wait_for": "design", "timeout": 4000},
               {"click": "design:run"}, {"wait_for": "design", "timeout": 4000}, {"quit": True}]
    _, report = run_session(x_display, BRAGG_MATERIAL, actions, tmp_path)
    design = report["design"]
    assert design is not None and "set" in design, (design, report["script_log"])
    # Pressed again, it searched from fresh samples (the next seed), from the first result (applied).
    assert design["seed"] == 1 and len(design["guesses"]) == 1, design
    assert [t["theta_deg"] for t in design["targets"]] == [t.theta_deg for t in expected]
    np.testing.assert_allclose([t["target_rgb"] for t in design["targets"]], [t.rgb for t in expected], atol=1e-12)


@pytest.mark.slow
def test_the_window_designs_with_a_medium_as_the_cli_does(x_display, tmp_path):
    # The mirror's n2 names chitin (its combo): the window designs with chitin's dispersion held, as
    # design --fix n2=chitin does, and reports it by name.
    import json

    from conftest import run_cli
    from explorer.design.media import mirror_with_media
    from explorer.physics.dispersion import LIBRARY
    from explorer.physics.natural import natural_rgb

    actions = [{"wait": 2}, {"set": {"n2": "chitin", "n1": 1.0}}, {"focus": "Design"}, {"wait": 2}, {"click": "design:run"},
               {"wait_for": "design", "timeout": 4000}, {"quit": True}]
    _, report = run_session(x_display, BRAGG_MATERIAL, actions, tmp_path)
    design = report["design"]
    assert design is not None and design["set"]["n2"] == "chitin", (design, report["script_log"])
    assert report["values"]["medium_n2"] > 0, report["values"]  # applied: the medium kept, not its number
    theta = [t["theta_deg"] for t in design["targets"]]
    found = {k: v for k, v in design["set"].items() if k != "n2"}
    np.testing.assert_allclose(natural_rgb(np.cos(np.radians(theta)), mirror_with_media(found, {"n2": LIBRARY["chitin"]})),
                               [t["achieved_rgb"] for t in design["targets"]], atol=1e-9)
    # The CLI's design of the same targets from the same start and seed.
    targets = [f"--target={t['theta_deg']:g}:" + ",".join(repr(c) for c in t["target_rgb"]) for t in design["targets"]]
    guess = ",".join(f"{k}={v}" for k, v in design["guesses"][0].items() if k != "n2")
    run = run_cli("design", "bragg_mirror", *targets, "--fix", "n2=chitin", "--guess", guess, "--seed", str(design["seed"]),
                  "--tries", "1", "--fix", "k1=0", "--fix", "k2=0", "--fix", "sigma=0", "--json")
    assert run.returncode == 0, run.stderr
    cli = json.loads(run.stdout)
    assert cli["set"]["n2"] == "chitin" and set(cli["set"]) == set(design["set"]), (cli["set"], design["set"])
    assert abs(cli["median_delta_e2000"] - design["median_delta_e2000"]) < 0.3, (cli, design)
