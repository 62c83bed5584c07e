"""
Meshes for the ``lit`` and ``env`` views (``render --view lit|env --mesh FILE.obj|teapot|cube|torus``), in
numpy (no GL): Wavefront OBJ files, the shapes generated here (the Utah teapot from its Bézier patches,
``shaders/meshes/teapot.bpt``; a cube; a torus), the view's camera, and the numpy rasteriser of a mesh's
normals, the twin of the GL pass of :mod:`explorer.gpu.mesh` (``shaders/views/mesh/``).

The camera is the sphere views': orthographic along ``-z``, ``V = (0, 0, 1)``, the image spanning
``[-1, 1]`` on its shorter side. A mesh is centred on its bounding box, scaled so that its farthest
vertex lies at :data:`FILL` of that half-width, and turned for a three-quarter view (:data:`YAW`, then
:data:`PITCH`). Each pixel shows the nearest surface's interpolated normal ``N`` and BRDF Explorer's
frame around it (``X = normalize(cross((0, 1, 0), N))``, ``Y = cross(N, X)``; ``X = (1, 0, 0)`` where
``N`` is vertical), so that a pixel is evaluated exactly as the sphere's pixel of the same normal.

An OBJ file: ``v x y z [w]``, ``vn x y z``, ``vt u [v [w]]``, ``f a b c ...`` with ``v``, ``v/vt``, ``v//vn`` or
``v/vt/vn`` references (1-based, negative from the end); polygons are split into fans. Other statements (``o``,
``g``, ``s``, ``usemtl``, ``mtllib``, ``l``, ``p``) are ignored. A face without normals gets the
area-weighted average of its vertices' face normals (for every face: a mesh is smooth or given). Texture
coordinates (where every corner has one; the generated shapes have theirs) carry a surface texture or structure
maps (:mod:`explorer.views.surface_texture`) onto the mesh: ``(u, v)`` with ``v`` from the top, as the sphere's
planar ``(u, v)`` (an OBJ's ``vt`` counts ``v`` from the bottom: ``1 - v``).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from explorer.errors import LocatedError
from explorer.resources import SHADER_DIR

#: The farthest vertex lies at this fraction of the image's half-width.
FILL = 0.9
#: The three-quarter view: a turn about the vertical (degrees), then a tilt toward the viewer.
YAW, PITCH = -30.0, 20.0
#: The shipped Bézier patches of the teapot, and its patches' tessellation (quads per side).
TEAPOT_PATCHES = SHADER_DIR / "meshes" / "teapot.bpt"
TEAPOT_DIVISIONS = 8
#: Faces an OBJ file may have (a bound on memory and on the numpy rasteriser's time).
MAX_FACES = 2_000_000


class MeshError(LocatedError):
    """A mesh file is missing or malformed (one line: the file and, where there is one, the line)."""


@dataclass(frozen=True)
class Mesh:
    """
    Triangles: ``positions`` and unit ``normals`` ``(V, 3)`` float64, ``triangles`` ``(T, 3)`` int64, ``name``, and the
    texture coordinates ``uvs`` ``(V, 2)`` (``v`` from the top), or None.
    """

    positions: np.ndarray
    normals: np.ndarray
    triangles: np.ndarray
    name: str
    uvs: np.ndarray | None = None


def _unit(v: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(length > 0.0, length, 1.0)


def vertex_normals(positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Each vertex's normal: the sum of its triangles' ``cross(b - a, c - a)`` (area-weighted), normalised."""
    a, b, c = (positions[triangles[:, k]] for k in range(3))
    face = np.cross(b - a, c - a)
    normals = np.zeros_like(positions)
    for k in range(3):
        np.add.at(normals, triangles[:, k], face)
    return _unit(normals)


# --------------------------------------------------------------------------------------------------
# OBJ


def _index(token: str, count: int, what: str, path: str, number: int) -> int:
    """A 1-based (or negative, from the end) OBJ reference as a 0-based index."""
    try:
        i = int(token)
    except ValueError:
        raise MeshError(path, number, f"face {what} index {token!r} is not an integer") from None
    index = i - 1 if i > 0 else count + i
    if i == 0 or not 0 <= index < count:
        raise MeshError(path, number, f"face {what} index {i} is out of range (the file has {count} {what}s so far)")
    return index


