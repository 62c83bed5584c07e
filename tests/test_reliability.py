"""
Bad inputs a new user tries: each ends as one line on stderr and a non-zero exit, never a traceback, a
signal, a silent wrong image or a partial file (the atomic outputs, the GL limits, the input domains, the
confined includes, the table cache). GL rows run the CLI in a subprocess (run_cli_process).
"""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli, run_cli_process


# -- outputs -------------------------------------------------------------------------------------------

def test_atomic_output_keeps_old_file_on_failure(tmp_path):
    """Any exception inside the block (a full disk, Ctrl-C) leaves the target as it was and no temp file."""
    from explorer.files import OutputError, atomic_output, write_bytes_atomic

    target = tmp_path / "f.png"
    target.write_bytes(b"old")
    for error in (OSError(28, "No space left on device"), KeyboardInterrupt(), SystemExit(143)):
        with pytest.raises((OutputError, KeyboardInterrupt, SystemExit)):
            with atomic_output(target) as temporary:
                temporary.write_bytes(b"partial")
                raise error
        assert target.read_bytes() == b"old" and sorted(p.name for p in tmp_path.iterdir()) == ["f.png"]
    write_bytes_atomic(target, b"new")
    assert target.read_bytes() == b"new" and sorted(p.name for p in tmp_path.iterdir()) == ["f.png"]


