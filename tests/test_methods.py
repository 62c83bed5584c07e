"""Each method is declared once (explorer/materials/methods.py): the twins, the app, the benchmarks and the
shaders take its number from there (the shaders through the ``#define``s every program receives)."""

from __future__ import annotations

import re

import pytest

from conftest import REPO_ROOT
from explorer.gpu.programs import build_program_source
from explorer.materials.brd import load_material
from explorer.materials.methods import BraggMethod, ThinFilmMethod, glsl_defines, methods_for

#: A method compared with, or set to, a literal number (in Python; the shaders' ``m`` too).
LITERAL = re.compile(r"""(\bmethod\b["']?\]?\s*(==|!=|<=|>=|<|>|=|:)\s*\(?\s*\d)|(method\s+(not\s+)?in\s+\(\d)""")
SHADER_LITERAL = re.compile(r"\bm\s*(==|!=|<=|>=|<|>)\s*\d")
#: Methods listed as literal numbers (``for m in (1, 2, 3, 4) if m != model.method``).
NUMBERS_LITERAL = re.compile(r"\b(m|method)\s+in\s+\((\d+,\s*)+\d+\)")


def test_no_method_number_outside_its_declaration():
    found = []
    files = [*(REPO_ROOT / "explorer").rglob("*.py"), *(REPO_ROOT / "shaders").glob("*.brd")]
    for path in files:
        if path.name == "methods.py":
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            code = line.split("#")[0] if path.suffix == ".py" else line.split("//")[0]
            if path.suffix == ".brd" and line.startswith("#"):
                continue
            if (LITERAL.search(code) or (path.suffix == ".brd" and SHADER_LITERAL.search(code))
                    or ("method" in code and NUMBERS_LITERAL.search(code))):  # not the quality s in (2, 3, 4, 5)
                found.append(f"{path.relative_to(REPO_ROOT)}:{number}: {line.strip()}")
    assert not found, "method numbers spelled outside explorer/materials/methods.py:\n" + "\n".join(found)


def test_the_check_sees_a_literal():
    assert LITERAL.search("if self.method == 3:") and LITERAL.search('values = {"method": 0}')
    assert NUMBERS_LITERAL.search("others = tuple(m for m in (1, 2, 3, 4) if m != model.method)")
    assert not NUMBERS_LITERAL.search('[{"method": int(B.SUBDIVIDED), "s": s} for s in (2, 3, 4, 5)]')
    assert SHADER_LITERAL.search("if (m == 4) return x;") and not SHADER_LITERAL.search("if (m == BRAGG_IMPROVED)")


@pytest.mark.parametrize("name, enumeration", [("bragg_mirror", BraggMethod), ("bragg_layer", BraggMethod),
                                                ("thin_film", ThinFilmMethod)])
def test_declared_range_matches_the_enumeration(name, enumeration):
    material = load_material(REPO_ROOT / "shaders" / f"{name}.brd")
    parameter = material.parameter("method")
    assert methods_for(material.model) is enumeration
    assert (parameter.min, parameter.max) == (min(enumeration), max(enumeration))


def test_every_program_defines_the_method_names():
    material = load_material(REPO_ROOT / "shaders" / "thin_film.brd")
    source = build_program_source(material, "gradient", (("method", int(ThinFilmMethod.NAIVE)),))
    text = source.code
    for name, value in glsl_defines().items():
        assert re.search(rf"#define {name} {value}\b", text), name
