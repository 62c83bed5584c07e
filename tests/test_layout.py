"""
The repository's layout: no module of ``explorer/`` over 1,000 lines (split by subject instead), study scripts under
``explorer/dev/`` rather than in ``docs/``, and a root that holds only the project's entries. Reads the tree: fast.
"""

from __future__ import annotations

import subprocess

from conftest import REPO_ROOT

#: The longest a module of the package may be.
MAX_LINES = 1000
#: What the repository's root holds, besides its dot-folders and dot-files.
ROOT_ENTRIES = {"pyproject.toml", "explorer", "shaders", "luts", "tests", "README.md", "docs", "LICENSE"}
#: The one folder of ``docs/`` that may hold Python: the plugin example a material's author copies.
DOCS_PYTHON = "plugin_example"


def long_modules(root, limit: int = MAX_LINES) -> list[str]:
    """``path: lines`` of every ``.py`` under ``root`` longer than ``limit`` lines."""
    lengths = {path: len(path.read_text(encoding="utf-8").splitlines()) for path in sorted(root.rglob("*.py"))}
    return [f"{path.relative_to(root.parent)}: {n}" for path, n in lengths.items() if n > limit]


def test_no_module_is_over_1000_lines():
    assert not long_modules(REPO_ROOT / "explorer"), "split by subject:\n" + "\n".join(long_modules(REPO_ROOT / "explorer"))


def test_the_length_check_sees_a_long_module(tmp_path):
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "short.py").write_text("x = 1\n" * 1000)
    (package / "long.py").write_text("x = 1\n" * 1001)
    assert long_modules(package) == ["pkg/long.py: 1001"]


def root_entries() -> set[str]:
    """The root's tracked entries (a checkout: ``git ls-files``), else what it holds; dot-entries left out."""
    try:
        listed = subprocess.run(["git", "ls-files"], cwd=REPO_ROOT, capture_output=True, text=True, check=True).stdout.split()
        names = {path.split("/")[0] for path in listed if (REPO_ROOT / path).exists()}
    except (OSError, subprocess.CalledProcessError):
        names = {p.name for p in REPO_ROOT.iterdir() if not p.name.endswith(".egg-info") and p.name not in ("build", "dist")}
    return {name for name in names if not name.startswith(".")}


def test_the_root_holds_only_its_entries():
    assert root_entries() == ROOT_ENTRIES


def test_docs_hold_no_python():
    scripts = [str(p.relative_to(REPO_ROOT)) for p in (REPO_ROOT / "docs").rglob("*.py") if DOCS_PYTHON not in p.parts]
    assert not scripts, f"study scripts belong in explorer/dev/: {scripts}"


def test_the_wheel_lists_every_package():
    """pyproject's explicit package list names every package of explorer/ but dev/ (the checkout's scripts)."""
    import tomllib

    listed = set(tomllib.loads((REPO_ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    packages = {".".join(init.parent.relative_to(REPO_ROOT).parts) for init in (REPO_ROOT / "explorer").rglob("__init__.py")}
    missing = sorted(p for p in packages - listed if p != "explorer.dev" and not p.startswith("explorer.dev."))
    assert not missing, f"pyproject.toml's [tool.setuptools] packages lacks {missing}"