def test_figure_on_a_full_disk_keeps_the_old_file(tmp_path):
    """``ulimit -f 8`` (8 blocks): the PNG cannot be written; the old file is intact, no temp file left."""
    old = tmp_path / "f.png"
    old.write_bytes(b"an old figure")
    script = (f"import resource, sys; resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096)); "
              f"sys.argv = ['bragg-explorer', 'figure', '--lobe', 'R=0.5 sigma=0.1', '--samples', '8', '--out', {str(old)!r}]; "
              f"from explorer.cli.commands import main; main()")
    run = subprocess.run([sys.executable, "-c", script], cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
    assert "cannot write" in one_line_error(run)
    assert old.read_bytes() == b"an old figure" and [p.name for p in tmp_path.iterdir()] == ["f.png"]


@pytest.mark.parametrize("args, fragment", [
    (["accuracy", "--plot", "/nonexistent/x.png"], "directory /nonexistent does not exist"),
    (["accuracy", "--strips", "x.xyz"], "must end in .png"),
    (["accuracy", "--plot", "x.xyz"], "must end in .png, .pdf or .svg"),
    (["figure", "--lobe", "R=0.5 sigma=0.1", "--out", "x.xyz"], "must end in .png, .pdf or .svg"),
    (["render", "bragg_mirror", "--out", "x.xyz"], "must end in .png, .npy or .exr"),
])
def test_outputs_are_checked_before_any_work(tmp_path, args, fragment):
    start = time.perf_counter()
    run = run_cli(*args, cwd=tmp_path)
    assert fragment in one_line_error(run)
    assert time.perf_counter() - start < 5.0 and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_interrupted_write_leaves_no_temp_file(tmp_path, signum):
    """Ctrl-C or SIGTERM while a large output is written: no temporary file, the target untouched."""
    target = tmp_path / "big.npy"
    target.write_bytes(b"old")
    script = textwrap.dedent(f"""
        import signal, sys, time
        from explorer.cli.commands import _terminate
        from explorer.files import atomic_output
        signal.signal(signal.SIGTERM, _terminate)
        with atomic_output({str(target)!r}) as temporary:
            with open(temporary, "wb") as stream:
                stream.write(b"x" * 1000)
                stream.flush()
                print("writing", flush=True)
                time.sleep(60)
    """)
    process = subprocess.Popen([sys.executable, "-c", script], cwd=REPO_ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdout.readline().strip() == "writing"
    assert len(list(tmp_path.iterdir())) == 2  # the target and the temporary file
    process.send_signal(signum)
    process.communicate(timeout=60)
    assert process.returncode != 0
    assert [p.name for p in tmp_path.iterdir()] == ["big.npy"] and target.read_bytes() == b"old"


# -- the table cache --------------------------------------------------------------------------------------

@pytest.fixture
def lut_dir(tmp_path, monkeypatch):
    from explorer.tables import luts

    monkeypatch.setattr(luts, "_cache", {})
    return tmp_path / "luts"


def test_cache_manifest_list_and_directory_table_regenerate(lut_dir):
    from explorer.tables import luts

    reference = luts.generate("cmf_1nm", lut_dir)
    (lut_dir / luts.MANIFEST).write_text("[]")
    assert luts.staleness("cmf_1nm", lut_dir) == "not in the manifest"
    np.testing.assert_array_equal(luts.load("cmf_1nm", lut_dir, log=lambda m: None), reference)
    assert luts.staleness("cmf_1nm", lut_dir) is None
    luts._cache.clear()
    (lut_dir / "cmf_1nm.npy").unlink()
    (lut_dir / "cmf_1nm.npy").mkdir()  # a directory where the table should be: regenerated in memory
    messages = []
    np.testing.assert_array_equal(luts.load("cmf_1nm", lut_dir, log=messages.append), reference)
    assert len(messages) == 1 and "regenerating cmf_1nm" in messages[0]


def test_cache_readers_never_see_partial_files(lut_dir):
    """One process regenerates the table over and over while others load it: every load succeeds."""
    from explorer.tables import luts

    luts.generate("cmf_cumulative", lut_dir)
    writer = subprocess.Popen([sys.executable, "-c", (
        "import sys; from pathlib import Path; from explorer.tables import luts; import explorer.physics.colorimetry\n"
        f"for _ in range(40): luts.generate('cmf_cumulative', Path({str(lut_dir)!r}))")], cwd=REPO_ROOT)
    reader = (f"import sys; from pathlib import Path; from explorer.tables import luts; import explorer.physics.colorimetry\n"
              f"for _ in range(200):\n"
              f"    luts._cache.clear(); t = luts.load('cmf_cumulative', Path({str(lut_dir)!r}), log=lambda m: None)\n"
              f"    assert t.shape == (472, 3)\n")
    readers = [subprocess.run([sys.executable, "-c", reader], cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
               for _ in range(2)]
    writer.wait(timeout=300)
    assert writer.returncode == 0
    for run in readers:
        assert run.returncode == 0, run.stderr
    assert sorted(p.name for p in lut_dir.iterdir() if not p.name.startswith(".")) == ["cmf_cumulative.npy", "manifest.json"]
    assert not [p for p in lut_dir.iterdir() if p.name.endswith(".npy") and p.name.startswith(".")]


# -- parameters ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("text, fragment", [
    ('{"values": {"d": %s}}' % ("9" * 400), "parameter 'd': value inf is outside its range [0, 3000]"),
    ('{"values": {"d": %s}}' % ("9" * 5000), "parameter 'd': value inf is outside its range [0, 3000]"),
    ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
    ('{"values": {"eta2": [1, [2, 3]]}}', "parameter 'eta2'"),
])
def test_json_params_huge_or_deep(tmp_path, text, fragment):
    params = tmp_path / "p.json"
    params.write_text(text)
    line = one_line_error(run_cli("render", "thin_film", "--params", params, "--out", tmp_path / "x.png"))
    assert "p.json" in line and fragment in line


@pytest.mark.parametrize("digits", [400, 5000])
def test_preset_with_a_huge_integer_names_file_and_line(tmp_path, digits):
    from explorer.materials.presets import PresetError, load_presets

    (tmp_path / "presets").mkdir()
    (tmp_path / "thin_film.brd").write_text((REPO_ROOT / "shaders" / "thin_film.brd").read_text())
    path = tmp_path / "presets" / "thin_film.toml"
    path.write_text(f'material = "thin_film.brd"\n\n[big]\nfigure = "x"\ndescription = "y"\nd = {"9" * digits}\n')
    with pytest.raises(PresetError) as info:
        load_presets(path)
    assert info.value.line == 6 and "\n" not in str(info.value)


def test_preset_naming_a_non_material_shows_nothing_of_it(tmp_path):
    from explorer.materials.presets import PresetError, load_presets

    secret = tmp_path / "secret.txt"
    secret.write_text("root:x:0:0:root:/root:/bin/bash\n")
    (tmp_path / "presets").mkdir()
    for material in (str(secret), "/etc/passwd"):
        path = tmp_path / "presets" / "p.toml"
        path.write_text(f'material = "{material}"\n[a]\nfigure = "x"\ndescription = "y"\n')
        with pytest.raises(PresetError) as info:
            load_presets(path)
        assert "root:" not in str(info.value) and info.value.line == 1
    run = run_cli("info", secret)
    assert "root" not in one_line_error(run).replace(str(tmp_path), "")
    bparam = tmp_path / "p.bparam"
    bparam.write_text("root:x:0:0:root:/root:/bin/bash\n")
    line = one_line_error(run_cli("render", "thin_film", "--params", bparam, "--out", tmp_path / "x.png"))
    assert "root:" not in line.replace(str(tmp_path), "")


@pytest.mark.parametrize("material, value, fragment", [
    ("bragg_stack", "rho_d=-1,-1,-1", "parameter 'rho_d': component -1 is outside its range [0, 1]"),
    ("bragg_layer", "rho_d=2", "outside its range [0, 1]"),
    ("layered_lobes", "eta_base=0,1,1", "outside its range [0.001, 10000000000]"),
    ("layered_lobes", "tau_1=" + "9" * 400, "parameter 'tau_1': "),
])
def test_colour_parameters_have_a_checked_range(tmp_path, material, value, fragment):
    line = one_line_error(run_cli("render", material, "--set", value, "--engine", "numpy", "--out", tmp_path / "x.png"))
    assert fragment in line


def test_colour_range_declaration():
    from explorer.materials.brd import MaterialError, parse_material

    shader = "::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(0.0); }\n::end shader\n"
    ours = parse_material("analytic\n::begin parameters\ncolor eta 1.5 1.5 2 1 4\n::end parameters\n" + shader, "m.brd")
    assert (ours.parameters[0].min, ours.parameters[0].max) == (1.0, 4.0)
    with pytest.raises(MaterialError, match="outside its range"):
        ours.resolve({"eta": "0.5"})
    with pytest.raises(MaterialError, match=r"m.brd:3: color 'c': default 2 2 2 is outside \[0, 1\]; declare another range"):
        parse_material("analytic\n::begin parameters\ncolor c 2 2 2\n::end parameters\n" + shader, "m.brd")
    theirs = parse_material("analytic\n::begin parameters\ncolor c 2 0 0\n::end parameters\n" + shader, "m.brdf")
    assert (theirs.parameters[0].min, theirs.parameters[0].max) == (0.0, 2.0)


@pytest.mark.parametrize("args, fragment", [
    (["inverse", "--lobe", "R=0.5 sigma=0.1 base=conductor eta=-1"], "eta_1 = [-1.0, -1.0, -1.0] must be positive"),
    (["inverse", "--lobe", "R=0.05 sigma=1e308"], "outside the model's domain [0, 1e+06)"),
    (["inverse", "--lobe", "R=0.05 sigma=1e6"], "outside the model's domain [0, 1e+06)"),
    (["figure", "--lobe", "R=-0.1 sigma=0.1", "--out", "f.png"], "R='-0.1': outside the model's domain [0, 1]"),
    (["figure", "--lobe", "R=1.5 sigma=0.1", "--out", "f.png"], "outside the model's domain [0, 1]"),
    (["figure", "--lobe", "R=0.5 sigma=-1", "--out", "f.png"], "outside the model's domain [0, 1e+06)"),
    (["render", "thin_film", "--view", "textured", "--dinc-range", "0,1e300", "--out", "x.png"], "need 0 <= MIN <= MAX <= 18000"),
    (["bench", "--size", "0"], "0 is not in the range x>=1"),
    (["bench", "--repeats", "0"], "0 is not in the range x>=1"),
    (["render", "bragg_mirror", "--size", "9" * 5000, "--out", "x.png"], "is not W or WxH"),
])
def test_domain_errors_are_one_line(tmp_path, args, fragment):
    assert fragment in one_line_error(run_cli(*args, cwd=tmp_path))
    assert list(tmp_path.iterdir()) == []


def test_inverse_refuses_a_clamped_variance():
    from explorer.physics.inverse import InverseError, Lobe, invert_lobes
    from explorer.physics.lobes import VARIANCE_MAX

    with pytest.raises(InverseError, match="must lie in"):
        invert_lobes([Lobe(0.05, VARIANCE_MAX)])


# -- images ---------------------------------------------------------------------------------------------------

def test_decompression_bomb_texture_is_one_line(tmp_path):
    from PIL import Image

    bomb = tmp_path / "bomb.png"
    Image.new("1", (20000, 20000)).save(bomb)  # 400 M pixels in about 50 kB
    assert bomb.stat().st_size < 1 << 20
    line = one_line_error(run_cli("render", "thin_film", "--view", "textured", "--texture", bomb, "--out", tmp_path / "x.png"))
    assert f"the limit, {Image.MAX_IMAGE_PIXELS}" in line


def test_huge_environment_header_is_refused_before_decoding(tmp_path):
    from PIL import Image

    huge = tmp_path / "huge.hdr"
    huge.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 20000 +X 20000\n" + bytes(64))
    line = one_line_error(run_cli("render", "bragg_mirror", "--view", "env", "--env", huge, "--out", tmp_path / "x.png"))
    assert "20000x20000" in line and str(Image.MAX_IMAGE_PIXELS) in line


def test_header_size_reads_hdr_and_exr(tmp_path):
    from explorer.views.env import _cv2, header_size

    cv2 = _cv2()
    image = np.ones((5, 7, 3), np.float32)
    for suffix in (".hdr", ".exr"):
        cv2.imwrite(str(tmp_path / f"e{suffix}"), image)
        assert header_size(tmp_path / f"e{suffix}") == (7, 5)


# -- GL limits --------------------------------------------------------------------------------------------------

def test_gl_limits_check_sizes():
    from explorer.gpu.context import GLLimitError, GLLimits

    limits = GLLimits(max_texture_size=4096, max_renderbuffer_size=2048, max_viewport=(2048, 1024), max_image_bytes=1 << 20)
    limits.check_target(256, 256)
    with pytest.raises(GLLimitError, match=r"^--size: 2049x8 is beyond what this GL allows: at most 2048x1024 \(GL_MAX_RENDERBUFFER_SIZE 2048"):
        limits.check_target(2049, 8)
    with pytest.raises(GLLimitError, match="65536 pixels"):
        limits.check_target(512, 512)  # within the sides, beyond the bytes
    limits.check_texture(4096, 1, 3, "env.hdr")
    with pytest.raises(GLLimitError, match=r"^env.hdr: a 8x4097 image is beyond this GL's largest texture: at most 4096"):
        limits.check_texture(8, 4097, 3, "env.hdr")


@pytest.mark.gl
def test_gl_limits_come_from_the_context(gl_renderer):
    info = gl_renderer.ctx.info
    assert gl_renderer.limits.max_texture_size == info["GL_MAX_TEXTURE_SIZE"]
    assert gl_renderer.limits.max_renderbuffer_size == info["GL_MAX_RENDERBUFFER_SIZE"]


@pytest.mark.gl
@pytest.mark.parametrize("size", ["12000", "16384", "16384x8192", "100000"])
def test_too_large_size_is_one_line_before_allocation(gl_renderer, tmp_path, size):
    start = time.perf_counter()
    line = one_line_error(run_cli_process("render", "bragg_mirror", "--size", size, "--out", tmp_path / "x.png"))
    assert time.perf_counter() - start < 60 and list(tmp_path.iterdir()) == []
    if size != "100000":
        side = min(gl_renderer.limits.max_target_side)
        assert f"at most {side}x{side}" in line and "GL_MAX_RENDERBUFFER_SIZE" in line


@pytest.mark.gl
def test_oversized_environment_and_texture_are_one_line(gl_renderer, tmp_path):
    """Taller than GL_MAX_TEXTURE_SIZE: the GPU engine says so instead of sampling zeros."""
    from PIL import Image

    from explorer.views.env import _cv2

    tall = gl_renderer.limits.max_texture_size + 16
    env = tmp_path / "tall.exr"
    _cv2().imwrite(str(env), np.full((tall, 8, 3), 0.5, np.float32))
    texture = tmp_path / "tall.png"
    Image.new("L", (2, tall), 128).save(texture)
    for args in (["--view", "env", "--env", env, "--spp", "4"], ["--view", "textured", "--texture", texture]):
        material = "thin_film" if "textured" in args else "bragg_mirror"
        line = one_line_error(run_cli_process("render", material, *args, "--size", "8", "--out", tmp_path / "x.png"))
        assert f"largest texture: at most {gl_renderer.limits.max_texture_size}" in line
    assert not (tmp_path / "x.png").exists()


# -- includes ---------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("target", ["/etc/passwd", "../x.glsl", "lib/../../x.glsl", "sub\\..\\..\\x.glsl"])
def test_includes_are_confined(tmp_path, target):
    from explorer.materials.glsl import ShaderBuilder, ShaderError

    (tmp_path / "x.glsl").write_text("float secret;\n")
    (tmp_path / "m").mkdir()
    builder = ShaderBuilder([REPO_ROOT / "shaders"])
    builder.add_source(f'#include "{target}"\n', str(tmp_path / "m" / "m.brd"))
    with pytest.raises(ShaderError, match="leaves the material's folder") as info:
        builder.build()
    assert "secret" not in str(info.value)


def test_include_through_a_link_is_refused(tmp_path):
    from explorer.materials.glsl import ShaderBuilder, ShaderError

    (tmp_path / "outside.glsl").write_text("float secret;\n")
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "in.glsl").symlink_to(tmp_path / "outside.glsl")
    builder = ShaderBuilder([])
    builder.add_source('#include "in.glsl"\n', str(tmp_path / "m" / "m.brd"))
    with pytest.raises(ShaderError, match="resolves outside"):
        builder.build()


