"""The position-free Monte Carlo reference (Section 4.2, :mod:`explorer.physics.position_free`) on limits
with known answers, each within 3 standard errors (plus the float32 tables' rounding where stated):

- one layer of tiny roughness in air over a black base is Yeh's mirror (the layer's reflectance table);
- two such layers are the incoherent pair ``R1 + T1^2 R2 / (1 - R1 R2)`` per wavelength (every bounce);
- an invisible layer (``n2 = n1 = nh``) under a coating is the coating's Fresnel reflectance, and over a
  Lambertian base the closed form with internal reflections,
  ``F + (1 - F) rho (1 - Fbar) / (1 - rho Fbar)`` with ``Fbar`` the interface's hemispherical reflectance
  from inside (both Fresnel and ``Fbar`` written out here, independently of the package);
- its BRDF is ``(1 - F(i)) (1 - F(o)) rho / (pi n^2 (1 - rho Fbar))``;
- one rough layer in air over a black base reflects once: the next-event BRDF is Eq. 34;
- reciprocity ``f(i, o) = f(o, i)``; the same seed gives the same numbers.
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.physics import colorimetry, layered, position_free
from explorer.physics.layered import LayeredBragg, RoughBraggLayer

SEED = 20261125
#: Standard errors of agreement.
SIGMAS = 3.0
#: The float32 tables and their linear interpolation, where a result is compared with the tables' values.
TABLE_ATOL = 1e-5

SMOOTH_A = RoughBraggLayer(n2=1.5, Lambda=500.0, delta=0.25, N=20, alpha=0.0)  # Figure 1's left mirror
SMOOTH_B = RoughBraggLayer(n2=1.5, Lambda=988.0, delta=0.5, N=10, alpha=0.0)  # Figure 7's B


def _within(estimate: position_free.PositionFreeResult, expected, atol: float = 0.0):
    error = np.abs(estimate.value - np.asarray(expected))
    bound = SIGMAS * estimate.stderr + atol
    assert np.all(error <= bound), f"error {error.max():.3g} beyond {SIGMAS} standard errors ({bound[error > bound]})"


def fresnel_unpolarised(cos_i, n_i, n_t):
    """Fresnel's unpolarised reflectance from index n_i into n_t, written out (1 past the critical angle)."""
    cos_i = np.asarray(cos_i, dtype=np.float64)
    sin_t2 = (n_i / n_t) ** 2 * (1.0 - cos_i**2)
    cos_t = np.sqrt(np.maximum(1.0 - sin_t2, 0.0))
    rs = (n_i * cos_i - n_t * cos_t) / (n_i * cos_i + n_t * cos_t)
    rp = (n_t * cos_i - n_i * cos_t) / (n_t * cos_i + n_i * cos_t)
    return np.where(sin_t2 >= 1.0, 1.0, 0.5 * (rs**2 + rp**2))


def internal_diffuse_reflectance(n: float, steps: int = 200000) -> float:
    """``Fbar = int_0^{pi/2} F(theta) 2 cos sin d theta`` from inside a medium of index ``n`` (midpoint rule in cos^2)."""
    mu2 = (np.arange(steps) + 0.5) / steps  # cos^2 theta, uniform: 2 cos sin d theta = d(cos^2)
    return float(np.mean(fresnel_unpolarised(np.sqrt(mu2), n, 1.0)))


def invisible(nh: float) -> RoughBraggLayer:
    """A layer of the host's own index: no reflection, and (alpha -> 0) no loss."""
    return RoughBraggLayer(n2=nh, Lambda=500.0, delta=0.5, N=10, alpha=0.0, n1=nh)


