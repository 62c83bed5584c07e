"""First-run set-up behind ``python3 -m explorer``.

Two commands do everything on a fresh Debian machine that has only Python 3,
pip and the base system:

* ``python3 -m explorer [ARGS...]``            -> set up, then ``explorer.cli.commands:main`` ARGS
* ``python3 -m explorer test [PYTEST ARGS...]`` -> set up (with test extras and Xvfb),
  then ``python -m pytest`` ARGS from the repository root

Set-up is idempotent and cheap the second time:

1. system packages (Mesa EGL; plus Xvfb/xauth for ``test``) are probed with a few
   ``stat`` calls and installed with ``apt-get`` (through ``sudo -n`` when not root)
   only when missing;
2. a virtual environment ``.venv/`` at the repository root receives
   ``pip install -e .`` (or ``.[test]``) constrained to the tested versions of
   ``explorer/dev/constraints.txt``; a stamp file in it records a hash of
   ``pyproject.toml``, the constraints, the Python version and the extras, and pip is skipped
   while the stamp matches;
3. the venv's interpreter is ``exec``'d, so signals and exit codes pass
   straight through.

``BRAGG_EXPLORER_NO_SETUP=1`` skips all of this and runs with the current
interpreter.  This module must import nothing outside the standard library:
it runs before any dependency exists.
"""

from __future__ import annotations

import contextlib
import glob
import hashlib
import json
import os
import platform
import shutil
import subprocess
import sys
import sysconfig
import time
from pathlib import Path
from typing import Callable, Iterable, Iterator, NoReturn, Sequence

from explorer.resources import SOURCE_ROOT

ENV_NO_SETUP = "BRAGG_EXPLORER_NO_SETUP"

#: The checkout that ``python3 -m explorer`` sets up (in an installed package there is none: see main).
REPO_ROOT = SOURCE_ROOT
VENV_DIR = REPO_ROOT / ".venv"
PYPROJECT = REPO_ROOT / "pyproject.toml"
STAMP_NAME = ".bragg-explorer-setup.json"
PIP_LOG_NAME = ".bragg-explorer-pip.log"
LOCK_PATH = REPO_ROOT / ".venv.lock"
#: The tested versions (``pip install -c``): a fresh machine gets what the tests passed with.
CONSTRAINTS = Path(__file__).resolve().parent / "constraints.txt"

MIN_PYTHON = (3, 10)  # pyproject.toml: requires-python = ">=3.10"

MODE_RUN = "run"
MODE_TEST = "test"

# Debian packages.  libgl1 is the GLVND libGL.so.1, which moderngl's EGL
# backend (glcontext) dlopens next to libEGL.so.1.
EGL_PACKAGES = ("libegl1", "libgl1", "libegl-mesa0", "libgl1-mesa-dri")
XVFB_PACKAGES = ("xvfb", "xauth")
# The Mitsuba extra's LLVM variants need a system libLLVM >= 17 (Debian 12's default 15 aborts the first
# render); drjit finds Debian's libllvm19 by itself. Optional: without it the scalar variants still run
# (explorer.mitsuba.variants probes LLVM in a subprocess), so a failed install is a note, not an error.
MITSUBA_PACKAGES = ("libllvm19",)
#: The pip extras that bring Mitsuba (the test extra includes it: CI runs the Mitsuba tests).
MITSUBA_EXTRAS = ("mitsuba", "test")

# npm packages the tests use (``test`` mode only), pinned: the Khronos glTF Validator checks the glTF export
# (tests/test_gltf.py). Installed with node's npm into a cache folder outside the checkout, shared by every
# checkout of this machine; skipped while the installed version matches. Without node or npm: one note.
NODE_PACKAGES = {"gltf-validator": "2.0.0-dev.3.10"}
ENV_NODE_PREFIX = "BRAGG_EXPLORER_NODE_PREFIX"


