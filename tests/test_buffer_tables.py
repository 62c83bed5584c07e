"""
Model tables as buffer textures (``samplerBuffer``, issue 22 item 3): made and released by GLResources, read
by the tabulated method as the 2D texture was (same texels, same float mix), in every view and draw path.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT
from explorer.gpu import Renderer
from explorer.gpu.context import GLLimitError
from explorer.gpu.resources import GL_SAMPLER_BUFFER, BufferTexture
from explorer.materials.brd import load_material

pytestmark = pytest.mark.gl

MIRROR = REPO_ROOT / "shaders" / "bragg_mirror.brd"
LAYER = REPO_ROOT / "shaders" / "bragg_layer.brd"


@pytest.fixture(scope="module")
def texture_renderer(gl_renderer):
    """A renderer on the same context that uploads 2D textures (the path a .brdf export keeps)."""
    renderer = Renderer(gl_renderer.ctx)
    renderer.buffer_tables = False
    yield renderer
    renderer.resources.close()


def test_this_gl_makes_buffer_tables(gl_renderer):
    # llvmpipe (GL 4.5) and PyOpenGL (a dependency): the tabulated path the bench measures.
    assert gl_renderer.buffer_tables
    program = gl_renderer.program(load_material(MIRROR), "sphere", {"method": 3})
    assert program["bragg_table"].gl_type == GL_SAMPLER_BUFFER


def test_buffer_texture_is_owned_replaced_in_place_and_released(gl_renderer):
    resources = gl_renderer.resources
    owned = resources.owned()
    rows = np.random.default_rng(0).random((1, 5, 4)).astype(np.float32)
    texture = resources.texture(rows, buffer=True, origin="table")
    assert isinstance(texture, BufferTexture) and texture.size == (5, 1) and resources.owned() == owned + 1
    assert resources.replace(texture, rows[:, ::-1], buffer=True, origin="table") is texture  # same size: rewritten
    np.testing.assert_array_equal(np.frombuffer(texture.buffer.read(), np.float32).reshape(5, 4), rows[0, ::-1])
    longer = resources.replace(texture, np.ones((1, 7, 4), np.float32), buffer=True, origin="table")
    assert longer is not texture and longer.size == (7, 1) and texture.glo == 0 and resources.owned() == owned + 1
    # A 2D texture of the same size is another kind: replaced, not written into.
    flat = resources.replace(longer, np.ones((1, 7, 4), np.float32), origin="table")
    assert not isinstance(flat, BufferTexture) and longer.glo == 0
    resources.release(flat)
    assert resources.owned() == owned and gl_renderer.ctx.error == "GL_NO_ERROR"


def test_a_table_beyond_the_buffer_limit_is_a_one_line_error(gl_renderer):
    limit = gl_renderer.limits.max_texture_buffer_texels
    with pytest.raises(GLLimitError) as caught:
        gl_renderer.resources.texture(np.zeros((1, limit + 1, 4), np.float32), buffer=True, origin="bragg_table")
    assert str(caught.value).startswith("bragg_table: ") and "\n" not in str(caught.value)


@pytest.mark.parametrize("view", ["sphere", "gradient", "lit", "scatter"])
def test_tabulated_mirror_reads_a_buffer_as_it_read_the_2d_texture(gl_renderer, texture_renderer, view):
    material = load_material(MIRROR)
    values = material.resolve({"method": 3, "Lambda": 560, "N": 30})
    from_buffer = gl_renderer.render(material, values, view, 48, 32)
    from_texture = texture_renderer.render(material, values, view, 48, 32)
    assert np.abs(from_texture).max() > 0.05
    # The same texels and the same float arithmetic: equal but for the compiler's rounding.
    np.testing.assert_allclose(from_buffer, from_texture, rtol=0, atol=1e-6)
    assert gl_renderer.ctx.error == "GL_NO_ERROR"


@pytest.mark.parametrize("method", [1, 3])
def test_layer_with_a_buffer_table_beside_2d_textures(gl_renderer, texture_renderer, method):
    """The lit layer binds the CMF texture (sampler2D) and its T_rgb table (samplerBuffer): units apart."""
    material = load_material(LAYER)
    values = material.resolve({"method": method})
    from_buffer = gl_renderer.render(material, values, "lit", 32, 32)
    assert gl_renderer.ctx.error == "GL_NO_ERROR"
    np.testing.assert_allclose(from_buffer, texture_renderer.render(material, values, "lit", 32, 32), rtol=0, atol=1e-6)


def test_env_view_with_unbound_samplers_beside_a_buffer_table(gl_renderer):
    """The env program declares samplers it is not given here (a textured mirror's): they must not share
    unit 0 with the buffer table, or GL refuses the draw."""
    from explorer.gpu.env import ProgressiveEnvRender
    from explorer.views.env import EnvironmentMap

    material = load_material(MIRROR)
    render = ProgressiveEnvRender(gl_renderer, material, material.resolve({"method": 3}), EnvironmentMap.default(), 16, 16)
    try:
        render.step(1)
        assert gl_renderer.ctx.error == "GL_NO_ERROR"
        assert np.abs(render.image()).max() > 0.05
    finally:
        render.release()


def test_lookup_profile_reads_every_table_it_times(gl_renderer):
    """explorer.dev.lookup_profile's exact variants show the table's linear interpolation (its 16-bit table
    was once an integer texture, incomplete under LINEAR filtering: it read 0 and timed as one fetch)."""
    from explorer.dev import lookup_profile

    images: dict = {}
    result = lookup_profile.profile(size=24, repeats=1, images=images)
    assert set(result) == set(images) == set(lookup_profile.VARIANTS)
    # The sphere's cos theta at each pixel centre (rows from the bottom, as GL reads them).
    p = 2.0 * (np.arange(24) + 0.5) / 24 - 1.0
    r2 = p[None, :] ** 2 + p[:, None] ** 2
    inside = r2 < 0.99
    x = np.sqrt(1.0 - r2[inside]) * (lookup_profile.ENTRIES - 1)
    i = np.minimum(x.astype(int), lookup_profile.ENTRIES - 2)
    table = lookup_profile.lookup_table()[:, :3].astype(np.float64)
    expected = table[i] + (x - i)[:, None] * (table[i + 1] - table[i])
    for name in ("buffer2", "fetch2", "texture2", "block2", "linear32f", "linear16"):
        np.testing.assert_allclose(images[name][inside], expected, atol=2e-4, err_msg=name)