def test_smooth_layer_is_yeh_mirror():
    stack = LayeredBragg(layers=(SMOOTH_A,), n1=1.0, rho_d=0.0)
    theta = np.array([0.0, 20.0, 45.0, 70.0, 85.0])
    result = position_free.directional_albedo(stack, theta, samples=2048, seed=SEED)
    table = layered.stack_tables(stack)[0].reflectance
    expected = colorimetry.spectrum_to_rgb(layered.lookup(table.astype(np.float64), np.radians(theta)))
    _within(result, expected, TABLE_ATOL)
    assert np.ptp(expected[:, 2]) > 0.3  # the band moves: a coloured, angle-dependent answer


def test_two_smooth_layers_bounce_incoherently():
    stack = LayeredBragg(layers=(SMOOTH_A, SMOOTH_B), n1=1.0, rho_d=0.0)
    theta = np.array([0.0, 30.0, 60.0])
    result = position_free.directional_albedo(stack, theta, samples=4096, seed=SEED)
    R1, R2 = (layered.lookup(t.reflectance.astype(np.float64), np.radians(theta)) for t in layered.stack_tables(stack))
    pair = R1 + (1.0 - R1) ** 2 * R2 / (1.0 - R1 * R2)  # every bounce between the mirrors, per wavelength
    _within(result, colorimetry.spectrum_to_rgb(pair), 1e-4)
    # The single-reflection specular colour lacks the bounces: the walk must see them.
    single = layered.stack_specular_rgb(stack, np.cos(np.radians(theta)))
    assert np.abs(colorimetry.spectrum_to_rgb(pair) - single).max() > 10 * result.stderr.max()


@pytest.mark.parametrize("nh", [1.3, 1.8])
def test_coating_alone_is_fresnel(nh):
    stack = LayeredBragg(layers=(invisible(nh),), n1=nh, rho_d=0.0)
    theta = np.array([0.0, 40.0, 75.0, 89.0])
    result = position_free.directional_albedo(stack, theta, samples=256, seed=SEED)
    expected = fresnel_unpolarised(np.cos(np.radians(theta)), 1.0, nh)
    np.testing.assert_allclose(result.value, np.repeat(expected[:, None], 3, axis=1), atol=1e-12)


@pytest.mark.parametrize("nh, rho", [(1.5, (0.8, 0.5, 0.2)), (2.0, (0.9, 0.9, 0.9))])
def test_lambertian_under_coating_closed_form(nh, rho):
    stack = LayeredBragg(layers=(invisible(nh),), n1=nh, rho_d=rho)
    theta = np.array([0.0, 45.0, 80.0])
    result = position_free.directional_albedo(stack, theta, samples=8192, seed=SEED)
    F = fresnel_unpolarised(np.cos(np.radians(theta)), 1.0, nh)[:, None]
    Fbar = internal_diffuse_reflectance(nh)
    rho = np.asarray(rho)[None, :]
    expected = F + (1.0 - F) * rho * (1.0 - Fbar) / (1.0 - rho * Fbar)
    _within(result, expected, TABLE_ATOL)
    # Without the internal reflections (one pass through the coating) it would be clearly less.
    assert np.all(expected - (F + (1.0 - F) * rho * (1.0 - Fbar)) > 5 * result.stderr)


def test_lambertian_under_coating_brdf():
    nh, rho = 1.6, np.array([0.7, 0.4, 0.9])
    stack = LayeredBragg(layers=(invisible(nh),), n1=nh, rho_d=rho)
    t_i, t_o = np.radians([10.0, 50.0, 70.0]), np.radians([60.0, 20.0, 75.0])
    i = np.stack([np.sin(t_i), 0 * t_i, np.cos(t_i)], -1)
    o = np.stack([-np.sin(t_o) * 0.6, np.sin(t_o) * 0.8, np.cos(t_o)], -1)
    result = position_free.brdf(stack, i, o, samples=4096, seed=SEED)
    Fi, Fo = (fresnel_unpolarised(np.cos(t), 1.0, nh)[:, None] for t in (t_i, t_o))
    expected = (1.0 - Fi) * (1.0 - Fo) * rho / (np.pi * nh**2 * (1.0 - rho * internal_diffuse_reflectance(nh)))
    _within(result, expected, TABLE_ATOL)


