"""The command line: bad input, ``info``, and renders on the GPU.

Bad input must end with exactly one line on stderr (naming the file and line where there is one),
a non-zero exit status, no traceback, and no output file (nor a temporary one) left behind. The
commands that need no GPU run in this process (conftest.run_cli, through the CLI's ``main``), once per
module; those that draw with GL in a subprocess (conftest.run_cli_process).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from conftest import BRAGG_MATERIAL, BRDF_DATA, CLI_ERROR_PREFIX as PREFIX, REPO_ROOT, CliRun, one_line_error, run_cli
from conftest import run_cli_process
from twins import Twins, assert_twins_equal


def relative(path: Path) -> str:
    return str(path.relative_to(REPO_ROOT))


def declaration_line(path: Path, name: str) -> int:
    """1-based line of the parameter declaration of ``name`` in a material file."""
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        tokens = line.split()
        if len(tokens) >= 2 and tokens[0] in ("float", "int", "bool", "color") and tokens[1] == name:
            return number
    raise AssertionError(f"{name} is not declared in {path}")


def parameters_section(path: Path) -> list[list[str]]:
    """The parameter lines of a material file, split into tokens (read here, not by explorer.materials.brd)."""
    rows, inside = [], False
    for line in path.read_text().splitlines():
        stripped = line.strip()
        if stripped.startswith("::begin parameters"):
            inside = True
        elif stripped.startswith("::end"):
            inside = False
        elif inside and stripped and not stripped.startswith("#"):
            rows.append(stripped.split("#", 1)[0].split())  # the trailing "# UNIT: meaning" apart
    return rows


# --------------------------------------------------------------------------------------------------
# Commands that need no GPU: run them all once, in this process


#: Malformed material files and the line each message must name (None: the whole file).
BAD_FILES = {
    "bad_bool_default.brdf": 4,
    "bad_default_range.brdf": 5,
    "bad_duplicate.brdf": 6,
    "bad_field_count.brdf": 4,
    "bad_identifier.brdf": 4,
    "bad_keyword_name.brdf": 4,
    "bad_kind_measured.brdf": 3,
    "bad_min_gt_max.brdf": 4,
    "bad_mismatched_end.brdf": 5,
    "bad_missing_header.brdf": 2,
    "bad_nested.brdf": 5,
    "bad_no_shader.brdf": None,
    "bad_not_a_number.brdf": 4,
    "bad_unknown_type.brdf": 5,
    "bad_unterminated.brdf": 6,
}
BAD_SIZES = ["0", "12xz", "0x5", "99999", "-5", "8x8x8"]
INFO_FILES = {
    "bragg_mirror.brd": BRAGG_MATERIAL,
    "colored_lambert.brdf": BRDF_DATA / "colored_lambert.brdf",
    "blinn_phong.brdf": BRDF_DATA / "blinn_phong.brdf",
}


def failure_cases(out: Path) -> dict[str, list[str]]:
    """Commands that must fail; each writes (if anything) into its own directory out/<case>."""
    material = relative(BRAGG_MATERIAL)
    cases = {
        "unknown --set name": ["render", material, "--size", "8", "--out", "{dir}/x.png", "--set", "bogus=1"],
        "value out of range": ["render", material, "--size", "8", "--out", "{dir}/x.png", "--set", "N=5000"],
        "value not a number": ["render", material, "--size", "8", "--out", "{dir}/x.png", "--set", "delta=half"],
        "--set without =": ["render", material, "--size", "8", "--out", "{dir}/x.png", "--set", "N"],
        "missing material": ["render", "shaders/no_such_material.brd", "--size", "8", "--out", "{dir}/x.png"],
        "missing --out directory": ["render", material, "--engine", "numpy", "--view", "gradient", "--size", "8",
                                    "--out", "{dir}/missing/x.png"],
        "bad extension": ["render", material, "--engine", "numpy", "--view", "gradient", "--size", "8",
                          "--out", "{dir}/x.jpg"],
        "--out is a directory": ["render", material, "--engine", "numpy", "--view", "gradient", "--size", "8",
                                 "--out", "{dir}/x.png"],
        "existing output untouched": ["render", material, "--size", "8", "--out", "{dir}/x.png", "--set", "n1=9"],
    }
    for name in BAD_FILES:
        cases[f"malformed {name}"] = ["render", relative(BRDF_DATA / name), "--size", "8", "--out", "{dir}/x.png"]
    for size in BAD_SIZES:
        cases[f"bad --size {size}"] = ["render", material, "--size", size, "--out", "{dir}/x.png"]
    return cases


@dataclass
class FailureRun:
    run: CliRun
    directory: Path
    before: dict[str, bytes]


@pytest.fixture(scope="module")
def cli_runs(tmp_path_factory):
    """Every GPU-free command of this module: failures and ``info --json``."""
    root = tmp_path_factory.mktemp("cli")
    jobs, failures = {}, {}
    for index, (case, args) in enumerate(failure_cases(root).items()):
        directory = root / f"case{index}"
        directory.mkdir()
        if case == "--out is a directory":
            (directory / "x.png").mkdir()
        if case == "existing output untouched":
            (directory / "x.png").write_bytes(b"previous image")
        before = {p.name: (p.read_bytes() if p.is_file() else b"") for p in directory.iterdir()}
        failures[case] = FailureRun(None, directory, before)  # type: ignore[arg-type]
        jobs[("fail", case)] = [a.replace("{dir}", str(directory)) for a in args]
    for name, path in INFO_FILES.items():
        jobs[("info", name)] = ["info", relative(path), "--json"]
    results = {job: run_cli(*args) for job, args in jobs.items()}
    for (kind, case), run in results.items():
        if kind == "fail":
            failures[case].run = run
    infos = {name: results[("info", name)] for name in INFO_FILES}
    return failures, infos


def check_one_line_failure(failure: FailureRun) -> str:
    line = one_line_error(failure.run)
    # Nothing written: no output, no temporary file; a previous output is left as it was.
    after = {p.name: (p.read_bytes() if p.is_file() else b"") for p in failure.directory.iterdir()}
    assert after == failure.before, f"files changed in the output directory: {sorted(after)}"
    return line[len(PREFIX):]


def test_unknown_set_name(cli_runs):
    message = check_one_line_failure(cli_runs[0]["unknown --set name"])
    assert message.startswith(f"{relative(BRAGG_MATERIAL)}: ")
    assert "bogus" in message
    for name in ("n1", "n2", "Lambda", "delta", "N", "nh", "method"):
        assert re.search(rf"\b{name}\b", message), f"valid name {name} not listed: {message}"


@pytest.mark.parametrize("case,parameter", [("value out of range", "N"), ("value not a number", "delta"),
                                            ("existing output untouched", "n1")])
def test_bad_value_names_declaration(cli_runs, case, parameter):
    message = check_one_line_failure(cli_runs[0][case])
    line = declaration_line(BRAGG_MATERIAL, parameter)
    assert message.startswith(f"{relative(BRAGG_MATERIAL)}:{line}: "), message
    assert f"'{parameter}'" in message


def test_out_of_range_message_gives_the_range(cli_runs):
    message = check_one_line_failure(cli_runs[0]["value out of range"])
    tokens = BRAGG_MATERIAL.read_text().splitlines()[declaration_line(BRAGG_MATERIAL, "N") - 1].split()
    low, high = float(tokens[2]), float(tokens[3])
    assert "5000" in message and f"{low:g}" in message and f"{high:g}" in message


@pytest.mark.parametrize("case", ["--set without =", "missing material"])
def test_other_bad_arguments(cli_runs, case):
    message = check_one_line_failure(cli_runs[0][case])
    expected = "--set" if case == "--set without =" else "shaders/no_such_material.brd"
    assert message.startswith(expected), message


@pytest.mark.parametrize("name", list(BAD_FILES))
def test_malformed_material_names_file_and_line(cli_runs, name):
    message = check_one_line_failure(cli_runs[0][f"malformed {name}"])
    where = relative(BRDF_DATA / name)
    line = BAD_FILES[name]
    expected = f"{where}:{line}: " if line is not None else f"{where}: "
    assert message.startswith(expected), message


@pytest.mark.parametrize("size", BAD_SIZES)
def test_bad_size(cli_runs, size):
    message = check_one_line_failure(cli_runs[0][f"bad --size {size}"])
    assert "--size" in message and size in message


@pytest.mark.parametrize("case", ["missing --out directory", "bad extension", "--out is a directory"])
def test_unwritable_out(cli_runs, case):
    message = check_one_line_failure(cli_runs[0][case])
    assert str(cli_runs[0][case].directory) in message


@pytest.mark.parametrize("name", list(INFO_FILES))
def test_info_json_schema(cli_runs, name):
    run = cli_runs[1][name]
    assert run.returncode == 0 and run.stderr == "", run.stderr
    info = json.loads(run.stdout)
    assert set(info) <= {"parameters", "methods", "capabilities"}
    if "methods" in info:  # the names of an int method parameter's values, from the enumeration
        from explorer.materials.brd import load_material
        from explorer.materials.methods import methods_for

        enumeration = methods_for(load_material(INFO_FILES[name]).model)
        assert info["methods"] == {str(int(m)): m.label for m in enumeration}
    rows = parameters_section(INFO_FILES[name])
    assert [p["name"] for p in info["parameters"]] == [row[1] for row in rows]
    for parameter, row in zip(info["parameters"], rows):
        assert set(parameter) == {"name", "type", "min", "max", "default", "unit", "doc"}
        assert parameter["type"] == row[0]
        if row[0] in ("float", "int"):
            assert [parameter["min"], parameter["max"], parameter["default"]] == [float(t) for t in row[2:5]]
            assert all(isinstance(parameter[k], (int, float)) and not isinstance(parameter[k], bool)
                       for k in ("min", "max", "default"))
            assert parameter["min"] <= parameter["default"] <= parameter["max"]
            if row[0] == "int":
                assert all(float(parameter[k]).is_integer() for k in ("min", "max", "default"))
        elif row[0] == "bool":
            assert parameter["min"] is None and parameter["max"] is None
            assert parameter["default"] is bool(int(row[2]))
        else:
            assert parameter["min"] <= min(parameter["default"]) <= max(parameter["default"]) <= parameter["max"]
            default = parameter["default"]
            assert isinstance(default, list) and len(default) == 3
            assert all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in default)
            assert default == [float(t) for t in row[2:5]]


def test_info_json_covers_the_four_kinds(cli_runs):
    kinds = {p["type"] for run in cli_runs[1].values() for p in json.loads(run.stdout)["parameters"]}
    assert kinds == {"float", "int", "bool", "color"}


# --------------------------------------------------------------------------------------------------
# Commands that render on the GPU


@pytest.mark.gl
def test_render_png_and_npy(gl_renderer, tmp_path):
    from explorer.physics.colorimetry import encode_srgb8
    from PIL import Image

    material = relative(BRAGG_MATERIAL)
    png, npy = tmp_path / "sphere.png", tmp_path / "sphere.npy"
    for out in (png, npy):
        run = run_cli_process("render", material, "--view", "sphere", "--size", "32", "--out", out)
        assert run.returncode == 0, run.stderr
        assert "Traceback" not in run.stderr
        assert len(run.stdout.splitlines()) == 1 and str(out) in run.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sphere.npy", "sphere.png"]  # no temporaries
    image = np.load(npy)
    assert image.dtype == np.float32 and image.shape == (32, 32, 3)
    assert np.isfinite(image).all()
    with Image.open(png) as picture:
        assert picture.format == "PNG" and picture.mode == "RGB" and picture.size == (32, 32)
        pixels = np.asarray(picture)
    # The PNG is the same render, sRGB-encoded and clamped.
    np.testing.assert_array_equal(pixels, encode_srgb8(image))


@pytest.mark.gl
def test_render_npy_equals_numpy_twin(gl_renderer, bragg_material, tmp_path):
    from explorer.materials.models import model_for
    from explorer.views.render import render_numpy

    out = tmp_path / "basic.npy"
    size = (40, 24)
    run = run_cli_process("render", relative(BRAGG_MATERIAL), "--view", "sphere", "--size", f"{size[0]}x{size[1]}",
              "--set", "method=1", "--set", "Lambda=300", "--out", out)
    assert run.returncode == 0, run.stderr
    image = np.load(out)
    assert image.dtype == np.float32 and image.shape == (size[1], size[0], 3)
    values = bragg_material.resolve({"method": "1", "Lambda": "300"})
    reference = render_numpy(model_for(bragg_material, values), "sphere", *size)
    assert_twins_equal(Twins.of(image, reference, "sphere"), "CLI sphere .npy")
    assert np.abs(reference).max() > 0.05  # a visible mirror, not an empty image


@pytest.mark.gl
def test_glsl_compile_error_names_file_and_line(gl_renderer, tmp_path):
    text = BRAGG_MATERIAL.read_text().splitlines(keepends=True)
    target = next(i for i, line in enumerate(text) if "return reference_rgb(" in line)
    text[target] = text[target].replace("return reference_rgb(", "return undeclared_thing + reference_rgb(")
    broken = tmp_path / "broken.brd"
    broken.write_text("".join(text))
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    run = run_cli_process("render", broken, "--size", "8", "--set", "method=0", "--out", out_dir / "x.png")
    failure = FailureRun(run, out_dir, {})
    message = check_one_line_failure(failure)
    assert message.startswith(f"{broken}:{target + 1}: "), message
    assert "undeclared_thing" in message
