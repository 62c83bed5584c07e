"""
The lit view's environment fill (:mod:`explorer.views.fill`): GL (``shaders/views/lit.glsl``, its table from the
albedo view) against its numpy twin; a Lambertian's closed form; ``render``'s default and ``--fill 0``.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT, run_cli
from twins import assert_twins_equal, render_both
from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.views.fill import DEFAULT_FILL, fill_angles, fill_radiance
from explorer.views.render import render_numpy

LAMBERT = REPO_ROOT / "tests" / "data" / "brdf" / "lambert.brdf"
SIZE = 40
#: The fill's coarse quadrature (2 nodes per theta_h cell, 32 azimuths) integrates a constant BRDF within 0.5 % (0.44 % measured).
FILL_QUADRATURE_RTOL = 5e-3


@pytest.mark.gl
@pytest.mark.parametrize("name, values", [("thin_film", {"method": 3}), ("ggx_schlick", {}), ("bragg_layer", {"method": 4}),
                                          ("layered_lobes", {})])
def test_lit_fill_twins(gl_renderer, name, values):
    """The filled lit view, GL against numpy within the BRDF views' tolerance; the fill adds light (luminance), also where N.L < 0."""
    material = load_material(REPO_ROOT / "shaders" / f"{name}.brd")
    resolved = material.resolve(values)
    twins = render_both(gl_renderer, material, resolved, "lit", (SIZE, SIZE), fill=DEFAULT_FILL)
    assert_twins_equal(twins, f"{name} lit with fill")
    unfilled = gl_renderer.render(material, resolved, "lit", SIZE, SIZE, light=twins.light)
    added = twins.gl - unfilled  # a vivid albedo has negative linear channels: its luminance is what is added
    assert added.max() > 1e-3 and (added @ np.array([0.2126, 0.7152, 0.0722])).min() > -1e-5, name
    # The program keeps no fill from one draw to the next: without the uniform, the light alone.
    again = gl_renderer.render(material, resolved, "lit", SIZE, SIZE, light=twins.light)
    np.testing.assert_array_equal(again, unfilled)


@pytest.mark.gl
def test_lambert_fill_is_its_reflectance(gl_renderer):
    """
    A Lambertian's albedo is its reflectance at every angle (BRDF Explorer's lambert.brdf, GL only): the table is
    rho, and with the light straight behind the sphere every pixel shows fill x rho.
    """
    material = load_material(LAMBERT)
    values = material.resolve({"reflectance": 0.6})
    table = np.asarray(gl_renderer.fill_table(material, values))
    assert table.shape == (fill_angles().size, 3)
    np.testing.assert_allclose(table, 0.6, rtol=FILL_QUADRATURE_RTOL)
    image = gl_renderer.render(material, values, "lit", SIZE, SIZE, light=(180.0, 0.0), uniforms={"fill": 0.2})
    inside = image.max(-1) > 0
    assert inside.mean() > 0.7
    np.testing.assert_allclose(image[inside], 0.2 * 0.6, rtol=FILL_QUADRATURE_RTOL)
    np.testing.assert_allclose(fill_radiance(table, np.array([1.0, 0.0]), 0.2), 0.2 * table[[0, -1]])


def test_render_fills_by_default_and_not_with_fill_zero(tmp_path):
    """``render --view lit``: the default fill (numpy engine, in-process), ``--fill 0`` the light alone; other views refuse it."""
    common = ("render", "ggx_schlick", "--view", "lit", "--size", "24", "--engine", "numpy")
    assert run_cli(*common, "--out", str(tmp_path / "filled.npy")).returncode == 0
    assert run_cli(*common, "--fill", "0", "--out", str(tmp_path / "alone.npy")).returncode == 0
    material = load_material(REPO_ROOT / "shaders" / "ggx_schlick.brd")
    model = model_for(material, material.resolve({}))
    np.testing.assert_allclose(np.load(tmp_path / "filled.npy"), render_numpy(model, "lit", 24, 24, fill=DEFAULT_FILL), atol=1e-6)
    np.testing.assert_allclose(np.load(tmp_path / "alone.npy"), render_numpy(model, "lit", 24, 24), atol=1e-6)
    bad = run_cli("render", "ggx_schlick", "--view", "sphere", "--fill", "0.1", "--engine", "numpy", "--out", str(tmp_path / "x.npy"))
    assert bad.returncode != 0 and "lit view" in bad.stderr and "Traceback" not in bad.stderr


@pytest.mark.gl
def test_fill_table_drafts_while_dragging(gl_renderer):
    """A dragged slider's previews reuse the material's last table (no albedo pass per frame); released, its own."""
    material = load_material(REPO_ROOT / "shaders" / "ggx_schlick.brd")
    before, after = material.resolve({"F0": 0.2}), material.resolve({"F0": 0.9})
    first = gl_renderer.fill_table(material, before)
    assert gl_renderer.fill_table(material, after, draft=True) == first
    own = gl_renderer.fill_table(material, after)
    assert np.asarray(own).mean() > np.asarray(first).mean() + 0.1  # a brighter Fresnel, a larger albedo
    assert gl_renderer.fill_table(material, after, draft=True) == own
