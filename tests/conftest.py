"""Shared fixtures: the repository root, the Bragg mirror material, one GL renderer and one X display per session.

GL tests (``@pytest.mark.gl``) take the ``gl_renderer`` fixture. Without an OpenGL 3.3 context
through EGL they are skipped on a developer machine, but they fail when ``CI=true``: continuous
integration must never pass by skipping the GPU half of the product. The failure message includes
:class:`explorer.gpu.GLUnavailable`'s, which names the Debian packages to install.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import subprocess
import tempfile
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parent.parent
BRAGG_MATERIAL = REPO_ROOT / "shaders" / "bragg_mirror.brd"
BRDF_DATA = REPO_ROOT / "tests" / "data" / "brdf"


#: How every CLI error line begins.
CLI_ERROR_PREFIX = "bragg-explorer: error: "


def one_line_error(run) -> str:
    """
    Assert that a CLI run (anything with ``returncode``, ``stdout``, ``stderr``) failed with exactly one
    line on stderr, prefixed :data:`CLI_ERROR_PREFIX`, and no traceback; returns that line.
    """
    assert run.returncode != 0, run.stderr
    assert "Traceback" not in run.stderr + run.stdout, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(CLI_ERROR_PREFIX), run.stderr
    return lines[0]


@dataclass
class CliRun:
    """What a CLI run left: like :class:`subprocess.CompletedProcess` (``returncode``, ``stdout``, ``stderr``)."""

    args: list[str]
    returncode: int
    stdout: str
    stderr: str


class GLContextInProcess(BaseException):
    """An in-process CLI run tried to create a GL context (a BaseException: the CLI must not catch it)."""


def run_cli(*args, cwd: Path | str = REPO_ROOT) -> CliRun:
    """
    ``bragg-explorer ARGS`` in this process, from ``cwd``: :func:`explorer.cli.commands.main`, the one
    path by which every error becomes one line and an exit status, with stdout and stderr captured and
    warnings ignored. For bad input and GPU-free outputs; a subprocess remains where the process is the
    point (``python3 -m explorer``, the bootstrap, no display, the wheel, the app) or where the CLI draws
    with GL: a second GL context would replace the session's current one, so creating one here raises
    :class:`GLContextInProcess`.
    """
    import moderngl

    from explorer.cli.commands import main

    def no_context(*_, **__):
        raise GLContextInProcess("run_cli: this command creates a GL context; run it in a subprocess")

    argv = [str(arg) for arg in args]
    stdout, stderr = io.StringIO(), io.StringIO()
    previous = os.getcwd()
    create = moderngl.create_standalone_context
    moderngl.create_standalone_context = no_context
    try:
        os.chdir(cwd)
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                main(argv)
                returncode = 0
            except SystemExit as exit_:
                if isinstance(exit_.code, str):
                    print(exit_.code, file=sys.stderr)
                returncode = exit_.code if isinstance(exit_.code, int) else int(exit_.code is not None)
    finally:
        moderngl.create_standalone_context = create
        os.chdir(previous)
    return CliRun(argv, returncode, stdout.getvalue(), stderr.getvalue())


#: Seconds for one CLI subprocess (imports colour-science, may compile shaders on llvmpipe).
CLI_TIMEOUT = 300


def run_cli_process(*args, cwd: Path | str = REPO_ROOT) -> CliRun:
    """``python -m explorer.cli.commands ARGS`` in a subprocess from ``cwd``: for the commands that draw with GL."""
    argv = [str(arg) for arg in args]
    completed = subprocess.run(
        [sys.executable, "-m", "explorer.cli.commands", *argv], cwd=cwd, capture_output=True, text=True,
        timeout=CLI_TIMEOUT, env={**os.environ, "PYTHONWARNINGS": "ignore"},
    )
    return CliRun(argv, completed.returncode, completed.stdout, completed.stderr)


def running_in_ci() -> bool:
    """True when the environment variable CI is "true" (GitHub Actions, GitLab CI and most others)."""
    return os.environ.get("CI", "").strip().lower() == "true"


def _new_renderer():
    """A renderer on a new GL context, or skip/fail (CI) without one."""
    from explorer.gpu import GLUnavailable, Renderer, create_context

    try:
        ctx, reason = create_context(), None
    except GLUnavailable as error:
        ctx, reason = None, str(error)
    if ctx is None:
        if running_in_ci():
            pytest.fail(f"CI=true and no OpenGL context: {reason}", pytrace=False)
        pytest.skip(reason)
    return Renderer(ctx)


#: The renderer the modules share (compiled programs are cached in it); replaced by :func:`renew_gl_renderer`.
SESSION_RENDERERS: list = []


def renew_gl_renderer() -> None:
    """
    Drop the shared renderer and its context: the next module gets a new one. tests/test_mitsuba.py calls it:
    Dr.Jit's LLVM backend (libLLVM 19), once started in a process, breaks what llvmpipe (Mesa's LLVM) compiled
    before it in that context (measured: later draws read their uniforms as 0 and some tables wrong). pytest tears a
    module's fixtures down when a worker moves on to another module, so a module that comes back after this takes
    the new one.
    """
    while SESSION_RENDERERS:
        SESSION_RENDERERS.pop().ctx.release()


@pytest.fixture(scope="module")
def gl_renderer():
    """The shared :class:`explorer.gpu.Renderer` (one for the session, unless :func:`renew_gl_renderer` was called)."""
    if not SESSION_RENDERERS:
        SESSION_RENDERERS.append(_new_renderer())
    return SESSION_RENDERERS[0]


#: Fixture scopes whose one set-up serves several tests of one module (a class's or a module's).
SHARED_SCOPES = ("class", "module", "package")
#: The key of xdist's ``workerinput`` naming the file where each worker writes its tests' groups.
GROUPS_KEY = "shared_set_up_groups"


def shared_set_up_group(item) -> str | None:
    """
    The test module of ``item`` when it uses a class- or module-scoped fixture of that module, else None.

    The suite runs on every core (pyproject's ``-n logical``): a test in no group goes to whichever worker is
    free, but a fixture shared by a module's tests is set up once per worker that runs any of them, so those
    tests stay together and pay for it once (the design round trips, the exports, the wheel). Conftest's
    fixtures (the GL renderer) serve the whole worker and group nothing.
    """
    module = item.nodeid.split("::")[0]
    for definitions in item._fixtureinfo.name2fixturedefs.values():
        fixture = definitions[-1]
        if fixture.scope in SHARED_SCOPES and (fixture.baseid == module or fixture.baseid.startswith(module + "::")):
            return module
    return None


def pytest_collection_modifyitems(config, items):
    """In an xdist worker: write each grouped test's group where the controller's scheduler reads it."""
    path = getattr(config, "workerinput", {}).get(GROUPS_KEY)
    if path is not None:
        from explorer.files import write_text_atomic

        groups = {item.nodeid: group for item in items if (group := shared_set_up_group(item)) is not None}
        write_text_atomic(Path(path) / f"{config.workerinput['workerid']}.json", json.dumps(groups))


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node):
    """xdist's controller, per worker: where it writes its groups (one folder per run)."""
    config = node.config
    if not hasattr(config, "_shared_set_up_groups"):
        config._shared_set_up_groups = tempfile.mkdtemp(prefix="pytest-groups-")
    node.workerinput[GROUPS_KEY] = config._shared_set_up_groups


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``-n``'s default distribution, with the tests of one group (:func:`shared_set_up_group`) on one worker."""
    if config.getoption("dist") != "load":
        return None  # a distribution asked for on the command line
    from parallel import SharedSetUpScheduling

    return SharedSetUpScheduling(config, log, lambda: getattr(config, "_shared_set_up_groups", None))


def pytest_unconfigure(config):
    folder = getattr(config, "_shared_set_up_groups", None)
    if folder is not None:
        shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture(scope="session")
def x_display():
    """
    A virtual X display (Xvfb) for the app windows: one per test process, whichever modules use it. Without
    Xvfb the tests that take it skip on a developer machine and fail when ``CI=true``, as the GL tests do.
    """
    from explorer.app.xvfb import XvfbUnavailable, virtual_display

    try:
        context = virtual_display()
        display = context.__enter__()
    except XvfbUnavailable as error:
        if running_in_ci():
            pytest.fail(f"CI=true and no X display for the app: {error}", pytrace=False)
        pytest.skip(str(error))
    yield display
    context.__exit__(None, None, None)


@pytest.fixture(scope="session")
def bragg_material():
    """``shaders/bragg_mirror.brd``, parsed."""
    from explorer.materials.brd import load_material

    return load_material(BRAGG_MATERIAL)
