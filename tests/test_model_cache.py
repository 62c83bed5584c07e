"""explorer.gpu.Renderer's model cache: tables built once per parameter set, and on a worker thread for the app."""

from __future__ import annotations

import functools

import threading

import numpy as np
import pytest

from conftest import REPO_ROOT
from explorer.gpu import Renderer, tables
from explorer.materials.brd import load_material

MIRROR = REPO_ROOT / "shaders" / "bragg_mirror.brd"


@pytest.fixture()
def counted_models(monkeypatch):
    """How many numpy models Renderer builds (explorer.gpu.tables.model_for calls)."""
    calls = []
    original = tables.model_for

    def counting(material, values):
        calls.append(threading.current_thread().name)
        return original(material, values)

    monkeypatch.setattr(tables, "model_for", counting)
    return calls


@pytest.mark.gl
def test_tables_are_built_once_per_parameter_set(gl_renderer, counted_models):
    material = load_material(MIRROR)
    values = material.resolve({"method": 3, "Lambda": 613})
    first = gl_renderer.render(material, values, "sphere", 16, 16)
    again = gl_renderer.render(material, values, "sphere", 16, 16)
    assert len(counted_models) == 1
    np.testing.assert_array_equal(first, again)
    other = gl_renderer.render(material, {**values, "Lambda": 614.0}, "sphere", 16, 16)
    assert len(counted_models) == 2 and not np.array_equal(first, other)


@pytest.mark.gl
def test_prepare_model_on_a_worker_thread_then_bind_uses_it(gl_renderer, counted_models):
    material = load_material(MIRROR)
    values = material.resolve({"method": 3, "Lambda": 777, "N": 13})
    assert not gl_renderer.model_ready(material, values)
    worker = threading.Thread(target=gl_renderer.prepare_model, args=(material, values), name="tables")
    worker.start()
    worker.join()
    assert counted_models == ["tables"] and gl_renderer.model_ready(material, values)
    image = gl_renderer.render(material, values, "sphere", 16, 16)
    assert counted_models == ["tables"], "bind rebuilt a model the worker had prepared"
    fresh = Renderer(gl_renderer.ctx).render(material, values, "sphere", 16, 16)
    np.testing.assert_array_equal(image, fresh)


def test_a_material_without_a_model_is_always_ready(gl_renderer):
    material = load_material(REPO_ROOT / "tests" / "data" / "brdf" / "lambert.brdf")
    assert gl_renderer.model_ready(material, material.resolve({}))


@pytest.mark.gl
def test_draft_table_while_dragging_then_the_real_one(gl_renderer):
    """
    The tabulated method's draft (bragg.draft_rgb_table, shown while a slider moves) is drawn at once, is not
    "ready", and is replaced, texture included, by the converged table on prepare_model: the image then
    equals a fresh renderer's.
    """
    from explorer.materials.models import model_for
    from explorer.physics import bragg
    from explorer.views.geometry import view_cos_theta

    material = load_material(MIRROR)
    values = material.resolve({"method": 3, "Lambda": 500, "N": 60, "delta": 0.5})
    assert gl_renderer.prepare_draft(material, values) and not gl_renderer.model_ready(material, values)
    draft = gl_renderer.render(material, values, "gradient", 128, 2)
    model = model_for(material, values)
    cos_theta, _ = view_cos_theta("gradient", 128, 2)
    expected_draft = bragg.tabulated_rgb(bragg.draft_rgb_table(model.mirror), cos_theta)
    np.testing.assert_allclose(draft, expected_draft, rtol=0, atol=2e-3)
    gl_renderer.prepare_model(material, values)
    assert gl_renderer.model_ready(material, values)
    real = gl_renderer.render(material, values, "gradient", 128, 2)
    np.testing.assert_array_equal(real, Renderer(gl_renderer.ctx).render(material, values, "gradient", 128, 2))
    # The draft is not converged (a coarse sampling, no refinement in angle): it differs from the real table.
    assert np.abs(real - draft).max() > 1e-4


def test_materials_without_draft_tables_are_not_drafted(gl_renderer):
    material = load_material(MIRROR)
    values = material.resolve({"method": 1, "Lambda": 321})  # a placeholder texel only: nothing to draft
    assert not gl_renderer.prepare_draft(material, values) and not gl_renderer.model_ready(material, values)
    lambert = load_material(REPO_ROOT / "tests" / "data" / "brdf" / "lambert.brdf")
    assert gl_renderer.prepare_draft(lambert, lambert.resolve({}))  # no model: drawable as it is


def test_stack_drafts_its_layer_tables_then_builds_the_real_ones(monkeypatch):
    """
    bragg_stack.brd drafts too: its model builds no tables until asked, its draft textures are the 1-nm
    layer tables (same shapes, close to the converged ones), and ModelCache.prepare replaces them.
    """
    from explorer.materials import models
    from explorer.physics import colorimetry

    material = load_material(REPO_ROOT / "shaders" / "bragg_stack.brd")
    values = material.resolve({"Lambda_1": 517.0})
    built = []
    original = models._layer_tables.__wrapped__
    # Cached as the real one is (the compensation asks for a layer's tables again): each build counted once.
    monkeypatch.setattr(models, "_layer_tables", functools.lru_cache(maxsize=None)(lambda layer, n1: built.append(layer) or original(layer, n1)))
    cache = tables.ModelCache()
    assert cache.prepare_draft(material, values) and not cache.ready(material, values) and cache.drawable(material, values)
    assert built == [], "drafting built the converged layer tables"
    draft = cache.entry(material, values)[1].tables
    cache.prepare(material, values)
    assert cache.ready(material, values) and len(built) == int(values["layers"])
    real = cache.entry(material, values)[1].tables
    assert draft.keys() == real.keys() and all(draft[k].shape == real[k].shape for k in real)
    # The colour of each layer's R_lambda table: the draft (1-nm samples) within 2e-2 of the converged one.
    used = int(values["layers"])
    rgb = [colorimetry.spectrum_to_rgb(t["stack_reflectance"][..., :used].astype(np.float64).swapaxes(-1, -2)) for t in (draft, real)]
    assert np.abs(rgb[0] - rgb[1]).max() < 2e-2 and not np.array_equal(draft["stack_reflectance"], real["stack_reflectance"])
