"""
Hypothesis fuzzing of every parser of user input, and of the command line: whatever the input, a
parser returns or raises its own one-line error type, and a command line ends with exit 0 or one line
on stderr; never a traceback, a hang or a partial file. Fixed seeds (``derandomize``), no example
database: each CI run tries the same inputs, at least 2,000 command lines among them.
"""

from __future__ import annotations

import json
from pathlib import Path

import click
import pytest
from hypothesis import HealthCheck, event, given, settings, strategies as st

from conftest import CLI_ERROR_PREFIX, REPO_ROOT, GLContextInProcess, run_cli

FUZZ = settings(derandomize=True, deadline=None, database=None, max_examples=60,
                suppress_health_check=list(HealthCheck))

#: Tokens a user might type, or mistype: numbers at and beyond every edge, odd text, paths outside.
NUMBERS = ["0", "1", "-1", "0.5", "1e308", "-1e308", "1e-320", "nan", "inf", "-inf", "9" * 400, "9" * 5000,
           "1_0", "0x10", "", " ", "1,2,3", "-1,-1,-1", "1,2", "2,0.5,0.5", "1e6", "3000", "3001"]
WORDS = ["analytic", "bparam", "float", "int", "bool", "color", "::begin", "::end", "parameters", "shader",
         "isFunc", "#", "# model: lambert", "# specialise: n", "#include \"../x.glsl\"", "#include \"/etc/passwd\"",
         "#include <lib/bragg.glsl>", "vec3", "BRDF(", "{", "}", "x", "n", "N", "gl_x", "a__b", "é", "\x00", "\t"]
token = st.sampled_from(NUMBERS + WORDS) | st.text(max_size=12)
line = st.lists(token, max_size=7).map(" ".join)


def _lines(lines: list[str]) -> str:
    return "\n".join(lines) + "\n"


@FUZZ
@given(st.lists(line | st.sampled_from([
    "analytic", "::begin parameters", "::end parameters", "::begin shader", "::end shader",
    "float x 0 1 0.5", "int n 1 10 2", "color c 1 1 1 0 2", "color c 0.5 0.5 0.5", "bool b 1",
    "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(x); }",
]), max_size=14), st.sampled_from(["m.brd", "m.brdf"]),
   st.dictionaries(st.sampled_from(["x", "n", "c", "b", "zz"]), token, max_size=3))
def test_fuzz_material_parser(lines, name, overrides):
    """``.brd``/``.brdf`` text: a Material or a one-line MaterialError; its values resolve or a MaterialError."""
    from explorer.materials.brd import MaterialError, parse_material

    try:
        material = parse_material(_lines(lines), name)
    except MaterialError as error:
        assert "\n" not in str(error)
        return
    try:
        material.resolve(overrides)
    except MaterialError as error:
        assert "\n" not in str(error)


@FUZZ
@given(st.lists(line | st.sampled_from([
    "bparam /x/m.brd", "::begin parameters", "::end parameters", "float d 0 3000 525", "color eta 1 2 3", "bool b 1",
]), max_size=10))
def test_fuzz_bparam(lines):
    from explorer.app.parameter_files import ParameterFileError, parse_bparam

    try:
        parse_bparam(_lines(lines), "p.bparam")
    except ParameterFileError as error:
        assert "\n" not in str(error)


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8)
    | st.sampled_from([10**400, -(10**400)]),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=6), children, max_size=4),
    max_leaves=12,
)


@FUZZ
@given(st.one_of(
    st.builds(lambda values: {"values": values}, st.dictionaries(st.sampled_from(["d", "eta2", "method", "x"]), json_values, max_size=4)),
    json_values,
), st.sampled_from(["", "[" * 3000, "{\"values\": ", "\ufeff"]))
def test_fuzz_json_parameter_sets(tmp_path_factory, document, prefix):
    from explorer.app.parameter_files import ParameterFileError, load_json
    from explorer.materials.brd import load_material

    path = tmp_path_factory.mktemp("json") / "p.json"
    text = prefix + json.dumps(document, allow_nan=True) if prefix else json.dumps(document, allow_nan=True)
    path.write_text(text)
    try:
        load_json(path, load_material(REPO_ROOT / "shaders" / "thin_film.brd"))
    except ParameterFileError as error:
        assert "\n" not in str(error)


