"""
``render``'s outputs and inputs beyond the basics: ``--exposure``, OpenEXR output, ``--params`` files;
built-in materials by bare name (``render``, ``info``, ``presets``) and ``presets`` of a material that has
none. Through the CLI in this process (conftest.run_cli): numpy-engine gradients where the GPU adds nothing;
the one GL render in a subprocess (conftest.run_cli_process).
"""

from __future__ import annotations

import json
import time

import numpy as np
import pytest
from PIL import Image

from conftest import BRAGG_MATERIAL, BRDF_DATA, CLI_ERROR_PREFIX, REPO_ROOT, one_line_error, run_cli_process
from conftest import run_cli as cli
from test_cli import relative

from explorer.app.parameter_files import save_values
from explorer.materials.brd import load_material
from explorer.physics.colorimetry import encode_srgb8

MATERIAL = relative(BRAGG_MATERIAL)
BUILTINS = sorted(path.stem for path in (REPO_ROOT / "shaders").glob("*.brd"))
#: A cheap render: the numpy twin's gradient of a vivid mirror (negative channels: outside sRGB).
GRADIENT = ["--engine", "numpy", "--view", "gradient", "--size", "24x4", "--set", "method=1", "--set", "Lambda=300"]


def read_exr(path) -> np.ndarray:
    """An OpenEXR file as float32 RGB, through OpenCV with OpenEXR enabled (as explorer.views.env reads them)."""
    from explorer.views.env import _cv2

    cv2 = _cv2()
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert image is not None, f"OpenCV cannot read {path}"
    return image[..., ::-1]


def test_exposure_scales_the_png_encode(tmp_path):
    runs = {
        name: cli("render", MATERIAL, *GRADIENT, *extra, "--out", tmp_path / name)
        for name, extra in (("plain.npy", []), ("bright.png", ["--exposure", "2.5"]), ("plain.png", []))
    }
    for run in runs.values():
        assert run.returncode == 0, run.stderr
    linear = np.load(tmp_path / "plain.npy")
    bright = np.asarray(Image.open(tmp_path / "bright.png"))
    plain = np.asarray(Image.open(tmp_path / "plain.png"))
    np.testing.assert_array_equal(plain, encode_srgb8(linear))
    np.testing.assert_array_equal(bright, encode_srgb8(linear * np.float32(2.5)))
    assert (bright.astype(int) >= plain).all() and (bright.astype(int) > plain).any()


def test_exr_is_linear_float32_rgb(tmp_path):
    for name in ("x.exr", "x.npy"):
        run = cli("render", MATERIAL, *GRADIENT, "--out", tmp_path / name)
        assert run.returncode == 0, run.stderr
        assert str(tmp_path / name) in run.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.exr", "x.npy"]  # no temporaries
    assert (tmp_path / "x.exr").read_bytes()[:4] == b"\x76\x2f\x31\x01"  # OpenEXR's magic number
    exr, npy = read_exr(tmp_path / "x.exr"), np.load(tmp_path / "x.npy")
    assert exr.dtype == np.float32 and exr.shape == npy.shape == (4, 24, 3)
    np.testing.assert_array_equal(exr, npy)  # float32 both ways: the same values, unclamped
    assert npy.min() < 0.0 and npy.max() > 0.05  # a vivid mirror: the file keeps negative channels


@pytest.mark.gl
def test_exr_of_a_gl_render(gl_renderer, bragg_material, tmp_path):
    run = run_cli_process("render", MATERIAL, "--view", "sphere", "--size", "16", "--set", "method=3", "--out", tmp_path / "s.exr")
    assert run.returncode == 0, run.stderr
    expected = gl_renderer.render(bragg_material, bragg_material.resolve({"method": "3"}), "sphere", 16, 16)
    np.testing.assert_allclose(read_exr(tmp_path / "s.exr"), expected, rtol=0, atol=1e-6)


