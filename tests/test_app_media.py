"""The app's medium combo: a named dispersion chosen beside the index sliders, an absorbing host refused."""

from __future__ import annotations

import pytest

from conftest import BRAGG_MATERIAL
from test_app import run_session

from explorer.materials.brd import load_material
from explorer.materials.media import MEDIA, medium_labels
from explorer.physics import dispersion


def test_medium_labels_are_the_library_by_number():
    values = load_material(BRAGG_MATERIAL).resolve({"n2": "melanin"})
    labels = medium_labels(values, "medium_n2")
    assert labels[0] == "(the number)" and [labels[i] for i in range(1, len(MEDIA) + 1)] == list(MEDIA)
    assert labels[int(values["medium_n2"])] == "melanin"


def test_app_chooses_a_medium_by_name(x_display, tmp_path):
    actions = [
        {"wait": 4}, {"wheel": "param:n1", "y": -30}, {"wait": 1},
        {"click": "param:medium_n2"}, {"wait": 1}, {"click": f"medium_n2:{MEDIA.index('chitin') + 1}"}, {"wait": 1},
        {"click": "param:medium_nh"}, {"wait": 1}, {"click": f"medium_nh:{MEDIA.index('melanin') + 1}"}, {"wait": 1},
        {"wait_complete": True}, {"quit": True},
    ]
    _, report = run_session(x_display, BRAGG_MATERIAL, actions, tmp_path)
    values = report["values"]
    assert values["medium_n2"] == MEDIA.index("chitin") + 1, report["script_log"]
    assert values["n2"] == pytest.approx(dispersion.LIBRARY["chitin"].real_at(550.0))  # the slider shows its n
    assert values["medium_nh"] == 0  # melanin absorbs: refused, the host unchanged
    assert {f"medium_n2:{i}" for i in range(len(MEDIA) + 1)} <= set(report["items"])


def test_app_chooses_a_stacks_host_medium(x_display, tmp_path):
    """bragg_stack's host has its combo beside the nh slider: chitin is taken (the slider shows its n at 550 nm)."""
    from conftest import REPO_ROOT

    actions = [
        {"wait": 4}, {"click": "param:medium_nh"}, {"wait": 1}, {"click": f"medium_nh:{MEDIA.index('chitin') + 1}"}, {"wait": 1},
        {"wait_complete": True}, {"quit": True},
    ]
    _, report = run_session(x_display, REPO_ROOT / "shaders" / "bragg_stack.brd", actions, tmp_path)
    values = report["values"]
    assert values["medium_nh"] == MEDIA.index("chitin") + 1, report["script_log"]
    assert values["nh"] == pytest.approx(dispersion.LIBRARY["chitin"].real_at(550.0))
    assert {f"medium_nh:{i}" for i in range(len(MEDIA) + 1)} <= set(report["items"])
