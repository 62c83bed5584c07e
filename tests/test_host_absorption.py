"""
The host's absorption between the layers of a stack (``tau_h``): Eq. 34 and the smooth limit attenuate each
gap a path crosses by exp(-tau_h / cos theta'); the position-free reference agrees, GL equals numpy, and one
layer over a black base is the attenuated single reflection (a closed form).
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.materials.brd import load_material
from explorer.physics import layered, position_free
from explorer.physics.layered import LayeredBragg, RoughBraggLayer
from explorer.resources import material_path
from twins import assert_twins_equal, render_both

SEED = 35
LAYER = RoughBraggLayer(n2=1.5, Lambda=500.0, delta=0.5, N=10, alpha=0.2)


def _directions(seed: int, count: int = 6) -> np.ndarray:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(count, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.3
    return v / np.linalg.norm(v, axis=1, keepdims=True)


@pytest.mark.parametrize("coating, nh", [(False, 1.0), (True, 1.4)])
def test_one_layer_over_black_is_the_attenuated_single_reflection(coating, nh):
    i, o = _directions(1), _directions(2)
    clear = layered.single_reflection_brdf(LayeredBragg(layers=(LAYER,), n1=nh, coating=coating), i, o)
    tau = 0.3
    absorbing = layered.single_reflection_brdf(LayeredBragg(layers=(LAYER,), n1=nh, coating=coating, tau_h=tau), i, o)
    # Closed form: the gap above the layer crossed down along i' and up along o' (Snell into the host).
    ci, co = (np.sqrt(1.0 - (1.0 - v[:, 2] ** 2) / (nh * nh if coating else 1.0)) for v in (i, o))
    np.testing.assert_allclose(absorbing, clear * np.exp(-tau / ci - tau / co)[:, None], rtol=1e-12, atol=1e-15)
    assert np.abs(absorbing).max() > 0.005


def test_position_free_agrees_with_the_closed_form():
    stack = LayeredBragg(layers=(LAYER,), n1=1.0, rho_d=0.0, tau_h=0.25)
    i, o = _directions(3), _directions(4)
    result = position_free.brdf(stack, i, o, samples=4096, seed=SEED)
    expected = layered.single_reflection_brdf(stack, i, o)
    error = np.abs(result.value - expected)
    assert np.all(error <= 3.0 * result.stderr + 1e-4 * np.abs(expected).max()), error.max()
    # Not the unattenuated value (the test could fail).
    clear = layered.single_reflection_brdf(LayeredBragg(layers=(LAYER,), n1=1.0, rho_d=0.0), i, o)
    assert np.any(np.abs(result.value - clear) > 3.0 * result.stderr + 1e-3)


def test_position_free_albedo_with_a_base_and_two_layers():
    """Multiple bounces too: with tau_h the albedo drops, and the furnace-like bound holds (albedo <= 1)."""
    layers = (RoughBraggLayer(n2=1.5, Lambda=500.0, delta=0.5, N=4, alpha=0.1), RoughBraggLayer(n2=1.6, Lambda=900.0, delta=0.5, N=4, alpha=0.2))
    clear = position_free.directional_albedo(LayeredBragg(layers=layers, n1=1.3, rho_d=0.8), [20.0], samples=1024, seed=SEED)
    absorbing = position_free.directional_albedo(LayeredBragg(layers=layers, n1=1.3, rho_d=0.8, tau_h=0.2), [20.0], samples=1024, seed=SEED)
    assert np.all(absorbing.value + 3 * absorbing.stderr < clear.value) and np.all(absorbing.value <= 1.0)


@pytest.mark.gl
@pytest.mark.parametrize("view", ["gradient", "lit"])
def test_gl_equals_numpy(gl_renderer, view):
    material = load_material(material_path("bragg_stack"))
    values = material.resolve({"layers": "2", "nh": "1.4", "tau_h": "0.4", "rho_d": "0.5,0.4,0.3", "alpha_1": "0.2"})
    twins = render_both(gl_renderer, material, values, view, (32, 32) if view == "lit" else (48, 4))
    assert_twins_equal(twins, f"bragg_stack tau_h, {view}")
    clear = render_both(gl_renderer, material, material.resolve({**values, "tau_h": 0.0}), view, (32, 32) if view == "lit" else (48, 4))
    assert np.abs(clear.reference).max() > np.abs(twins.reference).max() > 0.001


def test_tau_h_must_be_non_negative():
    with pytest.raises(ValueError, match="tau_h"):
        LayeredBragg(layers=(LAYER,), tau_h=-0.1)
