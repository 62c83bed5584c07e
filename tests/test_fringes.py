"""
The fast converged table (explorer/physics/bragg/windowed.py's windowed_converged_spectra): the fringe average plus the fringes near band edges
integrates to the converged reference's colours at any N, under a host and with n2 < n1, and its cost does
not grow with N (counted in samples, not timed: timings are ``bench --tables``).
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.physics import bragg, colorimetry

#: Of the brightest linear RGB channel (at least colorimetry.CONVERGENCE_FLOOR, as the integrator's own
#: tolerance): the table's nodes against the converged reference (bragg.reference_rgb without a step).
NODE_RTOL = 4e-4
#: Grazing, Brewster's (56.3 deg for 1 / 1.5), the critical angle of n2 < n1 (41.8 deg for 1.5 / 1), and others.
ANGLES_DEGREES = np.array([0.0, 30.0, 41.0, 42.5, 56.3, 70.0, 80.0, 86.0, 89.5])
MIRRORS = {
    "default": dict(n1=1.0, n2=1.5, Lambda=500.0, delta=0.5),
    "host": dict(n1=1.33, n2=1.8, Lambda=300.0, delta=0.5, nh=1.0),
    "n2<n1": dict(n1=1.5, n2=1.0, Lambda=500.0, delta=0.5),
}


def relative_error(rgb, reference):
    return np.abs(rgb - reference).max(axis=-1) / np.maximum(np.abs(reference).max(axis=-1), colorimetry.CONVERGENCE_FLOOR)


@pytest.mark.parametrize("N", [1, 20, 100, 300, 1000])
@pytest.mark.parametrize("name", sorted(MIRRORS))
def test_table_nodes_equal_converged_reference(name, N):
    mirror = bragg.BraggMirror(N=N, **MIRRORS[name])
    cos_theta = np.cos(np.radians(ANGLES_DEGREES))
    error = relative_error(bragg.converged_rgb(cos_theta, mirror), bragg.reference_rgb(cos_theta, mirror))
    assert error.max() <= NODE_RTOL, (error.max(), ANGLES_DEGREES[error.argmax()])


def test_table_equals_reference_on_random_mirrors():
    """Mirrors drawn at random (fixed seed) over indices, hosts, periods, delta and N, at random angles."""
    rng = np.random.default_rng(22)
    failures = []
    for _ in range(6):
        n1 = float(rng.choice([1.0, 1.33, 1.6]))
        nh = None if rng.random() < 0.5 else float(rng.choice([1.0, 1.45]))
        mirror = bragg.BraggMirror(
            n1, float(rng.uniform(1.0, 2.4)), float(rng.uniform(150.0, 1000.0)), float(rng.uniform(0.1, 0.9)),
            int(rng.choice([2, 7, 40, 250, 700])), None if nh == n1 else nh,
        )
        cos_theta = rng.uniform(0.0, 1.0, 4)
        error = relative_error(bragg.converged_rgb(cos_theta, mirror), bragg.reference_rgb(cos_theta, mirror))
        if error.max() > NODE_RTOL:
            failures.append(f"{mirror}: {error.max():.2e}")
    assert not failures, "\n".join(failures)


def test_window_covers_small_N_and_only_edges_for_large_N():
    """N <= 2 * EDGE_FRINGES * 2: the integrand is Yeh's R itself; N = 1000: the mean, except near edges."""
    cos_theta = np.cos(np.radians([0.0, 60.0, 85.0]))
    wavelengths = np.linspace(360.0, 830.0, 941)
    for N, exact_everywhere in ((4, True), (1000, False)):
        mirror = bragg.BraggMirror(N=N)
        windowed = bragg.windowed_spectrum_function(cos_theta, mirror, float64=True)(wavelengths, np.arange(3))
        exact = bragg.bragg_reflectance(cos_theta[:, None], wavelengths, mirror)
        if exact_everywhere:
            np.testing.assert_allclose(windowed, exact, atol=1e-9)
        else:
            # Half the samples or more lie away from edges, where the integrand is the smooth fringe average.
            assert np.mean(np.abs(windowed - exact) > 1e-3) > 0.5


def test_cost_is_bounded_in_N(monkeypatch):
    """
    Samples the table's rule evaluates, counted: bounded in N (at most 4x N = 20's, the peak near N = 300,
    then falling), where the converged reference's grow like N (x20 from N = 20 to N = 1000).
    """
    cos_theta = np.linspace(0.0, 1.0, 65)
    count = 0
    original = colorimetry.converged_spectra

    def counting_rule(spectrum, *args, **kwargs):
        def counting(wavelengths, rows):
            nonlocal count
            count += np.size(rows) * np.shape(wavelengths)[-1]
            return spectrum(wavelengths, rows)

        return original(counting, *args, **kwargs)

    monkeypatch.setattr(colorimetry, "converged_spectra", counting_rule)
    samples = {}
    for N in (20, 100, 300, 1000, 3000):
        count = 0
        # The windowed rule itself (the table takes band pieces from bragg.PIECES_MIN_N: tests/test_fast_tables.py).
        bragg.windowed_converged_spectra(cos_theta, bragg.BraggMirror(N=N), substeps_max=bragg.TABLE_MAX_SUBSTEPS)
        samples[N] = count
    assert max(samples.values()) <= 4.0 * samples[20], samples
    assert samples[3000] < samples[1000] < samples[300], samples


#: The draft table (bragg.draft_rgb_table) against the converged reference, of the brightest channel.
DRAFT_RTOL = 1.5e-2


def test_draft_table_is_close_at_any_N_and_closer_than_the_1nm_sum():
    rng = np.random.default_rng(9)
    cos_theta = rng.uniform(0.0, 1.0, 24)
    for N in (20, 300, 1000):
        mirror = bragg.BraggMirror(N=N)
        reference = bragg.reference_rgb(cos_theta, mirror)
        draft = relative_error(bragg.tabulated_rgb(bragg.draft_rgb_table(mirror), cos_theta), reference)
        one_nm = relative_error(bragg.reference_rgb(cos_theta, mirror, step=1.0), reference)
        assert draft.max() <= DRAFT_RTOL, (N, draft.max())
        assert draft.max() < one_nm.max(), (N, draft.max(), one_nm.max())
