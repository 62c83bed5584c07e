"""Every path that a comment, a docstring or a document names exists.

Paths of the repository (``explorer/…``, ``shaders/…``, ``luts/…``, ``tests/…``, ``docs/…``, ``.github/…``,
``.ci/…``) named in Python comments and docstrings, GLSL and material-file comments, TOML comments and the
Markdown documents. ``explorer/shaders`` and ``explorer/luts`` are where the wheel puts ``shaders/`` and
``luts/``; a segment in capitals (``shaders/views/NAME.glsl``) or with a wildcard is a pattern, not a path.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

from conftest import REPO_ROOT

PATH = re.compile(r"(?<![\w./-])((?:explorer|shaders|luts|tests|docs|\.github|\.ci)/[\w./-]*[\w/])")
#: The wheel's locations of the checkout's data folders (pyproject.toml's package-dir).
INSTALLED = {"explorer/shaders": "shaders", "explorer/luts": "luts"}
SKIPPED_PARTS = {".venv", ".git", "build", "__pycache__", ".pytest_cache", ".hypothesis"}


def _files(*suffixes: str):
    for path in REPO_ROOT.rglob("*"):
        if path.is_file() and path.suffix in suffixes and not SKIPPED_PARTS & set(path.relative_to(REPO_ROOT).parts):
            yield path


def _python_prose(text: str):
    """(line, text) of every comment and docstring of a Python file."""
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        if token.type == tokenize.COMMENT:
            yield token.start[0], token.string
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
                for offset, line in enumerate(body[0].value.value.splitlines()):
                    yield body[0].lineno + offset, line


def _comment_prose(text: str, markers: tuple[str, ...]):
    for number, line in enumerate(text.splitlines(), 1):
        starts = [line.find(m) for m in markers if m in line]
        if starts:
            yield number, line[min(starts):]


def prose(path: Path):
    text = path.read_text(encoding="utf-8", errors="replace")
    if path.suffix == ".py":
        return _python_prose(text)
    if path.suffix in (".glsl", ".brd", ".brdf"):
        return _comment_prose(text, ("//", "#"))
    if path.suffix == ".toml":
        return _comment_prose(text, ("#",))
    return enumerate(text.splitlines(), 1)


def exists(named: str) -> bool:
    named = named.rstrip(".")
    if "*" in named or any(part.split(".")[0].isupper() for part in named.split("/")):
        return True
    for installed, checkout in INSTALLED.items():
        if named == installed or named.startswith(installed + "/"):
            named = checkout + named[len(installed):]
    return (REPO_ROOT / named).exists()


def test_every_path_named_in_prose_exists():
    missing = [
        f"{path.relative_to(REPO_ROOT)}:{line}: {match.group(1)}"
        for path in _files(".py", ".glsl", ".brd", ".toml", ".md")
        for line, text in prose(path)
        for match in PATH.finditer(text)
        if not exists(match.group(1))
    ]
    assert not missing, "stale references:\n" + "\n".join(missing)


def test_the_check_sees_a_stale_reference():
    text = '"""See explorer/luts.py."""\n# and shaders/lib/gone.glsl\nx = "explorer/not_prose.py"\n'
    named = [m.group(1) for _, t in _python_prose(text) for m in PATH.finditer(t)]
    assert named == ["shaders/lib/gone.glsl", "explorer/luts.py"] or sorted(named) == sorted(["shaders/lib/gone.glsl", "explorer/luts.py"])
    assert not any(exists(n) for n in named)
    assert exists("explorer/shaders/lib/bragg.glsl") and exists("shaders/views/NAME.glsl")
