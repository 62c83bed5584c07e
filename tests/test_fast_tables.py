"""
Issue 22: the converged table built from fewer computed colours (explorer/physics/bragg/tables.py): midpoints from
a cubic where its error estimate allows (``_cubic_midpoints``), against independent values.
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.physics import bragg, colorimetry
from explorer.physics.bragg import band_pieces  # where the quadrature reads its helpers (patched below)


def test_cubic_midpoints_are_trusted_only_where_accurate():
    x = np.linspace(0.0, 1.0, 65)
    midpoints = 0.5 * (x[:-1] + x[1:])
    smooth = np.stack([0.5 + 0.4 * np.sin(3.0 * x), 0.5 + 0.3 * np.cos(2.0 * x), np.full_like(x, 0.5)], axis=-1)
    cubic, trusted = bragg._cubic_midpoints(smooth)
    exact = np.stack([0.5 + 0.4 * np.sin(3.0 * midpoints), 0.5 + 0.3 * np.cos(2.0 * midpoints), np.full_like(midpoints, 0.5)], axis=-1)
    assert trusted.sum() == x.size - 5  # all but the two intervals at each end
    assert np.abs(cubic[trusted] - exact[trusted]).max() <= bragg.TABLE_CUBIC_TOLERANCE * 0.9
    # A kink (as at a critical angle): the intervals around it are computed, not interpolated.
    kinked = np.repeat(np.abs(x - 0.5)[:, None], 3, axis=-1) + 0.2
    _, trusted = bragg._cubic_midpoints(kinked)
    assert not trusted[30:34].any() and trusted[10:20].all()


# --------------------------------------------------------------------------------------------------
# Gauss quadrature over band pieces (bragg.band_pieces_rgb)

#: Of the brightest linear RGB channel (at least colorimetry.CONVERGENCE_FLOOR), as tests/test_fringes.py.
NODE_RTOL = 4e-4


def relative_error(rgb, reference):
    return np.abs(rgb - reference).max(axis=-1) / np.maximum(np.abs(reference).max(axis=-1), colorimetry.CONVERGENCE_FLOOR)


def random_real_mirrors(seed: int, count: int, N_choices, hosts=(None,)):
    """Mirrors over bragg_mirror.brd's box (nh = n1, or a host of ``hosts``) and angles where every wave propagates."""
    rng = np.random.default_rng(seed)
    found = []
    while len(found) < count:
        mirror = bragg.BraggMirror(
            float(rng.uniform(1.0, 2.5)), float(rng.uniform(1.0, 2.5)), float(rng.uniform(50.0, 1500.0)),
            float(rng.uniform(0.0, 1.0)), int(rng.choice(N_choices)), hosts[int(rng.integers(len(hosts)))],
        )
        cos_theta = rng.uniform(0.0, 1.0, 3)
        first = bragg.cell_geometry(cos_theta, mirror, "s")
        real = (first.cos_theta_1.imag == 0) & (first.cos_theta_2.imag == 0)
        if real.any():
            found.append((mirror, cos_theta[real]))
    return found


def test_band_pieces_tile_the_visible_range(monkeypatch):
    """With R = 1 and flat CMFs the pieces' nodes integrate to the visible range's width: band edges, Airy
    points, fringe boundaries and the gaps' closed form neither overlap nor leave holes."""
    low, high = colorimetry.HAT_LOW, colorimetry.HAT_HIGH
    monkeypatch.setattr(band_pieces, "_line_reflectance", lambda lines, omega, line, kind: np.where(kind == 3, 0.0, 1.0))
    # Flat CMFs over [low, high] (ones at every 1-nm node) and their cumulative integral, for the nodes and the closed form.
    nodes = np.arange(int(round(high - low)) + 1, dtype=float)
    monkeypatch.setattr(band_pieces, "_cmf_nodes", lambda: (np.ones((nodes.size, 3)), np.repeat(nodes[:, None], 3, axis=1)))
    monkeypatch.setattr(colorimetry, "xyz_to_rgb", lambda xyz: xyz)
    # Hosts too: their fringe boundaries move to the host's transmission peaks (bragg._host_dip).
    for mirror, cos_theta in random_real_mirrors(5, 16, [1, 3, 20, 64, 100, 300, 1000], hosts=(None, 1.0, 1.33, 2.4)):
        width = bragg.band_pieces_rgb(cos_theta, mirror)
        np.testing.assert_allclose(width, high - low, rtol=1e-9, err_msg=str(mirror))