@FUZZ
@given(st.lists(line | st.sampled_from([
    'material = "thin_film.brd"', 'material = "/etc/passwd"', 'material = "../x.brd"', "[a]", '[a.b]',
    'figure = "F"', 'description = "D"', "d = 525", "d = " + "9" * 400, "d = " + "9" * 5000, "eta2 = [1, 2, 3]",
    "method = true", "d = [[[[1]]]]", "d = {x = 1}", "x = 1",
]), max_size=10))
def test_fuzz_presets(tmp_path_factory, lines):
    from explorer.materials.presets import PresetError, load_presets

    folder = tmp_path_factory.mktemp("presets")
    (folder / "thin_film.brd").write_text((REPO_ROOT / "shaders" / "thin_film.brd").read_text())
    (folder / "presets").mkdir()
    path = folder / "presets" / "thin_film.toml"
    path.write_text(_lines(lines))
    try:
        load_presets(path)
    except PresetError as error:
        assert "\n" not in str(error) and "root:" not in str(error)


@FUZZ
@given(st.sampled_from(["d", "eta2", "method", "rho_d", "tau_1", "eta_base", "coating", "N_1", "zz", ""]),
       st.lists(token, min_size=1, max_size=3).map(",".join), st.sampled_from(["thin_film", "bragg_stack", "layered_lobes"]))
def test_fuzz_set_values(name, value, material):
    from explorer.materials.brd import MaterialError, parse_assignment
    from explorer.resources import builtin_materials
    from explorer.materials.brd import load_material

    loaded = load_material(builtin_materials()[material])
    try:
        loaded.resolve(dict([parse_assignment(f"{name}={value}")]))
    except MaterialError as error:
        assert "\n" not in str(error)


@FUZZ
@given(st.lists(st.tuples(st.sampled_from(["R", "sigma", "layers", "base", "eta", "tau", "t", "eta_top", "x", ""]),
                          token | st.sampled_from(["dielectric", "conductor", "2", "0.3,0.2,0.1"])), max_size=6),
       st.sampled_from([" ", ";", "; "]))
def test_fuzz_lobe_strings(pairs, separator):
    from explorer.cli.inverse import parse_lobe

    spec = separator.join(f"{k}={v}" for k, v in pairs)
    try:
        parse_lobe(spec)
    except click.UsageError as error:
        assert "\n" not in error.format_message()


@FUZZ
@given(st.lists(token | st.integers(-5, 70000).map(str), min_size=1, max_size=3).map("x".join) | token,
       st.sampled_from(["sphere", "gradient", "env"]))
def test_fuzz_size(text, view):
    from explorer.cli.commands import MAX_SIZE, parse_size

    try:
        width, height = parse_size(text, view)
    except click.BadParameter as error:
        assert "\n" not in error.format_message()
    else:
        assert 1 <= width <= MAX_SIZE and 1 <= height <= MAX_SIZE


# -- the command line ---------------------------------------------------------------------------------------

MATERIALS = ["bragg_mirror", "thin_film", "layered_lobes", "bragg_stack", "nonexistent", "/etc/passwd", "/dev/null",
             "shaders", str(REPO_ROOT / "tests" / "data" / "brdf" / "colored_lambert.brdf")]
OUTS = ["x.png", "x.npy", "x.exr", "x.xyz", "x", "/nonexistent/x.png", ".", "sub/x.png", "x.PNG"]
OPTIONS = {
    "render": {
        "--view": ["sphere", "gradient", "lit", "slice", "scatter", "textured", "env", "bogus"],
        "--set": ["d=1e308", "rho_d=-1,-1,-1", "method=9", "x", "=1", "d=", "tau_1=" + "9" * 400, "eta2=1.5"],
        "--size": ["0", "2", "2x3", "abc", "1x", "9" * 5000, "16384", "70000", "-2"],
        "--engine": ["numpy", "gl", "cuda"],
        "--light": ["45,0", "200,0", "nan,0", "1", "a,b"],
        "--preset": ["figure7", "nope", ""],
        "--params": ["/etc/passwd", "/nonexistent.json", "p.json", "p.bparam"],
        "--exposure": ["2", "0", "-1", "nan", "x"],
        "--texture": ["/etc/passwd", "/nonexistent.png", "shaders"],
        "--dinc-range": ["0,1125", "0,1e300", "5,1", "x", "-1,2"],
        "--prefilter": ["on", "off", "maybe"],
        "--env": ["/etc/passwd", "x.hdr", "/nonexistent.exr"],
        "--spp": ["0", "1", "-1", "x"],
    },
    "info": {"--json": None},
    "presets": {"--json": None},
    "inverse": {"--lobe": ["R=0.5 sigma=0.1", "R=0.05 sigma=1e308", "R=2 sigma=0.1", "R=0.5 sigma=0.1 base=conductor eta=-1",
                           "R=0.5", "sigma=1", "R=0.3,0.2,0.1 sigma=0.2 layers=2", "bogus"], "--json": None, "--tir": None},
    "figure": {"--lobe": ["R=-0.5 sigma=0.1", "R=0.5 sigma=-1", "bad", "R=0.5 sigma=1e308"],
               "--out": ["x.xyz", "/nonexistent/f.png", "x"], "--samples": ["0", "7", "x", "500"]},
    "bench": {"--size": ["0", "-1", "x"], "--repeats": ["0", "-3", "y"], "--json": None},
    "accuracy": {"--plot": ["/nonexistent/x.png", "x.xyz", "x"], "--strips": ["x.xyz", "/nonexistent/s.png", "."]},
}
#: The valid values among those (a "clean" command line takes only these, to reach deeper).
VALID = {
    "--view": ["sphere", "gradient", "lit", "slice", "scatter", "textured", "env"], "--set": ["eta2=1.5", "d=1e308"],
    "--size": ["2", "2x3"], "--engine": ["numpy"], "--light": ["45,0"], "--preset": ["figure7"],
    "--exposure": ["2"], "--dinc-range": ["0,1125"], "--prefilter": ["on", "off"], "--spp": ["1"],
    "--lobe": ["R=0.5 sigma=0.1", "R=0.3,0.2,0.1 sigma=0.2 layers=2", "R=0.5 sigma=0.1 base=conductor eta=-1"],
}
#: Commands that would do seconds of work when every option is valid: each of their command lines
#: carries at least one invalid option value (all of theirs listed above are invalid).
ALWAYS_INVALID = {"figure", "bench", "accuracy"}