def test_params_files_then_set(tmp_path):
    """--params reads the app's JSON and BRDF Explorer's .bparam; --set overrides it; --preset is under it."""
    material = load_material(BRAGG_MATERIAL)
    chosen = material.resolve({"Lambda": 420, "N": 12, "delta": 0.3, "method": 1})
    save_values(tmp_path / "set.json", material, chosen)
    save_values(tmp_path / "set.bparam", material, chosen)
    jobs = {
        "set.npy": ["--set", "Lambda=420", "--set", "N=12", "--set", "delta=0.3"],
        "json.npy": ["--params", tmp_path / "set.json"],
        "bparam.npy": ["--params", tmp_path / "set.bparam"],
        "override.npy": ["--params", tmp_path / "set.json", "--set", "Lambda=600"],
        "direct.npy": ["--set", "Lambda=600", "--set", "N=12", "--set", "delta=0.3"],
        "preset.npy": ["--preset", "figure3", "--params", tmp_path / "set.json"],
    }
    base = ["--engine", "numpy", "--view", "gradient", "--size", "24x4", "--set", "method=1"]
    runs = {name: cli("render", MATERIAL, *base, *extra, "--out", tmp_path / name) for name, extra in jobs.items()}
    for name, run in runs.items():
        # The basic method is off here: render's one-line accuracy note is the only stderr allowed.
        unexpected = [line for line in run.stderr.splitlines() if ": note: method 1 basic is off here" not in line]
        assert run.returncode == 0 and not unexpected, f"{name}: {run.stderr}"
    image = {name: np.load(tmp_path / name) for name in jobs}
    np.testing.assert_allclose(image["json.npy"], image["set.npy"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(image["bparam.npy"], image["set.npy"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(image["override.npy"], image["direct.npy"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(image["preset.npy"], image["set.npy"], rtol=0, atol=1e-6)  # the file wins over the preset
    assert np.abs(image["override.npy"] - image["set.npy"]).max() > 1e-2  # Lambda=600 took effect


def test_params_names_another_material_has_are_skipped_with_a_warning(tmp_path):
    material = load_material(BRDF_DATA / "app_all_kinds.brdf")
    save_values(tmp_path / "other.json", material, material.resolve({}))
    run = cli("render", MATERIAL, *GRADIENT, "--params", tmp_path / "other.json", "--out", tmp_path / "x.npy")
    assert run.returncode == 0, run.stderr
    # render's one-line accuracy note (the chosen Bragg method off here) is not a warning.
    warnings = [line for line in run.stderr.strip().splitlines() if not line.startswith("bragg-explorer: note: ")]
    assert warnings and all(line.startswith("bragg-explorer: warning: ") and "skipped" in line for line in warnings)


BAD_CASES = [
    "missing params", "unreadable params", "malformed json", "bparam out of range", "exposure zero", "exposure negative",
    "exposure nan", "exposure text", "exposure of npy", "exposure of exr", "unknown extension", "unknown bare name",
    "unknown bare name info", "unknown bare name presets", "unknown bare name open",
]


def bad_inputs(tmp_path) -> dict[str, tuple[list, str]]:
    """Commands that must fail, and a word their one line must contain."""
    (tmp_path / "broken.json").write_text('{"values": {"N": 12,\n "Lambda": }\n}\n')
    (tmp_path / "range.bparam").write_text("bparam x.brd\n::begin parameters\nfloat N 1 1000 5000\n::end parameters\n")
    (tmp_path / "unreadable.json").mkdir()
    out = ["--out", tmp_path / "out" / "x.png"]
    return {
        "missing params": (["render", MATERIAL, *GRADIENT, "--params", tmp_path / "none.json", *out], "none.json"),
        "unreadable params": (["render", MATERIAL, *GRADIENT, "--params", tmp_path / "unreadable.json", *out], "unreadable.json"),
        "malformed json": (["render", MATERIAL, *GRADIENT, "--params", tmp_path / "broken.json", *out], "broken.json:2:"),
        "bparam out of range": (["render", MATERIAL, *GRADIENT, "--params", tmp_path / "range.bparam", *out], "range.bparam:3:"),
        "exposure zero": (["render", MATERIAL, *GRADIENT, "--exposure", "0", *out], "--exposure"),
        "exposure negative": (["render", MATERIAL, *GRADIENT, "--exposure", "-1", *out], "--exposure"),
        "exposure nan": (["render", MATERIAL, *GRADIENT, "--exposure", "nan", *out], "--exposure"),
        "exposure text": (["render", MATERIAL, *GRADIENT, "--exposure", "bright", *out], "--exposure"),
        "exposure of npy": (["render", MATERIAL, *GRADIENT, "--exposure", "2", "--out", tmp_path / "out" / "x.npy"], ".npy"),
        "exposure of exr": (["render", MATERIAL, *GRADIENT, "--exposure", "2", "--out", tmp_path / "out" / "x.exr"], ".exr"),
        "unknown extension": (["render", MATERIAL, *GRADIENT, "--out", tmp_path / "out" / "x.tiff"], ".exr"),
        "unknown bare name": (["render", "no_such_material", *GRADIENT, *out], "bragg_stack"),
        "unknown bare name info": (["info", "bragg_mirror.brdf"], "thin_film"),
        "unknown bare name presets": (["presets", "no_such_material"], "ggx_schlick"),
        "unknown bare name open": (["open", "no_such_material"], "bragg_layer"),
    }


@pytest.fixture(scope="module")
def bad_runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("bad")
    (root / "out").mkdir()
    cases = bad_inputs(root)
    assert list(cases) == BAD_CASES
    runs = {name: cli(*args) for name, (args, _) in cases.items()}
    return root, cases, runs


@pytest.mark.parametrize("case", BAD_CASES)
def test_bad_input_is_one_line_and_writes_nothing(bad_runs, case):
    root, cases, runs = bad_runs
    line = one_line_error(runs[case])
    assert cases[case][1] in line, line
    assert list((root / "out").iterdir()) == []


def test_unknown_bare_name_lists_the_builtins(bad_runs):
    line = one_line_error(bad_runs[2]["unknown bare name"])
    assert line.startswith(f"{CLI_ERROR_PREFIX}no_such_material: ")
    assert all(name in line for name in BUILTINS), line


def test_builtin_materials_by_bare_name_from_anywhere(tmp_path):
    """From a folder without shaders/: render, info and presets take a built-in's name; a file of that name wins."""
    run = cli("render", "bragg_mirror", *GRADIENT, "--out", tmp_path / "named.npy", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    reference = cli("render", MATERIAL, *GRADIENT, "--out", tmp_path / "path.npy")
    assert reference.returncode == 0, reference.stderr
    np.testing.assert_array_equal(np.load(tmp_path / "named.npy"), np.load(tmp_path / "path.npy"))
    info = cli("info", "thin_film.brd", "--json", cwd=tmp_path)
    assert info.returncode == 0, info.stderr
    assert "eta2" in {p["name"] for p in json.loads(info.stdout)["parameters"]}
    presets = cli("presets", "thin_film", cwd=tmp_path)
    assert presets.returncode == 0 and "figure1_leather" in presets.stdout, presets.stderr
    # A file in the working folder named like a built-in is that file.
    (tmp_path / "bragg_mirror.brd").write_text((REPO_ROOT / "shaders" / "ggx_schlick.brd").read_text())
    local = cli("info", "bragg_mirror.brd", "--json", cwd=tmp_path)
    assert local.returncode == 0, local.stderr
    assert {p["name"] for p in json.loads(local.stdout)["parameters"]} == {"alpha", "F0"}


def test_presets_of_a_material_without_presets_says_so(tmp_path):
    for material in ("ggx_schlick", relative(BRDF_DATA / "blinn_phong.brdf")):
        run = cli("presets", material)
        assert run.returncode == 0 and run.stderr == "", run.stderr
        assert run.stdout.strip().endswith(".toml)") and "no presets" in run.stdout, run.stdout
        assert len(run.stdout.strip().splitlines()) == 1
        listed = cli("presets", material, "--json")
        assert listed.returncode == 0 and json.loads(listed.stdout) == []
    everything = cli("presets", "--json")
    assert {row["material"] for row in json.loads(everything.stdout)} == {
        f"shaders/{path.stem}.brd" for path in (REPO_ROOT / "shaders" / "presets").glob("*.toml")}


def test_slow_commands_show_progress_and_quick_ones_stay_quiet(tmp_path, monkeypatch):
    """Work that cannot count its steps (a render, an export) says it is working every interval; a quick command prints nothing."""
    import re

    from explorer.cli import albedo

    run = cli("render", "ggx_schlick", "--view", "gradient", "--engine", "numpy", "--size", "8x1", "--out", tmp_path / "g.npy")
    assert run.returncode == 0 and "working" not in run.stderr, run.stderr
    monkeypatch.setattr(albedo, "PROGRESS_INTERVAL", 0.01)  # every command is slow at this scale
    from explorer.views import render as numpy_views

    drawn = numpy_views.render_numpy

    def slow(*args, **kwargs):  # tables cached by earlier tests make the render itself quicker than any interval
        time.sleep(0.2)
        return drawn(*args, **kwargs)

    monkeypatch.setattr(numpy_views, "render_numpy", slow)
    run = cli("render", "bragg_layer", "--view", "slice", "--engine", "numpy", "--size", "48", "--out", tmp_path / "s.npy")
    assert run.returncode == 0 and re.search(r"^bragg-explorer: render slice \(numpy\): working \(\d+ s\)$", run.stderr, re.M), run.stderr
    for target, out in (("brdf", "m.brdf"), ("materialx", "f.mtlx")):
        material = "bragg_mirror" if target == "brdf" else "thin_film"
        run = cli("export", material, "--to", target, tmp_path / out)
        assert run.returncode == 0 and f"export --to {target}: working" in run.stderr, run.stderr
    run = cli("spectrum", "bragg_mirror", "--set", "sigma=0.05", "--set", "N=4", "--json")  # disorder's realisations
    assert run.returncode == 0 and "spectrum: working" in run.stderr and json.loads(run.stdout)["R"], run.stderr
    lines = []
    monkeypatch.setattr(albedo.click, "echo", lambda text, err=False: lines.append((text, err)))
    progress = albedo.progress_printer("table", "rows")

    for done in range(1, 4):
        time.sleep(0.02)
        progress(done, 3)
    assert lines and all(err for _, err in lines) and lines[-1][0].startswith("bragg-explorer: table: 3/3 rows ("), lines
