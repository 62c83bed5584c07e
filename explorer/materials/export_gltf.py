"""
``export MATERIAL --to gltf OUT.glb [--mesh FILE] [--texture-table]``: a binary glTF 2.0 scene (pygltflib)
of a unit sphere (or a mesh) and an orthographic camera as the env view's, its material metallic-roughness
with ``KHR_materials_iridescence`` (docs/export.md).

- A single film (:func:`explorer.materials.gltf_film.direct_film`) maps directly: thickness, film index,
  and its base (a dielectric through ``KHR_materials_ior`` over a black base colour, or a metal whose base
  colour is its normal-incidence reflectance).
- Any other material gets the nearest single film (:func:`explorer.materials.gltf_film.fit_film`).
- Either way the material's ``extras.bragg_explorer`` holds the ΔE2000 per angle between the extension's
  reflection (the specification's formula) and the material's own reflectance.
- ``texture_table``: the exact table of ``--to table`` (:mod:`explorer.materials.export_table`) as well, in
  ``extras.bragg_explorer.table``: a 16-bit PNG image (``images[k]``) and the same values as float32
  (``bufferViews[k]``), with their lookup.

Roughness: the material's first roughness parameter ``alpha`` (GGX) -> ``roughnessFactor = sqrt(alpha)``
(glTF squares it); 0 for a smooth one.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from explorer.errors import LocatedError
from explorer.files import write_bytes_atomic
from explorer.materials import gltf_film

EXTENSION = "KHR_materials_iridescence"
IOR_EXTENSION = "KHR_materials_ior"
#: The UV sphere's segments around and rings from pole to pole.
SEGMENTS, RINGS = 64, 32
#: The orthographic camera's distance from the centre (it looks along -z, as the env view's).
CAMERA_DISTANCE = 3.0

_FLOAT, _UINT = 5126, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963


#: How the film was found (extras' ``mapping``).
MAPPINGS = {"direct": "direct: the film's own parameters",
            "refined": "the film's parameters moved to the least median ΔE2000 over theta (closer than the direct mapping)",
            "fit": "the nearest single film (metallic base)"}


class GltfExportError(LocatedError):
    """A glTF export that cannot be made (one line)."""


def unit_sphere(segments: int = SEGMENTS, rings: int = RINGS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (= normals) ``(V, 3)`` and counter-clockwise triangles ``(T, 3)`` of a UV sphere, no degenerate one."""
    theta = np.pi * np.arange(1, rings) / rings  # the rings between the poles
    phi = 2.0 * np.pi * np.arange(segments) / segments
    T, P = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(T) * np.sin(P), np.cos(T), np.sin(T) * np.cos(P)], axis=-1).reshape(-1, 3)
    positions = np.concatenate([[[0.0, 1.0, 0.0]], ring, [[0.0, -1.0, 0.0]]])
    north, south = 0, len(positions) - 1
    index = 1 + np.arange((rings - 1) * segments).reshape(rings - 1, segments)
    nxt = np.roll(index, -1, axis=1)
    tris = [np.stack([np.full(segments, north), index[0], nxt[0]], -1)]
    a, b, c, d = index[:-1], index[1:], nxt[1:], nxt[:-1]
    tris += [np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)]
    tris.append(np.stack([np.full(segments, south), nxt[-1], index[-1]], -1))
    return positions, positions.copy(), np.concatenate(tris).astype(np.int64)


def roughness_of(material, values) -> float:
    """glTF's ``roughnessFactor``: ``sqrt`` of the first roughness parameter (``alpha`` or ``alpha_1``), 0 without one."""
    names = [p.name for p in material.parameters if p.name == "alpha" or p.name.startswith("alpha_")]
    if not names:
        return 0.0
    return float(min(max(math.sqrt(max(float(values[sorted(names)[0]]), 0.0)), 0.0), 1.0))


def film_for(material, values) -> gltf_film.Film:
    """The film written for ``material`` at ``values``: the direct mapping where one exists, else the fit."""
    from explorer.materials.models import model_for
    from explorer.materials.twins import capabilities_of, supporting

    model = model_for(material, values)
    if model is None or not callable(getattr(model, "reflectance", None)):
        raise GltfExportError(material.path, None, "this material has no numpy twin to fit a film to (no known '# model:' line)")
    if not capabilities_of(material).supports("gltf"):
        raise GltfExportError(material.path, None, f"its twin declares no glTF export (exports: {', '.join(supporting('gltf'))})")
    direct = gltf_film.direct_film(model)
    if direct is None:
        return gltf_film.fit_film(gltf_film.target_rgb(model))
    film = gltf_film.refine_film(direct, gltf_film.target_rgb(model, gltf_film.DENSE_THETA_DEG))
    film.direct = direct
    return film


