"""The view registry (explorer.views.geometry.VIEW_REGISTRY): one entry per view template, and what follows from it."""

from __future__ import annotations

import pytest

from explorer.resources import SHADER_DIR
from explorer.views.geometry import BRDF_VIEWS, LIGHT_VIEWS, PLOT_VIEWS, VIEW_REGISTRY, VIEWS, view_named


def test_every_template_is_a_registered_view_and_back():
    templates = {path.stem for path in (SHADER_DIR / "views").glob("*.glsl")}
    assert templates == set(VIEW_REGISTRY)


def test_derived_lists_follow_the_registry():
    assert VIEWS == tuple(VIEW_REGISTRY)
    assert set(BRDF_VIEWS) == {"lit", "slice", "scatter"}
    assert set(LIGHT_VIEWS) == {"lit", "scatter", "textured", "theta_v", "lobe3d"}
    assert set(PLOT_VIEWS) == {"theta_v", "theta_h", "theta_d", "lobe3d", "albedo"}
    assert view_named("scatter").light_theta_max == 90.0  # an outgoing hemisphere: the light stays above it
    assert not view_named("gradient").square and view_named("gradient").default_size == (256, 32)


def test_unknown_view_is_one_line_listing_the_views():
    with pytest.raises(ValueError) as error:
        view_named("mirror")
    assert "\n" not in str(error.value) and all(name in str(error.value) for name in VIEWS)