def node_prefix() -> Path:
    """The npm prefix of :data:`NODE_PACKAGES` (its ``node_modules``): $BRAGG_EXPLORER_NODE_PREFIX, else the user's cache."""
    if os.environ.get(ENV_NODE_PREFIX):
        return Path(os.environ[ENV_NODE_PREFIX])
    cache = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(cache) / "bragg-explorer" / "node"


RUN_CLI_SNIPPET = "from explorer.dev.bootstrap import run_cli; run_cli()"
PIP_TAIL_LINES = 25


class SetupError(Exception):
    """A set-up step failed; the message is one line for the user."""


def log(message: str) -> None:
    print(f"[setup] {message}", file=sys.stderr, flush=True)


# --------------------------------------------------------------------------
# Command line


def wants_mitsuba(argv: Sequence[str]) -> bool:
    """Whether a CLI command line uses Mitsuba (``--engine mitsuba``, ``--to mitsuba``, ``bench --mitsuba``)."""
    argv = list(argv)
    for k, arg in enumerate(argv):
        if arg in ("--engine=mitsuba", "--to=mitsuba", "--mitsuba"):
            return True
        if arg in ("--engine", "--to") and k + 1 < len(argv) and argv[k + 1] == "mitsuba":
            return True
    return False


def wants_paint(argv: Sequence[str]) -> bool:
    """Whether a CLI command line paints with Dask (``design --target-image``, ``bench --paint``)."""
    return any(arg in ("--paint", "--target-image") or arg.startswith("--target-image=") for arg in argv)


def parse_mode(argv: Sequence[str]) -> tuple[str, list[str], tuple[str, ...]]:
    """Return (mode, remaining args, pip extras) for ``python3 -m explorer`` argv."""
    argv = list(argv)
    if argv and argv[0] == MODE_TEST:
        return MODE_TEST, argv[1:], ("test",)
    extras = (("mitsuba",) if wants_mitsuba(argv) else ()) + (("paint",) if wants_paint(argv) else ())
    return MODE_RUN, argv, extras


def system_packages_for(mode: str) -> tuple[str, ...]:
    return EGL_PACKAGES + (XVFB_PACKAGES if mode == MODE_TEST else ())


def optional_packages_for(extras: Sequence[str]) -> tuple[str, ...]:
    """System packages that only speed things up: libLLVM 19 for Mitsuba's LLVM variants."""
    return MITSUBA_PACKAGES if any(e in MITSUBA_EXTRAS for e in extras) else ()


def final_command(mode: str, python: str, args: Sequence[str]) -> list[str]:
    """The command line that replaces this process once set-up is done."""
    if mode == MODE_TEST:
        return [python, "-m", "pytest", *args]
    # Same as the `bragg-explorer` console script: import explorer.cli.commands and call
    # main() with the arguments in sys.argv (works for click and argparse alike).
    return [python, "-c", RUN_CLI_SNIPPET, *args]


def final_cwd(mode: str, cwd: str) -> str:
    """Tests run from the repository root; the main job keeps the user's cwd."""
    return str(REPO_ROOT) if mode == MODE_TEST else cwd


def child_environment(env: dict[str, str], venv_dir: Path) -> dict[str, str]:
    """Like `source .venv/bin/activate`: subprocesses find the venv's tools first."""
    env = dict(env)
    env.pop("PYTHONHOME", None)
    env["VIRTUAL_ENV"] = str(venv_dir)
    bin_dir = str(venv_dir / "bin")
    path = env.get("PATH", os.defpath).split(os.pathsep)
    if not path or path[0] != bin_dir:
        env["PATH"] = os.pathsep.join([bin_dir, *[p for p in path if p != bin_dir]])
    return env


# --------------------------------------------------------------------------
# Running the real job in this interpreter


def run_cli(args: Sequence[str] | None = None) -> NoReturn:
    """Call ``explorer.cli.commands:main`` as the console script would."""
    if args is not None:
        sys.argv = ["bragg-explorer", *args]
    else:
        sys.argv[0] = "bragg-explorer"
    try:
        from explorer.cli.commands import main as cli_main  # noqa: PLC0415
    except ModuleNotFoundError as exc:
        if exc.name in ("explorer.cli.commands", "explorer"):
            print(
                "[setup] error: explorer/cli/commands.py is missing (no explorer.cli.commands module to run)",
                file=sys.stderr,
            )
            raise SystemExit(1) from None
        raise
    result = cli_main()
    raise SystemExit(result if isinstance(result, int) else 0)