def parse_obj(text: str, path: str = "<obj>") -> Mesh:
    """An OBJ file's triangles (see the module's docstring); :class:`MeshError` with the line for a malformed one."""
    positions: list[tuple[float, float, float]] = []
    normals: list[tuple[float, float, float]] = []
    uvs: list[tuple[float, float]] = []
    corners: list[tuple[int, int, int]] = []  # (position, normal or -1, texture coordinates or -1) per triangle corner
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        keyword, *fields = line.split()
        if keyword in ("v", "vn"):
            if len(fields) < 3 or (keyword == "vn" and len(fields) > 3) or len(fields) > 4:
                raise MeshError(path, number, f"'{keyword}' needs 3 numbers (x y z{' [w]' if keyword == 'v' else ''}), got {len(fields)}")
            try:
                xyz = tuple(float(f) for f in fields[:3])
            except ValueError:
                raise MeshError(path, number, f"'{keyword}' has a field that is not a number: {' '.join(fields)[:60]!r}") from None
            if not all(math.isfinite(c) for c in xyz):
                raise MeshError(path, number, f"'{keyword}' has a non-finite coordinate")
            (positions if keyword == "v" else normals).append(xyz)
        elif keyword == "vt":
            try:
                uv = tuple(float(f) for f in fields[:2]) + ((0.0,) if len(fields) == 1 else ())
            except ValueError:
                raise MeshError(path, number, f"'vt' has a field that is not a number: {' '.join(fields)[:60]!r}") from None
            if not fields or len(fields) > 3 or not all(math.isfinite(c) for c in uv):
                raise MeshError(path, number, f"'vt' needs 1 to 3 finite numbers (u [v [w]]), got {' '.join(fields)[:60]!r}")
            uvs.append((uv[0], 1.0 - uv[1]))  # rows from the top, as the sphere's planar v
        elif keyword == "f":
            if len(fields) < 3:
                raise MeshError(path, number, f"a face needs at least 3 vertices, got {len(fields)}")
            face = []
            for field in fields:
                parts = field.split("/")
                if len(parts) > 3 or not parts[0]:
                    raise MeshError(path, number, f"face vertex {field!r} is not v, v/vt, v//vn or v/vt/vn")
                p = _index(parts[0], len(positions), "vertex", path, number)
                n = _index(parts[2], len(normals), "normal", path, number) if len(parts) == 3 and parts[2] else -1
                t = _index(parts[1], len(uvs), "texture coordinate", path, number) if len(parts) >= 2 and parts[1] else -1
                face.append((p, n, t))
            for k in range(1, len(face) - 1):  # a fan
                corners += [face[0], face[k], face[k + 1]]
            if len(corners) > 3 * MAX_FACES:
                raise MeshError(path, number, f"more than {MAX_FACES} triangles")
        # o, g, s, usemtl, mtllib, l, p and others: not geometry this view draws
    if not corners:
        raise MeshError(path, None, "no faces ('f' lines): nothing to draw")
    corner = np.array(corners, dtype=np.int64)
    position_array = np.array(positions, dtype=np.float64)
    textured = bool((corner[:, 2] >= 0).all())  # texture coordinates only where every corner has them
    uv_array = np.array(uvs, dtype=np.float64).reshape(-1, 2)
    if (corner[:, 1] < 0).any():  # a corner without a normal: every normal computed (smooth shading)
        smooth = vertex_normals(position_array, corner[:, 0].reshape(-1, 3))
        if not textured:
            return Mesh(position_array, smooth, corner[:, 0].reshape(-1, 3), path)
        unique, inverse = np.unique(corner[:, [0, 2]], axis=0, return_inverse=True)  # a vertex per (position, uv)
        return Mesh(position_array[unique[:, 0]], smooth[unique[:, 0]], inverse.reshape(-1, 3), path, uv_array[unique[:, 1]])
    unique, inverse = np.unique(corner if textured else corner[:, :2], axis=0, return_inverse=True)
    normal_array = _unit(np.array(normals, dtype=np.float64)[unique[:, 1]])
    if (np.linalg.norm(normal_array, axis=-1) == 0.0).any():
        raise MeshError(path, None, "a 'vn' normal is zero")
    return Mesh(position_array[unique[:, 0]], normal_array, inverse.reshape(-1, 3), path, uv_array[unique[:, 2]] if textured else None)


