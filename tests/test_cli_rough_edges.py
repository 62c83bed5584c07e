"""
Issue 18's rough edges of the CLI: ``--version``, ``--help`` naming ``test`` and showing whole command
summaries, ``info``'s method names and integers, ``render``'s default method (the app's, and said),
``--exposure auto``. In this process (conftest.run_cli), numpy-engine renders only.
"""

from __future__ import annotations

import re

import numpy as np
from PIL import Image

from conftest import REPO_ROOT, one_line_error, run_cli

from explorer.materials.methods import BraggMethod, ThinFilmMethod
from explorer.physics.colorimetry import encode_srgb8


def unwrapped(text: str) -> str:
    return " ".join(text.split())


def test_version_is_the_distribution_version():
    run = run_cli("--version")
    assert run.returncode == 0, run.stderr
    version = re.search(r'^version\s*=\s*"([^"]+)"', (REPO_ROOT / "pyproject.toml").read_text(), re.M).group(1)
    assert run.stdout.strip() == f"bragg-explorer {version}"


def test_help_names_the_test_command_and_whole_summaries():
    """Each command's line is its docstring's whole first paragraph (click cuts at ~45 characters or 'Figs.')."""
    from explorer.cli.commands import cli

    run = run_cli("--help")
    assert run.returncode == 0, run.stderr
    text = unwrapped(run.stdout)
    assert "python3 -m explorer test" in text
    commands = [c for c in cli.commands.values() if not c.hidden]
    assert len(commands) >= 10
    for command in commands:
        first = unwrapped((command.short_help or command.help).strip().split("\n\n")[0])
        assert f"{command.name} {first}" in text.replace("- ", "-"), command.name  # wrapped at a hyphen
        assert not first.endswith("..."), command.name
    assert "..." not in text.split("Commands:")[1]


def test_info_names_the_methods_and_prints_integers():
    run = run_cli("info", "bragg_mirror")
    assert run.returncode == 0, run.stderr
    lines = {line.split()[1]: line for line in run.stdout.splitlines()[1:] if line.split()[0] in ("int", "float", "bool", "color")}
    assert re.search(r"\bdefault 20 in \[1, 1000\]", lines["N"]), lines["N"]
    assert re.search(r"\bdefault 3 in \[1, 8\]", lines["s"]), lines["s"]
    names = ", ".join(f"{int(m)} {m.label}" for m in BraggMethod)  # from the enumeration, not restated
    assert f"methods: {names}" in run.stdout
    assert f"default {int(BraggMethod.TABULATED)} {BraggMethod.TABULATED.label} in" in lines["method"]
    film = run_cli("info", "thin_film", "--json")
    import json

    document = json.loads(film.stdout)
    assert document["methods"] == {str(int(m)): m.label for m in ThinFilmMethod}
    method = next(p for p in document["parameters"] if p["name"] == "method")
    assert '"default": 0,\n' in film.stdout and all(isinstance(method[k], int) for k in ("min", "max", "default"))
    floats = [p for p in document["parameters"] if p["type"] == "float"]
    assert floats and all(isinstance(p["default"], float) for p in floats)


def test_render_opens_the_default_material_as_the_app_and_says_which_method(tmp_path):
    """``render bragg_mirror`` without a method is the app's opening method (tabulated), named on stdout."""
    from explorer.app.state import initial_values
    from explorer.materials.brd import load_material
    from explorer.resources import DEFAULT_MATERIAL

    app_method = int(initial_values(load_material(DEFAULT_MATERIAL), None, True)["method"])
    base = ["render", "bragg_mirror", "--engine", "numpy", "--view", "gradient", "--size", "24x2"]
    plain = run_cli(*base, "--out", tmp_path / "plain.npy")
    assert plain.returncode == 0, plain.stderr
    label = f"{app_method} {BraggMethod(app_method).label}"
    assert f"method {label})" in plain.stdout, plain.stdout
    same = run_cli(*base, "--set", f"method={app_method}", "--out", tmp_path / "same.npy")
    assert same.returncode == 0, same.stderr
    other = run_cli(*base, "--set", "method=1", "--out", tmp_path / "other.npy")
    assert "method 1 basic)" in other.stdout
    np.testing.assert_array_equal(np.load(tmp_path / "plain.npy"), np.load(tmp_path / "same.npy"))
    assert np.abs(np.load(tmp_path / "plain.npy") - np.load(tmp_path / "other.npy")).max() > 1e-3
    # Another material keeps its file's default method.
    film = run_cli("render", "thin_film", "--engine", "numpy", "--view", "gradient", "--size", "8x2", "--out", tmp_path / "f.npy")
    assert f"method {int(ThinFilmMethod.REFERENCE)} {ThinFilmMethod.REFERENCE.label})" in film.stdout