def run_in_process(mode: str, args: Sequence[str]) -> NoReturn:
    if mode == MODE_TEST:
        os.chdir(REPO_ROOT)
        if str(REPO_ROOT) not in sys.path:
            sys.path.insert(0, str(REPO_ROOT))
        try:
            import pytest  # noqa: PLC0415
        except ModuleNotFoundError:
            print(
                f"[setup] error: pytest is not installed for {sys.executable} "
                f"(unset {ENV_NO_SETUP} to let set-up install it)",
                file=sys.stderr,
            )
            raise SystemExit(1) from None
        raise SystemExit(int(pytest.main(list(args))))
    run_cli(args)


# --------------------------------------------------------------------------
# System packages


def _multiarch() -> str:
    multiarch = sysconfig.get_config_var("MULTIARCH")
    if multiarch:
        return str(multiarch)
    machine = platform.machine()
    return {
        "x86_64": "x86_64-linux-gnu",
        "aarch64": "aarch64-linux-gnu",
        "armv7l": "arm-linux-gnueabihf",
        "i686": "i386-linux-gnu",
        "ppc64le": "powerpc64le-linux-gnu",
        "s390x": "s390x-linux-gnu",
        "riscv64": "riscv64-linux-gnu",
    }.get(machine, f"{machine}-linux-gnu")


def library_dirs() -> list[str]:
    ma = _multiarch()
    return [f"/usr/lib/{ma}", f"/lib/{ma}", "/usr/lib64", "/lib64", "/usr/lib", "/lib",
            "/usr/local/lib"]


_LDCONFIG_CACHE: str | None = None


def _ldconfig_listing() -> str:
    global _LDCONFIG_CACHE
    if _LDCONFIG_CACHE is None:
        _LDCONFIG_CACHE = ""
        for ldconfig in ("ldconfig", "/sbin/ldconfig", "/usr/sbin/ldconfig"):
            exe = shutil.which(ldconfig) if "/" not in ldconfig else ldconfig
            if exe and os.path.exists(exe):
                try:
                    _LDCONFIG_CACHE = subprocess.run(
                        [exe, "-p"], capture_output=True, text=True, timeout=10
                    ).stdout
                except (OSError, subprocess.SubprocessError):
                    continue
                break
    return _LDCONFIG_CACHE


def have_library(soname: str) -> bool:
    if any(os.path.exists(os.path.join(d, soname)) for d in library_dirs()):
        return True
    return any(line.strip().startswith(soname + " ") for line in _ldconfig_listing().splitlines())


def have_mesa_egl_vendor() -> bool:
    dirs = ["/usr/share/glvnd/egl_vendor.d", "/etc/glvnd/egl_vendor.d"]
    return any(glob.glob(os.path.join(d, "*mesa*.json")) for d in dirs)


def have_swrast_dri() -> bool:
    dirs = [os.path.join(d, "dri") for d in library_dirs()]
    return any(os.path.exists(os.path.join(d, "swrast_dri.so")) for d in dirs)


def have_program(name: str) -> bool:
    return bool(shutil.which(name)) or os.path.exists(f"/usr/bin/{name}")


PROBES: dict[str, Callable[[], bool]] = {
    "libegl1": lambda: have_library("libEGL.so.1"),
    "libgl1": lambda: have_library("libGL.so.1"),
    "libegl-mesa0": have_mesa_egl_vendor,
    "libgl1-mesa-dri": have_swrast_dri,
    "xvfb": lambda: have_program("Xvfb") and have_program("xvfb-run"),
    "xauth": lambda: have_program("xauth"),
    "libllvm19": lambda: have_library("libLLVM.so.19.1") or have_library("libLLVM-19.so.1"),
}


def probe(package: str) -> bool:
    return PROBES[package]()


