"""
``export --to table`` (the documented EXR layout) and ``--to materialx`` (validated by MaterialX itself):
what the files hold against the numpy twins, and bad input as one line.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from conftest import run_cli
from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.resources import material_path


def _read_exr(path):
    os.environ.setdefault("OPENCV_IO_ENABLE_OPENEXR", "1")
    import cv2

    return cv2.imread(str(path), cv2.IMREAD_UNCHANGED)[..., ::-1].astype(np.float64)


def test_smooth_table_is_the_reflectance(tmp_path):
    """A Bragg mirror's table is the converged (tabulated) colour, whatever the method it is exported at."""
    from explorer.materials.methods import BraggMethod

    out = tmp_path / "mirror.exr"
    run = run_cli("export", "bragg_mirror", "--set", "method=0", "--set", "Lambda=420", "--to", "table", out)
    assert run.returncode == 0, run.stderr
    table = _read_exr(out)
    from explorer.materials.export_table import COLUMNS

    assert table.shape == (1, COLUMNS, 3)
    material = load_material(material_path("bragg_mirror"))
    converged = material.resolve({"method": int(BraggMethod.TABULATED), "Lambda": 420})
    expected = model_for(material, converged).reflectance(np.linspace(0, 1, COLUMNS))
    np.testing.assert_allclose(table[0], expected, rtol=1e-6, atol=1e-7)
    # The 1-nm sum differs from the converged colour by at most 0.01 here.
    reference = model_for(material, material.resolve({"method": 0, "Lambda": 420})).reflectance(np.linspace(0, 1, COLUMNS))
    assert np.abs(reference - expected).max() < 0.01


def test_dense_reflectance_reads_the_film_within_1e_5():
    """The rough rows read a material's smooth colour from a dense copy: within 1e-5 of the method's own."""
    from explorer.materials import export_table as et

    material = load_material(material_path("thin_film"))
    for overrides in ({}, {"d": material.parameter("d").max}):
        model = model_for(material, material.resolve(overrides))
        c = np.random.default_rng(1).uniform(0.0, 1.0, 500)
        np.testing.assert_allclose(et._dense_reflectance(model)(c), model.reflectance(c), rtol=0, atol=1e-5)


def test_rough_table_rows_are_directional_albedos():
    """Row 0 is the smooth limit; a rough row is the albedo int f cos, checked by a plain cosine-weighted quadrature."""
    from explorer.materials import export_table as et

    material = load_material(material_path("ggx_schlick"))
    values = material.resolve({"F0": 0.5})
    old = et.ROWS
    et.ROWS = 4
    try:
        table = et.material_table(material, values)
    finally:
        et.ROWS = old
    assert table.shape == (4, et.COLUMNS, 3)
    model = model_for(material, values)
    np.testing.assert_allclose(table[0], model.reflectance(np.linspace(0, 1, et.COLUMNS)), rtol=1e-6)
    # alpha = 2/3 at cos theta = 0.6: a broad lobe, a dense midpoint rule in (cos theta_l, phi)
    alpha, j = 2.0 / 3.0, int(round(0.6 * (et.COLUMNS - 1)))
    cos_v = j / (et.COLUMNS - 1)
    rough = model_for(material, {**values, "alpha": alpha})
    c = (np.arange(400) + 0.5) / 400
    phi = (np.arange(400) + 0.5) / 400 * 2 * np.pi
    C, P = np.meshgrid(c, phi)
    s = np.sqrt(1 - C ** 2)
    l = np.stack([s * np.cos(P), s * np.sin(P), C], -1).reshape(-1, 3)
    v = np.broadcast_to([np.sqrt(1 - cos_v ** 2), 0, cos_v], l.shape)
    e = np.eye(3)
    albedo = (rough.brdf(l, v, e[2], e[0], e[1]) * l[:, 2:3]).sum(0) * (1 / 400) * (2 * np.pi / 400)
    np.testing.assert_allclose(table[2, j], albedo, rtol=0.03)
    assert (table[1:, -1].mean(-1) <= 1.0 + 1e-3).all()


def test_materialx_export_validates_and_maps_the_film(tmp_path):
    pytest.importorskip("MaterialX")
    from explorer.materials.export_materialx import validate_document

    out = tmp_path / "film.mtlx"
    run = run_cli("export", "thin_film", "--set", "d=410", "--set", "eta2=1.33", "--set", "alpha=0.09", "--to", "materialx", out)
    assert run.returncode == 0, run.stderr
    text = out.read_text()
    validate_document(text)
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlString(doc, text)
    node = doc.getNode("SR_thin_film")
    assert node.getCategory() == "standard_surface"
    assert node.getInputValue("thin_film_thickness") == pytest.approx(410)
    assert node.getInputValue("thin_film_IOR") == pytest.approx(1.33)
    assert node.getInputValue("specular_roughness") == pytest.approx(0.3)
    broken = text.replace('name="thin_film_IOR" type="float"', 'name="thin_film_IOR" type="color3"')
    with pytest.raises(Exception, match="validate"):
        validate_document(broken)


@pytest.mark.parametrize("args, hint", [
    (["export", "bragg_mirror", "--to", "materialx", "x.mtlx"], "thin film"),
    (["export", "thin_film", "--set", "eta1=1.3", "--to", "materialx", "x.mtlx"], "eta1"),
    (["export", "thin_film", "--to", "materialx", "x.txt"], ".mtlx"),
    (["export", "thin_film", "--to", "table", "x.png"], ".exr"),
    (["export", "thin_film", "--to", "table", "--mesh", "m.obj", "x.exr"], "--mesh"),
])
def test_bad_exports_are_one_line(tmp_path, args, hint):
    run = run_cli(*args, cwd=tmp_path)
    assert run.returncode != 0 and len(run.stderr.strip().splitlines()) == 1 and hint in run.stderr, run.stderr
    assert not any(tmp_path.iterdir())
