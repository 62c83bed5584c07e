"""
The materials in Blender (Cycles): ``export MATERIAL --to blender FILE.blend`` and
:func:`material` (docs/blender.md). Needs ``bpy`` (Blender as a Python module, 5.0.x).

- A smooth mirror (a twin whose env view is a Dirac: ``bragg_mirror``) is its reflectance baked into a
  float image over ``cos theta`` (:data:`TABLE_SIZE` columns, ``cos theta = j / (size - 1)``, texel centres
  as GL's), looked up per shading point from the Geometry node's Normal and Incoming, driving a Glossy
  BSDF at roughness 0: exact for a smooth mirror up to the table's linear interpolation.
- A single film (the thin film) maps onto the Principled BSDF's own Thin Film inputs (thickness, IOR) over
  a dielectric base (black base colour, IOR ``eta3``) or a metallic one (base colour its normal-incidence
  reflectance), roughness ``sqrt(alpha)``: editable in Blender, close but not exact (docs/blender.md).

The preview scene is the env view's: a unit sphere (smooth-shaded UV sphere), an orthographic camera
spanning ``[-1, 1]^2``, the environment as the world's Environment Texture in the same orientation, linear
colour management (view transform Standard, EXR output scene-linear). The explorer's frame (``+y`` up,
the viewer on ``+z``) is Blender's (``+z`` up, the viewer on ``-y``): ``(x, y, z) -> (x, -z, y)``; Blender's
equirectangular ``u`` is then ours minus a quarter turn, which the world image absorbs (its columns rolled).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from explorer.errors import LocatedError

#: Columns of the baked reflectance table.
TABLE_SIZE = 1024
#: The preview sphere's tessellation (smooth normals: the facets' positions differ by < 1e-3 of a pixel at 64²).
SEGMENTS, RINGS = 128, 64


class BlenderExportError(LocatedError):
    """A material Blender's mapping does not cover (one line)."""


def _bpy():
    try:
        import bpy
    except ImportError:
        raise BlenderExportError("bpy", None, "Blender's Python module is not installed (pip install '.[blender]')") from None
    return bpy


def _node(tree, kind, location=(0, 0), **inputs):
    node = tree.nodes.new(kind)
    node.location = location
    for name, value in inputs.items():
        node.inputs[name.replace("_", " ")].default_value = value
    return node


def _table_image(bpy, name: str, rgb: np.ndarray):
    """A float image of one row (``(W, 3)`` linear RGB), packed in the .blend, read as linear Rec. 709."""
    image = bpy.data.images.new(name, width=rgb.shape[0], height=1, float_buffer=True, alpha=False)
    rgba = np.concatenate([rgb, np.ones((rgb.shape[0], 1))], axis=1).astype(np.float32)
    image.colorspace_settings.name = "Linear Rec.709"  # before the pixels: setting it regenerates the image
    image.pixels.foreach_set(rgba.ravel().tolist())  # a list: bpy 5.0 cannot read numpy 2 buffers
    return image


def mapping_of(material, values) -> str:
    """``"table"`` (a smooth mirror), ``"principled"`` (a single film) or a :class:`BlenderExportError`."""
    from explorer.materials.models import model_for
    from explorer.materials.twins import capabilities_of

    model = model_for(material, values)
    if model is not None and capabilities_of(material).dirac:
        return "table"
    if model is not None and getattr(model, "film", None) is not None and hasattr(model, "thickness_d"):
        return "principled"
    raise BlenderExportError(material.path, None, "no Blender mapping for this material yet (a smooth Bragg mirror or a thin film)")


