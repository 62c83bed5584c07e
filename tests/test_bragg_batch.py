"""
The batched forward model (explorer.physics.bragg.batch, inverse design's): against the per-mirror path
(:func:`explorer.physics.bragg.bragg_reflectance`) at integer ``N``, its fringe average against the exact spectrum
averaged over many fringes, its continuous ``N`` continuous, and its complex branch against its real one.
"""

from __future__ import annotations

import numpy as np

from explorer.physics import bragg

KEYS = ("n1", "n2", "Lambda", "delta", "N", "nh")


def _mirror(values: dict, b: int) -> bragg.BraggMirror:
    nh = float(values["nh"][b])
    return bragg.BraggMirror(n1=float(values["n1"][b]), n2=float(values["n2"][b]), Lambda=float(values["Lambda"][b]),
                             delta=float(values["delta"][b]), N=int(values["N"][b]), nh=None if nh < 1.0 else nh)


def _random_mirrors(seed: int, count: int, N_max: float = 1000.0) -> dict:
    rng = np.random.default_rng(seed)
    return dict(n1=rng.uniform(1, 2.5, count), n2=rng.uniform(1, 2.5, count), Lambda=rng.uniform(50, 1500, count),
                delta=rng.uniform(0, 1, count), N=np.round(np.exp(rng.uniform(0, np.log(N_max), count))),
                nh=rng.uniform(0, 2.5, count))  # half with a host (nh >= 1), total internal reflection included


def test_batch_reflectance_equals_yeh_at_integer_N():
    values = _random_mirrors(3, 40)
    cos_theta = np.cos(np.radians([0.0, 25.0, 50.0, 75.0, 89.0]))
    wavelengths = np.linspace(360.0, 830.0, 60)
    batch = bragg.bragg_reflectance_batch(*(values[k] for k in KEYS), cos_theta, wavelengths)
    for b in range(40):
        exact = bragg.bragg_reflectance(cos_theta[:, None], wavelengths[None, :], _mirror(values, b))
        np.testing.assert_allclose(batch[b], exact, atol=1e-9)


def test_fringe_average_is_the_exact_spectrum_averaged_over_its_fringes():
    # Thick stacks (fringes ~0.1-0.4 nm apart) sampled as if every 4 nm: the batch's weight of the point value is 0,
    # its value the fringe average, whose mean over 2-nm windows (5-20 fringes) is the exact spectrum's mean there.
    values = dict(n1=np.array([1.0, 1.33, 1.5]), n2=np.array([1.5, 1.56, 2.2]), Lambda=np.array([900.0, 1200.0, 700.0]),
                  delta=np.array([0.5, 0.3, 0.6]), N=np.array([400.0, 300.0, 800.0]), nh=np.array([0.0, 1.0, 0.0]))
    cos_theta = np.cos(np.radians([0.0, 40.0]))
    fine = (np.array([450.0, 550.0, 650.0])[:, None] + np.linspace(-1.0, 1.0, 4001)[None, :]).ravel()
    averaged = bragg.bragg_reflectance_batch(*(values[k] for k in KEYS), cos_theta, fine, step=4.0).reshape(3, 2, 3, -1)
    point = bragg.bragg_reflectance_batch(*(values[k] for k in KEYS), cos_theta, fine).reshape(3, 2, 3, -1)
    for b in range(3):
        exact = bragg.bragg_reflectance(cos_theta[:, None], fine[None], _mirror(values, b)).reshape(2, 3, -1)
        np.testing.assert_allclose(point[b], exact, atol=1e-9)  # no step: the point values
        # a window holds a fractional count of fringes: its ends weigh up to ~1/10 of a fringe (measured: 3.0e-3 at most)
        np.testing.assert_allclose(averaged[b].mean(axis=-1), exact.mean(axis=-1), atol=5e-3)
        assert np.max(np.abs(averaged[b] - exact)) > 0.05 or np.ptp(exact) < 0.05  # not the point values: their mean


