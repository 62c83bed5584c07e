"""
The suite runs on every core (pytest-xdist): what keeps that safe and cheap.

Tests sharing a module's set-up are one unit of the workers' schedule (conftest.shared_set_up_group,
parallel.SharedSetUpScheduling), and the app tests' X servers, one per worker, pick their own display numbers.
"""

from __future__ import annotations

import os

import pytest

from conftest import running_in_ci, shared_set_up_group

SET_UPS: list[int] = []


@pytest.fixture(scope="module")
def shared_set_up():
    SET_UPS.append(1)
    return len(SET_UPS)


def test_a_test_of_a_module_set_up_joins_the_module_group(request, shared_set_up):
    assert shared_set_up == 1
    assert shared_set_up_group(request.node) == request.node.nodeid.split("::")[0]


def test_a_test_of_function_and_conftest_fixtures_goes_anywhere(request, tmp_path, bragg_material):
    assert shared_set_up_group(request.node) is None


def test_the_schedule_keeps_a_group_in_one_unit_and_spreads_the_rest(tmp_path):
    """The units the scheduler balances: a group's tests share one, every other test is its own."""
    import json

    from parallel import read_groups, unit_of

    groups = {"tests/test_a.py::test_1": "tests/test_a.py", "tests/test_a.py::test_2": "tests/test_a.py"}
    (tmp_path / "gw0.json").write_text(json.dumps(groups))
    (tmp_path / "gw1.json").write_text(json.dumps(groups))
    read = read_groups(str(tmp_path))
    assert read == groups and read_groups(None) == {}
    units = [unit_of(f"tests/test_a.py::test_{k}", read) for k in (1, 2, 3)]
    assert units == ["tests/test_a.py", "tests/test_a.py", "tests/test_a.py::test_3"]


def test_virtual_displays_started_together_get_their_own_numbers():
    from explorer.app.xvfb import XvfbUnavailable, virtual_display

    try:
        with virtual_display() as first, virtual_display() as second:
            assert first != second
            for display in (first, second):
                assert os.path.exists(f"/tmp/.X11-unix/X{display.removeprefix(':')}"), display
    except XvfbUnavailable as error:
        if running_in_ci():
            pytest.fail(f"CI=true and no Xvfb: {error}", pytrace=False)
        pytest.skip(str(error))
