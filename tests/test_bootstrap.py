"""Decision logic of explorer/dev/bootstrap.py, with every probe faked: nothing is installed."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from explorer.dev import bootstrap as bs

PYPROJECT = b'[project]\nname = "bragg-explorer"\ndependencies = ["numpy>=1.24"]\n'


# -- modes and command lines -------------------------------------------------


def test_parse_mode_main_job_keeps_all_args():
    assert bs.parse_mode([]) == ("run", [], ())
    assert bs.parse_mode(["render", "--out", "x.png"]) == ("run", ["render", "--out", "x.png"], ())
    # "test" only selects the test mode in first position.
    assert bs.parse_mode(["render", "test"]) == ("run", ["render", "test"], ())


def test_parse_mode_test_strips_keyword_and_adds_extras():
    assert bs.parse_mode(["test"]) == ("test", [], ("test",))
    assert bs.parse_mode(["test", "-q", "-k", "gl"]) == ("test", ["-q", "-k", "gl"], ("test",))


def test_mitsuba_commands_bring_the_mitsuba_extra():
    for argv in (["render", "m", "--engine", "mitsuba"], ["render", "--engine=mitsuba"],
                 ["export", "thin_film", "--to", "mitsuba", "d"], ["bench", "--mitsuba"]):
        assert bs.parse_mode(argv)[2] == ("mitsuba",), argv
    for argv in (["render", "--engine", "gl"], ["export", "x", "--to", "brdf", "mitsuba"], ["mitsuba"]):
        assert bs.parse_mode(argv)[2] == (), argv


def test_paint_commands_bring_the_paint_extra():
    for argv in (["design", "m", "--target-image", "a.png", "--out-maps", "d"], ["design", "--target-image=a.png"],
                 ["bench", "--paint"]):
        assert bs.parse_mode(argv)[2] == ("paint",), argv
    for argv in (["design", "m", "--target", "0:#ff0000"], ["render", "m", "--maps", "d"]):
        assert bs.parse_mode(argv)[2] == (), argv


def test_llvm_is_optional_and_only_for_the_mitsuba_extras(monkeypatch, capsys):
    assert bs.optional_packages_for(()) == ()
    assert bs.optional_packages_for(("mitsuba",)) == bs.optional_packages_for(("test",)) == ("libllvm19",)
    assert "libllvm19" in bs.PROBES
    monkeypatch.setattr(bs.sys, "platform", "linux")
    monkeypatch.setattr(bs, "missing_packages", lambda wanted: list(wanted))

    def fail(packages, **kwargs):
        raise bs.SetupError("[setup] error: no apt-get")
    monkeypatch.setattr(bs, "install_system_packages", fail)
    bs.ensure_optional_packages(("mitsuba",))  # a note, not an error
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "libllvm19" in err and "scalar" in err


def test_final_command_for_tests_is_pytest_module():
    assert bs.final_command("test", "/r/.venv/bin/python", ["-q", "-x"]) == [
        "/r/.venv/bin/python", "-m", "pytest", "-q", "-x"]


def test_final_command_for_main_job_calls_cli_main_with_args():
    cmd = bs.final_command("run", "/r/.venv/bin/python", ["render", "--size", "64"])
    assert cmd[:2] == ["/r/.venv/bin/python", "-c"]
    assert "run_cli" in cmd[2]
    assert cmd[3:] == ["render", "--size", "64"]


def test_final_cwd_tests_run_from_repo_root_main_job_keeps_cwd():
    assert bs.final_cwd("test", "/somewhere") == str(bs.REPO_ROOT)
    assert bs.final_cwd("run", "/somewhere") == "/somewhere"


def test_system_packages_per_mode():
    assert set(bs.system_packages_for("run")) == set(bs.EGL_PACKAGES)
    assert "xvfb" not in bs.system_packages_for("run")
    assert {"xvfb", "xauth"} <= set(bs.system_packages_for("test"))
    assert {"libegl1", "libegl-mesa0", "libgl1-mesa-dri"} <= set(bs.system_packages_for("test"))


def test_pip_command_with_and_without_extras():
    assert bs.pip_install_command("py", ())[-2:] == ["-e", "."]
    assert bs.pip_install_command("py", ("test",))[-2:] == ["-e", ".[test]"]
    assert bs.pip_install_command("py", ["test", "docs"])[-1] == ".[docs,test]"


def test_pip_command_pins_the_tested_versions():
    command = bs.pip_install_command("py", ("test",), bs.CONSTRAINTS)
    assert command[-4:] == ["-c", str(bs.CONSTRAINTS), "-e", ".[test]"]


def test_constraints_pin_every_requirement_exactly():
    """Each dependency of pyproject.toml (and the test extra) has one exact pin in the constraints."""
    import tomllib

    from packaging.requirements import Requirement

    project = tomllib.loads(bs.PYPROJECT.read_text())["project"]
    wanted = project["dependencies"] + project["optional-dependencies"]["test"]
    pins = {}
    for line in bs.CONSTRAINTS.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            requirement = Requirement(line)
            assert len(requirement.specifier) == 1 and next(iter(requirement.specifier)).operator == "=="
            pins[requirement.name.lower()] = requirement
    for text in wanted:
        requirement = Requirement(text)
        pin = pins[requirement.name.lower()]
        version = next(iter(pin.specifier)).version
        assert requirement.specifier.contains(version), (text, version)  # the pin satisfies pyproject


def test_stamp_invalidated_by_constraints():
    key = bs.stamp_key(PYPROJECT, "cpython-3.11", "/r/.venv", b"numpy==2.4.6\n")
    stamp = bs.make_stamp(key, [])
    assert not bs.stamp_matches(stamp, bs.stamp_key(PYPROJECT, "cpython-3.11", "/r/.venv", b"numpy==2.4.7\n"), ())


def test_child_environment_activates_venv():
    env = bs.child_environment({"PATH": "/usr/bin:/bin", "PYTHONHOME": "/x"}, Path("/r/.venv"))
    assert env["PATH"].split(":") == ["/r/.venv/bin", "/usr/bin", "/bin"]
    assert env["VIRTUAL_ENV"] == "/r/.venv"
    assert "PYTHONHOME" not in env
    # idempotent: not prepended twice
    assert bs.child_environment(env, Path("/r/.venv"))["PATH"] == env["PATH"]


# -- stamp ---------------------------------------------------------------------


def test_stamp_matches_same_inputs():
    key = bs.stamp_key(PYPROJECT, "cpython-3.11", "/r/.venv")
    assert bs.stamp_matches(bs.make_stamp(key, ["test"]), key, ("test",))
    assert bs.stamp_matches(bs.make_stamp(key, ["test"]), key, ())  # superset is fine


def test_stamp_invalidated_by_pyproject_python_or_location():
    key = bs.stamp_key(PYPROJECT, "cpython-3.11", "/r/.venv")
    stamp = bs.make_stamp(key, [])
    edited = PYPROJECT.replace(b"1.24", b"1.25")
    assert not bs.stamp_matches(stamp, bs.stamp_key(edited, "cpython-3.11", "/r/.venv"), ())
    assert not bs.stamp_matches(stamp, bs.stamp_key(PYPROJECT, "cpython-3.12", "/r/.venv"), ())
    assert not bs.stamp_matches(stamp, bs.stamp_key(PYPROJECT, "cpython-3.11", "/s/.venv"), ())


def test_stamp_invalidated_by_missing_extras():
    key = bs.stamp_key(PYPROJECT, "cpython-3.11", "/r/.venv")
    assert not bs.stamp_matches(bs.make_stamp(key, []), key, ("test",))


def test_stamp_rejects_garbage():
    key = bs.stamp_key(PYPROJECT, "cpython-3.11", "/r/.venv")
    assert not bs.stamp_matches(None, key, ())
    assert not bs.stamp_matches({"key": key}, key, ())
    assert not bs.stamp_matches({"key": key, "extras": "test"}, key, ())


def test_stamp_round_trip(tmp_path):
    key = bs.stamp_key(PYPROJECT, "cpython-3.11", str(tmp_path))
    path = tmp_path / bs.STAMP_NAME
    assert bs.read_stamp(path) is None
    bs.write_stamp(path, bs.make_stamp(key, ["test"]))
    assert json.loads(path.read_text()) == {"key": key, "extras": ["test"]}
    assert bs.stamp_matches(bs.read_stamp(path), key, ("test",))
    path.write_text("{not json")
    assert bs.read_stamp(path) is None


def test_venv_usable_needs_python_pip_and_same_version(tmp_path):
    venv = tmp_path / ".venv"
    (venv / "bin").mkdir(parents=True)
    assert not bs.venv_usable(venv, (3, 11))
    (venv / "bin" / "python").symlink_to(sys.executable)
    (venv / "bin" / "pip").write_text("")
    (venv / "pyvenv.cfg").write_text("home = /usr/bin\nversion = 3.11.7\n")
    assert bs.venv_usable(venv, (3, 11))
    assert not bs.venv_usable(venv, (3, 12))  # created by another Python
    (venv / "bin" / "python").unlink()
    (venv / "bin" / "python").symlink_to(tmp_path / "gone")  # base interpreter removed
    assert not bs.venv_usable(venv, (3, 11))


def _fake_repo(tmp_path, monkeypatch, stamp_extras):
    """Point bootstrap at a fake repo whose .venv looks complete; pip must not run."""
    (tmp_path / "pyproject.toml").write_bytes(PYPROJECT)
    venv = tmp_path / ".venv"
    (venv / "bin").mkdir(parents=True)
    (venv / "bin" / "python").symlink_to(sys.executable)
    (venv / "bin" / "pip").write_text("")
    v = sys.version_info
    (venv / "pyvenv.cfg").write_text(f"version = {v[0]}.{v[1]}.{v[2]}\n")
    monkeypatch.setattr(bs, "REPO_ROOT", tmp_path)
    monkeypatch.setattr(bs, "VENV_DIR", venv)
    monkeypatch.setattr(bs, "PYPROJECT", tmp_path / "pyproject.toml")
    monkeypatch.setattr(bs, "LOCK_PATH", tmp_path / ".venv.lock")
    monkeypatch.setattr(bs, "CONSTRAINTS", tmp_path / "constraints.txt")  # none: no pins
    key = bs.stamp_key(PYPROJECT, bs.python_tag(), str(venv))
    bs.write_stamp(venv / bs.STAMP_NAME, bs.make_stamp(key, stamp_extras))
    calls = []
    monkeypatch.setattr(bs, "pip_install", lambda py, extras, log: calls.append(list(extras)))
    monkeypatch.setattr(bs, "create_venv", lambda *a, **k: calls.append("venv"))
    return calls


def test_ensure_python_packages_skips_pip_when_stamp_matches(tmp_path, monkeypatch):
    calls = _fake_repo(tmp_path, monkeypatch, ["test"])
    assert bs.ensure_python_packages(("test",), inside=False) is False
    assert bs.ensure_python_packages((), inside=False) is False
    assert calls == []


def test_ensure_python_packages_runs_pip_for_new_extras_and_keeps_old(tmp_path, monkeypatch,
                                                                      capsys):
    calls = _fake_repo(tmp_path, monkeypatch, [])
    assert bs.ensure_python_packages(("test",), inside=False) is True
    assert calls == [["test"]]
    # stamp now records the extras, so the next run skips pip
    assert bs.ensure_python_packages(("test",), inside=False) is False
    # an edited pyproject re-runs pip, keeping the [test] extras installed before
    (tmp_path / "pyproject.toml").write_bytes(PYPROJECT + b"# edited\n")
    assert bs.ensure_python_packages((), inside=False) is True
    assert calls == [["test"], ["test"]]
    assert "[setup] installing Python packages" in capsys.readouterr().err


# -- system packages -----------------------------------------------------------


def test_missing_packages_from_fake_probes():
    present = {"libegl1", "libgl1", "xauth"}
    missing = bs.missing_packages(
        bs.system_packages_for("test"), probe=lambda p: p in present, dpkg=lambda pkgs: set())
    assert missing == ["libegl-mesa0", "libgl1-mesa-dri", "xvfb"]


def test_missing_packages_none_when_all_probes_pass():
    def dpkg(pkgs):
        raise AssertionError("dpkg must not be asked when the file probes pass")
    assert bs.missing_packages(bs.system_packages_for("test"), probe=lambda p: True,
                               dpkg=dpkg) == []


def test_missing_packages_trusts_dpkg_for_probe_misses():
    asked = []

    def dpkg(pkgs):
        asked.append(list(pkgs))
        return {"libgl1-mesa-dri"}  # installed, files just live somewhere unusual
    missing = bs.missing_packages(["libegl1", "libgl1-mesa-dri", "xvfb"],
                                  probe=lambda p: p == "libegl1", dpkg=dpkg)
    assert missing == ["xvfb"]
    assert asked == [["libgl1-mesa-dri", "xvfb"]]


def test_every_system_package_has_a_probe():
    for pkg in bs.system_packages_for("test"):
        assert pkg in bs.PROBES


def test_privilege_prefix():
    assert bs.privilege_prefix(euid=0, which=lambda n: None) == []
    assert bs.privilege_prefix(euid=1000, which=lambda n: None) is None
    assert bs.privilege_prefix(euid=1000, which=lambda n: "/usr/bin/sudo",
                               sudo_ok=lambda: True) == ["sudo", "-n"]
    assert bs.privilege_prefix(euid=1000, which=lambda n: "/usr/bin/sudo",
                               sudo_ok=lambda: False) is None


def _no_runner(*a, **k):
    raise AssertionError("apt-get must not run")


@pytest.mark.parametrize(
    ("which", "prefix", "reason"),
    [
        (lambda n: None, lambda: [], "no apt-get"),
        (lambda n: "/usr/bin/" + n, lambda: None, "no password-less sudo"),
    ],
)
def test_install_impossible_is_one_line_naming_packages(which, prefix, reason):
    pkgs = ["libegl1", "libegl-mesa0", "xvfb"]
    with pytest.raises(bs.SetupError) as info:
        bs.install_system_packages(pkgs, which=which, prefix_finder=prefix, runner=_no_runner,
                                   lists_empty=lambda: False)
    msg = str(info.value)
    assert "\n" not in msg
    assert msg.startswith("[setup] error:")
    assert reason in msg
    assert "apt-get install -y --no-install-recommends libegl1 libegl-mesa0 xvfb" in msg


def _recording_runner(results):
    calls = []

    def run(cmd, env=None):
        calls.append(cmd)
        assert env["DEBIAN_FRONTEND"] == "noninteractive"
        return results.pop(0)
    return run, calls


def test_install_runs_apt_without_update_when_lists_present():
    run, calls = _recording_runner([(0, "ok")])
    bs.install_system_packages(["xvfb"], which=lambda n: "/usr/bin/" + n,
                               prefix_finder=lambda: ["sudo", "-n"], runner=run,
                               lists_empty=lambda: False)
    assert len(calls) == 1
    assert calls[0][:7] == ["sudo", "-n", "env", "DEBIAN_FRONTEND=noninteractive", "apt-get",
                            "install", "-y"]
    assert "--no-install-recommends" in calls[0] and calls[0][-1] == "xvfb"


def test_apt_commands_as_root_have_no_prefix():
    assert bs.apt_install_command([], ["xvfb", "xauth"])[:4] == [
        "apt-get", "install", "-y", "--no-install-recommends"]
    assert bs.apt_install_command([], ["xvfb", "xauth"])[-2:] == ["xvfb", "xauth"]
    assert bs.apt_update_command([]) == ["apt-get", "update"]


def test_install_updates_first_when_lists_empty():
    run, calls = _recording_runner([(0, ""), (0, "")])
    bs.install_system_packages(["xvfb"], which=lambda n: "/usr/bin/" + n,
                               prefix_finder=lambda: [], runner=run, lists_empty=lambda: True)
    assert [c[:2] for c in calls] == [["apt-get", "update"], ["apt-get", "install"]]


def test_install_retries_after_update_on_failure():
    run, calls = _recording_runner([(100, "E: Unable to locate package xvfb"), (0, ""), (0, "")])
    bs.install_system_packages(["xvfb"], which=lambda n: "/usr/bin/" + n,
                               prefix_finder=lambda: [], runner=run, lists_empty=lambda: False)
    assert [c[1] for c in calls] == ["install", "update", "install"]
    assert all(c[0] == "apt-get" for c in calls)


def test_install_failure_shows_apt_tail_and_one_line_error(capsys):
    run, _ = _recording_runner([(100, "E: boom"), (100, "E: no network")])
    with pytest.raises(bs.SetupError) as info:
        bs.install_system_packages(["xvfb"], which=lambda n: "/usr/bin/" + n,
                                   prefix_finder=lambda: [], runner=run,
                                   lists_empty=lambda: False)
    assert "\n" not in str(info.value) and "xvfb" in str(info.value)
    assert "E: no network" in capsys.readouterr().err


def test_main_prints_one_line_and_fails_when_nothing_can_install(monkeypatch, capsys):
    monkeypatch.delenv(bs.ENV_NO_SETUP, raising=False)
    monkeypatch.setattr(bs.sys, "platform", "linux")
    monkeypatch.setattr(bs, "missing_packages", lambda wanted: ["libegl1", "xvfb"])
    monkeypatch.setattr(bs.shutil, "which", lambda name: None)  # no apt-get, no sudo

    def must_not_run(*a, **k):
        raise AssertionError("no further set-up after a system-package failure")
    monkeypatch.setattr(bs, "ensure_python_packages", must_not_run)
    monkeypatch.setattr(bs.os, "execve", must_not_run)
    assert bs.main(["test", "-q"]) != 0
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1, err
    assert "libegl1 xvfb" in err and "Traceback" not in err


def test_main_execs_venv_pytest_from_repo_root(monkeypatch, tmp_path):
    monkeypatch.delenv(bs.ENV_NO_SETUP, raising=False)
    monkeypatch.setattr(bs, "ensure_system_packages", lambda mode: None)
    monkeypatch.setattr(bs, "ensure_optional_packages", lambda extras: None)
    monkeypatch.setattr(bs, "ensure_node_packages", lambda mode: None)
    monkeypatch.setattr(bs, "ensure_blender", lambda mode, args: None)
    monkeypatch.setattr(bs, "ensure_python_packages", lambda extras, inside: False)
    monkeypatch.setattr(bs, "in_venv", lambda venv_dir: False)
    monkeypatch.chdir(tmp_path)
    seen = {}

    class Exec(Exception):
        pass

    def fake_execve(path, argv, env):
        seen.update(path=path, argv=argv, env=env, cwd=str(Path.cwd()))
        raise Exec
    monkeypatch.setattr(bs.os, "execve", fake_execve)
    with pytest.raises(Exec):
        bs.main(["test", "-x"])
    python = str(bs.VENV_DIR / "bin" / "python")
    assert seen["path"] == python
    assert seen["argv"] == [python, "-m", "pytest", "-x"]
    assert seen["cwd"] == str(bs.REPO_ROOT)
    assert seen["env"]["VIRTUAL_ENV"] == str(bs.VENV_DIR)


def test_no_setup_env_runs_in_process_without_setup(monkeypatch):
    monkeypatch.setenv(bs.ENV_NO_SETUP, "1")

    def must_not_run(*a, **k):
        raise AssertionError("set-up must be skipped")
    monkeypatch.setattr(bs, "ensure_system_packages", must_not_run)
    monkeypatch.setattr(bs, "ensure_python_packages", must_not_run)
    ran = []

    def fake_run(mode, args):
        ran.append((mode, args))
        raise SystemExit(7)
    monkeypatch.setattr(bs, "run_in_process", fake_run)
    with pytest.raises(SystemExit) as info:
        bs.main(["render", "--x"])
    assert info.value.code == 7
    assert ran == [("run", ["render", "--x"])]


def test_bootstrap_and_main_import_only_stdlib():
    """They run before any dependency exists: check in a clean interpreter."""
    code = (
        "import sys, runpy\n"
        "before = set(sys.modules)\n"
        "import explorer.dev.bootstrap\n"
        "new = {m.split('.')[0] for m in set(sys.modules) - before}\n"
        "std = set(sys.stdlib_module_names) | {'explorer', '_distutils_hack'}\n"
        "bad = sorted(m for m in new if m not in std and not m.startswith('_'))\n"
        "print(','.join(bad))\n"
    )
    src = Path(bs.__file__).resolve().parents[2]  # the checkout: explorer/dev/bootstrap.py
    out = subprocess.run([sys.executable, "-S", "-c", code], cwd=src, capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == ""
    main_src = (src / "explorer" / "__main__.py").read_text()
    # What runs on import: module-level statements and the try block (the CLI is imported only in an
    # installed wheel, whose dependencies pip brought).
    imports = [line.strip() for line in main_src.splitlines() if line.lstrip().startswith(("import", "from"))
               and not line.startswith("    from explorer.cli")]
    assert imports == ["import sys", "from explorer.dev.bootstrap import main"]


def test_node_packages_only_for_tests_and_skipped_when_installed(tmp_path, monkeypatch):
    """The test set-up npm-installs the pinned validator once into the cache folder; run mode never does."""
    monkeypatch.setenv(bs.ENV_NODE_PREFIX, str(tmp_path))
    calls = []

    def runner(cmd, env=None):
        calls.append(cmd)
        for spec in cmd[cmd.index("--loglevel=error") + 1:]:
            name, _, version = spec.rpartition("@")
            (tmp_path / "node_modules" / name).mkdir(parents=True)
            (tmp_path / "node_modules" / name / "package.json").write_text(json.dumps({"version": version}))
        return 0, ""

    which = lambda name: "/usr/bin/npm"  # noqa: E731
    bs.ensure_node_packages(bs.MODE_RUN, which, runner)
    assert calls == []
    bs.ensure_node_packages(bs.MODE_TEST, which, runner)
    assert len(calls) == 1 and calls[0][:4] == ["/usr/bin/npm", "install", "--prefix", str(tmp_path)]
    assert calls[0][-1] == "gltf-validator@" + bs.NODE_PACKAGES["gltf-validator"]
    bs.ensure_node_packages(bs.MODE_TEST, which, runner)
    assert len(calls) == 1  # the second time: nothing to do


def test_blender_installs_without_dependencies_once(tmp_path, monkeypatch):
    """bpy (numpy < 2 in its metadata) goes in alone, for `--to blender` and the tests, and only while missing."""
    calls = []
    monkeypatch.setattr(bs.sys, "version_info", (3, 11, 7))

    def runner(cmd, env=None):
        calls.append(cmd)
        (tmp_path / "lib" / "python3.11" / "site-packages" / "bpy-5.0.1.dist-info").mkdir(parents=True)
        return 0, ""

    bs.ensure_blender(bs.MODE_RUN, ["export", "x", "--to", "gltf", "o.glb"], tmp_path, runner)
    assert calls == []
    assert bs.wants_blender(["export", "x", "--to", "blender", "o.blend"]) and bs.wants_blender(["--to=blender"])
    bs.ensure_blender(bs.MODE_RUN, ["export", "x", "--to", "blender", "o.blend"], tmp_path, runner)
    assert len(calls) == 1 and "--no-deps" in calls[0] and calls[0][-1] == bs.BLENDER_REQUIREMENT
    bs.ensure_blender(bs.MODE_TEST, [], tmp_path, runner)
    assert len(calls) == 1
    monkeypatch.setenv(bs.ENV_NO_BLENDER, "1")
    bs.ensure_blender(bs.MODE_TEST, [], tmp_path / "other", runner)
    assert len(calls) == 1  # kept out of this test set-up
