"""
The materials in Blender (Cycles): ``export MATERIAL --to blender FILE.blend`` and
:func:`material` (docs/blender.md). Needs ``bpy`` (Blender as a Python module, 5.0.x).

- A smooth mirror (a twin whose env view is a Dirac: ``bragg_mirror``) is its reflectance baked into a
  float image over ``cos theta`` (:data:`TABLE_SIZE` columns, ``cos theta = j / (size - 1)``, texel centres
  as GL's), looked up per shading point from the Geometry node's Normal and Incoming, driving a Glossy
  BSDF at roughness 0: exact for a smooth mirror up to the table's linear interpolation.
- A rough material (a GGX roughness parameter) is its converged table (:func:`converged_tables`: its
  directional albedo over the Glossy's own at colour 1) colouring a GGX Glossy of its roughness, plus a
  Diffuse BSDF of its base's share where it has one (``rho_d``): exact under uniform light. ``film="principled"``
  maps a thin film onto Principled's Thin Film instead, and a stack of rough interfaces onto its coat and
  specular (the model's ``principled_layers``): editable in Blender, further off (docs/blender.md).
- Any other material is its directional albedo colouring a Diffuse BSDF.

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


#: Columns of a rough material's converged table (its colour varies slowly with the view: read linearly).
ROUGH_TABLE_SIZE = 64
#: How a thin film may map (``--blender-film``): its converged table (the default, the closer), or Principled's Thin Film.
FILM_PATHS = ("table", "principled")


def mapping_of(material, values) -> str:
    """
    ``"table"`` (a smooth mirror: its reflectance), ``"converged"`` (a rough material: its converged table
    driving a GGX lobe), ``"diffuse"`` (neither smooth nor
    GGX: its directional albedo colouring a Diffuse BSDF) or a :class:`BlenderExportError`.
    """
    from explorer.materials.models import model_for
    from explorer.materials.twins import capabilities_of

    model = model_for(material, values)
    if model is None or not callable(getattr(model, "reflectance", None)):
        raise BlenderExportError(material.path, None, "no Blender mapping: this material has no numpy twin (no known '# model:' line)")
    if capabilities_of(material).dirac:
        return "table"
    if _roughness_names(material):
        return "converged"
    return "diffuse"


def _roughness_names(material) -> list[str]:
    from explorer.materials.export_table import roughness_names

    return roughness_names(material)


def lobe_roughness(material, values) -> float:
    """The GGX ``alpha`` of the one lobe Cycles draws: the first roughness parameter (``alpha`` or ``alpha_1``)."""
    names = sorted(_roughness_names(material))
    return float(values[names[0]]) if names else 0.0


class _UnitLobe:
    """The GGX lobe of Cycles' Glossy BSDF at colour 1 (no Fresnel), Smith's separable shadowing as the twins'."""

    def __init__(self, alpha: float):
        self.alpha = alpha

    def brdf(self, L, V, N, X, Y) -> np.ndarray:
        from explorer.physics import microfacet

        lobe, _, _ = microfacet.microfacet_lobe(L, V, N, self.alpha)
        return np.repeat(lobe[..., None], 3, axis=-1)


def converged_tables(material, values, size: int = ROUGH_TABLE_SIZE) -> tuple[np.ndarray, np.ndarray | None]:
    """
    A rough material's converged tables over ``cos theta = j / (size - 1)``: the colour of a GGX Glossy of
    the lobe's roughness, its directional albedo over the Glossy's own at colour 1 (the split sum: exact
    under uniform light, the view-angle colour of a half-vector reflectance otherwise), and the diffuse
    base's share of the albedo (None without one): the albedo with the base (``rho_d``) less without it.
    """
    from explorer.materials.export_table import _albedo, _dense_reflectance, table_values
    from explorer.materials.models import model_for

    values = table_values(material, values)
    alpha = lobe_roughness(material, values)
    cos = np.linspace(0.0, 1.0, size)

    def albedo(v):
        model = model_for(material, v)
        if "film" in dir(model):  # a film reads its Fresnel from reflectance(): once, densely
            model.reflectance = _dense_reflectance(model_for(material, v))
        return _albedo(model, cos, alpha)

    total = albedo(values)
    unit = _albedo(_UnitLobe(max(alpha, 1e-3)), cos, alpha)[:, :1]
    diffuse = None
    rho_d = values.get("rho_d")
    if rho_d is not None and np.max(np.abs(np.asarray(rho_d, np.float64))) > 0.0:
        specular = albedo({**values, "rho_d": (0.0, 0.0, 0.0)})
        diffuse, total = np.maximum(total - specular, 0.0), specular
    return total / np.maximum(unit, 1e-9), diffuse


def _cos_lookup(tree, image, size: int, x: float):
    """An image lookup at ``u = (cos (W - 1) + 0.5) / W`` (node j at texel j's centre), ``cos`` = Normal . Incoming."""
    geometry = _node(tree, "ShaderNodeNewGeometry", (x - 800, 0))
    dot = _node(tree, "ShaderNodeVectorMath", (x - 600, 0))
    dot.operation = "DOT_PRODUCT"
    tree.links.new(geometry.outputs["Normal"], dot.inputs[0])
    tree.links.new(geometry.outputs["Incoming"], dot.inputs[1])
    texel = _node(tree, "ShaderNodeMath", (x - 400, 0))
    texel.operation = "MULTIPLY_ADD"
    texel.use_clamp = True
    tree.links.new(dot.outputs["Value"], texel.inputs[0])
    texel.inputs[1].default_value = (size - 1) / size
    texel.inputs[2].default_value = 0.5 / size
    uv = _node(tree, "ShaderNodeCombineXYZ", (x - 200, 0), Y=0.5)
    tree.links.new(texel.outputs["Value"], uv.inputs["X"])
    lookup = _node(tree, "ShaderNodeTexImage", (x, 0))
    lookup.image, lookup.interpolation, lookup.extension = image, "Linear", "EXTEND"
    tree.links.new(uv.outputs["Vector"], lookup.inputs["Vector"])
    return lookup


