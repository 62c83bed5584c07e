"""
``export MATERIAL --to mitsuba DIR``: the env view's scene as a Mitsuba 3 XML file beside its environment
(and a mesh of the user's in place of the sphere), which :func:`explorer.mitsuba.load_file` loads.

The XML names the BSDF plugin and its ``.brd`` parameters; ``illuminant`` is ``e`` (the explorer's colour
convention, used by the spectral variants only) and the film's ``pixel_format`` is a scene parameter
(``$pixel_format``, default ``rgb``; :func:`render_file` asks for ``xyz`` in the spectral variants and
converts with the explorer's matrix).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Mapping
from xml.sax.saxutils import quoteattr

from explorer.errors import LocatedError
from explorer.views.env import EnvironmentMap

SCENE_NAME = "scene.xml"
ENVIRONMENT_NAME = "environment.exr"
MESH_SUFFIXES = (".obj", ".ply")


class ExportError(LocatedError):
    """An export that cannot be written (one line naming the file)."""


def _value_xml(p, value) -> str:
    if p.type == "color":
        return f'<rgb name="{p.name}" value="{", ".join(f"{float(c):.9g}" for c in value)}"/>'
    if p.type == "bool":
        return f'<boolean name="{p.name}" value="{"true" if value else "false"}"/>'
    return f'<float name="{p.name}" value="{float(value):.9g}"/>'


def xml_comment(text: str) -> str:
    """``text`` made safe inside an XML comment, which may not hold ``--`` nor end in ``-`` (XML 1.0, section 2.5)."""
    while "--" in text:
        text = text.replace("--", "- -")
    return text + " " if text.endswith("-") else text


def scene_xml(material, values: Mapping[str, object], spp: int = 256, size: tuple[int, int] = (256, 256),
              mesh: str | None = None) -> str:
    """The env view's scene, with ``material`` at ``values``, as Mitsuba 3 XML text."""
    bsdf = "\n".join(f"        {_value_xml(p, values[p.name])}" for p in material.parameters)
    if mesh is None:
        shape = '    <shape type="sphere">\n        <ref id="material"/>\n    </shape>'
    else:
        kind = Path(mesh).suffix.lower()[1:]
        shape = (f'    <shape type="{kind}">\n        <string name="filename" value={quoteattr(mesh)}/>\n'
                 '        <ref id="material"/>\n    </shape>')
    return f"""<?xml version="1.0" encoding="utf-8"?>
<!-- {xml_comment(f"{material.model}: the explorer's env view, written by its export command (target mitsuba). Load it with")}
     explorer.mitsuba.load_file(path), which registers the explorer's BSDF plugins first. -->
<scene version="3.0.0">
    <default name="spp" value="{int(spp)}"/>
    <default name="pixel_format" value="rgb"/>
    <integrator type="path">
        <integer name="max_depth" value="2"/>
        <boolean name="hide_emitters" value="true"/>
    </integrator>
    <bsdf type="{material.model}" id="material">
{bsdf}
        <string name="illuminant" value="e"/>
    </bsdf>
{shape}
    <emitter type="envmap">
        <string name="filename" value="{ENVIRONMENT_NAME}"/>
    </emitter>
    <sensor type="orthographic">
        <transform name="to_world">
            <lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="{int(size[0])}"/>
            <integer name="height" value="{int(size[1])}"/>
            <string name="pixel_format" value="$pixel_format"/>
            <rfilter type="box"/>
        </film>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
    </sensor>
</scene>
"""


def _write_atomically(path: Path, write) -> None:
    """``write(temporary)`` then the rename, through :func:`explorer.files.atomic_output` (mode 0644 under the usual umask)."""
    from explorer.files import atomic_output

    with atomic_output(path) as temporary:
        write(temporary)


def export_scene(material, values: Mapping[str, object], directory: str | os.PathLike[str],
                 environment: EnvironmentMap | None = None, mesh: str | os.PathLike[str] | None = None,
                 spp: int = 256, size: tuple[int, int] = (256, 256)) -> Path:
    """
    Write ``DIR/scene.xml``, ``DIR/environment.exr`` (the environment resampled to Mitsuba's texel
    convention, :func:`explorer.mitsuba.scene.mitsuba_environment`) and a copy of ``mesh`` when given.
    Each file is written atomically. Returns the scene's path.
    """
    from explorer.mitsuba.scene import mitsuba_environment
    from explorer.views.images import OutputError, write_image

    if material.model is None or material.model not in _plugin_names():
        raise ExportError(material.path, None, f"no Mitsuba plugin for this material (plugins: {', '.join(_plugin_names())})")
    from explorer.materials.media import file_media_in

    files = file_media_in(values)
    if files:  # a scene file is read by another process, which knows the shipped media only
        raise ExportError(material.path, None, f"{files[0]} is a medium from a file: a Mitsuba scene carries the shipped "
                                               "media only (give that index as a number, or render with --engine mitsuba)")
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():
        raise ExportError(directory, None, "exists and is not a directory")
    mesh_name = None
    if mesh is not None:
        mesh = Path(mesh)
        if mesh.suffix.lower() not in MESH_SUFFIXES or not mesh.is_file():
            raise ExportError(mesh, None, "the mesh must be an existing .obj or .ply file")
        mesh_name = mesh.name
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise ExportError(directory, None, f"cannot create the directory ({error.strerror})") from None
    environment = environment if environment is not None else EnvironmentMap.default()
    try:
        write_image(mitsuba_environment(environment), directory / ENVIRONMENT_NAME)
        if mesh is not None:
            _write_atomically(directory / mesh_name, lambda tmp: shutil.copyfile(mesh, tmp))
        text = scene_xml(material, values, spp, size, mesh_name)
        _write_atomically(directory / SCENE_NAME, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    except OSError as error:
        raise ExportError(directory, None, f"cannot write ({error.strerror})") from None
    except OutputError as error:
        raise ExportError(directory, None, str(error)) from None
    return directory / SCENE_NAME


def _plugin_names() -> tuple[str, ...]:
    from explorer.mitsuba.bsdfs import plugin_names

    return plugin_names()