def dpkg_installed(packages: Sequence[str]) -> set[str]:
    """Which of ``packages`` dpkg reports as installed (empty without dpkg)."""
    if not packages or not shutil.which("dpkg-query"):
        return set()
    try:
        out = subprocess.run(
            ["dpkg-query", "-W", "-f=${Package} ${db:Status-Abbrev}\n", *packages],
            capture_output=True, text=True, timeout=30,
        ).stdout
    except (OSError, subprocess.SubprocessError):
        return set()
    installed = set()
    for line in out.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[1].startswith("ii"):
            installed.add(parts[0].split(":")[0])
    return installed


def missing_packages(
    wanted: Iterable[str],
    probe: Callable[[str], bool] = probe,
    dpkg: Callable[[Sequence[str]], set[str]] = dpkg_installed,
) -> list[str]:
    """Packages whose files are not found and that dpkg does not list either.

    The file probes are the fast path (a few ``stat`` calls).  dpkg is only
    asked about what they miss, so that an unusual file layout does not make
    every run call apt-get again.
    """
    missing = [p for p in wanted if not probe(p)]
    if missing:
        installed = dpkg(missing)
        missing = [p for p in missing if p not in installed]
    return missing


def privilege_prefix(
    euid: int | None = None,
    which: Callable[[str], str | None] | None = None,
    sudo_ok: Callable[[], bool] | None = None,
) -> list[str] | None:
    """[] as root, ["sudo", "-n"] with password-less sudo, else None."""
    if euid is None:
        euid = os.geteuid()
    if which is None:
        which = shutil.which
    if euid == 0:
        return []
    if not which("sudo"):
        return None
    if sudo_ok is None:
        def sudo_ok() -> bool:
            try:
                return subprocess.run(["sudo", "-n", "true"], capture_output=True,
                                      timeout=30).returncode == 0
            except (OSError, subprocess.SubprocessError):
                return False
    return ["sudo", "-n"] if sudo_ok() else None


def manual_install_message(packages: Sequence[str], reason: str) -> str:
    pkgs = " ".join(packages)
    return (
        f"[setup] error: missing system packages ({reason}); install them with "
        f"`sudo apt-get install -y --no-install-recommends {pkgs}` and run again "
        f"(or set {ENV_NO_SETUP}=1 to skip set-up)"
    )


def _apt(prefix: Sequence[str]) -> list[str]:
    # sudo resets the environment: pass DEBIAN_FRONTEND through `env`.
    if prefix:
        return [*prefix, "env", "DEBIAN_FRONTEND=noninteractive", "apt-get"]
    return ["apt-get"]


def apt_install_command(prefix: Sequence[str], packages: Sequence[str]) -> list[str]:
    return [*_apt(prefix), "install", "-y", "--no-install-recommends",
            "-o", "DPkg::Lock::Timeout=300", *packages]


def apt_update_command(prefix: Sequence[str]) -> list[str]:
    return [*_apt(prefix), "update"]


def apt_lists_empty(lists_dir: str = "/var/lib/apt/lists") -> bool:
    return not glob.glob(os.path.join(lists_dir, "*_Packages*"))


def _run_quiet(cmd: Sequence[str], env: dict[str, str] | None = None) -> tuple[int, str]:
    try:
        proc = subprocess.run(list(cmd), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, env=env)
    except OSError as exc:
        return 127, str(exc)
    return proc.returncode, proc.stdout


def _tail(text: str, n: int = PIP_TAIL_LINES) -> str:
    return "\n".join(text.rstrip().splitlines()[-n:])