def _glossy(tree, colour_socket, alpha: float, location):
    glossy = _node(tree, "ShaderNodeBsdfGlossy", location, Roughness=math.sqrt(max(alpha, 0.0)))
    glossy.distribution = "GGX"  # single scattering, as the env view's lobe
    tree.links.new(colour_socket, glossy.inputs["Color"])
    return glossy


def _principled_film(tree, material, model):
    """A single film through Principled's Thin Film: a dielectric base (black, IOR eta3) or a metal (its F0)."""
    eta1, eta2, eta3, kappa3 = (float(x) for x in model.film)
    if abs(eta1 - 1.0) > 1e-9:
        raise BlenderExportError(material.path, None, f"Blender's thin film lies in air: eta1 must be 1, got {eta1:g}")
    bsdf = _node(tree, "ShaderNodeBsdfPrincipled", (200, 0))
    bsdf.distribution = "GGX"  # single scattering, as the env view's lobe
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
    return bsdf


def material(bpy_material, material, values, film: str = "table") -> None:
    """
    Build ``material`` at ``values`` into ``bpy_material`` (its node tree replaced): the function FILE.py calls.
    ``film``: a thin film (or a stack of rough interfaces) through its converged table (``"table"``, the
    default: the closer, docs/blender.md) or Principled's own inputs (``"principled"``: Thin Film, or coat
    over specular; editable in Blender).
    """
    bpy = _bpy()
    from explorer.materials.models import model_for

    if film not in FILM_PATHS:
        raise BlenderExportError("film", None, f"a thin film maps as {' or '.join(FILM_PATHS)}, not {film!r}")
    kind = mapping_of(material, values)
    model = model_for(material, values)
    if kind == "converged" and film == "principled" and "film" in dir(model) and hasattr(model, "thickness_d"):
        kind = "principled"
    elif kind == "converged" and film == "principled" and callable(getattr(model, "principled_layers", None)):
        kind = "lobes"
    bpy_material.use_nodes = True
    tree = bpy_material.node_tree
    tree.nodes.clear()
    out = _node(tree, "ShaderNodeOutputMaterial", (800, 0))
    name = bpy_material.name
    if kind == "table":
        cos = np.linspace(0.0, 1.0, TABLE_SIZE)
        image = _table_image(bpy, f"{name} reflectance", np.asarray(model.reflectance(cos), np.float64))
        shader = _glossy(tree, _cos_lookup(tree, image, TABLE_SIZE, 0).outputs["Color"], 0.0, (300, 0))
    elif kind == "converged":
        specular, diffuse = converged_tables(material, values)
        lookup = _cos_lookup(tree, _table_image(bpy, f"{name} converged", specular), ROUGH_TABLE_SIZE, 0)
        shader = _glossy(tree, lookup.outputs["Color"], lobe_roughness(material, values), (300, 0))
        if diffuse is not None:
            base = _cos_lookup(tree, _table_image(bpy, f"{name} base", diffuse), ROUGH_TABLE_SIZE, 0)
            base.location = (0, -300)
            lambert = _node(tree, "ShaderNodeBsdfDiffuse", (300, -300))
            tree.links.new(base.outputs["Color"], lambert.inputs["Color"])
            add = _node(tree, "ShaderNodeAddShader", (550, 0))
            tree.links.new(shader.outputs["BSDF"], add.inputs[0])
            tree.links.new(lambert.outputs["BSDF"], add.inputs[1])
            shader = add
    elif kind == "diffuse":
        from explorer.materials.export_table import _albedo

        albedo = _albedo(model_for(material, values), np.linspace(0.0, 1.0, ROUGH_TABLE_SIZE), 1.0)
        lookup = _cos_lookup(tree, _table_image(bpy, f"{name} albedo", albedo), ROUGH_TABLE_SIZE, 0)
        shader = _node(tree, "ShaderNodeBsdfDiffuse", (300, 0))
        tree.links.new(lookup.outputs["Color"], shader.inputs["Color"])
    elif kind == "principled":
        shader = _principled_film(tree, material, model)
    else:
        shader = _principled_lobes(tree, model.principled_layers())
    tree.links.new(shader.outputs[0], out.inputs["Surface"])


def _principled_lobes(tree, layers: dict):
    """Principled's coat over its specular layer (``layers`` from the model's ``principled_layers``)."""
    bsdf = _node(tree, "ShaderNodeBsdfPrincipled", (200, 0))
    bsdf.distribution = "GGX"
    for name, value in layers.items():
        bsdf.inputs[name].default_value = value
    return bsdf


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


def preview_scene(material_file, values, environment, size: int = 64, samples: int = 64, film: str = "table"):
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
material(target, source, values, film={film!r})
'''


def export_blender(material_file, values, out: Path, environment, size: int = 64, samples: int = 64,
                   film: str = "table") -> tuple[Path, Path]:
    """Write ``out`` (.blend: the preview scene, its images packed as float EXR) and ``out``'s ``.py`` beside it."""
    from explorer.files import write_text_atomic

    if out.suffix.lower() != ".blend":
        raise BlenderExportError(out, None, "a Blender file: name it .blend")
    if not out.parent.is_dir():
        raise BlenderExportError(out, None, f"no such folder: {out.parent}")
    bpy = _bpy()
    preview_scene(material_file, values, environment, size, samples, film)
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
                                            values=plain, values_note="the exported values", film=film))
    return out, script
