"""Media from files in render (``--set n2=my_layer.csv``): read as the library's media are, bad files in one line."""

from __future__ import annotations

import numpy as np

from conftest import one_line_error, run_cli
from explorer.materials.brd import load_material
from explorer.materials.media import index_value, medium_number
from explorer.materials.models import model_for
from explorer.physics import dispersion
from explorer.resources import material_path

CSV = "wavelength_nm,n,k\n350,1.9,0.1\n600,1.8,0.05\n850,1.7,0.02\n"


def test_a_file_medium_renders_as_its_dispersion(tmp_path):
    (tmp_path / "layer.csv").write_text(CSV)
    material = load_material(material_path("bragg_mirror"))
    values = material.resolve({"n2": str(tmp_path / "layer.csv"), "N": 6, "Lambda": 250, "nh": 1})
    medium = index_value(values, "n2")
    assert isinstance(medium, dispersion.Dispersion) and medium.name == str(tmp_path / "layer.csv")
    assert values["medium_n2"] == medium_number(medium) > 8  # numbered after the library, once
    assert material.resolve({"n2": str(tmp_path / "layer.csv")})["medium_n2"] == values["medium_n2"]
    model = model_for(material, values)
    assert model.natural is not None and model.natural.n2 == medium
    # The colour is the one of the same medium given to the physics directly.
    from explorer.physics.natural import natural_rgb

    expected = natural_rgb(np.array([1.0, 0.5]), model.natural)
    np.testing.assert_allclose(model.reflectance(np.array([1.0, 0.5])), expected, atol=2e-3)
    run = run_cli("render", "bragg_mirror", "--set", f"n2={tmp_path / 'layer.csv'}", "--set", "N=6", "--view", "gradient",
                  "--size", "16x1", "--engine", "numpy", "--out", str(tmp_path / "g.npy"))
    assert run.returncode == 0, run.stderr
    from explorer.rendering import render_material

    direct = render_material(material, material.resolve({"n2": str(tmp_path / "layer.csv"), "N": 6}), "gradient", 16, 1, "numpy")
    np.testing.assert_allclose(np.load(tmp_path / "g.npy"), direct, atol=1e-6)
    plain = render_material(material, material.resolve({"n2": 1.8, "N": 6}), "gradient", 16, 1, "numpy")
    assert np.abs(direct - plain).max() > 0.01  # the file's absorption and dispersion show


def test_a_bad_medium_file_is_one_line_naming_its_line(tmp_path):
    (tmp_path / "bad.csv").write_text(CSV.replace("600,1.8", "600,x"))
    line = one_line_error(run_cli("render", "bragg_mirror", "--set", f"n2={tmp_path / 'bad.csv'}", "--view", "gradient",
                                  "--engine", "numpy", "--out", str(tmp_path / "g.png")))
    assert f"{tmp_path / 'bad.csv'}:3:" in line


def test_exports_refuse_a_file_medium_in_one_line(tmp_path):
    (tmp_path / "layer.csv").write_text(CSV)
    for to, out in (("brdf", tmp_path / "x.brdf"), ("mitsuba", tmp_path / "scene")):
        line = one_line_error(run_cli("export", "bragg_mirror", str(out), "--to", to, "--set", f"n2={tmp_path / 'layer.csv'}"))
        assert "medium from a file" in line and "n2=" in line