def test_one_rough_layer_in_air_reflects_once():
    layer = RoughBraggLayer(n2=1.5, Lambda=500.0, delta=0.5, N=10, alpha=0.2)
    stack = LayeredBragg(layers=(layer,), n1=1.0, rho_d=0.0)
    rng = np.random.default_rng(SEED)
    i = rng.normal(size=(6, 3))
    o = rng.normal(size=(6, 3))
    i[:, 2], o[:, 2] = np.abs(i[:, 2]) + 0.3, np.abs(o[:, 2]) + 0.3
    i /= np.linalg.norm(i, axis=1, keepdims=True)
    o /= np.linalg.norm(o, axis=1, keepdims=True)
    result = position_free.brdf(stack, i, o, samples=4096, seed=SEED)
    expected = layered.single_reflection_brdf(stack, i, o)
    assert np.abs(expected).max() > 0.05
    _within(result, expected, 1e-4 * np.abs(expected).max())


def test_reciprocity():
    layers = (RoughBraggLayer(n2=1.6, Lambda=500.0, delta=0.5, N=10, alpha=0.25),
              RoughBraggLayer(n2=1.7, Lambda=700.0, delta=0.4, N=5, alpha=0.4))
    stack = LayeredBragg(layers=layers, n1=1.4, rho_d=(0.6, 0.5, 0.3))
    t_i, t_o = np.radians([15.0, 40.0, 65.0]), np.radians([55.0, 30.0, 20.0])
    i = np.stack([np.sin(t_i), 0 * t_i, np.cos(t_i)], -1)
    o = np.stack([np.sin(t_o) * np.cos(2.0), np.sin(t_o) * np.sin(2.0), np.cos(t_o)], -1)
    walker = position_free.PositionFree(stack)
    forward = walker.brdf(i, o, samples=4096, seed=SEED)
    backward = walker.brdf(o, i, samples=4096, seed=SEED + 1)
    error = np.abs(forward.value - backward.value)
    assert np.all(error <= SIGMAS * np.hypot(forward.stderr, backward.stderr))
    assert np.all(forward.value > 5 * forward.stderr)  # a real signal, not noise against noise


def test_seeded_and_reproducible():
    stack = LayeredBragg(layers=(RoughBraggLayer(alpha=0.2),), n1=1.3, rho_d=0.4)
    a = position_free.directional_albedo(stack, [0.0, 60.0], samples=64, seed=7)
    b = position_free.directional_albedo(stack, [0.0, 60.0], samples=64, seed=7)
    c = position_free.directional_albedo(stack, [0.0, 60.0], samples=64, seed=8)
    np.testing.assert_array_equal(a.value, b.value)
    np.testing.assert_array_equal(a.stderr, b.stderr)
    assert not np.array_equal(a.value, c.value)


def test_bad_input():
    stack = LayeredBragg(layers=(RoughBraggLayer(),))
    with pytest.raises(ValueError, match="90"):
        position_free.directional_albedo(stack, [95.0], samples=8)
    with pytest.raises(ValueError, match="samples"):
        position_free.directional_albedo(stack, [10.0], samples=0)


def test_processes_do_not_change_the_result(monkeypatch):
    stack = LayeredBragg(layers=(RoughBraggLayer(alpha=0.2),), n1=1.3, rho_d=0.4)
    walker = position_free.PositionFree(stack)
    sequential = walker.albedo([0.0, 60.0], samples=256, seed=3)
    monkeypatch.setattr(position_free, "PARALLEL_PATHS", 1)
    monkeypatch.setattr(position_free, "_workers", lambda: 2)
    parallel = walker.albedo([0.0, 60.0], samples=256, seed=3)
    np.testing.assert_array_equal(parallel.value, sequential.value)
    np.testing.assert_array_equal(parallel.stderr, sequential.stderr)
