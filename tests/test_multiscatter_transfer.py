"""The light between a structure's rough layers, in the multiple-scattering compensation
(:mod:`explorer.physics.multiscatter_stack`): it keeps its direction in a few angular bins. Figure 1's two
layers at alpha = 0.2, against the position-free random walk computed here; treated as diffuse
(one bin) the same model is 9 % high at 0 deg and alpha = 0.2 (what the light a layer reflects once keeps
of its lobe) and 2 % low at alpha = 1 (the light scattered among pale facets leaves grazing).
"""

from __future__ import annotations

import numpy as np
from explorer.physics import colorimetry, layered, multiscatter_stack, position_free

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def figure1_pair(alpha: float) -> layered.LayeredBragg:
    """Figure 1's left layer over its right one (n = 1 / 1.5, N = 20) in air, over a black base."""
    return layered.LayeredBragg(layers=(layered.RoughBraggLayer(n2=1.5, Lambda=500.0, delta=0.25, N=20, alpha=alpha),
                                        layered.RoughBraggLayer(n2=1.5, Lambda=244.0, delta=0.413934, N=20, alpha=alpha)),
                                n1=1.0, rho_d=0.0)


def test_two_layers_against_the_walk():
    """At alpha = 0.2 and 0 deg, within the walk's 3 standard errors + 0.005, where the diffuse fluxes are more than 5 %
    off (at alpha = 1 their 2 % is more than a fast walk resolves: ``python3 -m explorer.dev.multiscatter_validation``)."""
    alpha, theta = 0.2, 0.0
    stack = figure1_pair(alpha)
    tables = layered.stack_tables(stack)
    terms = tuple(multiscatter_stack.layer_terms_of(t) for t in tables)
    Y = {}
    for name, edges in (("binned", multiscatter_stack.TRANSFER_EDGES_DEG), ("diffuse", (0.0, 90.0))):
        compensation = multiscatter_stack.stack_compensation(stack, tables, terms, edges_deg=edges)
        Y[name] = float(colorimetry.spectrum_to_rgb(compensation.albedo[0]) @ LUMINANCE)
    walk = position_free.PositionFree(stack, tables, "walk").albedo((theta,), samples=16384, seed=5)
    Y_walk = float(walk.value[0] @ LUMINANCE)
    error = float(np.sqrt(walk.stderr[0] ** 2 @ LUMINANCE**2))
    assert abs(Y["binned"] - Y_walk) <= 3.0 * error + 0.005, (Y, Y_walk, error)
    assert abs(Y["diffuse"] - Y_walk) >= 0.05 * Y_walk and abs(Y["diffuse"] - Y_walk) > 3.0 * error, (Y, Y_walk, error)


def test_scattered_spread_is_a_distribution_and_seeded():
    """Each bin's scattered light is spread over the bins (columns sum to 1, none negative), the same on every call
    (seeded), and not diffuse: with pale facets more of what goes down leaves grazing than diffuse light would."""
    R = np.full((361, colorimetry.WAVELENGTHS.size), 0.1)
    up, down = multiscatter_stack.scattered_spread(R, None, 1.0)
    np.testing.assert_allclose(up.sum(axis=1), 1.0, atol=1e-9)
    np.testing.assert_allclose(down.sum(axis=1), 1.0, atol=1e-9)
    assert up.min() >= 0.0 and down.min() >= 0.0
    multiscatter_stack.spread_ensemble.cache_clear()
    again = multiscatter_stack.scattered_spread(R, None, 1.0)
    np.testing.assert_array_equal(again[1], down)
    _, _, share = multiscatter_stack.transfer_bins()
    # Coming in below 81 deg, the light scattered down leaves within 9 deg of grazing 2-4 times as often as diffuse light.
    assert np.all(down[200, -1, :-1] > 1.8 * share[-1]), (down[200, -1], share[-1])
