"""
Structure maps on a thin film (``design thin_film --target-image ... --out-maps DIR``): each texel its own film, as the
film's twin declares (``THIN_FILM_MAPS``), in the textured (lit) and env views, on the sphere and on a mesh, GL against
the numpy twin; constant maps equal to the plain film; ``render thin_film --maps`` and the one line for a material that
declares no maps.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli
from test_maps_render import mesh_safe_pixels, render_maps_by_both_engines, write_map_folder
from twins import Twins, assert_twins_equal, render_both

FILM = REPO_ROOT / "shaders" / "thin_film.brd"
#: Not square, so that a swapped width and height or flipped rows show.
SIZE = (36, 28)
#: The maps' size (texels), coarser than the image and not square.
MAP_SIZE = (12, 10)
#: The film's fixed values a folder holds (as design writes them: the indices, d painted).
FIXED = {"eta1": 1.0, "eta3": 1.5, "kappa3": 0.0}


def film_ramps(width: int = MAP_SIZE[0], height: int = MAP_SIZE[1]) -> dict[str, np.ndarray]:
    """d across (a few fringes), eta2 in two halves down, one texel off the mask (NaN): every map shows."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    maps = {"d": 150.0 + 500.0 * x / (width - 1), "eta2": np.where(y < height // 2, 1.33, 2.0)}
    maps["d"][height // 2, width // 2] = np.nan
    return maps


@pytest.fixture(scope="module")
def film():
    from explorer.materials.brd import load_material

    return load_material(FILM)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("film_maps") / "ramps"
    write_map_folder(path, film_ramps(), FIXED, model="thin_film")
    return path


def hue_spread(image: np.ndarray) -> float:
    """The largest standard deviation of the chromaticities ``rgb / (r + g + b)`` over the lit pixels (the films' colours vary)."""
    rgb = np.asarray(image, np.float64).reshape(-1, 3)
    lit = rgb.sum(axis=-1) > 1e-4
    return float((rgb[lit] / rgb[lit].sum(axis=-1, keepdims=True)).std(axis=0).max())


def map_texture(folder, film, **values):
    from explorer.views.surface_texture import MapTexture

    return MapTexture.from_folder(folder, film, film.resolve(values))


def test_the_film_declares_its_maps_and_the_table_holds_each_texel(folder, film):
    from explorer.materials.twins import capabilities_of
    from explorer.physics.structure_maps import structure_texels

    fields = capabilities_of(film).maps.fields
    assert set(fields) >= {"d", "eta2"}
    texture, values = map_texture(folder, film)
    index = np.arange(MAP_SIZE[0] * MAP_SIZE[1], dtype=np.float64)
    inside, slots = structure_texels(texture.structures, index)
    maps = film_ramps()
    expected_inside = np.isfinite(maps["d"]).ravel()
    np.testing.assert_array_equal(inside, expected_inside)
    for k, name in enumerate(fields):
        expected = maps[name].ravel() if name in maps else np.full(index.size, FIXED[name])
        np.testing.assert_allclose(slots[inside, k], expected[inside], rtol=1e-6, err_msg=name)


def test_constant_film_maps_are_the_plain_film(tmp_path, film):
    """Maps of one film everywhere: the textured view is the lit view of that film (numpy)."""
    from explorer.materials.models import model_for
    from explorer.views.render import render_numpy

    write_map_folder(tmp_path, {"d": np.full((4, 5), 420.0), "eta2": np.full((4, 5), 1.6)}, FIXED, model="thin_film")
    texture, values = map_texture(tmp_path, film, method=3, alpha=0.3)
    plain = film.resolve({"method": 3, "alpha": 0.3, "d": 420.0, "eta2": 1.6, **FIXED})
    mapped = render_numpy(model_for(film, values), "textured", *SIZE, light=(20.0, 30.0), thickness=texture)
    lit = render_numpy(model_for(film, plain), "lit", *SIZE, light=(20.0, 30.0))
    assert np.abs(lit).max() > 0.05
    np.testing.assert_allclose(mapped, lit, atol=1e-6)


@pytest.mark.gl
@pytest.mark.parametrize("method", [0, 3, 5])
def test_film_maps_textured_gl_equals_numpy(gl_renderer, folder, film, method):
    """The reference, a Fourier method and naive RGB, each texel its own film, on the lit sphere."""
    texture, values = map_texture(folder, film, method=method, alpha=0.3)
    twins = render_both(gl_renderer, film, values, "textured", SIZE, light=(20.0, 30.0), thickness=texture)
    assert np.abs(twins.reference).max() > 0.02
    assert_twins_equal(twins, f"film maps textured method {method}")
    assert hue_spread(twins.reference) > 0.05  # the maps show


@pytest.mark.gl
def test_film_maps_on_a_mesh_gl_equals_numpy(gl_renderer, folder, film):
    from explorer.gpu.mesh import render_mesh
    from explorer.materials.models import model_for
    from explorer.views.mesh import mesh_named
    from explorer.views.render import render_numpy

    mesh, size = mesh_named("torus"), 40
    texture, values = map_texture(folder, film, method=3, alpha=0.3)
    gl = render_mesh(gl_renderer, film, values, "textured", mesh, size, size, light=(20.0, 30.0),
                     surface=texture.gl_arguments(film, values, size, size))
    reference = render_numpy(model_for(film, values), "textured", size, size, light=(20.0, 30.0), thickness=texture, mesh=mesh)
    safe = mesh_safe_pixels(mesh, size, MAP_SIZE)
    assert safe.sum() > 0.3 * (np.abs(reference).sum(axis=-1) > 0).sum()
    assert hue_spread(np.where(safe[..., None], reference, 0.0)) > 0.05
    assert_twins_equal(Twins(gl, reference, safe, "textured", (20.0, 30.0)), "film maps on the torus")


@pytest.mark.gl
def test_film_maps_under_an_environment_gl_equals_numpy(gl_renderer, folder, film):
    """The env view of the rough film's maps: the GPU's Monte Carlo mean within its standard errors of the exact integral."""
    from explorer.gpu.env import ProgressiveEnvRender
    from explorer.materials.models import model_for
    from explorer.views.env import env_integral_numpy
    from explorer.views.twin_check import env_pixels, smooth_environment

    size = 12
    texture, values = map_texture(folder, film, method=5, alpha=0.3)
    environment = smooth_environment()
    render = ProgressiveEnvRender(gl_renderer, film, values, environment, size, size, surface=texture)
    try:
        render.step(512)
        gl, error = render.image(), render.standard_error()
    finally:
        render.release()
    compared = env_pixels(size, size)
    pixels = np.argwhere(compared)
    exact = env_integral_numpy(model_for(film, values), environment, size, size, surface=texture, pixels=pixels)
    reference = np.zeros((size, size, 3))
    reference[compared] = exact
    assert np.abs(exact).max() > 0.01
    plain = env_integral_numpy(model_for(film, film.resolve({**values, "d": 400.0})), environment, size, size, pixels=pixels)
    assert np.abs(plain - exact).max() > 0.005  # the maps show
    assert_twins_equal(Twins(gl, reference, compared, "env", None, error), "film maps under the environment")


# -- the command line --------------------------------------------------------------------------------------


@pytest.mark.gl
def test_cli_render_film_maps_gl_equals_numpy(folder, tmp_path):
    """``render --maps DIR`` of a film's folder (MATERIAL from params.json) by GL equals ``--engine numpy``."""
    shown = render_maps_by_both_engines(folder, tmp_path, "--set", "method=3", "--size", "36x28")
    for stdout, _ in shown.values():
        assert "d, eta2 from 12x10 maps" in stdout, stdout
    assert_twins_equal(Twins.of(shown["gl"][1], shown["numpy"][1], "textured"), "render --maps (film)")


def test_cli_a_material_without_maps_is_one_line(folder, tmp_path):
    """A material whose twin declares no structure maps: one line naming the folder's parameters, no image."""
    import shutil

    layer = tmp_path / "layer"
    shutil.copytree(folder, layer)
    write_map_folder(layer, {"Lambda": np.full((3, 4), 400.0)}, {}, model="bragg_layer")
    out = tmp_path / "out.npy"
    line = one_line_error(run_cli("render", "bragg_layer", "--maps", layer, "--engine", "numpy", "--size", "8", "--out", out))
    assert "layer/params.json" in line and "declares none" in line, line
    assert not out.exists()


@pytest.mark.gl
def test_film_flat_maps_gl_equals_numpy(gl_renderer, folder, film):
    """The flat image (``render --maps --theta --engine gl``) of a film's maps against its twin."""
    from explorer.materials.models import model_for
    from explorer.views.maps import flat_gl, flat_numpy

    texture, values = map_texture(folder, film, method=3)
    gl = flat_gl(gl_renderer, film, values, texture, 30.0)
    reference = flat_numpy(model_for(film, values), texture, 30.0)
    assert hue_spread(reference) > 0.05
    assert_twins_equal(Twins(gl, reference, np.ones(gl.shape[:2], bool), "gradient"), "film flat maps")


def test_app_opens_a_film_map_folder(x_display, tmp_path, gl_renderer, folder, film):
    """
    ``open FILM --maps DIR``: the Texture window shows the film's maps (``d`` and ``eta2``, each with its size and
    range) and draws them on the sphere; the image's mean RGB equals what ``render --maps DIR --view textured`` draws.
    """
    from test_app import run_session

    from explorer.rendering import render_material

    actions = [{"view_size": 64}, {"wait": 2}, {"focus": "Texture"}, {"wait": 3}, {"wait_for": "texture_view"}, {"quit": True}]
    _, report = run_session(x_display, FILM, actions, tmp_path, "--maps", str(folder))
    shown = report["texture_view"]
    assert shown is not None and shown.get("maps_folder") == str(folder), shown
    maps = film_ramps()
    assert set(shown["maps"]) == set(maps)
    for name, image in maps.items():
        assert shown["maps"][name]["size"] == list(MAP_SIZE)
        np.testing.assert_allclose([shown["maps"][name]["min"], shown["maps"][name]["max"]], [np.nanmin(image), np.nanmax(image)], rtol=1e-6)
    assert set(shown["shown"]) == {"textured:sphere"}, shown
    values = film.resolve(shown["values"])
    texture, _ = map_texture(folder, film, **shown["values"])
    width, height = shown["size"]
    theta = np.degrees(np.arccos(np.clip(shown["light"][2], -1.0, 1.0)))
    phi = np.degrees(np.arctan2(shown["light"][1], shown["light"][0]))
    image = render_material(film, values, "textured", width, height, "gl", light=(theta, phi), thickness=texture, renderer=gl_renderer)
    assert hue_spread(image) > 0.01
    np.testing.assert_allclose(shown["shown"]["textured:sphere"], image.reshape(-1, 3).mean(axis=0), rtol=1e-3, atol=1e-5)