def test_band_pieces_equal_converged_reference_on_random_mirrors():
    """Random mirrors over the box, every N regime: Yeh's R throughout (N < 64), edges plus the fringe average."""
    failures = []
    for mirror, cos_theta in random_real_mirrors(22, 16, [1, 7, 20, 64, 150, 300, 1000]):
        error = relative_error(bragg.band_pieces_rgb(cos_theta, mirror), bragg.reference_rgb(cos_theta, mirror))
        if error.max() > NODE_RTOL:
            failures.append(f"{mirror} at cos {cos_theta[error.argmax()]:.4f}: {error.max():.2e}")
    assert not failures, "\n".join(failures)


def _reflectances_per_angle(monkeypatch, cos_theta, mirror_at) -> dict[int, float]:
    """Reflectances :func:`bragg.band_pieces_rgb` evaluates per angle, counted, for ``mirror_at(N)`` at N = 1000, 3000, 10000."""
    count = 0
    original = bragg._line_reflectance

    def counting(lines, omega, line, kind):
        nonlocal count
        count += int(np.sum(kind != 2))
        return original(lines, omega, line, kind)

    monkeypatch.setattr(band_pieces, "_line_reflectance", counting)
    samples = {}
    for N in (1000, 3000, 10000):
        count = 0
        bragg.band_pieces_rgb(cos_theta, mirror_at(N))
        samples[N] = count / cos_theta.size
    return samples


def test_band_pieces_cost_is_bounded_in_N(monkeypatch):
    """Reflectances evaluated per angle, counted: bounded from N = 1000 to N = 10000 (no fringe floor)."""
    samples = _reflectances_per_angle(monkeypatch, np.linspace(0.0, 1.0, 17), lambda N: bragg.BraggMirror(N=N))
    assert max(samples.values()) <= 1.5 * min(samples.values()) and max(samples.values()) < 2000, samples


def test_band_pieces_refuse_complex_angles():
    with pytest.raises(ValueError, match="real angles only"):
        bragg.band_pieces_rgb([0.5], bragg.BraggMirror(n1=1.5, n2=1.0, N=20))  # beyond the critical angle
    with pytest.raises(ValueError, match="real angles only"):
        bragg.band_pieces_rgb([0.5], bragg.BraggMirror(N=20, nh=1.4))  # total reflection at the host interface


# --------------------------------------------------------------------------------------------------
# Band pieces under a host nh != n1 (Appendix D)

from hypothesis import HealthCheck, Phase, given, seed, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


def propagating_angles(mirror, cos_theta):
    first = bragg.cell_geometry(cos_theta, mirror, "s")
    return cos_theta[(first.cos_theta_1.imag == 0) & (first.cos_theta_2.imag == 0)]


