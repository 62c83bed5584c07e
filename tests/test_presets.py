"""Presets (shaders/presets/*.toml): every one resolves and renders; --preset, --set and bad input."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli
from explorer.materials.media import medium_name
from explorer.materials.models import GGXSchlickModel
from explorer.materials.presets import PRESET_DIR, PresetError, all_preset_files, load_presets

PRESET_FILES = sorted(PRESET_DIR.glob("*.toml"))
#: A fast method per material for the GL smoke test.
FAST_METHOD = {"thin_film": 1, "bragg_mirror": 1, "bragg_layer": 1}


def all_presets():
    return [(f.path.stem, p) for f in all_preset_files() for p in f.presets.values()]


def test_both_materials_have_presets():
    stems = {p.stem for p in PRESET_FILES}
    assert {"thin_film", "bragg_mirror"} <= stems
    names = {stem: set(load_presets(PRESET_DIR / f"{stem}.toml").presets) for stem in ("thin_film", "bragg_mirror")}
    assert {"figure1_leather", "figure7"} <= names["thin_film"]
    assert len([n for n in names["bragg_mirror"] if n.startswith("figure4_")]) == 9
    assert len([n for n in names["bragg_mirror"] if n.startswith("table3_")]) == 3


@pytest.mark.parametrize("stem, preset", all_presets(), ids=lambda x: getattr(x, "name", x))
def test_preset_resolves_within_range(stem, preset):
    values = preset.resolve()
    assert preset.figure and preset.description
    for name, value in preset.values.items():
        parameter = preset.material.parameter(name)
        if parameter.type in ("color", "bool"):  # no range: one number (grey) or r, g, b; true or false
            assert values[name] == parameter.coerce(value)
            continue
        assert parameter.min <= float(values[name]) <= parameter.max
        if isinstance(value, str):  # an index naming a medium: its medium_NAME selects it
            assert medium_name(values, name) == value
            continue
        assert float(values[name]) == pytest.approx(float(value))


def test_stack_presets_cover_the_papers_figures():
    presets = load_presets(PRESET_DIR / "bragg_stack.toml").presets
    for prefix, count in {"figure1_": 11, "figure7_": 4, "figure10_": 24, "figure11_": 7, "figure12_": 9, "table3_": 3,
                          "supplemental10_": 9, "supplemental11_": 9}.items():
        assert len([n for n in presets if n.startswith(prefix)]) == count, prefix
    left = presets["figure1_left_alpha04"].resolve()  # d1 = 125 nm, d2 = 375 nm
    assert (left["Lambda_1"] * left["delta_1"], left["Lambda_1"] * (1 - left["delta_1"]), left["N_1"], left["alpha_1"]) == (125, 375, 20, 0.4)
    pair = presets["figure1_stacked_pair"].resolve()
    assert pair["layers"] == 2 and pair["Lambda_1"] == 500 and pair["Lambda_2"] == 244 and pair["alpha_2"] == 0.1
    assert pair["Lambda_2"] * pair["delta_2"] == pytest.approx(101, abs=1e-3)
    prime = presets["figure7_A_prime"].resolve()
    assert (prime["nh"], prime["n1_1"], prime["Lambda_1"], prime["N_1"], prime["alpha_1"]) == (1.35, 1.35, 500, 10, 0.1)
    beetle = presets["table3_purple"].resolve()
    assert (beetle["nh"], beetle["n1_1"], beetle["n2_1"], beetle["Lambda_1"], beetle["delta_1"], beetle["N_1"], beetle["alpha_1"]) == (
        1, 1.6, 1.68, 205, 0.51, 6, 0.05)
    assert tuple(beetle["rho_d"]) == (0, 0, 0)
    coated = presets["supplemental11_L500_d50"].resolve()
    assert (coated["nh"], coated["n1_1"], coated["n2_1"], coated["alpha_1"]) == (1.4, 1.4, 1.6, 0.1)


def test_figure_values_from_the_papers():
    film = load_presets(PRESET_DIR / "thin_film.toml").presets
    f1 = film["figure1_leather"].resolve()
    assert (f1["eta2"], f1["d"], f1["alpha"], f1["eta3"]) == (1.3, 290.0, 0.2, 1.0)
    f7 = film["figure7"].resolve()
    assert (f7["eta2"], f7["d"], f7["eta3"], f7["kappa3"]) == (1.5, 525.0, 1.09, 0.0)
    mirror = load_presets(PRESET_DIR / "bragg_mirror.toml").presets
    f3 = mirror["figure3"].resolve()
    assert (f3["n1"], f3["n2"], f3["Lambda"], f3["delta"], f3["N"]) == (1.0, 1.5, 630.0, 0.5, 10.0)
    green = mirror["table3_green_blue"].resolve()
    assert (green["n1"], green["n2"], green["Lambda"], green["delta"], green["N"], green["nh"]) == (1.59, 1.67, 160, 0.51, 8, 1)


@pytest.mark.gl
def test_every_preset_renders_finite_in_gl(gl_renderer):
    for stem, preset in all_presets():
        values = preset.resolve({"method": FAST_METHOD[stem]} if stem in FAST_METHOD else {})
        image = gl_renderer.render(preset.material, values, "lit", 8, 8)
        assert np.isfinite(image).all(), (stem, preset.name)
        assert image.max() > 0.0, (stem, preset.name)


def test_ggx_schlick_twin_is_microfacet_times_schlick():
    model = GGXSchlickModel({"alpha": 0.3, "F0": 0.04})
    L = np.array([[np.sin(0.4), 0.0, np.cos(0.4)]])
    V = np.array([[-np.sin(0.2), 0.0, np.cos(0.2)]])
    N = np.array([[0.0, 0.0, 1.0]])
    from explorer.physics import microfacet
    from explorer.physics.fresnel import fresnel_schlick

    H = (L + V) / np.linalg.norm(L + V)
    expected = (microfacet.ggx_D(H[0, 2], 0.3) * microfacet.smith_G1(L[0, 2], 0.3) * microfacet.smith_G1(V[0, 2], 0.3)
                * fresnel_schlick(float(np.sum(H * L)), 0.04) / (4 * L[0, 2] * V[0, 2]))
    assert model.brdf(L, V, N, None, None)[0] == pytest.approx(np.full(3, expected), rel=1e-9)


@pytest.mark.gl
def test_ggx_schlick_gl_equals_numpy(gl_renderer):
    from explorer.materials.brd import load_material
    from twins import assert_twins_equal, render_both

    material = load_material(REPO_ROOT / "shaders" / "ggx_schlick.brd")
    values = material.resolve({"alpha": 0.25, "F0": 0.1})
    assert_twins_equal(render_both(gl_renderer, material, values, "lit", (24, 24), light=None), "ggx_schlick lit")


def test_preset_then_set_overrides(tmp_path):
    out = tmp_path / "x.npy"
    run = run_cli("render", "shaders/thin_film.brd", "--engine", "numpy", "--view", "gradient", "--size", "8x2",
              "--preset", "figure17_boar", "--set", "d=100", "--set", "method=3", "--out", out)
    assert run.returncode == 0, run.stderr
    got = np.load(out)
    from explorer.materials.brd import load_material
    from explorer.views.render import render_numpy
    from explorer.materials.thinfilm_model import ThinFilmModel

    material = load_material(REPO_ROOT / "shaders" / "thin_film.brd")
    boar = load_presets(PRESET_DIR / "thin_film.toml").presets["figure17_boar"]
    expected = render_numpy(ThinFilmModel(boar.resolve({"d": 100, "method": 3})), "gradient", 8, 2)
    assert np.allclose(got, expected, atol=1e-6)
    preset_only = render_numpy(ThinFilmModel(boar.resolve({"method": 3})), "gradient", 8, 2)
    assert not np.allclose(got, preset_only, atol=1e-3)  # d = 100 took effect over the preset's 600
    assert material.resolve({})["eta3"] != boar.resolve()["eta3"]


def test_unknown_preset_is_one_line(tmp_path):
    run = run_cli("render", "shaders/bragg_mirror.brd", "--preset", "no_such", "--size", "8", "--out", tmp_path / "x.png")
    line = one_line_error(run)
    assert "no_such" in line and "figure3" in line and "table3_red" in line
    assert not (tmp_path / "x.png").exists()


def test_presets_command_lists_name_material_description():
    run = run_cli("presets")
    assert run.returncode == 0, run.stderr
    assert "figure1_leather" in run.stdout and "thin_film.brd" in run.stdout and "table3_purple" in run.stdout
    run = run_cli("presets", "thin_film", "--json")
    rows = json.loads(run.stdout)
    assert {r["material"] for r in rows} == {"shaders/thin_film.brd"}
    assert all(r["description"] for r in rows)
    run = run_cli("presets", "no_such_material")
    assert run.returncode != 0 and len(run.stderr.strip().splitlines()) == 1


def write_presets(tmp_path: Path, body: str) -> Path:
    """A presets file whose material is the repository's thin film (copied next to it)."""
    shaders = tmp_path / "shaders"
    (shaders / "presets").mkdir(parents=True, exist_ok=True)
    for name in ("thin_film.brd",):
        (shaders / name).write_text((REPO_ROOT / "shaders" / name).read_text())
    (shaders / "lib").symlink_to(REPO_ROOT / "shaders" / "lib") if not (shaders / "lib").exists() else None
    path = shaders / "presets" / "thin_film.toml"
    path.write_text('material = "thin_film.brd"\n\n' + body)
    return path


@pytest.mark.parametrize("body, line, words", [
    ('[a]\nfigure = "F"\ndescription = "D"\nd = -5\n', 6, ("d", "range")),
    ('[a]\nfigure = "F"\ndescription = "D"\nbogus = 1\n', 6, ("bogus", "valid names")),
    ('[a]\nfigure = "F"\ndescription = "D"\nd = = 3\n', 6, ("TOML",)),
    ('[a]\nfigure = "F"\nd = 3\n', 3, ("description",)),
])
def test_malformed_presets_file_is_one_located_line(tmp_path, body, line, words):
    path = write_presets(tmp_path, body)
    with pytest.raises(PresetError) as caught:
        load_presets(path)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(f"{os.path.relpath(path)}:{line}:"), message
    for word in words:
        assert word in message, message


def test_malformed_presets_file_through_the_cli(tmp_path):
    path = write_presets(tmp_path, '[a]\nfigure = "F"\ndescription = "D"\neta2 = 9\n')
    run = run_cli("render", path.parent.parent / "thin_film.brd", "--preset", "a", "--size", "8", "--out", tmp_path / "x.png")
    line = one_line_error(run)
    assert "thin_film.toml:6:" in line and "eta2" in line