def load_obj(path: str | os.PathLike[str]) -> Mesh:
    """Read an OBJ file (UTF-8 or Latin-1); :class:`MeshError`, one line, when it is missing or malformed."""
    name = os.fspath(path)
    try:
        data = Path(path).read_bytes()
    except OSError as error:
        raise MeshError(name, None, f"cannot read mesh file: {error.strerror or error}") from None
    if b"\0" in data[:4096]:
        raise MeshError(name, None, f"binary data ({len(data)} bytes), not a Wavefront OBJ text file")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = data.decode("latin-1")
    return parse_obj(text, name)


# --------------------------------------------------------------------------------------------------
# Generated shapes


def cube() -> Mesh:
    """A unit cube, flat-shaded: 6 faces of 4 vertices each with the face's normal."""
    positions, normals, triangles, uvs = [], [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[axis] = sign
            u, v = np.roll(np.eye(3), 1, axis=0)[axis], np.roll(np.eye(3), 2, axis=0)[axis]
            if sign > 0:
                u, v = v, u  # cross(u, v) = n: counter-clockwise seen from outside
            base = len(positions)
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                positions.append(0.5 * (n + a * u + b * v))
                normals.append(n)
                uvs.append((0.5 * (a + 1), 0.5 * (1 - b)))  # each face the whole texture
            triangles += [(base, base + 1, base + 2), (base, base + 2, base + 3)]
    return Mesh(np.array(positions), np.array(normals), np.array(triangles, dtype=np.int64), "cube", np.array(uvs))


def torus(major: float = 1.0, minor: float = 0.4, around: int = 64, across: int = 32) -> Mesh:
    """
    A torus about the vertical ``y`` axis, its exact normals: ``around`` x ``across`` quads; the texture once around
    each way (the seams' vertices doubled, so that the coordinates do not run back across a quad).
    """
    u = 2.0 * np.pi * np.arange(around + 1) / around
    v = 2.0 * np.pi * np.arange(across + 1) / across
    U, V = np.meshgrid(u, v, indexing="ij")
    normals = np.stack([np.cos(V) * np.cos(U), np.sin(V), np.cos(V) * np.sin(U)], axis=-1)
    centre = np.stack([major * np.cos(U), np.zeros_like(U), major * np.sin(U)], axis=-1)
    positions = centre + minor * normals
    side = across + 1
    i, j = np.meshgrid(np.arange(around), np.arange(across), indexing="ij")
    a, b = i * side + j, (i + 1) * side + j
    c, d = (i + 1) * side + j + 1, i * side + j + 1
    triangles = np.concatenate([np.stack([a, d, c], -1).reshape(-1, 3), np.stack([a, c, b], -1).reshape(-1, 3)])
    uvs = np.stack([U / (2.0 * np.pi), V / (2.0 * np.pi)], axis=-1).reshape(-1, 2)
    return Mesh(positions.reshape(-1, 3), normals.reshape(-1, 3), triangles, "torus", uvs)


def read_bezier_patches(path: str | os.PathLike[str] = TEAPOT_PATCHES) -> np.ndarray:
    """
    Bézier patches in Newell's text format (``#`` comments; the patch count, one line of 16 1-based
    control point indices per patch; the point count, one ``x y z`` per line): ``(P, 4, 4, 3)`` float64.
    """
    name = os.fspath(path)
    lines = [(n, line.split("#", 1)[0].replace(",", " ").split()) for n, line in enumerate(Path(path).read_text().splitlines(), 1)]
    lines = [(n, fields) for n, fields in lines if fields]
    try:
        count = int(lines[0][1][0])
        patches = np.array([[int(i) for i in fields] for _, fields in lines[1:1 + count]], dtype=np.int64)
        points = np.array([[float(c) for c in fields] for _, fields in lines[2 + count:]], dtype=np.float64)
        if patches.shape != (count, 16) or points.shape != (int(lines[1 + count][1][0]), 3):
            raise ValueError("counts")
    except (ValueError, IndexError):
        raise MeshError(name, None, "not Bézier patches (a patch count, 16 indices per patch, a point count, x y z per point)") from None
    return points[patches - 1].reshape(count, 4, 4, 3)


def bezier_mesh(patches: np.ndarray, divisions: int, name: str) -> Mesh:
    """
    Bicubic Bézier patches tessellated into ``divisions`` x ``divisions`` quads each; normals from the
    patch's tangents (``cross(dP/du, dP/dv)``, oriented away from the centroid where a patch is degenerate:
    the area-weighted normals of the triangles there).
    """
    t = np.linspace(0.0, 1.0, divisions + 1)

    def bernstein(t):
        return np.stack([(1 - t) ** 3, 3 * t * (1 - t) ** 2, 3 * t * t * (1 - t), t ** 3], axis=-1)

    def derivative(t):
        return np.stack([-3 * (1 - t) ** 2, 3 * (1 - t) ** 2 - 6 * t * (1 - t), 6 * t * (1 - t) - 3 * t * t, 3 * t * t], axis=-1)

    B, dB = bernstein(t), derivative(t)
    points = np.einsum("ui,vj,pijc->puvc", B, B, patches)
    du = np.einsum("ui,vj,pijc->puvc", dB, B, patches)
    dv = np.einsum("ui,vj,pijc->puvc", B, dB, patches)
    normals = np.cross(du, dv)
    count = patches.shape[0]
    side = divisions + 1
    base = (np.arange(count) * side * side)[:, None, None]
    i, j = np.meshgrid(np.arange(divisions), np.arange(divisions), indexing="ij")
    a = base + i * side + j
    b, c, d = a + side, a + side + 1, a + 1
    triangles = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    positions, normals = points.reshape(-1, 3), normals.reshape(-1, 3)
    # Newell's patches wind either way: orient each patch's tangent normals away from the centroid.
    outward = np.sign(np.sum(normals.reshape(count, -1, 3) * (points.reshape(count, -1, 3) - positions.mean(axis=0)), axis=(1, 2)))
    normals = normals * np.repeat(np.where(outward == 0, 1.0, outward), side * side)[:, None]
    degenerate = np.linalg.norm(normals, axis=-1) < 1e-9 * max(1.0, float(np.abs(positions).max()))
    faces = triangles.copy()
    flip = np.sum(np.cross(positions[faces[:, 1]] - positions[faces[:, 0]], positions[faces[:, 2]] - positions[faces[:, 0]])
                  * normals[faces].sum(axis=1), axis=-1) < 0
    faces[flip] = faces[flip][:, ::-1]  # triangles wound as their normals point
    normals = _unit(normals)
    if degenerate.any():  # a pole (the lid's knob, the bottom): the area-weighted normal of the welded vertex
        welded, index = np.unique(np.round(positions, 9), axis=0, return_inverse=True)
        index = index.reshape(-1)
        normals[degenerate] = vertex_normals(welded, index[faces])[index][degenerate]
    uvs = np.tile(np.stack(np.meshgrid(t, t, indexing="ij"), axis=-1).reshape(-1, 2), (count, 1))  # each patch the whole texture
    return Mesh(positions, normals, faces, name, uvs)


def teapot(divisions: int = TEAPOT_DIVISIONS) -> Mesh:
    """The Utah teapot (:data:`TEAPOT_PATCHES`), turned from its data's z-up to the view's y-up."""
    mesh = bezier_mesh(read_bezier_patches(), divisions, "teapot")
    up = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # (x, y, z) -> (x, z, -y), a rotation
    return Mesh(mesh.positions @ up.T, mesh.normals @ up.T, mesh.triangles, "teapot", mesh.uvs)


#: The shapes ``--mesh NAME`` generates.
SHAPES = {"teapot": teapot, "cube": cube, "torus": torus}


def mesh_named(text: str | os.PathLike[str]) -> Mesh:
    """``--mesh``: a shape of :data:`SHAPES` by name, else an OBJ file (:class:`MeshError` if it is neither)."""
    text = os.fspath(text)
    if text in SHAPES and not Path(text).exists():
        return SHAPES[text]()
    if not Path(text).exists() and os.sep not in text and "." not in text:
        raise MeshError(text, None, f"no such mesh file, nor a shape ({', '.join(SHAPES)})")
    return load_obj(text)


# --------------------------------------------------------------------------------------------------
# The camera and the numpy rasteriser


def view_rotation() -> np.ndarray:
    """The three-quarter view's rotation: :data:`YAW` about ``y``, then :data:`PITCH` about ``x``."""
    yaw, pitch = math.radians(YAW), math.radians(PITCH)
    about_y = np.array([[math.cos(yaw), 0.0, math.sin(yaw)], [0.0, 1.0, 0.0], [-math.sin(yaw), 0.0, math.cos(yaw)]])
    about_x = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(pitch), -math.sin(pitch)], [0.0, math.sin(pitch), math.cos(pitch)]])
    return about_x @ about_y


