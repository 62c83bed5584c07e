"""
The documents speak to users: no tracker words in README.md and docs/; docs/README.md indexes every page;
docs/tutorial.md's commands run as written, in order, in an empty folder.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO_ROOT, run_cli

DOCS = REPO_ROOT / "docs"
#: Words of a bug tracker, not of a user's document (whole words, any case).
TRACKER_WORDS = re.compile(r"\b(issues?|items?|acceptance)\b", re.IGNORECASE)
#: A tutorial command's budget (s): the design, the slowest, takes ~5 s of CPU alone; more on a shared machine.
COMMAND_TIMEOUT_S = 300
#: Commands that draw nothing with GL: run in this process (conftest.run_cli refuses a GL context, so one that
#: starts drawing fails the test rather than passing unseen).
GPU_FREE = ("info", "design", "export")


def _documents() -> list[Path]:
    return [REPO_ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]


def test_no_tracker_words_in_documents():
    """No page says "issue", "item" or "acceptance": a reader has no tracker."""
    found = []
    for path in _documents():
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
            match = TRACKER_WORDS.search(line)
            if match:
                found.append(f"{path.relative_to(REPO_ROOT)}:{number}: {match.group(0)!r}")
    assert not found, "\n".join(found)


def test_tracker_words_pattern_finds_them():
    """The check above can fail: the pattern finds the words it is for, and not words that contain them."""
    assert TRACKER_WORDS.search("Issue 18, items 3 and 5") and TRACKER_WORDS.search("the acceptance's threshold")
    assert not TRACKER_WORDS.search("tissues and itemised lists")


def test_docs_index_links_every_page():
    """docs/README.md links each page of docs/ (and each link resolves)."""
    index = (DOCS / "README.md").read_text(encoding="utf-8")
    links = set(re.findall(r"\]\(([^)#]+)\)", index))
    for link in links:
        assert (DOCS / link).resolve().exists(), f"docs/README.md links {link}, which does not exist"
    pages = {path.name for path in DOCS.glob("*.md")} - {"README.md"}
    missing = sorted(pages - links)
    assert not missing, f"docs/README.md does not link {missing}"


def tutorial_commands() -> list[str]:
    """The command lines of docs/tutorial.md's ```sh blocks, in order."""
    text = (DOCS / "tutorial.md").read_text(encoding="utf-8")
    commands = []
    for block in re.findall(r"^```sh\n(.*?)^```", text, flags=re.MULTILINE | re.DOTALL):
        commands += [line.strip() for line in block.splitlines() if line.strip() and not line.strip().startswith("#")]
    return commands


@pytest.mark.slow
def test_tutorial_commands_run(tmp_path):
    """
    Each command of the tutorial, as written (``python3 -m explorer`` run by this interpreter; the GPU-free ones
    through the same entry point in this process), in an empty folder without a display (the first launch writes
    the headless views), exits 0; the files it promises are there.
    """
    commands = tutorial_commands()
    assert len(commands) >= 8 and all(c.startswith("python3 -m explorer") for c in commands), commands
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env.update(PYTHONPATH=str(REPO_ROOT), BRAGG_EXPLORER_NO_SETUP="1")
    for command in commands:
        args = shlex.split(command)[3:]
        if args and args[0] in GPU_FREE:  # the same CLI entry point, without a new interpreter's start (~2.5 s of CPU each)
            run = run_cli(*args, cwd=tmp_path)
        else:
            argv = [sys.executable, "-m", "explorer", *args]
            run = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=COMMAND_TIMEOUT_S)
        assert run.returncode == 0, f"{command}\n{run.stderr[-2000:]}"
        assert "Traceback" not in run.stderr, f"{command}\n{run.stderr[-2000:]}"
    for name in ("out", "strip.png", "sphere.png", "gold.json", "gold_strip.png", "gold_lit.png", "gold.brdf", "gold_brdf.png",
                 "gold_scene/scene.xml"):
        assert (tmp_path / name).exists(), f"the tutorial promises {name}"
