"""The stack's host absorption (tau_h) on both of its BRDF paths: single scattering and multiple scattering."""

from __future__ import annotations

import pytest

from conftest import REPO_ROOT
from explorer.materials.brd import load_material
from explorer.gpu.twin_check import check_material


@pytest.mark.parametrize("multiple_scattering", [0, 1])
def test_absorbing_host_gl_equals_numpy(gl_renderer, multiple_scattering):
    """GL and numpy cross the same gaps: a tau_h that only one of them applied is tens of tolerances off."""
    material = load_material(REPO_ROOT / "shaders" / "bragg_stack.brd")
    values = material.resolve({"tau_h": 1.0, "multiple_scattering": multiple_scattering, "alpha_1": 0.6})
    results = check_material(gl_renderer, material, values, views=("lit", "slice"))
    assert results and all(result.passed for result in results), [str(result) for result in results]


def test_compensated_layer_gl_equals_numpy(gl_renderer):
    """bragg_layer's multiple-scattering lobe (one table fetch) in GL and numpy, over a coloured base."""
    material = load_material(REPO_ROOT / "shaders" / "bragg_layer.brd")
    values = material.resolve({"multiple_scattering": 1, "alpha": 0.8, "rho_d": "0.3,0.5,0.2", "N": 10})
    results = check_material(gl_renderer, material, values, views=("lit", "slice"))
    assert results and all(result.passed for result in results), [str(result) for result in results]
