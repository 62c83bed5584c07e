"""The microsurface random walk (Heitz et al. 2016, :mod:`explorer.physics.microsurface`) inside the
position-free reference (``microsurface="walk"``), on limits with known answers:

- the white furnace: facets that reflect everything (``R = 1``, a conductor) over a black base reflect all
  the light at every roughness and angle, within the standard error, where single scattering loses up to
  70 %;
- lossless facets over a white base (``R = 0.5`` or ``R = 0``: the light crosses) reflect all the light;
- the walk's first event is Smith's height-correlated single scattering (Heitz 2014, Eq. 99):
  ``E1(i) = E_m[(1 + Lambda(i)) / (1 + Lambda(i) + Lambda(o))]`` over the normals visible from ``i``,
  written out here by quadrature;
- a transparent layer lets every path through, in its own direction (ballistic, Section 4.2.1);
- the same seed gives the same numbers.
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.physics import layered, microfacet, microsurface, position_free
from explorer.physics.layered import LayeredBragg, RoughBraggLayer

SEED = 20261128
SIGMAS = 3.0
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def flat_tables(stack: LayeredBragg, R: float):
    """Layer tables whose facets reflect ``R`` at every angle and wavelength (the furnace's test hook)."""
    tables = []
    for layer in stack.layers:
        built = layered.layer_tables(layer, stack.n1)
        reflectance = np.full_like(built.reflectance, R)
        F = layered.transmission_filter_for(layer.alpha)
        transmissivity = (F.weights.astype(np.float32) @ (np.float32(1.0) - reflectance)).astype(np.float32)
        tables.append(layered.LayerTables(layer, stack.n1, built.theta, reflectance, transmissivity))
    return tables


def luminance_within(result, expected: float):
    Y = result.value @ LUMINANCE
    Y_err = np.sqrt((result.stderr**2) @ LUMINANCE**2)
    assert np.all(np.abs(Y - expected) <= SIGMAS * Y_err + 1e-12), f"Y {Y} vs {expected} (stderr {Y_err})"
    return Y


@pytest.mark.parametrize("alpha", [0.6, 1.0])
def test_white_furnace_conductor(alpha):
    stack = LayeredBragg(layers=(RoughBraggLayer(alpha=alpha),), n1=1.0, rho_d=0.0)
    tables = flat_tables(stack, 1.0)
    walk = position_free.PositionFree(stack, tables, "walk").albedo([0.0, 45.0, 70.0], samples=2048, seed=SEED)
    luminance_within(walk, 1.0)
    assert np.all(np.abs(walk.value - 1.0) <= SIGMAS * walk.stderr + 1e-12)
    single = position_free.PositionFree(stack, tables, "single").albedo([0.0, 45.0, 70.0], samples=2048, seed=SEED)
    assert np.all(single.value @ LUMINANCE < 0.7)  # what the walk must add


@pytest.mark.parametrize("R", [0.5, 0.0])
def test_lossless_layer_over_white_base(R):
    stack = LayeredBragg(layers=(RoughBraggLayer(alpha=0.8),), n1=1.0, rho_d=1.0)
    walk = position_free.PositionFree(stack, flat_tables(stack, R), "walk").albedo([10.0, 60.0], samples=1024, seed=SEED)
    luminance_within(walk, 1.0)


def test_first_event_is_height_correlated_smith():
    alpha, theta = 0.7, np.radians(50.0)
    n = 200_000
    rng = np.random.default_rng(SEED)
    d = np.tile([-np.sin(theta), 0.0, -np.cos(theta)], (n, 1))
    ones = np.ones((n, 1))
    _, _, _, up, alive, events, reflections = microsurface.walk(d, ones, ones.copy(), alpha, lambda c, rows: np.ones((rows.size, 1)), rng)
    assert alive.all() and up.all()
    np.testing.assert_array_equal(reflections, events)  # white facets: every event is a reflection
    once = np.mean(events == 1)
    # Quadrature over the visible normals (midpoints of the sampler's unit square).
    k = 400
    u1, u2 = np.meshgrid((np.arange(k) + 0.5) / k, (np.arange(k) + 0.5) / k)
    i = np.array([np.sin(theta), 0.0, np.cos(theta)])
    m = microfacet.sample_ggx_visible_normal(np.broadcast_to(i, (k * k, 3)), alpha, u1.ravel(), u2.ravel())
    o = 2.0 * (m @ i)[:, None] * m - i

    def lam(c):
        c = np.clip(c, 1e-12, 1.0)
        return 0.5 * (np.sqrt(1.0 + alpha**2 * (1.0 - c * c) / (c * c)) - 1.0)

    E1 = np.mean(np.where(o[:, 2] > 0.0, (1.0 + lam(i[2])) / (1.0 + lam(i[2]) + lam(o[:, 2])), 0.0))
    assert abs(once - E1) <= 4.0 * np.sqrt(E1 * (1.0 - E1) / n) + 2e-4, (once, E1)
    assert 0.1 < 1.0 - once < 0.5  # a fair share scatters more than once at this roughness


def test_transparent_layer_is_ballistic():
    rng = np.random.default_rng(SEED)
    n = 5000
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ones = np.ones((n, 2))
    out, beta, _, up, alive, events, reflections = microsurface.walk(d, ones, ones.copy(), 1.0, lambda c, rows: np.zeros((rows.size, 2)), rng)
    assert not reflections.any()
    # Grazing rays zigzag through many facets: a few reach the walk's limit (near the horizon only).
    assert np.mean(alive) > 0.99 and np.all(np.abs(d[~alive, 2]) < 0.05)
    assert not up[alive & (d[:, 2] < 0)].any() and up[alive & (d[:, 2] > 0)].all()
    np.testing.assert_allclose(out, d)
    np.testing.assert_allclose(beta, 1.0)
    assert events.max() > 1  # some crossed more than one facet


def test_walk_seeded_and_albedo_only():
    stack = LayeredBragg(layers=(RoughBraggLayer(alpha=0.5),), n1=1.3, rho_d=0.2)
    a = position_free.PositionFree(stack, microsurface="walk").albedo([30.0], samples=256, seed=3)
    b = position_free.PositionFree(stack, microsurface="walk").albedo([30.0], samples=256, seed=3)
    np.testing.assert_array_equal(a.value, b.value)
    with pytest.raises(ValueError, match="albedo only"):
        position_free.PositionFree(stack, microsurface="walk").brdf([[0, 0, 1]], [[0, 0, 1]], samples=4)
    with pytest.raises(ValueError, match="microsurface"):
        position_free.PositionFree(stack, microsurface="double")


def test_orders_split_the_walk_and_first_order_is_eq17_for_white_facets():
    """The per-order study's parts add up to what left the layer; with white facets nothing goes down and
    its first order is the height-correlated Smith term, above Eq. 17's separable one (quadrature)."""
    from explorer.dev import multiscatter_orders as orders

    half = np.full((361, 471), 0.5, np.float32)
    parts = orders.walk_orders(half, 0.8, 40.0, (100, 200), 2000, seed=SEED)
    total = parts["up1"] + parts["up2"] + parts["down0"] + parts["down1"]
    assert np.all(total > 0.995) and np.all(total <= 1.0)
    np.testing.assert_allclose(parts["up"], parts["up1"] + parts["up2"])
    white = np.ones((361, 471), np.float32)
    parts = orders.walk_orders(white, 0.8, 40.0, (100,), 4000, seed=SEED)
    assert parts["down0"][0] == 0.0 and parts["down1"][0] == 0.0
    eq17 = orders.eq17_albedo(white, 0.8, 40.0, (100,))[0]
    assert eq17 < parts["up1"][0] < eq17 + 0.1, (eq17, parts["up1"])
