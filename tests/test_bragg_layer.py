"""shaders/bragg_layer.brd: one rough Bragg layer over a diffuse base, GL against numpy.

The numpy twin is :class:`explorer.materials.models.BraggLayerModel`; the tolerance is tests/twins.py's
BRDF_TOLERANCE (2e-3 relative to a pixel's largest |channel| where it exceeds 1e-3, absolute below).
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli
from explorer.physics import bragg, colorimetry, layered
from explorer.materials.brd import load_material
from explorer.materials.models import BraggLayerModel, model_for
from explorer.materials.presets import PRESET_DIR, load_presets
from test_brdf_views import SIZE, SMALL
from twins import assert_twins_equal, render_both

LAYER_MATERIAL = REPO_ROOT / "shaders" / "bragg_layer.brd"

#: (overrides, size): methods 1 and 3 at the test views' size, the spectral reference smaller (~1 s per 32x32).
CASES = {
    "basic": ({"method": "1", "alpha": "0.3", "rho_d": "0.2,0.5,0.8"}, SIZE),
    "tabulated": ({"method": 3, "alpha": 0.15, "Lambda": "300", "rho_d": "0.6"}, SIZE),
    "reference": ({"method": 0, "N": "8", "alpha": "0.3", "rho_d": "0.5,0.3,0.1"}, SMALL),
}


@pytest.fixture(scope="module")
def layer_material():
    return load_material(LAYER_MATERIAL)


def directions(count: int, seed: int) -> np.ndarray:
    """Unit directions above the surface (n = +z), cos theta in [0.05, 1]."""
    rng = np.random.default_rng(seed)
    cos_theta = rng.uniform(0.05, 1.0, count)
    phi = rng.uniform(0.0, 2.0 * np.pi, count)
    sin_theta = np.sqrt(1.0 - cos_theta**2)
    return np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=-1)


@pytest.mark.gl
@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("view", ["lit", "slice"])
def test_gl_equals_numpy_twin(gl_renderer, layer_material, case, view):
    overrides, (width, height) = CASES[case]
    twins = render_both(gl_renderer, layer_material, layer_material.resolve(overrides), view, (width, height))
    assert_twins_equal(twins, f"bragg_layer {case}, {view}")
    assert np.abs(twins.reference).max() > 0.05, "an empty image"


@pytest.mark.parametrize("method", [0, 1, 3, 4])
def test_numpy_brdf_is_reciprocal(layer_material, method):
    values = layer_material.resolve({"method": method, "alpha": 0.2, "rho_d": "0.3,0.6,0.9", "N": 10})
    model = model_for(layer_material, values)
    assert isinstance(model, BraggLayerModel)
    L, V = directions(64, 1), directions(64, 2)
    N = np.array([0.0, 0.0, 1.0])
    forward, backward = model.brdf(L, V, N, None, None), model.brdf(V, L, N, None, None)
    assert np.abs(forward).max() > 0.0
    np.testing.assert_allclose(forward, backward, rtol=1e-12, atol=1e-15)


def test_absorbing_base_reference_is_the_rough_bragg_brdf_in_rgb(layer_material):
    """rho_d = 0, method 0: Eq. 17 with Yeh's reflectance, integrated to RGB (explorer.physics.microfacet)."""
    values = layer_material.resolve({"method": 0, "alpha": 0.25, "rho_d": 0, "N": 12, "Lambda": 420})
    model = model_for(layer_material, values)
    L, V = directions(6, 3), directions(6, 4)
    ours = model.brdf(L, V, np.array([0.0, 0.0, 1.0]), None, None)
    spectral = layered.rough_bragg_brdf(L, V, model.mirror, 0.25)
    expected = colorimetry.spectrum_to_rgb(spectral)
    assert np.abs(expected).max() > 1e-2
    np.testing.assert_allclose(ours, expected, rtol=1e-7, atol=1e-12)


def test_base_term_is_rho_d_over_pi_times_the_transmission_table(layer_material):
    """Below the horizon nothing; the diffuse term alone is rho_d / pi T(theta_i) T(theta_o)."""
    with_base = model_for(layer_material, layer_material.resolve({"method": 1, "alpha": 0.1, "rho_d": "0.2,0.4,0.8"}))
    without = model_for(layer_material, layer_material.resolve({"method": 1, "alpha": 0.1, "rho_d": 0}))
    L, V = directions(16, 5), directions(16, 6)
    N = np.array([0.0, 0.0, 1.0])
    table = with_base.transmission_table
    assert table.shape == (bragg.TABLE_SIZE, 3) and table.dtype == np.float32
    expected = np.array([0.2, 0.4, 0.8]) / np.pi * bragg.tabulated_rgb(table, L[:, 2]) * bragg.tabulated_rgb(table, V[:, 2])
    np.testing.assert_allclose(with_base.brdf(L, V, N, None, None) - without.brdf(L, V, N, None, None), expected, atol=1e-12)
    # At grazing incidence G1 = 0 lets nothing through (Eq. 30); at normal incidence most light crosses.
    assert np.isfinite(table).all() and np.abs(table[0]).max() < 1e-6 and table[-1].sum() > 1.0
    below = V * np.array([1.0, 1.0, -1.0])
    np.testing.assert_array_equal(with_base.brdf(L, below, N, None, None), 0.0)
    assert set(with_base.textures()) == {"bragg_table", "transmission_table", "layer_lobe"}
    assert not with_base.textures()["layer_lobe"].any()  # alpha 0.1: the compensation's weight is 0, no lobe


def test_alpha_out_of_range_is_one_line(tmp_path):
    out = tmp_path / "x.png"
    run = run_cli("render", "shaders/bragg_layer.brd", "--view", "lit", "--set", "alpha=2", "--size", "8", "--out", out)
    line = one_line_error(run)
    assert "alpha" in line and "[0, 1]" in line
    assert not out.exists()


def test_figure8_presets():
    presets = load_presets(PRESET_DIR / "bragg_layer.toml").presets
    alphas = []
    for preset in presets.values():
        values = preset.resolve()
        assert (values["n1"], values["n2"], values["Lambda"], values["delta"], values["N"]) == (1.0, 1.5, 500.0, 0.5, 20.0)
        assert tuple(values["rho_d"]) == (0.0, 0.0, 0.0)
        alphas.append(values["alpha"])
    assert sorted(alphas) == [0.025, 0.1, 0.4]
