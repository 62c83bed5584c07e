"""Every public module-level function of explorer/physics carries type hints (issue 21).

Parsed with ``ast`` so the check costs nothing and imports no module.
"""
from __future__ import annotations

import ast
from pathlib import Path

PHYSICS = Path(__file__).resolve().parent.parent / "explorer" / "physics"


def _missing_annotations(path: Path) -> list[str]:
    """Return ``file:line name(param)`` for each unannotated parameter or return."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    missing = []
    for node in tree.body:
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        if node.name.startswith("_"):
            continue
        a = node.args
        params = a.posonlyargs + a.args + a.kwonlyargs
        params += [p for p in (a.vararg, a.kwarg) if p is not None]
        where = f"{path.name}:{node.lineno} {node.name}"
        missing += [f"{where}({p.arg})" for p in params if p.annotation is None]
        if node.returns is None:
            missing.append(f"{where} -> return")
    return missing


def test_physics_modules_found():
    # Guards against a wrong path silently passing the check below.
    assert len(list(PHYSICS.glob("*.py"))) >= 5


def test_public_physics_functions_are_annotated():
    missing = [m for f in sorted(PHYSICS.glob("*.py")) for m in _missing_annotations(f)]
    assert not missing, "missing type hints:\n" + "\n".join(missing)