def install_system_packages(
    packages: Sequence[str],
    *,
    what: str | None = None,
    which: Callable[[str], str | None] | None = None,
    prefix_finder: Callable[[], list[str] | None] | None = None,
    runner: Callable[..., tuple[int, str]] | None = None,
    lists_empty: Callable[[], bool] | None = None,
) -> None:
    """apt-get install ``packages``; raise SetupError (one line) when impossible.

    Progress is announced (as ``what``) only once apt-get can actually run, so
    that a machine where nothing can install sees exactly one line.
    """
    which = which or shutil.which
    prefix_finder = prefix_finder or (lambda: privilege_prefix(which=which))
    runner = runner or _run_quiet
    lists_empty = lists_empty or apt_lists_empty
    if not packages:
        return
    if not which("apt-get"):
        raise SetupError(manual_install_message(packages, "no apt-get on this system"))
    prefix = prefix_finder()
    if prefix is None:
        raise SetupError(manual_install_message(
            packages, "not root and no password-less sudo"))
    log(f"installing {what or ' '.join(packages)} (apt-get, first run only)…")
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    install = apt_install_command(prefix, packages)
    update = apt_update_command(prefix)
    output = ""
    if lists_empty():
        code, output = runner(update, env=env)
    code, out = runner(install, env=env)
    output += out
    if code != 0:  # stale or missing package lists: refresh them once and retry
        code, out = runner(update, env=env)
        output += out
        if code == 0:
            code, out = runner(install, env=env)
            output += out
    if code != 0:
        print(_tail(output), file=sys.stderr)
        raise SetupError(manual_install_message(packages, "apt-get failed, see above"))


def system_packages_label(packages: Sequence[str]) -> str:
    names = []
    if any(p in EGL_PACKAGES for p in packages):
        names.append("Mesa EGL")
    if any(p in XVFB_PACKAGES for p in packages):
        names.append("Xvfb")
    return " and ".join(names) or " ".join(packages)


def ensure_system_packages(mode: str) -> None:
    if not sys.platform.startswith("linux"):
        return
    missing = missing_packages(system_packages_for(mode))
    if not missing:
        return
    start = time.monotonic()
    install_system_packages(
        missing, what=f"{system_packages_label(missing)} ({' '.join(missing)})")
    log(f"system packages installed ({time.monotonic() - start:.0f} s)")


def ensure_optional_packages(extras: Sequence[str]) -> None:
    """Install :func:`optional_packages_for` ``extras``; where that fails, one note (scalar Mitsuba still runs)."""
    if not sys.platform.startswith("linux"):
        return
    missing = missing_packages(optional_packages_for(extras))
    if not missing:
        return
    try:
        install_system_packages(missing, what=f"LLVM 19 for Mitsuba's fast variants ({' '.join(missing)})")
    except SetupError:
        log(f"note: {' '.join(missing)} not installed: Mitsuba falls back to its (slow) scalar variants")


def missing_node_packages(prefix: Path, packages: dict[str, str] = NODE_PACKAGES) -> list[str]:
    """``name@version`` of each package whose pinned version is not installed under ``prefix``."""
    missing = []
    for name, version in packages.items():
        try:
            installed = json.loads((prefix / "node_modules" / name / "package.json").read_text()).get("version")
        except (OSError, ValueError, AttributeError):
            installed = None
        if installed != version:
            missing.append(f"{name}@{version}")
    return missing


def npm_install_command(npm: str, prefix: Path, specs: Sequence[str]) -> list[str]:
    return [npm, "install", "--prefix", str(prefix), "--no-audit", "--no-fund", "--no-save", "--loglevel=error", *specs]


def ensure_node_packages(mode: str, which: Callable[[str], str | None] | None = None,
                         runner: Callable[..., tuple[int, str]] | None = None) -> None:
    """``test`` mode: npm-install :data:`NODE_PACKAGES` into :func:`node_prefix` when missing; a note where it cannot."""
    if mode != MODE_TEST:
        return
    prefix = node_prefix()
    missing = missing_node_packages(prefix)
    if not missing:
        return
    npm = (which or shutil.which)("npm")
    if not npm:
        log(f"note: npm not found: {' '.join(missing)} not installed (the glTF export's validation tests need it)")
        return
    log(f"installing {' '.join(missing)} with npm into {prefix} (first run only)…")
    prefix.mkdir(parents=True, exist_ok=True)
    code, out = (runner or _run_quiet)(npm_install_command(npm, prefix, missing))
    if code != 0:
        print(_tail(out), file=sys.stderr)
        log(f"note: npm install failed (exit {code}): the glTF export's validation tests will fail")


