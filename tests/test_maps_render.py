"""
Structure maps (``design --target-image``'s folders) drawn on the sphere: each texel its own Bragg mirror in the
textured (lit) and env views, GL against the numpy twin, the structure table read back, constant maps equal to the
homogeneous mirror, ``render --maps`` and its one-line errors for bad folders.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import one_line_error, run_cli, run_cli_process
from twins import Twins, assert_twins_equal, render_both

#: Not square, so that a swapped width and height or flipped rows show.
SIZE = (36, 28)
#: The maps' size (texels): not square either, and coarser than the image (each texel several pixels).
MAP_SIZE = (12, 10)


def write_map_folder(folder, maps: dict[str, np.ndarray], fixed: dict | None = None, model: str = "bragg_mirror") -> None:
    """A map folder as ``design --out-maps`` writes one: an EXR per map (the value in every channel) and ``params.json``."""
    from explorer.views.images import write_image

    folder.mkdir(parents=True, exist_ok=True)
    for name, image in maps.items():
        write_image(np.repeat(np.asarray(image, np.float32)[..., None], 3, axis=-1), folder / f"{name}.exr")
    params = {"material": model, "model": model, "fixed": {"n1": 1.0, "n2": 1.5, "nh": 0.0} if fixed is None else fixed,
              "free": list(maps), "angles_deg": [0.0], "seed": 0, "shape": list(next(iter(maps.values())).shape)}
    (folder / "params.json").write_text(json.dumps(params), encoding="utf-8")


def ramps(width: int = MAP_SIZE[0], height: int = MAP_SIZE[1]) -> dict[str, np.ndarray]:
    """Lambda across, delta down, N in two halves, one texel off the mask (NaN): every map shows."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    maps = {"Lambda": 250.0 + 300.0 * x / (width - 1), "delta": 0.3 + 0.4 * y / (height - 1), "N": np.where(x < width // 2, 8.0, 20.0)}
    maps["Lambda"][height // 2, width // 2] = np.nan
    return maps


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("maps") / "ramps"
    write_map_folder(path, ramps())
    return path


@pytest.fixture(scope="module")
def mirror():
    from explorer.materials.brd import load_material
    from explorer.resources import material_path

    return load_material(material_path("bragg_mirror"))


def map_texture(folder, mirror, **values):
    from explorer.views.surface_texture import MapTexture

    return MapTexture.from_folder(folder, mirror, mirror.resolve(values))


def test_structure_table_reads_back_every_texel(folder, mirror):
    """mapped_mirrors (the shader's mapped_mirror) gives each texel's maps and the fixed values; none off the mask."""
    from explorer.physics.bragg import mapped_mirrors

    texture, values = map_texture(folder, mirror)
    maps = ramps()
    index = np.arange(MAP_SIZE[0] * MAP_SIZE[1], dtype=np.float64)
    seen = np.zeros(index.shape, bool)
    for samples, m in mapped_mirrors(texture.structures, index):
        assert not (seen & samples).any()
        seen |= samples
        np.testing.assert_allclose(m.Lambda, maps["Lambda"].ravel()[samples], rtol=1e-6)
        np.testing.assert_allclose(m.delta, maps["delta"].ravel()[samples], rtol=1e-6)
        assert np.all(maps["N"].ravel()[samples] == m.N) and (m.n1, m.n2, m.nh) == (1.0, 1.5, None)
    assert not seen[MAP_SIZE[0] * (MAP_SIZE[1] // 2) + MAP_SIZE[0] // 2] and seen.sum() == index.size - 1


def test_constant_maps_are_the_homogeneous_mirror(tmp_path, mirror):
    """Maps holding the material's own Lambda, delta and N everywhere: the textured view of the plain mirror (numpy)."""
    from explorer.materials.models import model_for
    from explorer.views.render import render_numpy
    from explorer.views.surface_texture import BraggTexture

    write_map_folder(tmp_path, {"Lambda": np.full((4, 5), 420.0), "delta": np.full((4, 5), 0.35), "N": np.full((4, 5), 12.0)})
    texture, values = map_texture(tmp_path, mirror, method=4)
    plain = mirror.resolve({"method": 4, "Lambda": 420.0, "delta": 0.35, "N": 12})
    mapped = render_numpy(model_for(mirror, values), "textured", *SIZE, light=(20.0, 30.0), thickness=texture)
    homogeneous = render_numpy(model_for(mirror, plain), "textured", *SIZE, light=(20.0, 30.0), thickness=BraggTexture(np.zeros((2, 2), np.float32), "none"))
    assert np.abs(homogeneous).max() > 0.05
    np.testing.assert_allclose(mapped, homogeneous, atol=1e-6)


@pytest.mark.gl
@pytest.mark.parametrize("method", [3, 0])
def test_maps_textured_gl_equals_numpy(gl_renderer, folder, mirror, method):
    """The tabulated method (the improved approximation per texel) and the spectral reference, on the lit sphere."""
    texture, values = map_texture(folder, mirror, method=method)
    twins = render_both(gl_renderer, mirror, values, "textured", SIZE, light=(20.0, 30.0), thickness=texture)
    assert np.abs(twins.reference).max() > 0.05
    assert_twins_equal(twins, f"maps textured method {method}")
    # The maps show: the left and right halves (N 8 and 20) and the top and bottom (delta) differ.
    inside = np.abs(twins.reference).sum(axis=-1) > 0
    assert np.abs(twins.reference[inside]).std(axis=0).max() > 0.05


@pytest.mark.gl
@pytest.mark.parametrize("method", [0, 4])
def test_maps_under_an_environment_gl_equals_numpy(gl_renderer, folder, mirror, method):
    """
    The env view: each texel's Dirac under the environment (exact after one sample), against the exact integral; by the
    spectral reference and the improved approximation (the tabulated method's stand-in per texel; its fringe count takes
    the band edges' Bloch phase exactly, so float32 no longer moves its sub-boxes: explorer.physics.bragg.bloch_phase).
    """
    from explorer.gpu.env import render_env
    from explorer.materials.models import model_for
    from explorer.views.env import EnvironmentMap, env_integral_numpy

    texture, values = map_texture(folder, mirror, method=method)
    environment = EnvironmentMap.default()
    gl = render_env(mirror, values, *SIZE, environment=environment, spp=1, renderer=gl_renderer, surface=texture)
    reference = env_integral_numpy(model_for(mirror, values), environment, *SIZE, surface=texture)
    assert_twins_equal(Twins.of(gl, reference, "env"), f"maps env method {method}")
    plain = render_env(mirror, values, *SIZE, environment=environment, spp=1, renderer=gl_renderer)
    assert np.abs(plain - gl).max() > 0.02  # the maps show


# -- on a mesh, by its texture coordinates ------------------------------------------------------------------


def mesh_safe_pixels(mesh, size, texels) -> np.ndarray:
    """Pixels GL and numpy decide alike: away from triangle edges and overlaps, and from texel borders (nearest reads)."""
    from test_mesh import MESH_DEPTH_GAP, MESH_EDGE_MARGIN

    from explorer.views.mesh import rasterise

    surface = rasterise(mesh, size, size)
    scaled = surface.uvs * np.array(texels, np.float64)
    border = np.abs(scaled - np.rint(scaled)).min(axis=-1) < 1e-3
    return surface.covered & (surface.margin > MESH_EDGE_MARGIN) & (surface.depth_gap > MESH_DEPTH_GAP) & ~border


@pytest.mark.gl
@pytest.mark.parametrize("shape", ["cube", "torus"])
def test_maps_on_a_mesh_gl_equals_numpy(gl_renderer, folder, mirror, shape):
    """
    The maps carried by the mesh's texture coordinates (each cube face, the torus once around), GL against numpy, by
    the spectral reference (a mesh's float32 normals against float64 ones: the approximations' box choices may flip).
    """
    from explorer.gpu.mesh import render_mesh
    from explorer.materials.models import model_for
    from explorer.views.mesh import mesh_named
    from explorer.views.render import render_numpy

    mesh, size = mesh_named(shape), 48
    texture, values = map_texture(folder, mirror, method=0)
    gl = render_mesh(gl_renderer, mirror, values, "textured", mesh, size, size, light=(20.0, 30.0),
                     surface=texture.gl_arguments(mirror, values, size, size))
    reference = render_numpy(model_for(mirror, values), "textured", size, size, light=(20.0, 30.0), thickness=texture, mesh=mesh)
    safe = mesh_safe_pixels(mesh, size, MAP_SIZE)
    assert safe.sum() > 0.3 * (np.abs(reference).sum(axis=-1) > 0).sum()
    assert np.abs(reference[safe]).std(axis=0).max() > 0.05  # the maps show
    assert_twins_equal(Twins(gl, reference, safe, "textured", (20.0, 30.0)), f"maps on the {shape}")


@pytest.mark.gl
@pytest.mark.parametrize("method", [0, 4])
def test_maps_on_a_mesh_under_an_environment_gl_equals_numpy(gl_renderer, folder, mirror, method):
    from explorer.gpu.env import render_env
    from explorer.materials.models import model_for
    from explorer.views.env import EnvironmentMap, env_integral_numpy
    from explorer.views.mesh import torus

    mesh, size = torus(), 32
    texture, values = map_texture(folder, mirror, method=method)  # see the sphere's test above
    environment = EnvironmentMap.default()
    gl = render_env(mirror, values, size, size, environment=environment, spp=1, renderer=gl_renderer, surface=texture, mesh=mesh)
    reference = env_integral_numpy(model_for(mirror, values), environment, size, size, surface=texture, mesh=mesh)
    safe = mesh_safe_pixels(mesh, size, MAP_SIZE)
    assert_twins_equal(Twins(gl, reference, safe, "env", None), f"maps on the torus under the environment, method {method}")


def test_obj_texture_coordinates(tmp_path):
    """vt read (v from the top, as the sphere's planar v), a vertex per (position, coordinates); none unless every corner has one."""
    from explorer.views.mesh import MeshError, parse_obj

    quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
    mesh = parse_obj(quad + "f 1/1 2/2 3/3\nf 1/5 3/3 4/4\n")
    assert mesh.uvs is not None and len(mesh.positions) == 5  # vertex 1 twice: two coordinates
    by_corner = {tuple(p[:2]) + tuple(t) for p, t in zip(mesh.positions, mesh.uvs)}
    assert (0.0, 0.0, 0.0, 1.0) in by_corner and (0.0, 0.0, 0.5, 0.5) in by_corner and (1.0, 1.0, 1.0, 0.0) in by_corner
    assert parse_obj(quad + "f 1/1 2/2 3/3\nf 1 3 4\n").uvs is None
    with pytest.raises(MeshError, match=r"<obj>:5:"):
        parse_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt a b\nf 1/1 2/1 3/1\n")


# -- the command line --------------------------------------------------------------------------------------


def render_maps_by_both_engines(folder, tmp_path, *args, gl_view: str = "textured") -> dict[str, tuple[str, np.ndarray]]:
    """
    ``render --maps FOLDER ARGS`` to .npy by GL (in a subprocess: it draws; view ``gl_view``) and by ``--engine numpy``
    (in this process; the textured view): each engine's stdout and image. Each run must succeed.
    """
    shown = {}
    for engine, view in (("gl", gl_view), ("numpy", "textured")):
        out = tmp_path / f"{engine}.npy"
        run = (run_cli_process if engine == "gl" else run_cli)("render", "--maps", folder, "--view", view, "--engine", engine, *args,
                                                              "--out", out)
        assert run.returncode == 0, run.stderr
        shown[engine] = (run.stdout, np.load(out))
    return shown


@pytest.mark.gl
def test_cli_render_maps_gl_equals_numpy(folder, tmp_path):
    """``render --maps DIR`` (MATERIAL from params.json; lit = the textured view) by GL equals ``--engine numpy``."""
    shown = render_maps_by_both_engines(folder, tmp_path, "--size", "36x28", gl_view="lit")
    for stdout, _ in shown.values():
        assert "Lambda, delta, N from 12x10 maps" in stdout, stdout
    assert_twins_equal(Twins.of(shown["gl"][1], shown["numpy"][1], "textured"), "render --maps")


def test_cli_render_maps_bad_folders(folder, tmp_path):
    """Each bad folder: one line naming the file at fault, no image written."""
    import shutil

    def copy(name):
        path = tmp_path / name
        shutil.copytree(folder, path)
        return path

    corrupt = copy("corrupt")
    (corrupt / "delta.exr").write_bytes(b"not an EXR")
    sizes = copy("sizes")
    write_map_folder(sizes, {**ramps(), "delta": np.full((5, 6), 0.5)})
    stranger = copy("stranger")
    write_map_folder(stranger, {**ramps(), "k9": np.zeros(MAP_SIZE[::-1])})
    not_structure = copy("sigma")
    write_map_folder(not_structure, {**ramps(), "sigma": np.zeros(MAP_SIZE[::-1])})
    out_of_range = copy("range")
    write_map_folder(out_of_range, {**ramps(), "Lambda": np.full(MAP_SIZE[::-1], 3000.0)})
    film = copy("film")
    write_map_folder(film, ramps(), model="thin_film")
    no_params = copy("no_params")
    (no_params / "params.json").unlink()
    cases = {
        "missing folder": (tmp_path / "nowhere", "params.json"),
        "no params.json": (no_params, "no_params/params.json"),
        "corrupt map": (corrupt, "corrupt/delta.exr"),
        "sizes differ": (sizes, "sizes/delta.exr"),
        "no such parameter": (stranger, "stranger/k9.exr"),
        "not a structure parameter": (not_structure, "sigma/sigma.exr"),
        "out of range": (out_of_range, "range/Lambda.exr"),
        "another model": (film, "film/params.json"),
    }
    out = tmp_path / "out.npy"
    for name, (path, named) in cases.items():
        line = one_line_error(run_cli("render", "bragg_mirror", "--maps", path, "--view", "textured", "--engine", "numpy",
                                      "--size", "8", "--out", out))
        assert named in line, f"{name}: {line}"
        assert not out.exists(), name
    bare = tmp_path / "bare.obj"  # no texture coordinates
    bare.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", encoding="utf-8")
    for args, named in (((("--view", "sphere")), "--maps"), (("--mesh", bare, "--view", "lit"), "--mesh"),
                        (("--texture", "x.png"), "--maps")):
        line = one_line_error(run_cli("render", "bragg_mirror", "--maps", folder, "--engine", "numpy", *args, "--out", out))
        assert named in line, line


# -- the app -----------------------------------------------------------------------------------------------


def test_app_opens_a_map_folder(x_display, tmp_path, gl_renderer, folder, mirror):
    """
    ``open --maps DIR`` (the material from the folder): the Texture window shows each map with its range and draws the
    maps on the sphere, then on the torus, lit and under the environment: each image's mean RGB equals what ``render
    --maps DIR [--mesh torus] --view textured|env`` draws (:func:`explorer.rendering.render_material` and
    :func:`explorer.gpu.env.render_env`; the smooth mirror's Dirac is exact after one sample).
    """
    from test_app import run_session

    from explorer.gpu.env import render_env
    from explorer.rendering import render_material
    from explorer.views.env import ENVIRONMENTS
    from explorer.views.mesh import mesh_named

    actions = [{"set": {"method": 4}}, {"view_size": 64}, {"wait": 2}, {"focus": "Texture"}, {"wait": 3}, {"wait_for": "texture_view"},
               {"click": "texture_model_combo"}, {"wait": 2}, {"click": "texture_model:torus"}, {"wait": 3}, {"wait_for": "texture_view"},
               {"click": "texture_env"}, {"wait": 3}, {"wait_for": "texture_view"}, {"quit": True}]
    _, report = run_session(x_display, "bragg_mirror", actions, tmp_path, "--maps", str(folder))
    shown = report["texture_view"]
    assert "clicked texture_env" in report["script_log"], report["script_log"]
    assert shown is not None and shown.get("maps_folder") == str(folder), shown
    maps = ramps()
    assert set(shown["maps"]) == set(maps)
    for name, image in maps.items():
        assert shown["maps"][name]["size"] == list(MAP_SIZE)
        np.testing.assert_allclose([shown["maps"][name]["min"], shown["maps"][name]["max"]], [np.nanmin(image), np.nanmax(image)], rtol=1e-6)
    assert shown["model"] == "torus" and set(shown["shown"]) == {"textured:sphere", "textured:torus", "env:torus"}, shown
    values = mirror.resolve(shown["values"])
    assert (values["n1"], values["n2"], values["method"]) == (1.0, 1.5, 4)
    texture, _ = map_texture(folder, mirror, **shown["values"])
    width, height = shown["size"]
    torus = mesh_named("torus")
    theta = np.degrees(np.arccos(np.clip(shown["light"][2], -1.0, 1.0)))
    phi = np.degrees(np.arctan2(shown["light"][1], shown["light"][0]))
    images = {f"textured:{name}": render_material(mirror, values, "textured", width, height, "gl", light=(theta, phi), thickness=texture,
                                                  mesh=mesh, renderer=gl_renderer)
              for name, mesh in (("sphere", None), ("torus", torus))}
    images["env:torus"] = render_env(mirror, values, width, height, environment=ENVIRONMENTS[shown["environment"]](), spp=1,
                                     renderer=gl_renderer, surface=texture, mesh=torus)
    for name, image in images.items():
        assert np.abs(image).max() > 0.05, name
        np.testing.assert_allclose(shown["shown"][name], image.reshape(-1, 3).mean(axis=0), rtol=1e-3, atol=1e-5, err_msg=name)
    assert np.abs(np.subtract(shown["shown"]["textured:torus"], shown["shown"]["env:torus"])).max() > 1e-3


def test_open_with_a_bad_map_folder_is_one_line(tmp_path):
    line = one_line_error(run_cli("open", "bragg_mirror", "--maps", tmp_path / "nowhere"))
    assert "nowhere/params.json" in line, line



# -- the flat image (--theta): one pixel a texel ------------------------------------------------------------


@pytest.mark.gl
@pytest.mark.parametrize("method", [0, 4])
def test_flat_maps_gl_equals_numpy(gl_renderer, folder, mirror, method):
    """``shaders/views/flat/textured.glsl`` against its twin (flat_numpy), at 0 and 45 degrees; off the mask black."""
    from explorer.materials.models import model_for
    from explorer.views.maps import flat_gl, flat_numpy

    texture, values = map_texture(folder, mirror, method=method)
    for theta in (0.0, 45.0):
        gl = flat_gl(gl_renderer, mirror, values, texture, theta)
        reference = flat_numpy(model_for(mirror, values), texture, theta)
        assert gl.shape == reference.shape == (MAP_SIZE[1], MAP_SIZE[0], 3)
        assert np.abs(reference).max() > 0.3 and np.all(reference[MAP_SIZE[1] // 2, MAP_SIZE[0] // 2] == 0.0)
        assert_twins_equal(Twins(gl, reference, np.ones(gl.shape[:2], bool), "gradient"), f"flat maps method {method} at {theta:g}")


@pytest.mark.gl
def test_cli_flat_maps_gl_is_near_the_converged_colours(folder, tmp_path):
    """``render --maps --theta`` by GL at the spectral reference: within 1e-2 of ``--engine numpy``'s converged colours."""
    shown = render_maps_by_both_engines(folder, tmp_path, "--set", "method=0", "--theta", "30")
    images = {engine: image for engine, (_, image) in shown.items()}
    assert images["gl"].shape == (MAP_SIZE[1], MAP_SIZE[0], 3)
    assert np.abs(images["gl"] - images["numpy"]).max() < 1e-2
