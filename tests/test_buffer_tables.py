"""
Model tables as buffer textures (issue 22 item 3): made and released by GLResources; the tabulated methods'
tables packed one interval a texel (explorer.gpu.packed_tables, a ``usamplerBuffer``), read by the GLSL
twin as numpy reads them, and within the packing's rounding of the 2D-texture path, in every view and draw path.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT
from explorer.gpu import Renderer
from explorer.gpu.context import GLLimitError
from explorer.gpu.packed_tables import PACKED_CODE_MAX, pack_table_intervals, packed_tabulated_rgb, unpack_table_intervals
from explorer.gpu.resources import GL_UNSIGNED_INT_SAMPLER_BUFFER, BufferTexture
from explorer.physics import bragg
from explorer.views.geometry import view_cos_theta
from explorer.materials.brd import load_material

MIRROR = REPO_ROOT / "shaders" / "bragg_mirror.brd"
LAYER = REPO_ROOT / "shaders" / "bragg_layer.brd"


@pytest.fixture(scope="module")
def texture_renderer(gl_renderer):
    """A renderer on the same context that uploads 2D textures (the path a .brdf export keeps)."""
    renderer = Renderer(gl_renderer.ctx)
    renderer.buffer_tables = False
    yield renderer
    renderer.resources.close()


@pytest.mark.gl
def test_this_gl_makes_buffer_tables(gl_renderer):
    # llvmpipe (GL 4.5) and PyOpenGL (a dependency): the tabulated path the bench measures.
    assert gl_renderer.buffer_tables
    program = gl_renderer.program(load_material(MIRROR), "sphere", {"method": 3})
    assert program["bragg_table"].gl_type == GL_UNSIGNED_INT_SAMPLER_BUFFER


@pytest.mark.gl
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
    # Another kind of the same size (a 2D texture, uint32 texels) is replaced, not written into.
    flat = resources.replace(longer, np.ones((1, 7, 4), np.float32), origin="table")
    assert not isinstance(flat, BufferTexture) and longer.glo == 0
    packed = resources.replace(flat, np.arange(28, dtype=np.uint32).reshape(1, 7, 4), buffer=True, dtype="u4")
    assert isinstance(packed, BufferTexture) and packed.dtype == "u4" and resources.owned() == owned + 1
    np.testing.assert_array_equal(np.frombuffer(packed.buffer.read(), np.uint32), np.arange(28))
    resources.release(packed)
    assert resources.owned() == owned and gl_renderer.ctx.error == "GL_NO_ERROR"


def test_packing_rounds_each_entry_to_half_a_code_of_its_interval():
    rng = np.random.default_rng(7)
    tables = [rng.normal(0.3, 0.6, (n, 3)) for n in (2, 3, 65, 513)]
    tables += [np.zeros((4, 3)), np.array([[0.2, -0.1, 1e-9]]), np.r_[np.zeros((3, 3)), np.full((2, 3), -1.3)]]
    for table in tables:
        texels = pack_table_intervals(table)
        start, end = unpack_table_intervals(texels)
        ends = (table[:-1], table[1:]) if len(table) > 1 else (table, table)
        largest = np.maximum(np.abs(ends[0]).max(axis=1), np.abs(ends[1]).max(axis=1))[:, None]
        for decoded, entry in zip((start, end), ends):
            assert np.all(np.abs(decoded - entry) <= largest * (0.5 / PACKED_CODE_MAX + 1e-7))
        # The lookup: linear between the decoded ends, entry k at cos theta = k / (n - 1), as the float table's.
        cos_theta = np.linspace(0.0, 1.0, 997)
        expected = bragg.tabulated_rgb(np.asarray(table, np.float64), cos_theta) if len(table) > 1 else np.broadcast_to(table, (997, 3))
        assert np.abs(packed_tabulated_rgb(texels, cos_theta) - expected).max() <= np.abs(table).max() * 0.6 / PACKED_CODE_MAX
    with pytest.raises(ValueError, match="finite"):
        pack_table_intervals(np.array([[0.1, np.nan, 0.2], [0.0, 0.0, 0.0]]))


@pytest.mark.gl
def test_a_table_beyond_the_buffer_limit_is_a_one_line_error(gl_renderer):
    limit = gl_renderer.limits.max_texture_buffer_texels
    with pytest.raises(GLLimitError) as caught:
        gl_renderer.resources.texture(np.zeros((1, limit + 1, 4), np.float32), buffer=True, origin="bragg_table")
    assert str(caught.value).startswith("bragg_table: ") and "\n" not in str(caught.value)


@pytest.mark.gl
@pytest.mark.parametrize("view", ["sphere", "gradient", "lit", "scatter"])
def test_tabulated_mirror_reads_the_packed_table_as_the_2d_texture_within_its_rounding(gl_renderer, texture_renderer, view):
    material = load_material(MIRROR)
    values = material.resolve({"method": 3, "Lambda": 560, "N": 30})
    packed = gl_renderer.render(material, values, view, 48, 32)
    from_texture = texture_renderer.render(material, values, view, 48, 32)
    assert np.abs(from_texture).max() > 0.05 and gl_renderer.ctx.error == "GL_NO_ERROR"
    # Entries rounded to half a code of their interval's largest |channel| (<= 1.53e-5 of it); the BRDF
    # views multiply the reflectance by their lobe.
    np.testing.assert_allclose(packed, from_texture, rtol=0, atol=2e-5 * np.abs(from_texture).max())


@pytest.mark.gl
def test_gl_packed_lookup_is_its_numpy_twin(gl_renderer):
    """The gradient view shows the reflectance at each pixel's cos theta: GLSL's packed_tabulated_rgb there
    equals explorer.gpu.packed_tables.packed_tabulated_rgb of the same texels, to float32 rounding."""
    material = load_material(MIRROR)
    values = material.resolve({"method": 3, "Lambda": 430, "N": 12, "n2": 1.9})
    image = gl_renderer.render(material, values, "gradient", 300, 4)
    model = gl_renderer.models.entry(material, values)[1].model
    cos_theta, _ = view_cos_theta("gradient", 300, 4)
    expected = packed_tabulated_rgb(pack_table_intervals(model.table), cos_theta)
    np.testing.assert_allclose(image, expected, rtol=0, atol=2e-6)


@pytest.mark.gl
@pytest.mark.parametrize("method", [1, 3])
def test_layer_with_a_buffer_table_beside_2d_textures(gl_renderer, texture_renderer, method):
    """The lit layer binds the CMF texture (sampler2D) and its T_rgb table (samplerBuffer): units apart."""
    material = load_material(LAYER)
    values = material.resolve({"method": method})
    from_buffer = gl_renderer.render(material, values, "lit", 32, 32)
    assert gl_renderer.ctx.error == "GL_NO_ERROR"
    from_texture = texture_renderer.render(material, values, "lit", 32, 32)
    np.testing.assert_allclose(from_buffer, from_texture, rtol=0, atol=2e-5 * np.abs(from_texture).max())


@pytest.mark.gl
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


@pytest.mark.gl
def test_lookup_profile_reads_every_table_it_times(gl_renderer):
    """explorer.dev.lookup_profile's exact variants show the table's linear interpolation (its 16-bit table
    was once an integer texture, incomplete under LINEAR filtering: it read 0 and timed as one fetch)."""
    from explorer.dev import lookup_profile

    images: dict = {}
    result = lookup_profile.profile(size=24, repeats=1, images=images, ctx=gl_renderer.ctx)
    assert set(result) == set(images) == set(lookup_profile.VARIANTS)
    # The sphere's cos theta at each pixel centre (rows from the bottom, as GL reads them).
    p = 2.0 * (np.arange(24) + 0.5) / 24 - 1.0
    r2 = p[None, :] ** 2 + p[:, None] ** 2
    inside = r2 < 0.99
    x = np.sqrt(1.0 - r2[inside]) * (lookup_profile.ENTRIES - 1)
    i = np.minimum(x.astype(int), lookup_profile.ENTRIES - 2)
    table = lookup_profile.lookup_table()[:, :3].astype(np.float64)
    expected = table[i] + (x - i)[:, None] * (table[i + 1] - table[i])
    for name in ("packed", "buffer2", "fetch2", "texture2", "block2", "linear32f", "linear16"):
        np.testing.assert_allclose(images[name][inside], expected, atol=2e-4, err_msg=name)