def _json_value(value):
    if isinstance(value, (bool, str)):
        return value
    if isinstance(value, (tuple, list, np.ndarray)):
        return [float(c) for c in value]
    return float(value)


def _png16(table: np.ndarray) -> tuple[bytes, float, float]:
    """A 16-bit RGB PNG of ``table`` ``(H, W, 3)`` and its decoding ``value = offset + scale * png / 65535``."""
    import cv2

    low, high = float(np.min(table)), float(np.max(table))
    offset, scale = min(low, 0.0), max(high - min(low, 0.0), 1e-12)
    codes = np.round((table - offset) / scale * 65535.0).astype(np.uint16)
    ok, data = cv2.imencode(".png", np.ascontiguousarray(codes[..., ::-1]))
    if not ok:
        raise GltfExportError("<table>", None, "OpenCV could not encode the table as PNG")
    return data.tobytes(), offset, scale


class _Blob:
    """The GLB's binary chunk, built as buffer views (4-byte aligned)."""

    def __init__(self):
        self.data = bytearray()
        self.views: list = []

    def add(self, payload: bytes, target: int | None = None) -> int:
        import pygltflib

        while len(self.data) % 4:
            self.data += b"\0"
        self.views.append(pygltflib.BufferView(buffer=0, byteOffset=len(self.data), byteLength=len(payload), target=target))
        self.data += payload
        return len(self.views) - 1


def gltf_bytes(material, values, film: gltf_film.Film, mesh: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
               table: np.ndarray | None = None, name: str = "material") -> bytes:
    """The ``.glb`` bytes: ``mesh`` (positions, normals, triangles; default :func:`unit_sphere`) with the film's material."""
    import pygltflib

    positions, normals, triangles = unit_sphere() if mesh is None else mesh
    positions = np.ascontiguousarray(positions, dtype=np.float32)
    normals = np.asarray(normals, dtype=np.float64)
    normals = np.ascontiguousarray(normals / np.linalg.norm(normals, axis=-1, keepdims=True), dtype=np.float32)
    indices = np.ascontiguousarray(np.asarray(triangles).reshape(-1), dtype=np.uint32)
    blob = _Blob()
    accessors = [
        pygltflib.Accessor(bufferView=blob.add(indices.tobytes(), _ELEMENT_ARRAY_BUFFER), componentType=_UINT,
                           count=int(indices.size), type="SCALAR", min=[int(indices.min())], max=[int(indices.max())]),
        pygltflib.Accessor(bufferView=blob.add(positions.tobytes(), _ARRAY_BUFFER), componentType=_FLOAT,
                           count=len(positions), type="VEC3", min=positions.min(axis=0).tolist(), max=positions.max(axis=0).tolist()),
        pygltflib.Accessor(bufferView=blob.add(normals.tobytes(), _ARRAY_BUFFER), componentType=_FLOAT, count=len(normals), type="VEC3"),
    ]
    extensions = {EXTENSION: {"iridescenceFactor": film.factor, "iridescenceIor": film.ior,
                              "iridescenceThicknessMaximum": film.thickness}}
    used = [EXTENSION]
    if film.metallic < 0.5:
        extensions[IOR_EXTENSION] = {"ior": film.base_ior}
        used.append(IOR_EXTENSION)
    delta = np.asarray(film.delta_e, dtype=np.float64)
    extras = {
        "material": name,
        "values": {k: _json_value(v) for k, v in values.items()},
        "mapping": MAPPINGS[film.mapping],
        "reflectance": "linear Rec. 709 of the mirror direction, glTF's model (KHR_materials_iridescence's formula) against the material's",
        "theta_deg": [float(t) for t in gltf_film.THETA_DEG],
        "delta_e_2000": [round(float(x), 4) for x in delta],
        "median_delta_e_2000": round(float(np.median(delta)), 4),
        "max_delta_e_2000": round(float(np.max(delta)), 4),
    }
    direct = film.direct
    if direct is not None:
        extras["direct"] = {"thickness": direct.thickness, "ior": direct.ior, "metallic": direct.metallic,
                            "base_color": list(direct.base_color), "base_ior": direct.base_ior,
                            "delta_e_2000": [round(float(x), 4) for x in direct.delta_e],
                            "median_delta_e_2000": round(float(np.median(direct.delta_e)), 4)}
    images = []
    if table is not None:
        png, offset, scale = _png16(table)
        images.append(pygltflib.Image(bufferView=blob.add(png), mimeType="image/png", name="reflectance_table"))
        raw = blob.add(np.ascontiguousarray(table, dtype="<f4").tobytes())
        extras["table"] = {
            "image": 0, "bufferView": raw, "width": int(table.shape[1]), "height": int(table.shape[0]),
            "png": "16-bit RGB, linear: value = offset + scale * code / 65535",
            "offset": offset, "scale": scale,
            "float32": "the same values, row-major (height, width, 3), little-endian",
            "lookup": ("column j = 0 .. width-1 at cos(theta) = j / (width-1), theta the view's angle to the normal; "
                       "row i at roughness alpha = i / (height-1) (one row: a smooth material); row 0 is the "
                       "reflectance, the others the directional albedo; sample bilinearly; linear sRGB, white (1, 1, 1)"),
        }
    pbr = pygltflib.PbrMetallicRoughness(baseColorFactor=[*(float(c) for c in film.base_color), 1.0],
                                         metallicFactor=float(film.metallic), roughnessFactor=roughness_of(material, values))
    gltf = pygltflib.GLTF2(
        asset=pygltflib.Asset(version="2.0", generator="bragg-explorer"),
        extensionsUsed=used,
        scene=0,
        scenes=[pygltflib.Scene(nodes=[0, 1])],
        nodes=[pygltflib.Node(mesh=0, name=name),
               pygltflib.Node(camera=0, translation=[0.0, 0.0, CAMERA_DISTANCE], name="camera")],
        cameras=[pygltflib.Camera(type="orthographic", orthographic=pygltflib.Orthographic(
            xmag=1.0, ymag=1.0, znear=0.01, zfar=2.0 * CAMERA_DISTANCE))],
        meshes=[pygltflib.Mesh(primitives=[pygltflib.Primitive(attributes=pygltflib.Attributes(POSITION=1, NORMAL=2),
                                                                indices=0, material=0)], name=name)],
        materials=[pygltflib.Material(name=name, pbrMetallicRoughness=pbr, extensions=extensions,
                                      extras={"bragg_explorer": extras})],
        accessors=accessors,
        bufferViews=blob.views,
        images=images,
        buffers=[pygltflib.Buffer(byteLength=len(blob.data))],
    )
    gltf.set_binary_blob(bytes(blob.data))
    return b"".join(gltf.save_to_bytes())