def material(bpy_material, material, values, film: str = "principled") -> None:
    """
    Build ``material`` at ``values`` into ``bpy_material`` (its node tree replaced): the function FILE.py calls.
    ``film``: a thin film through Principled's Thin Film (``"principled"``), or its table (``"table"``: the
    reflectance at the view angle colouring a GGX Glossy of roughness ``sqrt(alpha)``).
    """
    bpy = _bpy()
    from explorer.materials.models import model_for

    kind = mapping_of(material, values)
    if kind == "principled" and film == "table":
        kind = "table"
    model = model_for(material, values)
    bpy_material.use_nodes = True
    tree = bpy_material.node_tree
    tree.nodes.clear()
    out = _node(tree, "ShaderNodeOutputMaterial", (600, 0))
    if kind == "table":
        cos = np.linspace(0.0, 1.0, TABLE_SIZE)
        image = _table_image(bpy, f"{bpy_material.name} reflectance", np.asarray(model.reflectance(cos), np.float64))
        geometry = _node(tree, "ShaderNodeNewGeometry", (-800, 0))
        dot = _node(tree, "ShaderNodeVectorMath", (-600, 0))
        dot.operation = "DOT_PRODUCT"
        tree.links.new(geometry.outputs["Normal"], dot.inputs[0])
        tree.links.new(geometry.outputs["Incoming"], dot.inputs[1])
        # u = (cos (W - 1) + 0.5) / W: node j at texel j's centre (GL's and Blender's linear filtering alike).
        texel = _node(tree, "ShaderNodeMath", (-400, 0))
        texel.operation = "MULTIPLY_ADD"
        texel.use_clamp = True
        tree.links.new(dot.outputs["Value"], texel.inputs[0])
        texel.inputs[1].default_value = (TABLE_SIZE - 1) / TABLE_SIZE
        texel.inputs[2].default_value = 0.5 / TABLE_SIZE
        uv = _node(tree, "ShaderNodeCombineXYZ", (-200, 0), Y=0.5)
        tree.links.new(texel.outputs["Value"], uv.inputs["X"])
        lookup = _node(tree, "ShaderNodeTexImage", (0, 0))
        lookup.image, lookup.interpolation, lookup.extension = image, "Linear", "EXTEND"
        tree.links.new(uv.outputs["Vector"], lookup.inputs["Vector"])
        glossy = _node(tree, "ShaderNodeBsdfGlossy", (300, 0), Roughness=math.sqrt(max(float(getattr(model, "alpha", 0.0)), 0.0)))
        if "distribution" in dir(glossy):
            glossy.distribution = "GGX"  # single scattering, as the env view's lobe
        tree.links.new(lookup.outputs["Color"], glossy.inputs["Color"])
        tree.links.new(glossy.outputs["BSDF"], out.inputs["Surface"])
    else:
        eta1, eta2, eta3, kappa3 = (float(x) for x in model.film)
        if abs(eta1 - 1.0) > 1e-9:
            raise BlenderExportError(material.path, None, f"Blender's thin film lies in air: eta1 must be 1, got {eta1:g}")
        bsdf = _node(tree, "ShaderNodeBsdfPrincipled", (200, 0))
        bsdf.inputs["Roughness"].default_value = math.sqrt(max(float(getattr(model, "alpha", 0.0)), 0.0))
        bsdf.inputs["Thin Film Thickness"].default_value = float(model.thickness_d)
        bsdf.inputs["Thin Film IOR"].default_value = eta2
        if kappa3 > 0.0:
            f0 = abs((complex(eta3, kappa3) - 1.0) / (complex(eta3, kappa3) + 1.0)) ** 2
            bsdf.inputs["Metallic"].default_value = 1.0
            bsdf.inputs["Base Color"].default_value = (f0, f0, f0, 1.0)
        else:
            bsdf.inputs["Metallic"].default_value = 0.0
            bsdf.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)
            bsdf.inputs["IOR"].default_value = eta3
        tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])


