"""
The Design window in a scripted session under Xvfb: its default targets designed on the worker thread while
the window keeps drawing, the result applied to the mirror, and the reachable chromaticities plotted.
"""

from __future__ import annotations

import numpy as np

from conftest import BRAGG_MATERIAL
from test_app import run_session, x_display  # noqa: F401  (the session's virtual display)

from explorer.physics.design import forward_rgb


def test_design_panel_runs_in_the_background_and_applies(x_display, tmp_path):  # noqa: F811
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