# Blender as a Python module for `export --to blender` and its tests (docs/blender.md). Its wheel asks for
# numpy < 2, which the pinned numpy 2 excludes, so it cannot be an extra resolved with the constraints: it is
# installed alone, without dependencies (it imports and renders with numpy 2; its own numpy modules do not
# load). CPython 3.11 only, about 1 GB installed: on first use (`--to blender`) and for the tests.
BLENDER_REQUIREMENT = "bpy==5.0.1"
#: Set (to anything but 0) to keep bpy out of a test set-up (a shared machine's disk).
ENV_NO_BLENDER = "BRAGG_EXPLORER_NO_BLENDER"


def wants_blender(argv: Sequence[str]) -> bool:
    argv = list(argv)
    return "--to=blender" in argv or any(a == "--to" and k + 1 < len(argv) and argv[k + 1] == "blender" for k, a in enumerate(argv))


def ensure_blender(mode: str, argv: Sequence[str], venv_dir: Path | None = None,
                   runner: Callable[..., tuple[int, str]] | None = None) -> None:
    """pip-install :data:`BLENDER_REQUIREMENT` (no dependencies) into the venv when a command or the tests need it."""
    if mode != MODE_TEST and not wants_blender(argv):
        return
    if mode == MODE_TEST and os.environ.get(ENV_NO_BLENDER, "") not in ("", "0"):
        return  # a developer's choice: the Blender tests then skip (CI=true: they fail)
    venv_dir = venv_dir or VENV_DIR
    name, _, version = BLENDER_REQUIREMENT.partition("==")
    if glob.glob(str(venv_dir / "lib" / "python*" / "site-packages" / f"{name}-{version}.dist-info")):
        return
    if sys.version_info[:2] != (3, 11):
        log(f"note: {BLENDER_REQUIREMENT} is built for CPython 3.11 only: the Blender export and its tests need it")
        return
    log(f"installing {BLENDER_REQUIREMENT} (Blender as a Python module, about 1 GB; first use only)…")
    code, out = (runner or _run_quiet)([str(venv_python(venv_dir)), "-m", "pip", "install", "--disable-pip-version-check",
                                        "--no-input", "--no-deps", BLENDER_REQUIREMENT])
    if code != 0:
        print(_tail(out), file=sys.stderr)
        log(f"note: pip install {BLENDER_REQUIREMENT} failed (exit {code}): the Blender export is unavailable")


# --------------------------------------------------------------------------
# Virtual environment and Python packages


def python_tag(version_info: Sequence[int] = tuple(sys.version_info[:2]),
               implementation: str = sys.implementation.name) -> str:
    return f"{implementation}-{version_info[0]}.{version_info[1]}"


def stamp_key(pyproject_text: bytes, python: str, venv_dir: str, constraints_text: bytes = b"") -> str:
    h = hashlib.sha256()
    for part in (pyproject_text, python.encode(), os.fsencode(venv_dir), constraints_text):
        h.update(len(part).to_bytes(8, "little"))
        h.update(part)
    return h.hexdigest()


def make_stamp(key: str, extras: Iterable[str]) -> dict:
    return {"key": key, "extras": sorted(set(extras))}


def stamp_matches(stamp: dict | None, key: str, extras: Iterable[str]) -> bool:
    """True when pip can be skipped: same key and every wanted extra installed."""
    if not isinstance(stamp, dict) or stamp.get("key") != key:
        return False
    installed = stamp.get("extras")
    return isinstance(installed, list) and set(extras) <= set(installed)


def read_stamp(path: Path) -> dict | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def write_stamp(path: Path, stamp: dict) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(stamp) + "\n")
    os.replace(tmp, path)


def venv_python(venv_dir: Path = VENV_DIR) -> Path:
    return venv_dir / "bin" / "python"


