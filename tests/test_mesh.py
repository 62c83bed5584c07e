"""
Meshes in the lit and env views (``render --view lit|env --mesh``): OBJ files (normals given, computed,
malformed), the generated shapes, the numpy rasteriser against a sphere's closed form, the GL pass and
views against their numpy twins, and the CLI.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli, run_cli_process
from twins import BRDF_TOLERANCE, Twins, assert_twins_equal

from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.views.mesh import (
    FILL, Mesh, MeshError, cube, mesh_named, parse_obj, rasterise, surface_frame, teapot, torus, vertex_normals,
)
from explorer.views.render import render_numpy

GGX = REPO_ROOT / "shaders" / "ggx_schlick.brd"
#: Pixels compared between GL and numpy: the smallest barycentric coordinate of the pixel's triangle above
#: this (GL's and numpy's coverage tests agree away from an edge), and the next surface behind at least this
#: much deeper (not where two surfaces intersect: the teapot's spout and handle enter its body).
MESH_EDGE_MARGIN = 1e-3
MESH_DEPTH_GAP = 1e-3
#: Of the pixels either side covers, at most this fraction may be covered by one side only (edges, float32).
COVERAGE_MISMATCH = 0.01


def uv_sphere(rings: int = 64, segments: int = 128) -> Mesh:
    """A unit sphere of quads (triangles), its exact normals: the sphere view's surface as a mesh."""
    theta = np.linspace(0.0, np.pi, rings + 1)
    phi = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    T, P = np.meshgrid(theta, phi, indexing="ij")
    positions = np.stack([np.sin(T) * np.cos(P), np.cos(T), np.sin(T) * np.sin(P)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a = i * (segments + 1) + j
    b, c, d = a + segments + 1, a + segments + 2, a + 1
    triangles = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return Mesh(positions, positions.copy(), triangles, "sphere")


# -- OBJ files ----------------------------------------------------------------------------------------


def test_obj_with_normals_keeps_them_and_splits_polygons():
    text = """# a quad and a triangle
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vn 0 0 2
vn 1 0 0
o quad
f 1//1 2//1 3//1 4//1
f -4/1/2 -3/1/2 -2/1/2
"""
    mesh = parse_obj(text, "quad.obj")
    assert mesh.triangles.shape == (3, 3)
    corners = mesh.normals[mesh.triangles]
    np.testing.assert_allclose(corners[:2], np.broadcast_to([0, 0, 1], (2, 3, 3)))  # normalised
    np.testing.assert_allclose(corners[2], np.broadcast_to([1, 0, 0], (3, 3)))
    np.testing.assert_allclose(mesh.positions[mesh.triangles[2]], [[0, 0, 0], [1, 0, 0], [1, 1, 0]])


def test_obj_without_normals_gets_area_weighted_ones():
    """An octahedron's 6 corners, each shared by 4 equal faces: each computed normal is its corner's direction."""
    corners = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    faces = []
    for sx in (0, 1):
        for sy in (2, 3):
            for sz in (4, 5):
                a, b, c = sx + 1, sy + 1, sz + 1
                outward = np.dot(np.cross(np.subtract(corners[sy], corners[sx]), np.subtract(corners[sz], corners[sx])),
                                 np.add(np.add(corners[sx], corners[sy]), corners[sz])) > 0
                faces.append(f"{a} {b} {c}" if outward else f"{a} {c} {b}")
    text = "".join(f"v {x} {y} {z}\n" for x, y, z in corners) + "".join(f"f {f}\n" for f in faces)
    mesh = parse_obj(text)
    np.testing.assert_allclose(mesh.normals, mesh.positions, atol=1e-12)
    np.testing.assert_allclose(vertex_normals(mesh.positions, mesh.triangles), mesh.normals)


MALFORMED = {
    "not a number": ("v 0 0 0\nv 1 zero 0\n", 2, "not a number"),
    "index out of range": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, "index 4 is out of range"),
    "index zero": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 4, "index 0 is out of range"),
    "two vertices": ("v 0 0 0\nv 1 0 0\n\nf 1 2\n", 4, "at least 3 vertices"),
    "bad reference": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/2/3/4 2 3\n", 4, "not v, v/vt, v//vn or v/vt/vn"),
    "normal out of range": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n", 5, "normal index 2"),
    "short vertex": ("v 0 0\n", 1, "needs 3 numbers"),
    "non-finite": ("v 0 nan 0\n", 1, "non-finite"),
    "no faces": ("v 0 0 0\n", None, "no faces"),
}


