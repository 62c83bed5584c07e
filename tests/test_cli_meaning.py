"""
What the command line and the sliders say: every parameter of every built-in material has a unit and a
one-line meaning (its ``.brd`` line's trailing comment, which BRDF Explorer ignores), shown by ``info``,
``info --json`` and the app's tooltips; commands printed run as printed; "did you mean" for names; paths
reported as typed; documented options in ``--help``; ``open`` without a material opens the default one.
"""

from __future__ import annotations

import json

import pytest

from conftest import run_cli

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