@seed(2022)
@settings(max_examples=40, deadline=None, database=None, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.too_slow])
@given(draw=st.integers(0, 2**32 - 1), N=st.sampled_from([64, 100, 300, 1000]), nh=st.sampled_from([1.0, 1.33, 1.6, 2.4]))
def test_band_pieces_under_a_host_equal_converged_reference(draw, N, nh):
    """A host (Appendix D: |r_hN|^2 at the nodes, its coherent fringe average, fringes cut at its own transmission
    peaks) over bragg_mirror.brd's box, n2 < n1 and n2 > n1, Lambda 50-1500 nm, at propagating angles: within
    NODE_RTOL of the converged reference (tests/test_fringes.py's tolerance)."""
    rng = np.random.default_rng(draw)
    n1, n2 = rng.uniform(1.0, 2.5, 2)
    if nh == 1.0:
        n1 = 1.0 + 1.5 * float(rng.uniform(0.05, 1.0))  # nh = 1 with n1 != 1
    mirror = bragg.BraggMirror(float(n1), float(n2), float(rng.uniform(50.0, 1500.0)), float(rng.uniform(0.0, 1.0)), N, nh)
    cos_theta = propagating_angles(mirror, rng.uniform(0.0, 1.0, 2))
    if cos_theta.size:
        error = relative_error(bragg.band_pieces_rgb(cos_theta, mirror), bragg.reference_rgb(cos_theta, mirror))
        assert error.max() <= NODE_RTOL, (mirror, error.max(), cos_theta[error.argmax()])


@pytest.mark.parametrize("mirror, cos_theta", [
    (bragg.BraggMirror(1.5, 2.0, 300.0, 0.001, 1000, nh=1.0), [0.1, 0.3]),  # nearly closed gaps: peaks off the edges
    (bragg.BraggMirror(1.5, 1.0, 500.0, 0.5, 64, nh=1.0), [0.02, 0.05]),  # grazing: host and mirror form a cavity
    # Weak contrast: the host's interference with the mirror, first order in r1, in 6-nm fringes: 4.4e-4 averaged.
    (bragg.BraggMirror(1.0537408035934563, 1.1014253733312716, 171.63939826275566, 0.3635945633961879, 300, 1.0), [0.5167]),
], ids=["delta=0.001,N=1000", "grazing,N=64", "weak,N=300"])
def test_band_pieces_under_a_host_where_its_peaks_move_far(mirror, cos_theta):
    """The host's peaks far from the mirror's dips (psi0 ~ pi / 2 in N K Lambda): 1.5e-2 and 7e-4 before the boundaries
    followed them (unwrapped, a fringe back where a peak would sit between an edge and the first boundary)."""
    cos_theta = np.asarray(cos_theta)
    error = relative_error(bragg.band_pieces_rgb(cos_theta, mirror), bragg.reference_rgb(cos_theta, mirror))
    assert error.max() <= NODE_RTOL, (error.max(), cos_theta[error.argmax()])


@pytest.mark.parametrize("N", [1, 20, 100, 1000])
def test_band_pieces_under_a_vanishing_host_equal_no_host(N, monkeypatch):
    """nh -> n1: the host's path (complex r_hN, shifted fringe boundaries, its fringe average) tends to Yeh's."""
    monkeypatch.setattr(band_pieces, "HOST_FRINGE_NODES", bragg.FRINGE_NODES)  # the same nodes: only the formulas differ
    monkeypatch.setattr(band_pieces, "HOST_FRINGE_MEAN_GROWTH", bragg.FRINGE_MEAN_GROWTH)
    mirror = bragg.BraggMirror(1.33, 1.8, 500.0, 0.4, N)
    cos_theta = np.linspace(0.05, 1.0, 5)
    host = bragg.band_pieces_rgb(cos_theta, bragg.BraggMirror(1.33, 1.8, 500.0, 0.4, N, nh=1.33 + 1e-9))
    np.testing.assert_allclose(host, bragg.band_pieces_rgb(cos_theta, mirror), atol=1e-7)


@pytest.mark.parametrize("mirror", [bragg.BraggMirror(1.0, 1.5, 500.0, 0.5, 1000, nh=1.33),
                                    bragg.BraggMirror(1.5, 1.0, 80.0, 0.9, 3, nh=2.4)], ids=["N=1000", "N=3,n2<n1"])
def test_table_rule_under_total_reflection_at_the_host(mirror):
    """Beyond the host interface's critical angle (nh > n1) n1 is evanescent below the mirror too: R = 1 (white)."""
    cos_theta = np.array([0.0, 0.2, 0.5])
    assert (bragg.cell_geometry(cos_theta, mirror, "s").cos_theta_1.imag != 0).all()
    np.testing.assert_allclose(bragg.converged_rgb(cos_theta, mirror), bragg.reference_rgb(cos_theta, mirror), atol=1e-12)


