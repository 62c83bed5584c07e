"""Shared fixtures: the repository root, the Bragg mirror material, and one GL renderer per session.

GL tests (``@pytest.mark.gl``) take the ``gl_renderer`` fixture. Without an OpenGL 3.3 context
through EGL they are skipped on a developer machine, but they fail when ``CI=true``: continuous
integration must never pass by skipping the GPU half of the product. The failure message includes
:class:`explorer.gpu.GLUnavailable`'s, which names the Debian packages to install.
"""

from __future__ import annotations

import os
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


def running_in_ci() -> bool:
    """True when the environment variable CI is "true" (GitHub Actions, GitLab CI and most others)."""
    return os.environ.get("CI", "").strip().lower() == "true"


@pytest.fixture(scope="session")
def gl_renderer():
    """One :class:`explorer.gpu.Renderer` for the whole session (compiled programs are cached in it)."""
    from explorer.gpu import GLUnavailable, Renderer, create_context

    try:
        ctx, reason = create_context(), None
    except GLUnavailable as error:
        ctx, reason = None, str(error)
    if ctx is None:
        if running_in_ci():
            pytest.fail(f"CI=true and no OpenGL context: {reason}", pytrace=False)
        pytest.skip(reason)
    renderer = Renderer(ctx)
    yield renderer
    ctx.release()


@pytest.fixture(scope="session")
def bragg_material():
    """``shaders/bragg_mirror.brd``, parsed."""
    from explorer.materials.brd import load_material

    return load_material(BRAGG_MATERIAL)