@st.composite
def command_lines(draw):
    command = draw(st.sampled_from(list(OPTIONS) + ["bogus", "--version", "--help", "render --help"]))
    if command not in OPTIONS:
        return command.split()
    argv = [command]
    if command in ("render", "info", "presets") and draw(st.booleans() if command == "presets" else st.just(True)):
        argv.append(draw(st.sampled_from(MATERIALS)))
    options = OPTIONS[command]
    clean = command not in ALWAYS_INVALID and draw(st.booleans())
    names = draw(st.lists(st.sampled_from(sorted(options)), min_size=1 if command in ALWAYS_INVALID else 0, max_size=5))
    if command in ALWAYS_INVALID and not any(options[n] for n in names):
        names.append(next(n for n in sorted(options) if options[n]))
    for name in names:
        if options[name] is None or (clean and name not in VALID):
            argv += [name] if options[name] is None else []
            continue
        argv += [name, draw(st.sampled_from(VALID[name] if clean else options[name]))]
    if command == "render":
        argv += ["--out", draw(st.sampled_from(OUTS))]
        if "--engine" not in argv or draw(st.booleans()):
            argv += ["--engine", "numpy"]
        if "env" in argv:
            argv += ["--size", "1", "--engine", "gl"]  # the numpy env integral takes seconds a pixel
        elif "--size" not in argv:
            argv += ["--size", "2"]
    if command == "inverse" and "--lobe" not in argv and draw(st.booleans()):
        argv += ["--lobe", "R=0.4 sigma=0.05"]
    extra = [] if clean else draw(st.sampled_from([[], [], [], ["--bogus"], ["--debug"], [""], ["-"]]))
    return argv + extra


@pytest.fixture(scope="module")
def fuzz_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("argv")
    (folder / "sub").mkdir()
    (folder / "p.json").write_text('{"values": {"d": %s}}' % ("9" * 400))
    (folder / "p.bparam").write_text("root:x:0:0:root:/root:/bin/bash\n")
    (folder / "x.hdr").write_bytes(b"#?RADIANCE\n\n-Y 20000 +X 20000\n")
    return folder


def _check_run(argv, folder: Path) -> None:
    before = {p.name for p in folder.iterdir()}
    try:
        run = run_cli(*argv, cwd=folder)
    except GLContextInProcess:
        event("reached the GPU")
        return  # valid up to the GPU: the GL renders are tested in subprocesses elsewhere
    event(f"{argv[0]}: exit {run.returncode}")
    assert "Traceback" not in run.stdout + run.stderr, (argv, run.stderr)
    assert "internal error" not in run.stderr, (argv, run.stderr)
    if run.returncode != 0:
        lines = [l for l in run.stderr.strip().splitlines() if not l.startswith("bragg-explorer: warning:")]
        assert len(lines) == 1 and lines[0].startswith(CLI_ERROR_PREFIX), (argv, run.stderr)
    left = {p.name for p in folder.iterdir()} - before
    assert not [name for name in left if name.startswith(".") and ".tmp" in name], (argv, left)
    for name in left:  # a new output is whole: it exists only after a successful run
        assert run.returncode == 0, (argv, left)
        (folder / name).unlink()


@settings(FUZZ, max_examples=2000)
@given(command_lines())
@pytest.mark.slow
def test_fuzz_command_lines(fuzz_folder, argv):
    """At least 2,000 generated command lines (fixed seed), in this process: exit 0 or one line, nothing partial."""
    _check_run(argv, fuzz_folder)