def describe(film: gltf_film.Film) -> str:
    """The ΔE2000 per angle, for the console."""
    pairs = "  ".join(f"{t:g}:{e:.2f}" for t, e in zip(gltf_film.THETA_DEG, film.delta_e))
    how = {"direct": "direct mapping", "refined": "thin film, refined", "fit": "nearest single film"}[film.mapping]
    return (f"{how}: thickness {film.thickness:.1f} nm, film IOR {film.ior:.4f}, factor {film.factor:.3f}, "
            f"{'metal, base colour ' + ', '.join(f'{c:.4f}' for c in film.base_color) if film.metallic >= 0.5 else f'dielectric, IOR {film.base_ior:.4f}'}\n"
            f"ΔE2000 by theta (deg:ΔE): {pairs}\n"
            f"median {np.median(film.delta_e):.2f}, max {np.max(film.delta_e):.2f}"
            + (f" (the direct mapping's: median {np.median(film.direct.delta_e):.2f}, max {np.max(film.direct.delta_e):.2f})"
               if film.direct is not None else ""))


def export_gltf(material, values, out: Path, mesh=None, texture_table: bool = False) -> tuple[Path, gltf_film.Film]:
    """Write the ``.glb`` to ``out`` atomically; return it and the film written."""
    if out.suffix.lower() != ".glb":
        raise GltfExportError(out, None, "a binary glTF file: name it .glb")
    film = film_for(material, values)
    table = None
    if texture_table:
        from explorer.materials.export_table import material_table

        table = np.asarray(material_table(material, values), dtype=np.float32)
    name = Path(str(material.path)).stem
    write_bytes_atomic(out, gltf_bytes(material, values, film, mesh, table, name))
    return out, film


def read_extras(path: Path) -> dict:
    """The ``extras.bragg_explorer`` of a written ``.glb``'s first material (pygltflib)."""
    import pygltflib

    gltf = pygltflib.GLTF2().load_binary(str(path))
    extras = gltf.materials[0].extras
    return json.loads(json.dumps(extras))["bragg_explorer"]
