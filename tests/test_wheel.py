"""
``pip install .`` gives a package that renders: the wheel, installed into a fresh virtual environment
outside the repository, renders every built-in material through EGL from /tmp with the installed
``bragg-explorer`` console script, and writes nothing into its installation.

The wheel is built offline from a copy of the files it is made of (``pip wheel --no-build-isolation``
with this environment's setuptools, a test extra; an in-tree build would write ``build/`` into the
checkout). The fresh environment gets its dependencies from this one through a ``.pth`` line, which adds
the folder to ``sys.path`` but runs none of its ``.pth`` files: the checkout's editable install stays out,
and the tests assert that the ``explorer`` imported is the installed one.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from conftest import CLI_ERROR_PREFIX, REPO_ROOT, one_line_error, running_in_ci

#: What the wheel is built from (the design card's top level, less the tests).
SOURCES = ("pyproject.toml", "README.md", "explorer", "shaders", "luts")
BUILTINS = sorted(path.stem for path in (REPO_ROOT / "shaders").glob("*.brd"))
#: A view per built-in that exercises its shader: the BRDF materials under a light, the others' reflectance.
VIEWS = {"bragg_mirror": "sphere", "schlick_fresnel": "sphere"}
SIZE = 24
TIMEOUT = 240
#: pyproject.toml's build-system requirement (an SPDX license string), also in the test extra.
MIN_SETUPTOOLS = 77


@dataclass
class Installed:
    root: Path
    venv: Path
    site_packages: Path
    wheel: Path
    env: dict[str, str]
    cwd: Path
    cache: Path

    def run(self, *args, script: str = "bragg-explorer") -> subprocess.CompletedProcess:
        """A command of the fresh environment (its console script by default), from a folder in /tmp."""
        return subprocess.run([str(self.venv / "bin" / script), *map(str, args)], cwd=self.cwd, env=self.env,
                              capture_output=True, text=True, timeout=TIMEOUT)


def _check(command: list[str], **kwargs) -> None:
    run = subprocess.run(command, capture_output=True, text=True, timeout=TIMEOUT, **kwargs)
    assert run.returncode == 0, f"{' '.join(command)}\n{run.stdout}\n{run.stderr}"


def snapshot(folder: Path) -> dict[str, tuple[int, int]]:
    """Every file below ``folder`` with its size and modification time, less Python's own bytecode cache."""
    return {
        str(path.relative_to(folder)): (path.stat().st_size, path.stat().st_mtime_ns)
        for path in sorted(folder.rglob("*"))
        if path.is_file() and "__pycache__" not in path.parts
    }