@pytest.mark.parametrize("case", list(MALFORMED))
def test_malformed_obj_is_one_line_with_its_line(tmp_path, case):
    text, line, message = MALFORMED[case]
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(MeshError, match=message) as error:
        mesh_named(path)
    assert error.value.line == line
    where = f"{path}:{line}: " if line else f"{path}: "
    run = run_cli("render", GGX, "--view", "lit", "--mesh", path, "--out", tmp_path / "x.png")
    assert one_line_error(run).endswith(where + str(error.value.message))


def test_mesh_argument_errors(tmp_path):
    out = tmp_path / "x.png"
    assert "no such mesh file, nor a shape (teapot, cube, torus)" in one_line_error(run_cli("render", GGX, "--view", "lit", "--mesh", "sphere", "--out", out))
    assert "--mesh" in one_line_error(run_cli("render", GGX, "--view", "slice", "--mesh", "cube", "--out", out))
    assert "cannot read mesh file" in one_line_error(run_cli("render", GGX, "--view", "lit", "--mesh", tmp_path / "none.obj", "--out", out))
    binary = tmp_path / "b.obj"
    binary.write_bytes(b"\0\1\2")
    assert "binary data (3 bytes)" in one_line_error(run_cli("render", GGX, "--view", "lit", "--mesh", binary, "--out", out))