def venv_version(venv_dir: Path) -> str | None:
    """'3.11' from pyvenv.cfg, or None."""
    try:
        text = (venv_dir / "pyvenv.cfg").read_text()
    except OSError:
        return None
    for line in text.splitlines():
        key, _, value = line.partition("=")
        if key.strip() in ("version", "version_info"):
            parts = value.strip().split(".")
            if len(parts) >= 2:
                return f"{parts[0]}.{parts[1]}"
    return None


def venv_usable(venv_dir: Path, version_info: Sequence[int] = tuple(sys.version_info[:2])
                ) -> bool:
    """The venv exists, its interpreter still resolves, it has pip, same X.Y."""
    return (
        os.path.exists(venv_python(venv_dir))  # follows the symlink to the base python
        and (venv_dir / "bin" / "pip").exists()
        and venv_version(venv_dir) == f"{version_info[0]}.{version_info[1]}"
    )


def in_venv(venv_dir: Path = VENV_DIR) -> bool:
    try:
        return Path(sys.prefix).resolve() == venv_dir.resolve()
    except OSError:
        return False


def pip_install_command(python: str, extras: Sequence[str], constraints: Path | None = None) -> list[str]:
    target = "." if not extras else f".[{','.join(sorted(extras))}]"
    pinned = ["-c", str(constraints)] if constraints is not None else []
    return [python, "-m", "pip", "install", "--disable-pip-version-check", "--no-input",
            *pinned, "-e", target]


def venv_package_for(version_info: Sequence[int] = tuple(sys.version_info[:2])) -> str:
    return f"python{version_info[0]}.{version_info[1]}-venv"


def is_debian_system_python() -> bool:
    return os.path.realpath(sys.base_prefix) == "/usr" and shutil.which("apt-get") is not None


def create_venv(venv_dir: Path, clear: bool) -> None:
    import importlib.util  # noqa: PLC0415

    pkg = venv_package_for()
    has_modules = all(importlib.util.find_spec(m) for m in ("venv", "ensurepip"))
    if not has_modules and is_debian_system_python():
        install_system_packages([pkg])
        importlib.invalidate_caches()
        has_modules = all(importlib.util.find_spec(m) for m in ("venv", "ensurepip"))
    if not has_modules:
        raise SetupError(f"[setup] error: Python's venv module is missing; install the "
                         f"Debian package {pkg} (apt-get install {pkg}) and run again")
    cmd = [sys.executable, "-m", "venv", *(["--clear"] if clear else []), str(venv_dir)]
    code, out = _run_quiet(cmd)
    if code != 0 and "ensurepip" in out and is_debian_system_python():
        # Debian ships venv without ensurepip's wheels unless pythonX.Y-venv is there.
        install_system_packages([pkg])
        code, out = _run_quiet([sys.executable, "-m", "venv", "--clear", str(venv_dir)])
    if code != 0:
        print(_tail(out), file=sys.stderr)
        if "ensurepip" in out:
            raise SetupError(f"[setup] error: could not create .venv: ensurepip is missing; "
                             f"install the Debian package {pkg} and run again")
        raise SetupError(f"[setup] error: `{' '.join(cmd)}` failed (see above)")


def pip_install(python: str, extras: Sequence[str], log_path: Path) -> None:
    cmd = pip_install_command(python, extras, CONSTRAINTS if CONSTRAINTS.exists() else None)
    with open(log_path, "w") as fh:
        fh.write("$ " + " ".join(cmd) + "\n")
        fh.flush()
        try:
            code = subprocess.run(cmd, cwd=REPO_ROOT, stdin=subprocess.DEVNULL, stdout=fh,
                                  stderr=subprocess.STDOUT).returncode
        except OSError as exc:
            fh.write(f"{exc}\n")
            code = 127
    if code != 0:
        try:
            print(_tail(log_path.read_text()), file=sys.stderr)
        except OSError:
            pass
        raise SetupError(f"[setup] error: pip install failed (exit {code}); "
                         f"full log in {log_path}")