def test_continuous_N_is_continuous_through_the_integers():
    values = _random_mirrors(7, 30, N_max=200.0)
    values["N"] = np.maximum(values["N"], 2.0)
    cos_theta = np.cos(np.radians([0.0, 60.0]))
    wavelengths = np.linspace(360.0, 830.0, 48)
    at = lambda N: bragg.bragg_reflectance_batch(*(values[k] for k in KEYS[:4]), N, values["nh"], cos_theta, wavelengths)
    whole, below, above = at(values["N"]), at(values["N"] - 1e-7), at(values["N"] + 1e-7)
    assert np.max(np.abs(below - whole)) < 1e-4 and np.max(np.abs(above - whole)) < 1e-4
    assert np.max(np.abs(at(values["N"] + 0.5) - whole)) > 1e-3  # between the counts: a colour no stack has


def test_complex_indices_without_absorption_equal_the_real_branch():
    values = _random_mirrors(5, 24, N_max=300.0)
    cos_theta = np.cos(np.radians([0.0, 30.0, 70.0]))
    wavelengths = np.linspace(360.0, 830.0, 40)
    real = bragg.bragg_reflectance_batch(*(values[k] for k in KEYS), cos_theta, wavelengths)
    complex_ = bragg.bragg_reflectance_batch(*(values[k].astype(np.complex128) if k in ("n1", "n2") else values[k] for k in KEYS),
                                             cos_theta, wavelengths)
    np.testing.assert_allclose(complex_, real, atol=1e-9)


#: The lossless real path against the complex coefficients: both exact, they differ by rounding (measured: 2.4e-11).
LOSSLESS_TWIN_TOLERANCE = 1e-9
#: The analytic derivatives against central differences of the batch's colours, relative to the largest derivative
#: of each parameter over the rows (measured: <= 2e-6 in the design box; differences of 1e-7 relative steps).
GRADIENT_TOLERANCE = 1e-4