# -- the shapes ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("make", [teapot, cube, torus])
def test_shapes_are_closed_outward_and_wound_as_their_normals(make):
    mesh = make()
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=-1), 1.0, atol=1e-9)
    a, b, c = (mesh.positions[mesh.triangles[:, k]] for k in range(3))
    face = np.cross(b - a, c - a)
    big = np.linalg.norm(face, axis=-1) > 1e-9
    agree = np.sum(face * mesh.normals[mesh.triangles].sum(axis=1), axis=-1)[big] > 0
    assert agree.mean() > 0.99
    # Divergence theorem: a closed, outward surface encloses a positive volume sum(a . (b x c)) / 6.
    volume = np.sum(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6.0
    expected = {"cube": 1.0, "torus": 2 * np.pi ** 2 * 1.0 * 0.4 ** 2}.get(mesh.name)
    assert volume > 0
    if expected is not None:
        assert volume == pytest.approx(expected, rel=0.01)


def test_teapot_is_upright():
    """The lid's knob on top (+y), the spout toward +x, the handle toward -x (Newell's data turned to y-up)."""
    p = teapot().positions
    assert p[:, 1].argmax() in np.nonzero(np.hypot(p[:, 0], p[:, 2]) < 0.25)[0]
    assert p[:, 0].max() > 3.3 and p[:, 0].min() < -2.9


# -- the numpy rasteriser -----------------------------------------------------------------------------


def test_rasterised_sphere_is_the_sphere_view():
    """A sphere mesh of radius FILL: its pixels' normals are the sphere view's, (x, y, sqrt(1 - r^2)) / FILL."""
    size = 96
    surface = rasterise(uv_sphere(), size, size)
    x = 2.0 * (np.arange(size) + 0.5) / size - 1.0
    X, Y = np.meshgrid(x, -x)
    r2 = (X * X + Y * Y) / FILL ** 2
    inner = r2 < 0.95
    outside = r2 > 1.02
    assert surface.covered[inner].all() and not surface.covered[outside].any()
    N = surface_frame(surface.normals[inner])[0].astype(np.float64)
    expected = np.stack([X[inner] / FILL, Y[inner] / FILL, np.sqrt(1.0 - r2[inner])], axis=-1)
    angle = np.degrees(np.arccos(np.clip(np.sum(N * expected, axis=-1), -1, 1)))
    assert angle.max() < 1.0, angle.max()


# -- GL against numpy ---------------------------------------------------------------------------------


def mesh_twins(renderer, material, values, mesh, size, light=(30.0, 120.0)) -> Twins:
    from explorer.gpu.mesh import mesh_normals, render_mesh

    gl = render_mesh(renderer, material, values, "lit", mesh, size, size, light=light)
    reference = render_numpy(model_for(material, values), "lit", size, size, light=light, mesh=mesh)
    surface = rasterise(mesh, size, size)
    gl_covered = mesh_normals(renderer, mesh, size, size)[::-1, :, 3] > 0
    either = gl_covered | surface.covered
    assert (gl_covered != surface.covered).sum() <= COVERAGE_MISMATCH * either.sum()
    safe = surface.covered & gl_covered & (surface.margin > MESH_EDGE_MARGIN) & (surface.depth_gap > MESH_DEPTH_GAP)
    assert safe.sum() > 0.5 * either.sum()
    np.testing.assert_array_equal(gl[~either], 0.0)
    return Twins(gl, reference, safe, "lit", light)


@pytest.mark.gl
@pytest.mark.parametrize("make", [teapot, cube, torus])
def test_gl_mesh_lit_view_equals_numpy(gl_renderer, make):
    material = load_material(GGX)
    values = material.resolve({"alpha": 0.3, "F0": 0.9})
    twins = mesh_twins(gl_renderer, material, values, make(), 96)
    assert np.abs(twins.reference).max() > 0.02
    assert_twins_equal(twins, f"{make.__name__} lit", BRDF_TOLERANCE)


@pytest.mark.gl
def test_gl_mesh_env_view_converges_to_the_numpy_integral(gl_renderer):
    from test_env import HANDFUL_MAX_Z, progressive_mean, smooth_environment

    from explorer.views.env import env_integral_numpy

    material = load_material(GGX)
    values = material.resolve({"alpha": 0.4, "F0": 0.8})
    mesh, size = torus(), 24
    surface = rasterise(mesh, size, size)
    safe = np.argwhere(surface.covered & (surface.margin > 0.05) & (surface.depth_gap > 0.05))
    pixels = safe[np.linspace(0, len(safe) - 1, 10).astype(int)]
    environment = smooth_environment()
    mean, se = progressive_mean(gl_renderer, material, values, environment, size, 2048, mesh=mesh)
    exact = env_integral_numpy(model_for(material, values), environment, size, size, pixels, mesh=mesh)
    rows, columns = pixels.T
    z = (mean[rows, columns] - exact) / np.maximum(se[rows, columns], 1e-30)
    assert np.abs(exact).max() > 0.05
    assert np.abs(z).max() <= HANDFUL_MAX_Z, f"z = {z.round(2).tolist()}"
    assert not mean[~(surface.covered | np.roll(surface.covered, 1, 0) | np.roll(surface.covered, 1, 1))].any()


# -- the CLI ------------------------------------------------------------------------------------------


@pytest.mark.gl
def test_cli_mesh_render_gl_and_numpy(tmp_path):
    gl, numpy_out = tmp_path / "gl.npy", tmp_path / "numpy.npy"
    run = run_cli_process("render", GGX, "--view", "lit", "--mesh", "teapot", "--size", "64", "--set", "F0=0.9", "--out", gl)
    assert run.returncode == 0, run.stderr
    run = run_cli("render", GGX, "--view", "lit", "--mesh", "teapot", "--size", "64", "--set", "F0=0.9", "--engine", "numpy", "--out", numpy_out)
    assert run.returncode == 0, run.stderr
    surface = rasterise(teapot(), 64, 64)
    safe = surface.covered & (surface.margin > MESH_EDGE_MARGIN) & (surface.depth_gap > MESH_DEPTH_GAP)
    assert_twins_equal(Twins(np.load(gl), np.load(numpy_out), safe, "lit"), "teapot via the CLI", BRDF_TOLERANCE)


@pytest.mark.gl
def test_the_normals_pass_leaves_no_deleted_framebuffer_bound(gl_renderer):
    """moderngl rebinds its last bound framebuffer after making one: the pass's own, released, was a GL error."""
    from explorer.gpu.mesh import mesh_normals

    ctx = gl_renderer.ctx
    for _ in range(8):  # clear what earlier tests left (glGetError clears one flag a call)
        if ctx.error == "GL_NO_ERROR":
            break
    assert ctx.error == "GL_NO_ERROR"
    mesh_normals(gl_renderer, cube(), 8, 8)
    assert ctx.error == "GL_NO_ERROR", "pass"
    framebuffer = gl_renderer.target(4, 4)
    assert ctx.error == "GL_NO_ERROR", "target"
    gl_renderer.resources.release(framebuffer)
    assert ctx.error == "GL_NO_ERROR"