@contextlib.contextmanager
def setup_lock(path: Path = LOCK_PATH) -> Iterator[None]:
    """Serialise concurrent first runs (two terminals, parallel test processes)."""
    try:
        import fcntl  # noqa: PLC0415
        fh = open(path, "a")
    except (ImportError, OSError):
        yield
        return
    try:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            log("waiting for another set-up of .venv to finish…")
            fcntl.flock(fh, fcntl.LOCK_EX)
        yield
    finally:
        fh.close()


def current_key() -> str:
    try:
        text = PYPROJECT.read_bytes()
    except OSError as exc:
        raise SetupError(f"[setup] error: cannot read {PYPROJECT}: {exc.strerror}") from None
    constraints = CONSTRAINTS.read_bytes() if CONSTRAINTS.exists() else b""
    return stamp_key(text, python_tag(), str(VENV_DIR), constraints)


def ensure_python_packages(extras: Sequence[str], inside: bool) -> bool:
    """Make .venv ready; return True when pip had to run."""
    stamp_path = VENV_DIR / STAMP_NAME
    key = current_key()
    if (inside or venv_usable(VENV_DIR)) and stamp_matches(read_stamp(stamp_path), key, extras):
        return False
    with setup_lock():
        # Someone else may have finished the job while we waited for the lock.
        fresh = not (inside or venv_usable(VENV_DIR))
        if not fresh and stamp_matches(read_stamp(stamp_path), key, extras):
            return False
        start = time.monotonic()
        if fresh:
            log("creating the virtual environment .venv …")
            create_venv(VENV_DIR, clear=VENV_DIR.exists())
        old = None if fresh else read_stamp(stamp_path)
        # Keep the extras installed before (e.g. [test]) so that switching
        # between the two commands does not reinstall back and forth.
        keep = old.get("extras", []) if isinstance(old, dict) else []
        keep = [e for e in keep if isinstance(e, str)]
        want = sorted(set(extras) | set(keep))
        what = "Python packages" + (f" with [{','.join(want)}] extras" if want else "")
        when = "first run, about a minute" if fresh else "pyproject.toml or extras changed"
        log(f"installing {what} into .venv ({when})…")
        with contextlib.suppress(OSError):
            stamp_path.unlink()
        python = sys.executable if inside else str(venv_python(VENV_DIR))
        pip_install(python, want, VENV_DIR / PIP_LOG_NAME)
        write_stamp(stamp_path, make_stamp(key, want))
        log(f"Python packages ready ({time.monotonic() - start:.0f} s)")
        return True


# --------------------------------------------------------------------------
# Entry point


def main(argv: Sequence[str] | None = None) -> int:
    if argv is None:
        argv = sys.argv[1:]
    mode, args, extras = parse_mode(argv)
    if sys.version_info < MIN_PYTHON:
        print(f"[setup] error: Python {'.'.join(map(str, MIN_PYTHON))} or newer is needed "
              f"(this is {platform.python_version()} at {sys.executable})", file=sys.stderr)
        return 1
    if not PYPROJECT.is_file():
        # An installed package (pip install): pip brought its dependencies; no checkout, no .venv to set up.
        if mode == MODE_TEST:
            print("[setup] error: the tests run from a source checkout (git clone), not an installed package",
                  file=sys.stderr)
            return 1
        run_in_process(mode, args)
    if os.environ.get(ENV_NO_SETUP, "") not in ("", "0"):
        run_in_process(mode, args)
    try:
        ensure_system_packages(mode)
        ensure_optional_packages(extras)
        ensure_node_packages(mode)
        inside = in_venv(VENV_DIR)
        installed = ensure_python_packages(extras, inside)
        ensure_blender(mode, args)
    except SetupError as exc:
        print(str(exc), file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("[setup] interrupted", file=sys.stderr)
        return 130
    if inside and not installed:
        run_in_process(mode, args)
    python = sys.executable if inside else str(venv_python(VENV_DIR))
    cmd = final_command(mode, python, args)
    os.chdir(final_cwd(mode, os.getcwd()))
    sys.stdout.flush()
    sys.stderr.flush()
    os.execve(python, cmd, child_environment(dict(os.environ), VENV_DIR))
    return 0  # not reached