def test_band_pieces_under_a_host_cost_is_bounded_in_N(monkeypatch):
    """Under a host too, reflectances per angle do not grow from N = 1000 to 10000."""
    samples = _reflectances_per_angle(monkeypatch, np.linspace(0.05, 1.0, 9), lambda N: bragg.BraggMirror(1.33, 1.8, N=N, nh=1.0))
    # HOST_FRINGE_NODES (8, not 6) per half fringe near band edges: ~2100-2400 a line pair here.
    assert max(samples.values()) <= 1.5 * min(samples.values()) and max(samples.values()) < 3000, samples


# --------------------------------------------------------------------------------------------------
# The table against the converged reference on random mirrors over bragg_mirror.brd's box (issue 22)

#: Between the table's entries (linear interpolation), as tests/test_converged.py's TABLE_RTOL.
TABLE_RTOL = 2e-3


# A fixed seed and no shrinking; each example draws its mirror from a numpy generator seeded by hypothesis (hypothesis's
# own floats cluster on the box's corners and mutate one mirror after a few examples).
@seed(22)
@settings(max_examples=20, deadline=None, database=None, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.too_slow])
@given(draw=st.integers(0, 2**32 - 1), N=st.sampled_from([1, 20, 100, 300, 1000]), host=st.booleans())
def test_table_equals_converged_reference_on_random_mirrors(draw, N, host):
    """Any mirror of bragg_mirror.brd's box (indices 1-2.5, a host nh != n1 or none, n2 < n1 with total internal
    reflection and evanescent layers, Lambda 50-1500 nm, delta 0-1), N from 1 to 1000, at random angles: the table's
    rule within NODE_RTOL of the converged reference, its lookups (interpolated entries) within TABLE_RTOL."""
    rng = np.random.default_rng(draw)
    n1, n2, nh = rng.uniform(1.0, 2.5, 3)
    mirror = bragg.BraggMirror(float(n1), float(n2), float(rng.uniform(50.0, 1500.0)), float(rng.uniform(0.0, 1.0)), N,
                               float(nh) if host else None)
    cos_theta = rng.uniform(0.0, 1.0, 3)
    reference = bragg.reference_rgb(cos_theta, mirror)
    error = relative_error(bragg.converged_rgb(cos_theta, mirror), reference)
    assert error.max() <= NODE_RTOL, (mirror, error.max(), cos_theta[error.argmax()])
    table = bragg.tabulated_rgb_table(mirror)
    assert table.dtype == np.float32 and table.shape[1] == 3 and not table.flags.writeable
    error = relative_error(bragg.tabulated_rgb(table, cos_theta), reference)
    assert error.max() <= TABLE_RTOL, (mirror, error.max(), cos_theta[error.argmax()])


@pytest.mark.parametrize("mirror", [
    bragg.BraggMirror(1.0, 1.5, 50.0, 0.5, 64),  # fringes ~30 nm wide: the fringe average was off by 2e-2
    bragg.BraggMirror(2.1666854836047436, 1.6154686637578541, 50.0, 0.32038940770826296, 100),  # the same, evanescent n2
    bragg.BraggMirror(1.0, 1.5, 50.0, 0.5, 100, nh=1.4),  # the same under a host
], ids=["Lambda=50,N=64", "Lambda=50,N=100,evanescent", "Lambda=50,N=100,host"])
def test_table_rule_with_wide_fringes(mirror):
    """Short periods: few fringes, each wider than the CMFs' features, where averaging over them is wrong."""
    cos_theta = np.array([0.95, 0.649, 0.3, 0.076])
    error = relative_error(bragg.converged_rgb(cos_theta, mirror), bragg.reference_rgb(cos_theta, mirror))
    assert error.max() <= NODE_RTOL, (error.max(), cos_theta[error.argmax()])