def test_exposure_auto_brings_a_dark_film_to_white(tmp_path):
    """The README's thin film under one light: nearly black at exposure 1, its bright end near white with auto (under AgX)."""
    from explorer.views.exposure import AUTO_EXPOSURE_PERCENTILE, auto_exposure
    from explorer.views.tonemap import agx, display_srgb8

    base = ["render", "thin_film", "--engine", "numpy", "--view", "lit", "--preset", "figure1_leather", "--set", "method=3",
            "--size", "48"]
    run_cli(*base, "--out", tmp_path / "linear.npy")
    auto = run_cli(*base, "--exposure", "auto", "--out", tmp_path / "auto.png")
    assert auto.returncode == 0, auto.stderr
    linear = np.load(tmp_path / "linear.npy")
    factor = auto_exposure(linear, "agx")  # the lit view's curve
    assert f"exposure auto: {factor:.3g}" in auto.stderr
    png = np.asarray(Image.open(tmp_path / "auto.png").convert("RGB")).astype(int)
    assert np.abs(png - display_srgb8(linear, factor, "agx").astype(int)).max() <= 1
    peak = linear.max(-1)
    drawn = peak > 1e-6
    assert np.percentile(peak[drawn], AUTO_EXPOSURE_PERCENTILE) < 0.5  # dim as rendered
    near_white = encode_srgb8(agx(np.full(3, 4.0)))[0]  # AUTO_WHITE["agx"] as AgX shows it (~237 of 255)
    assert np.percentile(png.max(-1)[drawn], AUTO_EXPOSURE_PERCENTILE) >= near_white - 3
    assert auto_exposure(np.zeros((4, 4, 3))) == 1.0
    line = one_line_error(run_cli(*base, "--exposure", "auto", "--out", tmp_path / "x.npy"))
    assert "--exposure" in line
    line = one_line_error(run_cli(*base, "--exposure", "bright", "--out", tmp_path / "x.png"))
    assert "or auto" in line


def test_open_several_materials_names_the_one_that_fails(tmp_path):
    """``open A B``: a missing or malformed second material is one line naming it, before any window."""
    line = one_line_error(run_cli("open", "bragg_mirror", tmp_path / "missing.brd"))
    assert "missing.brd" in line
    broken = tmp_path / "broken.brdf"
    broken.write_text("analytic\n::begin parameters\nfloat x 0 1\n::end parameters\n")
    line = one_line_error(run_cli("open", "ggx_schlick", broken))
    assert line.startswith(f"bragg-explorer: error: {broken}:3: "), line


def test_every_bragg_material_opens_on_the_tabulated_method_whatever_its_name(tmp_path):
    """A built-in Bragg material and a copy under another name (even one whose file still declares the
    1-nm reference) open on the tabulated method in render, albedo and the app; method 0 stays a choice."""
    from explorer.app.state import initial_values
    from explorer.materials.brd import load_material
    from explorer.resources import builtin_materials

    tabulated = f"method {int(BraggMethod.TABULATED)} {BraggMethod.TABULATED.label})"
    layer = builtin_materials()["bragg_layer"]
    copy = tmp_path / "my_layer.brd"
    copy.write_text(layer.read_text().replace("int method 0 4 3", "int method 0 4 0"))
    assert "int method 0 4 0" in copy.read_text()
    for path in (layer, builtin_materials()["bragg_mirror"], copy):
        assert int(initial_values(load_material(path), None, False)["method"]) == int(BraggMethod.TABULATED), path
        run = run_cli("render", path, "--engine", "numpy", "--view", "gradient", "--size", "8x1", "--out", tmp_path / "g.npy")
        assert run.returncode == 0 and tabulated in run.stdout, (path, run.stdout, run.stderr)
    plain = run_cli("albedo", copy, "--theta", "30", "--json")
    chosen = run_cli("albedo", copy, "--theta", "30", "--json", "--set", f"method={int(BraggMethod.TABULATED)}")
    assert plain.returncode == 0 and plain.stdout == chosen.stdout, plain.stderr
    reference = run_cli("render", copy, "--engine", "numpy", "--view", "gradient", "--size", "8x1", "--set", "method=0",
                        "--out", tmp_path / "r.npy")
    assert f"method 0 {BraggMethod.REFERENCE.label})" in reference.stdout


def test_strips_list_the_methods_in_their_order():
    from explorer.app.data import BRAGG_STRIP_METHODS

    assert [int(m) for m in BRAGG_STRIP_METHODS] == sorted(int(m) for m in BraggMethod)