# -- the last resort ------------------------------------------------------------------------------------------------

def test_unexpected_error_is_one_line_unless_debug(monkeypatch):
    from explorer.cli import commands

    def broken(*_, **__):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(commands, "_load", broken)
    monkeypatch.delenv(commands.DEBUG_ENV, raising=False)
    line = one_line_error(run_cli("info", "bragg_mirror"))
    assert "internal error (a bug): ZeroDivisionError: boom" in line and "--debug" in line
    run = run_cli("--debug", "info", "bragg_mirror")
    assert "Traceback" in run.stderr and run.returncode == 1
    monkeypatch.setenv(commands.DEBUG_ENV, "1")
    assert "Traceback" in run_cli("info", "bragg_mirror").stderr


@pytest.mark.parametrize("material, view", [("bragg_mirror", "sphere"), ("thin_film", "lit"), ("thin_film", "textured"),
                                            ("layered_lobes", "slice")])
def test_numpy_views_in_chunks_are_the_same_image(monkeypatch, material, view):
    """The numpy engine evaluates pixels in chunks (bounded memory at any --size): the same image as at once."""
    from explorer.materials.brd import load_material
    from explorer.materials.models import model_for
    from explorer.resources import builtin_materials
    from explorer.views import render

    loaded = load_material(builtin_materials()[material])
    model = model_for(loaded, loaded.resolve())
    whole = render.render_numpy(model, view, 24, 24)
    monkeypatch.setattr(render, "CHUNK_PIXELS", 37)
    np.testing.assert_array_equal(render.render_numpy(model, view, 24, 24), whole)


