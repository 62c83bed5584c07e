"""
The app draws through the render service (explorer/rendering.py): its progressive jobs are requested by
:func:`explorer.rendering.request_view`, bound as :func:`explorer.rendering.gl_inputs` describes a view, which is
what ``render`` draws headless. A job the app requested by hand would fail the scan; a view the service describes
differently for the app and for ``render`` would fail the comparison.
"""

from __future__ import annotations

import ast

import numpy as np
import pytest

from conftest import REPO_ROOT

#: The only ``X.request(...)`` calls the app may make itself: the accuracy badge's and the env render's (not views
#: of the GL engine's progressive jobs).
OTHER_REQUESTS = {"self.badge", "scheduler.env"}


def app_job_requests(root) -> list[str]:
    """``path:line receiver`` of every ``receiver.request(...)`` call under ``root/explorer/app`` but :data:`OTHER_REQUESTS`."""
    found = []
    for path in sorted((root / "explorer" / "app").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "request":
                receiver = ast.unparse(node.func.value)
                if receiver not in OTHER_REQUESTS:
                    found.append(f"{path.relative_to(root)}:{node.lineno} {receiver}")
    return found


def test_the_app_requests_its_views_through_the_render_service():
    assert not app_job_requests(REPO_ROOT), "request the view with explorer.rendering.request_view: " + "; ".join(
        app_job_requests(REPO_ROOT))


def test_the_scan_sees_a_job_requested_by_hand(tmp_path):
    (tmp_path / "explorer" / "app").mkdir(parents=True)
    (tmp_path / "explorer" / "app" / "x.py").write_text("job.request(m, v, 'lit', (8, 8))\nself.badge.request(m, v, False)\n")
    assert app_job_requests(tmp_path) == ["explorer/app/x.py:1 job"]


@pytest.mark.gl
@pytest.mark.parametrize("view", ["lit", "theta_h", "textured"])
def test_a_progressive_job_requested_through_the_service_is_the_render_command(gl_renderer, view):
    """The app's job, refined in row bands, equals ``render_material``'s GL image of the same view (fill, plot, texture)."""
    from explorer.gpu.progressive import CostModel, ProgressiveView
    from explorer.materials.brd import load_material
    from explorer.rendering import render_material, request_view
    from explorer.views.geometry import light_direction
    from explorer.views.plots import PlotSettings
    from explorer.views.surface_texture import default_texture

    name = "thin_film" if view == "textured" else "ggx_schlick"
    material = load_material(REPO_ROOT / "shaders" / f"{name}.brd")
    values = material.resolve({"alpha": 0.3})
    size, light = (24, 24) if view != "theta_h" else (64, 1), (30.0, 120.0)
    described = {"light": tuple(float(c) for c in light_direction(light))}
    headless = {"light": light}
    if view == "lit":
        described["fill"] = headless["fill"] = 0.4
    if view == "theta_h":
        described["plot"] = headless["plot"] = PlotSettings(log=True)
    if view == "textured":
        surface = default_texture(material)
        described["surface"], headless["thickness"] = surface.gl_arguments(material, values, *size), surface
    job = ProgressiveView(gl_renderer, CostModel())
    request_view(job, material, values, view, size, **described)
    while not job.complete:
        job.work(1e3)
    assert job.error is None, job.error
    # The session's renderer: a second GL context made current in this process would take its later calls.
    expected = render_material(material, values, view, *size, "gl", renderer=gl_renderer, **headless)
    assert np.abs(expected).max() > 0.01
    np.testing.assert_array_equal(job.read(), expected)


def test_a_views_tables_keep_their_identity():
    """A progressive job without an inputs_key knows its tables by identity: a copy per frame would restart it each frame."""
    from explorer.rendering import gl_inputs

    surface = {"inputs": {"thickness": np.zeros((2, 2))}, "uniforms": {"prefilter": False}}
    bound = gl_inputs("textured", surface=surface, uniforms={"a": 1.0})
    assert bound["inputs"] is surface["inputs"] and bound["uniforms"] == {"a": 1.0, "prefilter": False}
    normals = {"mesh_normals": np.zeros((2, 2, 3))}
    assert gl_inputs("lit", inputs=normals, fill=0.5)["inputs"] is normals
    assert gl_inputs("lit", fill=0.5)["uniforms"] == {"fill": 0.5} and gl_inputs("lit")["inputs"] is None
