"""
What the exports write is what they say: every XML and JSON file parsed by a strict parser (xml.etree,
json), every .brdf read as BRDF Explorer and the explorer read it, every file written with mode 0644 under
the usual umask; an exported .brdf bakes the tabulated method's table for its values whatever the exported
method, and away from them falls back to the improved approximation, never to black.
"""

from __future__ import annotations

import json
import os
import stat
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from conftest import run_cli
from test_export_brdf import parse_brdf

from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod
from explorer.resources import builtin_materials, material_path


@pytest.fixture
def usual_umask():
    previous = os.umask(0o022)
    try:
        yield
    finally:
        os.umask(previous)


def _mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def test_every_export_is_well_formed_and_0644(tmp_path, usual_umask):
    written = []
    scene_dir = tmp_path / "scene"
    run = run_cli("export", "bragg_mirror", "--to", "mitsuba", scene_dir)
    assert run.returncode == 0, run.stderr
    scene = scene_dir / "scene.xml"
    root = ET.parse(scene).getroot()  # strict: a "--" inside a comment is "not well-formed"
    assert root.tag == "scene"
    assert "--" not in scene.read_text().split("<!--", 1)[1].split("-->", 1)[0]
    written += [scene, scene_dir / "environment.exr"]

    mtlx = tmp_path / "film.mtlx"
    assert run_cli("export", "thin_film", "--to", "materialx", mtlx).returncode == 0
    ET.parse(mtlx)
    written.append(mtlx)

    glb = tmp_path / "film.glb"
    assert run_cli("export", "thin_film", "--to", "gltf", glb).returncode == 0
    data = glb.read_bytes()
    length = int.from_bytes(data[12:16], "little")
    assert data[16:20] == b"JSON"
    json.loads(data[20:20 + length].decode("utf-8"))
    written.append(glb)

    brdf = tmp_path / "m.brdf"
    assert run_cli("export", "bragg_mirror", "--to", "brdf", brdf).returncode == 0
    parameters, shader = parse_brdf(brdf.read_text())
    assert parameters and "vec3 BRDF(" in shader
    load_material(brdf)  # the explorer's parser: no warning, no error
    written += [brdf, brdf.with_suffix(".bparam")]

    table = tmp_path / "t.exr"
    assert run_cli("export", "bragg_mirror", "--to", "table", table).returncode == 0
    written.append(table)

    params = tmp_path / "p.json"
    from explorer.app.parameter_files import save_values

    material = load_material(material_path("bragg_mirror"))
    save_values(params, material, material.resolve({}))
    json.loads(params.read_text())
    written.append(params)

    for path in written:
        assert _mode(path) == 0o644, (path, oct(_mode(path)))


@pytest.mark.gl
def test_exported_brdf_bakes_the_tabulated_table_and_never_goes_black(gl_renderer, tmp_path):
    """``export bragg_mirror --to brdf --set Lambda=400`` (here at the 1-nm reference, another method than
    the table's): method 3 of the file equals the original's within 1e-3 of the peak; each method of the
    file renders colours; moving Lambda, method 3 reads method 4."""
    out = tmp_path / "m.brdf"
    run = run_cli("export", "bragg_mirror", "--to", "brdf", out, "--set", "Lambda=400", "--set", "method=0")
    assert run.returncode == 0, run.stderr
    text = out.read_text()
    header = text[:text.index("::begin parameters")]
    tabulated, improved = (f"{int(m)} {m.label}" for m in (BraggMethod.TABULATED, BraggMethod.IMPROVED))
    assert "baked for" in header and "Lambda = 400" in header and f"falls back to method {improved}" in header
    exported = load_material(out)
    original = load_material(material_path("bragg_mirror"))
    size = (48, 1)
    reference = gl_renderer.render(original, original.resolve({"Lambda": 400, "method": int(BraggMethod.TABULATED)}), "gradient", *size)
    peak = np.abs(reference).max()
    for method in BraggMethod:
        image = gl_renderer.render(exported, exported.resolve({"method": int(method)}), "gradient", *size)
        assert np.isfinite(image).all() and image.max() > 0.05, (method, image.max())
        if method == BraggMethod.TABULATED:
            assert np.abs(image - reference).max() <= 1e-3 * peak
    moved = {"Lambda": 520}
    at_3 = gl_renderer.render(exported, exported.resolve({**moved, "method": int(BraggMethod.TABULATED)}), "gradient", *size)
    at_4 = gl_renderer.render(exported, exported.resolve({**moved, "method": int(BraggMethod.IMPROVED)}), "gradient", *size)
    assert at_3.max() > 0.05
    np.testing.assert_array_equal(at_3, at_4)
    assert f"method {tabulated}" in header


def test_table_export_bakes_every_bragg_material_at_the_tabulated_method():
    """``export --to table`` bakes a Bragg material (built-in or a copy) at the tabulated method whatever its
    file's or the user's method; other materials keep theirs."""
    from explorer.materials.export_table import table_values
    from explorer.materials.methods import methods_for

    bragg = 0
    for name, path in builtin_materials().items():
        material = load_material(path)
        if not any(p.name == "method" for p in material.parameters):
            continue
        values = table_values(material, material.resolve({"method": 0}))
        expected = int(BraggMethod.TABULATED) if methods_for(material) is BraggMethod else 0
        assert int(values["method"]) == expected, name
        bragg += methods_for(material) is BraggMethod
    assert bragg >= 2