def _world(bpy, scene, environment) -> None:
    pixels = np.roll(np.asarray(environment.pixels, np.float32), -(environment.width // 4), axis=1)  # Blender's u = ours - 1/4
    pixels = np.roll(pixels, int(round(environment.turn * environment.width)), axis=1)
    height, width = pixels.shape[:2]
    image = bpy.data.images.new("environment", width=width, height=height, float_buffer=True, alpha=False)
    rgba = np.concatenate([pixels[::-1], np.ones((height, width, 1), np.float32)], axis=2)  # Blender's rows from the bottom
    image.colorspace_settings.name = "Linear Rec.709"  # before the pixels: setting it regenerates the image
    image.pixels.foreach_set(rgba.ravel().tolist())  # a list: bpy 5.0 cannot read numpy 2 buffers
    world = bpy.data.worlds.new("environment")
    world.use_nodes = True
    tree = world.node_tree
    tree.nodes.clear()
    texture = _node(tree, "ShaderNodeTexEnvironment", (-300, 0))
    texture.image, texture.interpolation = image, "Linear"
    background = _node(tree, "ShaderNodeBackground", (0, 0), Strength=1.0)
    output = _node(tree, "ShaderNodeOutputWorld", (200, 0))
    tree.links.new(texture.outputs["Color"], background.inputs["Color"])
    tree.links.new(background.outputs["Background"], output.inputs["Surface"])
    scene.world = world


def preview_scene(material_file, values, environment, size: int = 64, samples: int = 64, film: str = "principled"):
    """A fresh scene (factory settings, nothing else) holding the env view's preview of ``material_file``."""
    bpy = _bpy()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = int(samples)
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 1  # one bounce off a convex sphere, as the env view
    scene.render.resolution_x = scene.render.resolution_y = int(size)
    scene.render.film_transparent = True  # off the sphere: 0, as the env view's background
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.render.image_settings.file_format = "OPEN_EXR"
    mesh = bpy.data.meshes.new("sphere")
    obj = bpy.data.objects.new("sphere", mesh)
    scene.collection.objects.link(obj)
    import bmesh

    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=SEGMENTS, v_segments=RINGS, radius=1.0)
    bm.to_mesh(mesh)
    bm.free()
    mesh.shade_smooth()
    bpy_material = bpy.data.materials.new(Path(str(material_file.path)).stem)
    material(bpy_material, material_file, values, film)
    mesh.materials.append(bpy_material)
    camera = bpy.data.cameras.new("camera")
    camera.type, camera.ortho_scale, camera.clip_end = "ORTHO", 2.0, 10.0
    camera_object = bpy.data.objects.new("camera", camera)
    camera_object.location = (0.0, -4.0, 0.0)  # the viewer on our +z
    camera_object.rotation_euler = (math.pi / 2, 0.0, 0.0)  # looking along +y, up +z
    scene.collection.objects.link(camera_object)
    scene.camera = camera_object
    _world(bpy, scene, environment)
    return scene


def render(scene, out: Path) -> np.ndarray:
    """Render ``scene`` with Cycles to ``out`` (EXR) and return its linear RGB ``(H, W, 3)``."""
    bpy = _bpy()
    from explorer.views.images import read_linear_image

    scene.render.filepath = str(out)
    bpy.ops.render.render(write_still=True)
    return np.asarray(read_linear_image(out), dtype=np.float64)[..., :3]


SCRIPT = '''"""
Rebuild {name} ({values_note}) on a material of your own .blend: run it inside Blender (Text Editor >
Run Script) or with bpy, where the bragg-explorer package is importable. It builds the node tree of
explorer.blender.material on the active object's material (a new one where it has none).
"""
import bpy

from explorer.blender import material
from explorer.materials.brd import load_material

source = load_material({path!r})
values = source.resolve({values!r})
target = bpy.context.object.active_material if bpy.context.object is not None else None
if target is None:
    target = bpy.data.materials.new({name!r})
    if bpy.context.object is not None:
        bpy.context.object.data.materials.append(target)
material(target, source, values)
'''


def export_blender(material_file, values, out: Path, environment, size: int = 64, samples: int = 64) -> tuple[Path, Path]:
    """Write ``out`` (.blend: the preview scene, its images packed as float EXR) and ``out``'s ``.py`` beside it."""
    from explorer.files import write_text_atomic

    if out.suffix.lower() != ".blend":
        raise BlenderExportError(out, None, "a Blender file: name it .blend")
    if not out.parent.is_dir():
        raise BlenderExportError(out, None, f"no such folder: {out.parent}")
    bpy = _bpy()
    preview_scene(material_file, values, environment, size, samples)
    for image in bpy.data.images:
        if image.source == "GENERATED":
            image.file_format = "OPEN_EXR"  # packed as float, not as an 8-bit PNG
            image.pack()
    temporary = out.with_name(out.name + ".tmp.blend")
    bpy.ops.wm.save_as_mainfile(filepath=str(temporary), compress=True)
    temporary.replace(out)
    out.chmod(0o644)
    script = out.with_suffix(".py")
    plain = {k: (list(v) if isinstance(v, tuple) else v) for k, v in values.items()}
    write_text_atomic(script, SCRIPT.format(name=Path(str(material_file.path)).stem, path=str(Path(str(material_file.path)).resolve()),
                                            values=plain, values_note="the exported values"))
    return out, script