def _lossless_twin_mirrors(count: int) -> dict:
    """Random structures (N from 1 to 1000), and quarter-wave ones whose band edge falls on a node (both phases pi)."""
    rng = np.random.default_rng(11)
    values = dict(n1=rng.uniform(1, 2.5, count), n2=rng.uniform(1, 2.5, count), Lambda=rng.uniform(50, 1500, count),
                  delta=rng.uniform(0, 1, count), N=np.exp(rng.uniform(0, np.log(1000.0), count)), nh=np.zeros(count))
    edge = slice(0, count // 4)
    # p1 = p2 = lambda0 / 2 at normal incidence, lambda0 = 500 nm (a node of the wavelengths below): cos K Lambda = 1.
    values["delta"][edge] = values["n2"][edge] / (values["n1"][edge] + values["n2"][edge])
    values["Lambda"][edge] = 250.0 / (values["n1"][edge] * values["delta"][edge])
    values["N"][: count // 8] = np.round(values["N"][: count // 8])
    values["N"][0], values["N"][1] = 1.0, 1000.0
    return values


def test_lossless_path_equals_the_complex_path():
    # Grazing angles and evanescent layers (n1 > n2) included: those rows take the complex path inside the batch.
    from explorer.physics.bragg import batch
    from explorer.physics.colorimetry import interpolant_nodes

    values = _lossless_twin_mirrors(64)
    cos_theta = np.cos(np.radians([0.0, 30.0, 60.0, 85.0, 89.9]))
    nodes, _ = interpolant_nodes(2.0)
    assert 500.0 in nodes
    for step in (None, 2.0, 8.0):
        fast = bragg.bragg_reflectance_batch(*(values[k] for k in KEYS), cos_theta, nodes, step=step)
        columns = [batch._column(values[k], np.float64) for k in KEYS]
        exact = batch._host_reflectance(*columns, np.maximum(cos_theta.reshape(1, -1, 1), bragg.COS_THETA_MIN),
                                        nodes.reshape(1, 1, -1), step, None)
        # At the quarter-wave rows' 500 nm the cell reflects nothing (r1 = 0 to rounding): the complex fringe average is
        # 0/0 there (its limit |P/S|^2 of two roundings), the fast path's is the cell's own value, 0.
        node = int(np.flatnonzero(nodes == 500.0)[0])
        exact[:16, 0, node] = 0.0
        assert np.all(fast[:16, 0, node] < 1e-12)
        np.testing.assert_allclose(fast, exact, atol=LOSSLESS_TWIN_TOLERANCE)
    # A dispersive lossless medium (an index per wavelength) takes the same path.
    n2 = np.broadcast_to((1.5 + 0.02 * (500.0 / nodes) ** 2).reshape(1, 1, -1), (64, 1, nodes.size))
    fast = bragg.bragg_reflectance_batch(values["n1"], n2, values["Lambda"], values["delta"], values["N"], values["nh"], cos_theta, nodes,
                                         step=2.0)
    exact = batch._host_reflectance(batch._column(values["n1"]), n2, *(batch._column(values[k]) for k in ("Lambda", "delta", "N", "nh")),
                                    np.maximum(cos_theta.reshape(1, -1, 1), bragg.COS_THETA_MIN), nodes.reshape(1, 1, -1), 2.0, None)
    np.testing.assert_allclose(fast, exact, atol=LOSSLESS_TWIN_TOLERANCE)


def test_analytic_derivatives_equal_central_differences():
    from explorer.materials.models import bragg_rgb_batch, bragg_rgb_gradient

    rng = np.random.default_rng(4)
    count = 48
    values = dict(n1=np.ones(count), n2=np.full(count, 1.5), Lambda=rng.uniform(100, 400, count), delta=rng.uniform(0.05, 0.95, count),
                  N=np.exp(rng.uniform(0, np.log(40.0), count)), nh=np.zeros(count))
    values["n1"][::2], values["n2"][::2] = 1.33, 1.56  # other indices (light from the lower one: every wave propagates)
    cos_theta = np.cos(np.radians([0.0, 45.0, 80.0]))
    rgb, derivatives = bragg_rgb_gradient(values, cos_theta)
    np.testing.assert_allclose(rgb, bragg_rgb_batch(values, cos_theta), atol=LOSSLESS_TWIN_TOLERANCE)
    for name in ("Lambda", "delta", "N"):
        h = 1e-7 * np.maximum(np.abs(values[name]), 1.0)
        up, down = dict(values), dict(values)
        up[name], down[name] = values[name] + h, values[name] - h
        central = (bragg_rgb_batch(up, cos_theta) - bragg_rgb_batch(down, cos_theta)) / (2.0 * h[:, None, None])
        scale = np.max(np.abs(central), axis=(1, 2), keepdims=True)
        assert np.max(np.abs(derivatives[name] - central) / scale) < GRADIENT_TOLERANCE, name
    # Under a separate host the batch declares no gradient: the caller differences it.
    assert bragg_rgb_gradient({**values, "nh": np.full(count, 1.2)}, cos_theta) is None


def test_reference_of_many_mirrors_equals_one_at_a_time():
    rng = np.random.default_rng(9)
    mirrors = [bragg.BraggMirror(n1=float(rng.uniform(1, 2)), n2=float(rng.uniform(1, 2)), Lambda=float(rng.uniform(100, 600)),
                                 delta=float(rng.uniform(0.1, 0.9)), N=int(rng.integers(1, 60)), nh=None if k % 4 else 1.2) for k in range(12)]
    cos_theta = np.cos(np.radians([0.0, 45.0, 85.0]))
    many = bragg.reference_rgb_many(cos_theta, mirrors)
    for m, mirror in enumerate(mirrors):
        np.testing.assert_allclose(many[m], bragg.reference_rgb(cos_theta, mirror), atol=1e-9)
