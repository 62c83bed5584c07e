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
