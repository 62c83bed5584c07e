"""
Issue 22: the converged table built from fewer computed colours (explorer/physics/bragg.py): midpoints from
a cubic where its error estimate allows (``_cubic_midpoints``), against independent values.
"""

from __future__ import annotations

import numpy as np

from explorer.physics import bragg


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