def test_numpy_engine_has_the_same_image_budget(tmp_path):
    line = one_line_error(run_cli("render", "bragg_mirror", "--engine", "numpy", "--size", "16384", "--out", tmp_path / "x.png"))
    assert "16384x16384 is more than the 67108864 pixels" in line


def test_env_samples_are_bounded_by_the_float32_count(tmp_path):
    from explorer.gpu.env import MAX_SPP

    args = ("render", "bragg_mirror", "--view", "env", "--size", "1", "--spp", str(MAX_SPP + 1), "--out", tmp_path / "x.png")
    assert f"at most {MAX_SPP}" in one_line_error(run_cli(*args))


@pytest.mark.parametrize("name", ["p.json", "p.bparam"])
def test_app_parameter_saves_are_atomic(tmp_path, monkeypatch, name):
    """The app's Files tab saves through the same helper: a failed save keeps the old file, leaves nothing else."""
    from explorer import files
    from explorer.app.parameter_files import ParameterFileError, save_values
    from explorer.materials.brd import load_material

    material = load_material(REPO_ROOT / "shaders" / "thin_film.brd")
    target = tmp_path / name
    target.write_text("old")

    def full_disk(*_):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files.os, "replace", full_disk)
    with pytest.raises(ParameterFileError, match="No space left on device"):
        save_values(target, material, material.resolve())
    assert target.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == [name]
    monkeypatch.undo()
    save_values(target, material, material.resolve())
    assert target.read_text() != "old" and [p.name for p in tmp_path.iterdir()] == [name]
    with pytest.raises(ParameterFileError, match="does not exist"):
        save_values(tmp_path / "missing" / name, material, material.resolve())


@pytest.mark.parametrize("first_line", ["hunter2", "root:x:0:0:root:/root:/bin/bash", "API_KEY = abc", "\u00e9t\u00e9 42"])
def test_a_file_that_is_no_material_is_named_not_quoted(tmp_path, first_line):
    path = tmp_path / "secret"
    path.write_text(first_line + "\nmore\n")
    line = one_line_error(run_cli("info", path))
    assert "not a material file" in line and first_line.split()[0] not in line.replace(str(path), "")


def test_json_integers_stay_integers(tmp_path):
    """A bool written 1 and an int written 3 load as before (integers are not read as floats)."""
    from explorer.app.parameter_files import load_json
    from explorer.materials.brd import load_material

    path = tmp_path / "p.json"
    path.write_text('{"values": {"coating": 1, "layers": 3}}')
    loaded = load_json(path, load_material(REPO_ROOT / "shaders" / "bragg_stack.brd"))
    assert loaded.values == {"coating": True, "layers": 3.0}
