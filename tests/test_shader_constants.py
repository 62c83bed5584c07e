"""The GLSL library's shared constants come from the physics (explorer/materials/shader_constants.py):
written at assembly, never copied by hand into shaders/lib."""

from __future__ import annotations

import re

import numpy as np
import pytest

from conftest import REPO_ROOT
from explorer.materials.glsl import ShaderBuilder
from explorer.materials.shader_constants import GENERATED, declaration

LIB = REPO_ROOT / "shaders" / "lib"
CONST = re.compile(r"^\s*const\s+(?:int|float|vec3)\s+(\w+)\s*=", re.M)


def generated_names() -> dict[str, str]:
    return {name: block for block, make in GENERATED.items() for name in CONST.findall(make())}


def test_no_library_file_declares_a_generated_constant():
    names = generated_names()
    for path in LIB.glob("*.glsl"):
        declared = set(CONST.findall(path.read_text()))
        assert not declared & set(names), f"{path.name} copies {sorted(declared & set(names))} (generated in {names})"


@pytest.mark.parametrize("block", sorted(GENERATED))
def test_each_block_is_included_by_its_library_file(block):
    stem = block.removeprefix("generated/")
    assert f'#include "{block}"' in (LIB / stem).read_text()


def test_declarations_round_trip():
    assert declaration("A", 3) == "const int A = 3;"
    assert declaration("B", 1e-15) == "const float B = 1e-15;"
    assert declaration("C", 10.0) == "const float C = 10.0;"
    assert declaration("D", (606.0, 539.0, 445.0)) == "const vec3 D = vec3(606.0, 539.0, 445.0);"
    with pytest.raises(ValueError):
        declaration("E", float("inf"))


def test_a_program_gets_the_blocks_once_and_compiles(gl_renderer):
    builder = ShaderBuilder(include_dirs=[REPO_ROOT / "shaders"], version="330 core")
    builder.add_source('#include "lib/layered.glsl"\n#include "lib/thinfilm.glsl"\n#include "lib/lobes.glsl"\n'
                       "out vec4 colour;\nvoid main() { colour = vec4(float(THETA_ROWS) + D_INC_BLEND + VARIANCE_MAX); }\n",
                       "<test>")
    program = builder.build()
    for name in ("THETA_ROWS", "D_INC_BLEND", "VARIANCE_MAX", "CMF_COUNT"):
        assert len(re.findall(rf"const\s+\w+\s+{name}\s*=", program.code)) == 1, name
    gl_renderer.ctx.program(vertex_shader="#version 330 core\nin vec2 p; void main() { gl_Position = vec4(p, 0.0, 1.0); }",
                            fragment_shader=program.code).release()
    assert np.isfinite(float(re.search(r"const float THETA_STEP = ([^;]+);", program.code).group(1)))
