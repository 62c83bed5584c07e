"""
The package's import graph has no cycles: every ``import`` of an ``explorer`` module, at
module level or inside a function, is an edge; a cycle means the layers are not layered.
"""

from __future__ import annotations

import ast
from pathlib import Path

from conftest import REPO_ROOT

PACKAGE = REPO_ROOT / "explorer"


def module_name(path: Path) -> str:
    """``explorer/app/state.py`` -> ``explorer.app.state``; a package's ``__init__.py`` is the package."""
    parts = list(path.relative_to(REPO_ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def import_graph() -> dict[str, set[str]]:
    """``{module: modules it imports}`` over explorer's modules (function-level imports included)."""
    paths = {module_name(p): p for p in PACKAGE.rglob("*.py")}
    graph: dict[str, set[str]] = {name: set() for name in paths}
    for name, path in paths.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join(anchor + ([base] if base else []))
                # `from PKG import NAME` imports the module PKG.NAME when there is one, else PKG itself.
                targets = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in paths else base for alias in node.names]
            else:
                continue
            graph[name].update(t for t in targets if t in paths and t != name)
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as a list of modules (first = last), or None (depth-first search)."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for target in sorted(graph[node]):
            if state.get(target) == 1:
                return path[path.index(target):] + [target]
            if target not in state and (cycle := visit(target)):
                return cycle
        path.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


def test_the_graph_sees_relative_and_function_level_imports():
    graph = import_graph()
    assert "explorer.materials.brd" in graph["explorer.cli.commands"]  # module level, relative
    assert "explorer.bench" in graph["explorer.cli.commands"]  # inside a function


def test_find_cycle_finds_one():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_no_import_cycles():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


#: The packages from the bottom up: a package imports only packages of a lower rank (or its own).
#: ``errors`` is the foundation, ``resources`` (paths) and ``files`` (atomic outputs) stand on it; the
#: store ``tables`` knows no physics; ``plugins`` (the public API of material plugins) re-exports ``materials``;
#: ``design`` (the inverse design, over the physics' forward models) stands on ``materials`` too; ``views`` (what each
#: pixel of a view shows, without GL) comes below ``gpu``, which draws the views; ``mitsuba`` (the plugins, compared
#: with the GL views) above it; ``rendering`` (any view by any engine, the render service) dispatches to all three;
#: ``bench`` (the benchmarks and accuracy studies, the app's frame times among them) stands on the ``app``; ``cli``
#: opens the ``app``; ``dev`` (the checkout's set-up and regeneration scripts, not in the wheel) and ``__main__``
#: stand outside.
LAYERS = {
    "errors": 0,
    "resources": 1, "files": 1,
    "tables": 2,
    "physics": 3,
    "materials": 4,
    "plugins": 5, "design": 5,
    "views": 6,
    "gpu": 7,
    "mitsuba": 8, "blender": 8,
    "rendering": 9,
    "app": 10,
    "bench": 11,
    "cli": 12,
    "dev": 13, "__main__": 14,
}


def package_of(module: str) -> str:
    """``explorer.physics.bragg`` -> ``physics``; ``explorer`` itself -> ``""``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def package_violations(graph: dict[str, set[str]]) -> list[str]:
    """Every import of a package of the same or a higher rank than the importer's (a package's own excluded)."""
    bad = []
    for module, targets in sorted(graph.items()):
        source = package_of(module)
        for target in sorted(targets):
            destination = package_of(target)
            if not source or not destination or destination == source:
                continue
            if LAYERS[destination] >= LAYERS[source]:
                bad.append(f"{module} ({source}) imports {target} ({destination})")
    return bad


def test_every_package_has_a_rank():
    assert {p.name.removesuffix(".py") for p in PACKAGE.iterdir() if p.name != "__init__.py" and
            (p.suffix == ".py" or (p / "__init__.py").exists())} == set(LAYERS)


def test_packages_import_only_packages_below():
    """From the bottom: errors, resources and files, tables (the store), physics, materials, views, gpu,
    app, cli. The store knows no physics: the physics modules register their tables with it."""
    violations = package_violations(import_graph())
    assert not violations, "imports against the package order:\n" + "\n".join(violations)


def test_the_package_check_sees_an_upward_import():
    graph = {"explorer.tables.luts": {"explorer.physics.colorimetry"}, "explorer.physics.colorimetry": {"explorer.tables.luts"}}
    assert package_violations(graph) == ["explorer.tables.luts (tables) imports explorer.physics.colorimetry (physics)"]


#: The one module outside ``cli`` that starts it: the checkout's launcher. The app and the scripts of ``dev`` reach
#: rendering, studies and design through the packages below (``explorer.rendering``, ``explorer.bench``,
#: ``explorer.design``), never through the command line's modules.
CLI_LAUNCHERS = {"explorer.dev.bootstrap"}


def cli_importers(graph: dict[str, set[str]]) -> list[str]:
    """The modules of ``app`` and ``dev`` (launchers excepted) that import a module of ``cli``."""
    return sorted(f"{module} imports {target}" for module, targets in graph.items() for target in targets
                  if package_of(module) in ("app", "dev") and module not in CLI_LAUNCHERS and package_of(target) == "cli")


def test_app_and_dev_do_not_import_the_cli():
    importers = cli_importers(import_graph())
    assert not importers, "\n".join(importers)


def test_the_cli_check_sees_an_import():
    graph = {"explorer.dev.figure7": {"explorer.cli.commands"}, "explorer.dev.bootstrap": {"explorer.cli.commands"}}
    assert cli_importers(graph) == ["explorer.dev.figure7 imports explorer.cli.commands"]