def view_space(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """
    ``(positions, normals)`` in the view: centred on the bounding box, scaled to :data:`FILL`, turned by
    :func:`view_rotation`; ``x``, ``y`` in units of the image's half-width, ``z`` toward the viewer. Float32,
    as the GL pass receives them.
    """
    lo, hi = mesh.positions.min(axis=0), mesh.positions.max(axis=0)
    centred = mesh.positions - 0.5 * (lo + hi)
    radius = float(np.linalg.norm(centred, axis=-1).max()) or 1.0
    rotation = view_rotation()
    positions = (centred * (FILL / radius)) @ rotation.T
    normals = mesh.normals @ rotation.T
    return positions.astype(np.float32), normals.astype(np.float32)


def aspect_scale(width: int, height: int) -> tuple[float, float]:
    """Multipliers of view ``x`` and ``y`` to clip space: the shorter side spans [-1, 1]."""
    side = min(width, height)
    return side / width, side / height


@dataclass(frozen=True)
class Rasterised:
    """
    The numpy rasteriser's image (rows from the top): the interpolated normal (not normalised) ``(H, W, 3)``,
    the covered pixels, and per pixel the smallest barycentric coordinate of its triangle and the depth
    gap to the next surface (where GL and numpy may decide differently: edges and intersections).
    """

    normals: np.ndarray
    covered: np.ndarray
    margin: np.ndarray
    depth_gap: np.ndarray
    #: The interpolated texture coordinates ``(H, W, 2)`` (zeros for a mesh without them).
    uvs: np.ndarray | None = None


def rasterise(mesh: Mesh, width: int, height: int) -> Rasterised:
    """
    The mesh's normals per pixel centre, nearest surface first (the twin of :mod:`explorer.gpu.mesh`'s GL
    pass; orthographic, so barycentric interpolation in the image is GL's): float64 edge functions per
    triangle over its bounding box of pixels.
    """
    positions, normals = (a.astype(np.float64) for a in view_space(mesh))
    sx, sy = aspect_scale(width, height)
    px = (positions[:, 0] * sx + 1.0) * 0.5 * width - 0.5  # pixel column of each vertex (centres at integers)
    py = (1.0 - positions[:, 1] * sy) * 0.5 * height - 0.5  # row from the top
    depth = np.full((height, width), -np.inf)
    second = np.full((height, width), -np.inf)
    out = np.zeros((height, width, 3))
    uv_out = np.zeros((height, width, 2))
    uvs = np.zeros((len(positions), 2)) if mesh.uvs is None else mesh.uvs.astype(np.float32).astype(np.float64)  # as GL receives them
    margin = np.zeros((height, width))
    for a, b, c in mesh.triangles:
        xs, ys = px[[a, b, c]], py[[a, b, c]]
        area = (xs[1] - xs[0]) * (ys[2] - ys[0]) - (xs[2] - xs[0]) * (ys[1] - ys[0])
        if area == 0.0:
            continue
        c0, c1 = max(int(math.ceil(xs.min())), 0), min(int(math.floor(xs.max())), width - 1)
        r0, r1 = max(int(math.ceil(ys.min())), 0), min(int(math.floor(ys.max())), height - 1)
        if c0 > c1 or r0 > r1:
            continue
        X, Y = np.meshgrid(np.arange(c0, c1 + 1, dtype=np.float64), np.arange(r0, r1 + 1, dtype=np.float64))
        w0 = ((xs[1] - X) * (ys[2] - Y) - (xs[2] - X) * (ys[1] - Y)) / area
        w1 = ((xs[2] - X) * (ys[0] - Y) - (xs[0] - X) * (ys[2] - Y)) / area
        w2 = 1.0 - w0 - w1
        smallest = np.minimum(np.minimum(w0, w1), w2)
        inside = smallest >= 0.0
        if not inside.any():
            continue
        z = w0 * positions[a, 2] + w1 * positions[b, 2] + w2 * positions[c, 2]
        window = (slice(r0, r1 + 1), slice(c0, c1 + 1))
        nearest = inside & (z > depth[window])
        behind = inside & ~nearest
        second[window] = np.where(nearest, depth[window], np.where(behind, np.maximum(second[window], z), second[window]))
        depth[window] = np.where(nearest, z, depth[window])
        n = w0[..., None] * normals[a] + w1[..., None] * normals[b] + w2[..., None] * normals[c]
        out[window] = np.where(nearest[..., None], n, out[window])
        t = w0[..., None] * uvs[a] + w1[..., None] * uvs[b] + w2[..., None] * uvs[c]
        uv_out[window] = np.where(nearest[..., None], t, uv_out[window])
        margin[window] = np.where(nearest, smallest, margin[window])
    covered = np.isfinite(depth)
    with np.errstate(invalid="ignore"):  # -inf - -inf off the mesh
        gap = np.where(covered, depth - second, np.inf)
    return Rasterised(out, covered, margin, gap, uv_out)


def surface_frame(N: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    ``(N, X, Y)`` around interpolated normals ``(..., 3)``, in float32 as the shader (``mesh_surface`` in
    ``shaders/lib/views.glsl``): ``N`` normalised, ``X = normalize(cross((0, 1, 0), N))`` (``(1, 0, 0)``
    where that cross product vanishes), ``Y = normalize(cross(N, X))``.
    """
    f32 = np.float32
    N = np.asarray(N, dtype=f32)
    N = N / np.sqrt(np.sum(N * N, axis=-1, keepdims=True))
    cross = np.cross(np.array([0, 1, 0], f32), N)
    length = np.sqrt(np.sum(cross * cross, axis=-1, keepdims=True))
    X = np.where(length > f32(1e-6), cross / np.where(length > 0, length, f32(1)), np.array([1, 0, 0], f32))
    Y = np.cross(N, X)
    Y = Y / np.sqrt(np.sum(Y * Y, axis=-1, keepdims=True))
    return N.astype(f32), X.astype(f32), Y.astype(f32)


def mesh_view_geometry(normals: np.ndarray, covered: np.ndarray, light: tuple[float, float] | None = None):
    """
    The arguments of ``BRDF(L, V, N, X, Y)`` at each pixel of a mesh's lit view, as
    :func:`explorer.views.geometry.brdf_view_geometry` returns them for the sphere: ``(L, V, N, X, Y,
    inside, factor)`` from the interpolated ``normals`` ``(H, W, 3)`` and the ``covered`` mask.
    """
    from explorer.views.geometry import light_direction

    height, width = covered.shape
    shape = (height, width, 3)
    safe = np.where(covered[..., None], normals, np.array([0.0, 0.0, 1.0]))
    N, X, Y = surface_frame(safe)
    L = np.broadcast_to(light_direction(light), shape)
    V = np.broadcast_to(np.array([0, 0, 1], np.float32), shape)
    factor = np.maximum(np.sum(N.astype(np.float64) * L, axis=-1), 0.0)
    return L, V, N, X, Y, covered.copy(), factor
