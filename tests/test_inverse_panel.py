"""
The Inverse window's logic without a window: every position of its class sliders is a member of the class
(a stack whose lobes at normal incidence are the requested ones), and the plot's drag point snaps to the
nearest member.
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.app.panels.inverse import LobeEdit, class_choice, class_image, nearest_point, solve
from explorer.physics.inverse import forward_lobes

CASES = {
    "2-layer coloured (Fig. 12)": [LobeEdit([0.1, 0.2, 0.1], 0.03, 2)],
    "1-layer conductor (Fig. 4b)": [LobeEdit([0.9, 0.7, 0.5], 0.03, 1, "conductor")],
    "2-layer conductor (Fig. 16)": [LobeEdit([0.5, 0.5, 0.5], 0.03, 2, "conductor")],
    "coloured lobe under a clear coat": [LobeEdit([0.04] * 3, 0.0, 1), LobeEdit([0.12, 0.08, 0.04], 0.05, 1)],
}


@pytest.mark.parametrize("name", CASES)
def test_every_slider_position_is_a_member(name):
    edits = CASES[name]
    stacks = []
    for t, u in [(0.0, 0.0), (0.3, 0.7), (1.0, 1.0)]:
        for e in edits:
            e.t, e.u = t, u
        solution = solve(edits)
        assert solution.error == "" and solution.stack is not None, solution.error
        energies, _ = forward_lobes(solution.stack, [e.layers for e in edits])
        np.testing.assert_allclose(energies, [e.energy for e in edits], atol=1e-6)
        stacks.append(solution.stack)
    # The ends of the walk are different stacks (the class is not a single point).
    first, last = stacks[0], stacks[-1]
    assert any(not np.allclose(first.eta[i], last.eta[i]) or not np.allclose(first.kappa[i], last.kappa[i])
               for i in range(1, first.count + 1))


def test_drag_point_snaps_to_the_nearest_member():
    solution = solve([LobeEdit([0.1, 0.2, 0.1], 0.03, 2)])
    cls = solution.classes[0]
    for t, u in [(0.0, 0.0), (0.5, 0.5), (1.0, 0.25)]:
        choice = class_choice(cls, t, u)
        assert class_choice(cls, *nearest_point(cls, choice["eta_top"], choice["eta"])) == choice
    image = class_image(cls)
    assert image.dtype == np.uint8 and image.shape[2] == 4 and image[..., 3].max() > 0


def test_unachievable_lobe_is_one_line():
    solution = solve([LobeEdit([0.7] * 3, 0.03, 1)])
    assert solution.stack is None and solution.error.startswith("lobe 1: energy 0.7 is not achievable")
    assert "\n" not in solution.error
