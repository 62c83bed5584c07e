"""
What the command line and the sliders say: every parameter of every built-in material has a unit and a
one-line meaning (its ``.brd`` line's trailing comment, which BRDF Explorer ignores), shown by ``info``,
``info --json`` and the app's tooltips; commands printed run as printed; "did you mean" for names; paths
reported as typed; documented options in ``--help``; ``open`` without a material opens the default one.
"""

from __future__ import annotations

import json

import pytest

from conftest import REPO_ROOT, one_line_error, run_cli

from explorer.materials.brd import parse_material
from explorer.resources import builtin_materials


@pytest.mark.parametrize("name", sorted(builtin_materials()))
def test_info_json_gives_every_parameter_a_unit_and_a_meaning(name):
    run = run_cli("info", name, "--json")
    assert run.returncode == 0, run.stderr
    for parameter in json.loads(run.stdout)["parameters"]:
        assert parameter["unit"] and " " not in parameter["unit"], (name, parameter)
        assert len(parameter["doc"]) >= 10 and "\n" not in parameter["doc"], (name, parameter)
    text = run_cli("info", name).stdout
    for parameter in json.loads(run.stdout)["parameters"]:
        assert parameter["doc"] in text, (name, parameter["name"])


def test_the_trailing_comment_is_a_unit_and_a_meaning_and_brdf_explorer_ignores_it():
    from explorer.app.panels.parameters import parameter_tooltip
    from test_export_brdf import parse_brdf

    text = ("analytic\n::begin parameters\nfloat Lambda 100 1000 420  # nm: period of the mirror\n"
            "float plain 0 1 0.5\nfloat loose 0 1 0.5  # just words\n::end parameters\n"
            "::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(Lambda); }\n::end shader\n")
    material = parse_material(text, "m.brd")
    Lambda, plain, loose = material.parameters
    assert (Lambda.unit, Lambda.doc, Lambda.default) == ("nm", "period of the mirror", 420.0)
    assert (plain.unit, plain.doc) == ("", "") and (loose.unit, loose.doc) == ("", "just words")
    tip = parameter_tooltip(Lambda)
    assert tip.startswith("period of the mirror\n") and "[100, 1000] nm" in tip
    parameters, _ = parse_brdf(text)  # BRDF Explorer's reading: the comment after the fields is ignored
    assert parameters[0][:5] == ["float", "Lambda", "100", "1000", "420"]


def test_an_exported_brdf_keeps_the_meanings(tmp_path):
    out = tmp_path / "m.brdf"
    assert run_cli("export", "bragg_mirror", "--to", "brdf", out).returncode == 0
    from explorer.materials.brd import load_material

    exported = {p.name: p for p in load_material(out).parameters}
    assert exported["Lambda"].unit == "nm" and "period" in exported["Lambda"].doc


def test_did_you_mean_for_materials_parameters_presets_and_views(tmp_path):
    out = tmp_path / "x.png"
    cases = {
        ("render", "bragg_mirrror", "--out", out): "did you mean 'bragg_mirror'?",
        ("render", "bragg_mirror", "--set", "Lamda=400", "--out", out): "did you mean 'Lambda'?",
        ("render", "bragg_layer", "--preset", "figure8_alpha01x", "--out", out): "did you mean 'figure8_alpha01'?",
        ("render", "bragg_mirror", "--view", "sphre", "--out", out): "did you mean 'sphere'?",
        ("albedo", "thin_flim"): "did you mean 'thin_film'?",
    }
    for args, hint in cases.items():
        line = one_line_error(run_cli(*args))
        assert hint in line, (args, line)


def test_params_alone_names_its_material_and_paths_are_reported_as_typed(tmp_path):
    from explorer.app.parameter_files import save_values
    from explorer.materials.brd import load_material

    material = load_material(builtin_materials()["thin_film"])
    params = tmp_path / "params.json"
    save_values(params, material, material.resolve({"d": 400.0}))
    out = tmp_path / "g.npy"
    run = run_cli("render", "--params", params, "--view", "gradient", "--engine", "numpy", "--size", "8x1", "--out", out)
    assert run.returncode == 0, run.stderr
    reference = tmp_path / "r.npy"
    run_cli("render", "thin_film", "--set", "d=400", "--view", "gradient", "--engine", "numpy", "--size", "8x1", "--out", reference)
    import numpy as np

    np.testing.assert_array_equal(np.load(out), np.load(reference))
    missing = tmp_path / "nowhere" / "p.json"  # absolute, from another working directory
    line = one_line_error(run_cli("render", "thin_film", "--params", missing, "--out", out, cwd=REPO_ROOT / "docs"))
    assert f"{missing}:" in line, line
    line = one_line_error(run_cli("render", "--out", out))
    assert "MATERIAL" in line


def test_a_built_in_named_by_name_is_reported_by_name(tmp_path):
    """Errors about a built-in typed as a name name it so, not by its installed file's absolute path; a file stays as typed."""
    from explorer.resources import SHADER_DIR

    out = tmp_path / "x.npy"
    for cwd in (REPO_ROOT, tmp_path):
        line = one_line_error(run_cli("render", "bragg_layer", "--set", "Lambda=9999", "--out", out, cwd=cwd))
        assert "error: bragg_layer:" in line and str(SHADER_DIR) not in line, line
        line = one_line_error(run_cli("export", "bragg_mirror.brd", "--to", "materialx", tmp_path / "x.mtlx", cwd=cwd))
        assert "error: bragg_mirror.brd:" in line and str(SHADER_DIR) not in line, line
    typed = SHADER_DIR / "bragg_mirror.brd"  # a file named by its path keeps it
    line = one_line_error(run_cli("render", typed, "--set", "Lamda=400", "--out", out, cwd=tmp_path))
    assert f"error: {typed}:" in line, line


def test_open_documents_its_options_and_opens_the_default_material_without_one(monkeypatch):
    text = run_cli("open", "--help").stdout
    for option in ("--script", "--window-size", "--report"):
        assert option in text, option
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    run = run_cli("open")  # no display here: the error is the display's, not a missing argument
    assert "Missing argument" not in run.stderr and "display" in run.stderr, run.stderr


def test_printed_commands_run_as_printed(tmp_path, monkeypatch):
    """Without the console script on PATH (a checkout), a printed command is ``python3 -m explorer ...``."""
    import shlex

    from conftest import run_cli_process
    from explorer.cli.design import render_command
    from explorer.cli.materials import PROG, command_prefix

    monkeypatch.setenv("PATH", str(tmp_path))
    assert command_prefix() == "python3 -m explorer"
    (tmp_path / PROG).write_text("#!/bin/sh\n")
    (tmp_path / PROG).chmod(0o755)
    assert command_prefix() == PROG
    monkeypatch.undo()
    printed = render_command("bragg_mirror", {"Lambda": 420.0})
    words = shlex.split(printed)
    prefix = shlex.split(command_prefix())
    assert words[:len(prefix)] == prefix
    args = [a.replace("design.png", str(tmp_path / "design.png")) for a in words[len(prefix):]]
    run = run_cli_process(*args, "--size", "16x2")
    assert run.returncode == 0 and (tmp_path / "design.png").is_file(), run.stderr