def _require_build_tools() -> None:
    """setuptools >= 77 (the test extra): skipped on a developer's older environment, a failure in CI."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        found = version("setuptools")
    except PackageNotFoundError:
        found = None
    if found is not None and int(found.split(".")[0]) >= MIN_SETUPTOOLS:
        return
    reason = (f"building the wheel needs setuptools >= {MIN_SETUPTOOLS} (found {found or 'none'}); "
              f"python3 -m explorer test installs the test extra's")
    if running_in_ci():
        pytest.fail(f"CI=true: {reason}", pytrace=False)
    pytest.skip(reason)


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Installed:
    _require_build_tools()
    root = tmp_path_factory.mktemp("wheel")
    source = root / "source"
    source.mkdir()
    for name in SOURCES:
        origin = REPO_ROOT / name
        if origin.is_dir():
            shutil.copytree(origin, source / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        else:
            shutil.copy2(origin, source / name)
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "--no-input"]
    _check([*pip, "wheel", "--no-deps", "--no-build-isolation", "--no-index", "-q", "-w", str(root / "dist"), str(source)])
    (wheel,) = (root / "dist").glob("bragg_explorer-*.whl")
    venv = root / "venv"
    _check([sys.executable, "-m", "venv", "--without-pip", str(venv)])
    site_packages = Path(subprocess.run(
        [str(venv / "bin" / "python"), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
        capture_output=True, text=True, check=True, timeout=60).stdout.strip())
    assert site_packages.is_relative_to(venv)
    # The dependencies: this interpreter's site-packages folders, after the fresh one's own (a path line
    # runs nothing in them); never the checkout itself.
    ours = dict.fromkeys(p for p in sys.path if Path(p).name in ("site-packages", "dist-packages") and Path(p).is_dir())
    (site_packages / "zz_test_dependencies.pth").write_text("".join(f"{path}\n" for path in ours))
    # This environment's pip, run by the fresh interpreter (any pip version; no --python option needed). The
    # checkout's own install is visible to it through the .pth: --force-reinstall installs the wheel anyway.
    _check([str(venv / "bin" / "python"), *pip[1:], "install", "--no-deps", "--no-index", "--force-reinstall", "-q",
            str(wheel)])
    cwd, cache = root / "work", root / "cache"
    cwd.mkdir()
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "PYTHONSTARTUP", "BRAGG_EXPLORER_NO_SETUP")}
    # A cache of its own, but Mesa's compiled shaders from the usual one (llvmpipe compiles slowly).
    mesa_cache = os.environ.get("MESA_SHADER_CACHE_DIR") or str(
        Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "mesa_shader_cache")
    env.update(PATH=f"{venv / 'bin'}{os.pathsep}{env.get('PATH', os.defpath)}", XDG_CACHE_HOME=str(cache),
               MESA_SHADER_CACHE_DIR=mesa_cache, PYTHONWARNINGS="ignore")
    return Installed(root, venv, site_packages, wheel, env, cwd, cache)


def test_installed_package_is_the_wheel(installed):
    """The fresh environment imports the installed package, not the checkout, and finds its data inside it."""
    code = ("import explorer, explorer.resources as r, explorer.tables.luts as l; "
            "print(explorer.__file__); print(r.SHADER_DIR); print(r.LUT_DIR); print(r.CHECKOUT_ROOT); print(l.cache_lut_dir())")
    run = installed.run("-c", code, script="python")
    assert run.returncode == 0, run.stderr
    module, shaders, tables, checkout, cache = run.stdout.split("\n")[:5]
    package = installed.site_packages / "explorer"
    assert Path(module) == package / "__init__.py"
    assert Path(shaders) == package / "shaders" and Path(tables) == package / "luts"
    assert checkout == "None"
    assert Path(cache) == installed.cache / "bragg-explorer" / "luts"
    names = set(zipfile.ZipFile(installed.wheel).namelist())
    tracked = {str(p.relative_to(REPO_ROOT)) for d in ("shaders", "luts") for p in (REPO_ROOT / d).rglob("*")
               if p.is_file() and "__pycache__" not in p.parts}
    missing = sorted(name for name in tracked if f"explorer/{name}" not in names)
    assert not missing, f"not in the wheel: {missing}"
    assert not [name for name in names if name.startswith("explorer/dev/")], "the checkout's set-up is in the wheel"


def _render_jobs(installed: Installed) -> dict[str, list[str]]:
    jobs = {}
    for name in BUILTINS:
        view = VIEWS.get(name, "lit")
        jobs[name] = ["render", name, "--view", view, "--size", str(SIZE), "--out", f"{name}.npy"]
    # The shipped presets, environment and thickness texture; the bootstrap's entry point when installed.
    jobs["preset"] = ["render", "bragg_stack.brd", "--view", "lit", "--preset", "figure1_stacked_pair", "--size", "16",
                      "--out", "preset.npy"]
    jobs["env"] = ["render", "ggx_schlick", "--view", "env", "--spp", "4", "--size", "16", "--out", "env.npy"]
    jobs["mesh"] = ["render", "ggx_schlick", "--view", "lit", "--mesh", "teapot", "--size", "16", "--out", "mesh.npy"]  # shaders/meshes, views/mesh
    jobs["textured"] = ["render", "thin_film", "--view", "textured", "--set", "method=3", "--size", "16",
                        "--out", "textured.npy"]
    jobs["png"] = ["render", "bragg_mirror", "--view", "gradient", "--exposure", "2", "--size", "32", "--out", "strip.png"]
    return jobs


@pytest.mark.slow
def test_installed_package_renders_every_builtin(installed):
    """Every built-in material, by its bare name, renders finite and non-black; the installation is untouched."""
    before = snapshot(installed.venv)
    jobs = _render_jobs(installed)
    with ThreadPoolExecutor(max_workers=3) as pool:
        runs = dict(zip(jobs, pool.map(lambda args: installed.run(*args), jobs.values())))
    runs["module"] = installed.run("-m", "explorer", "render", "schlick_fresnel", "--view", "gradient", "--size", "8",
                                   "--out", "module.npy", script="python")
    runs["presets"] = installed.run("presets")
    runs["info"] = installed.run("info", "thin_film")
    runs["unknown"] = installed.run("render", "no_such_material", "--out", "x.png")
    for name, run in runs.items():
        if name == "unknown":
            continue
        assert run.returncode == 0, f"{name}: {run.stderr}"
        assert "Traceback" not in run.stderr and "luts: regenerating" not in run.stderr, run.stderr
    for name in [*BUILTINS, "preset", "env", "textured", "module"]:
        image = np.load(installed.cwd / f"{name}.npy")
        assert image.ndim == 3 and image.shape[2] == 3 and np.isfinite(image).all(), name
        # The sphere's centre is lit (a light at 45 degrees, the env sky, or the reflectance at normal incidence).
        centre = image[image.shape[0] // 2 - 2:image.shape[0] // 2 + 2, image.shape[1] // 2 - 2:image.shape[1] // 2 + 2]
        assert centre.max() > 1e-3, f"{name}: black where the sphere is ({centre.max():.3g})"
    assert (installed.cwd / "strip.png").stat().st_size > 0
    assert "figure1_stacked_pair" in runs["presets"].stdout and "thin_film" in runs["presets"].stdout
    assert "eta2" in runs["info"].stdout
    line = one_line_error(runs["unknown"])
    assert line.startswith(f"{CLI_ERROR_PREFIX}no_such_material: ") and all(name in line for name in BUILTINS)
    assert snapshot(installed.venv) == before, "the renders wrote into the installation"
    assert not (installed.cache / "bragg-explorer").exists(), "the shipped tables are current: nothing to cache"


def test_stale_shipped_table_regenerates_into_the_user_cache(installed):
    """An altered table of the installation is regenerated into $XDG_CACHE_HOME, never in site-packages."""
    table = installed.site_packages / "explorer" / "luts" / "cmf_cumulative.npy"
    original = table.read_bytes()
    try:
        altered = np.load(table)
        altered[200, 1] += 1e-3
        np.save(table, altered)
        before = snapshot(installed.venv)
        messages = []
        for attempt in range(2):
            run = installed.run("render", "bragg_mirror", "--view", "gradient", "--set", "method=1", "--size", "8",
                                "--out", f"stale{attempt}.npy")
            assert run.returncode == 0, run.stderr
            messages.append([line for line in run.stderr.splitlines() if "luts:" in line])
        assert snapshot(installed.venv) == before, "regenerating wrote into the installation"
        cached = installed.cache / "bragg-explorer" / "luts"
        # Regenerated once, into the cache, then read from there silently.
        assert len(messages[0]) == 1 and "cmf_cumulative" in messages[0][0] and str(cached) in messages[0][0], messages
        assert messages[1] == []
        assert {p.name for p in cached.iterdir()} == {"cmf_cumulative.npy", "manifest.json"}
        np.testing.assert_allclose(np.load(cached / "cmf_cumulative.npy"), np.load(REPO_ROOT / "luts" / "cmf_cumulative.npy"),
                                   rtol=0, atol=1e-12)
        np.testing.assert_array_equal(np.load(installed.cwd / "stale0.npy"), np.load(installed.cwd / "stale1.npy"))
    finally:
        table.write_bytes(original)


def test_installed_package_never_rewrites_its_shipped_files(installed):
    """The developer commands that regenerate shipped files refuse in an installation, in one line."""
    before = snapshot(installed.venv)
    for module in ("explorer.views.env",):  # (the tables are regenerated by explorer/dev, not in the wheel)
        run = installed.run("-m", module, script="python")
        assert run.returncode != 0 and "Traceback" not in run.stderr, run.stderr
        assert len(run.stderr.strip().splitlines()) == 1 and "installed package" in run.stderr, run.stderr
    run = installed.run("-m", "explorer", "test", script="python")
    assert run.returncode != 0 and "source checkout" in run.stderr and "Traceback" not in run.stderr, run.stderr
    assert snapshot(installed.venv) == before
