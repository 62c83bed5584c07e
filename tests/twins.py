"""
GL images against their numpy twins, for the tests: the harness itself (one way to render both, the
named tolerances, the comparison) is :mod:`explorer.views.twin_check`, shared with ``bragg-explorer check``;
here it becomes assertions.
"""

from __future__ import annotations

import numpy as np

from explorer.views.geometry import brdf_view_geometry, view_cos_theta
from explorer.views.twin_check import (  # noqa: F401  (the tests import the harness from here)
    BRDF_TOLERANCE, COLOUR_TOLERANCE, COLOUR_VIEWS, FLOOR, GL_ATOL, LIGHTS, RIM_EXCLUSION, RTOL, Tolerance, Twins,
    compare, compared_pixels, render_both, tolerance_for,
)


def assert_twins_equal(twins: Twins, what: str = "", tolerance: Tolerance | None = None) -> None:
    """Both images finite and equal within ``tolerance`` (default :func:`tolerance_for` the view) on the compared pixels."""
    result = compare(twins, tolerance)
    assert result.passed, result.message(what)


def assert_black_outside(twins: Twins) -> None:
    """Off the disc (rim excluded), both images are exactly 0; the disc leaves some pixels out."""
    height, width = twins.gl.shape[:2]
    if twins.view in COLOUR_VIEWS:
        inside = view_cos_theta(twins.view, width, height)[1]
    else:
        inside = brdf_view_geometry(twins.view, width, height, twins.light)[5]
    outside = ~inside & twins.compared
    assert outside.any(), f"{twins.view}: no pixel outside the disc"
    np.testing.assert_array_equal(twins.gl[outside], 0.0)
    np.testing.assert_array_equal(twins.reference[outside], 0.0)
