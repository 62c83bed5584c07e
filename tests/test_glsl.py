"""Tests for explorer.materials.glsl: #include expansion, #line mapping, compile logs.

Only `test_gl_compile_error_maps_to_included_file` needs an OpenGL context.
"""

from __future__ import annotations

import os
import pickle
import re
from pathlib import Path
from textwrap import dedent

import pytest

from explorer.materials.glsl import (
    LINE_STRIDE,
    PREAMBLE,
    Program,
    ShaderBuilder,
    ShaderError,
    compile_error,
    compile_error_message,
    map_log,
)

LINE_RE = re.compile(r"#line (\d+) (\d+)")


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def body(program: Program) -> list[str]:
    """The emitted lines that are not #line directives or the preamble."""
    lines = program.code.split("\n")[:-1]
    start = next(i for i, t in enumerate(lines) if LINE_RE.fullmatch(t))
    return [t for t in lines[start:] if not LINE_RE.fullmatch(t)]


def check_line_mapping(program: Program, generated: dict[str, str] | None = None) -> int:
    """Check every emitted line against the real file that the #lines name.

    Walks the code as a GLSL compiler numbers it: ``#line L S`` makes the next
    line number L of source string S.  Each emitted line must equal the real
    file's line at `Program.locate` (S, L); blank lines may also stand for a
    removed ``#include`` or ``#version``.  `generated` gives the text of
    ``<name>`` chunks.  Returns how many lines were checked.
    """
    texts = {name: text.splitlines() for name, text in (generated or {}).items()}
    current: list[int] | None = None
    checked = 0
    for text in program.code.split("\n")[:-1]:
        if match := LINE_RE.fullmatch(text):
            current = [int(match[2]), int(match[1])]
            continue
        if current is None:  # the preamble: #version and #defines
            continue
        name, line = program.locate(current[0], current[1])
        if name not in texts:
            texts[name] = Path(name).read_text().splitlines()
        real = texts[name][line - 1]
        if text == "" and real != "":
            assert re.match(r"\s*#\s*(include|version)\b", real), (name, line, real)
        else:
            assert text == real, (name, line)
            checked += 1
        current[1] += 1
    return checked


# --- assembly -------------------------------------------------------------------


def test_version_and_defines_come_first(tmp_path: Path) -> None:
    b = ShaderBuilder([], version="330 core")
    b.define("USE_FRESNEL")
    b.define("SAMPLES", 16)
    b.define("FLAG", True)
    b.define("SAMPLES", 32)  # redefining replaces
    b.add_source("void main() {}\n", "<main>")
    program = b.build()
    lines = program.code.split("\n")
    assert lines[:5] == [
        "#version 330 core",
        "#define USE_FRESNEL",
        "#define SAMPLES 32",
        "#define FLAG 1",
        f"#line {LINE_STRIDE + 1} 1",
    ]
    assert lines[5] == "void main() {}"
    assert program.sources == [PREAMBLE, "<main>"]
    assert program.locate(1, LINE_STRIDE + 1) == ("<main>", 1)
    with pytest.raises(ValueError):
        b.define("not a name", 1)


def test_plain_line_numbering(tmp_path: Path) -> None:
    write(tmp_path / "inc.glsl", "float f();\n")
    main = write(tmp_path / "main.frag", 'uniform float a;\n#include "inc.glsl"\nvoid main() {}\n')
    b = ShaderBuilder([], line_stride=0)
    b.add_file(main)
    program = b.build()
    inc = os.path.normpath(tmp_path / "inc.glsl")
    assert program.code.split("\n")[1:] == [
        "#line 1 1",
        "uniform float a;",
        "#line 1 2",
        "float f();",
        "#line 3 1",
        "void main() {}",
        "",
    ]
    assert program.sources == [PREAMBLE, str(main), inc]
    assert check_line_mapping(program) == 3


def test_chunks_with_first_line_map_to_their_file(tmp_path: Path) -> None:
    # A material file whose shader section starts on line 4.
    brd = write(
        tmp_path / "m.brd",
        "analytic\n# c\n::begin shader\nfloat k = 1.0;\n\nvec3 f() { return vec3(k); }\n::end shader\n",
    )
    shader = "".join(brd.read_text().splitlines(keepends=True)[3:6])
    b = ShaderBuilder([])
    b.add_source("uniform float n;\n", "<uniforms>")
    b.add_source(shader, str(brd), first_line=4)
    b.add_source(shader, str(brd), first_line=4)  # same file again: same source number
    program = b.build()
    assert program.sources == [PREAMBLE, "<uniforms>", str(brd)]
    assert program.code.count(f"#line {2 * LINE_STRIDE + 4} 2") == 2
    assert check_line_mapping(program, {"<uniforms>": "uniform float n;\n"}) == 7


def test_version_lines_inside_chunks_are_blanked(tmp_path: Path) -> None:
    write(tmp_path / "lib.glsl", "#version 120\nfloat g();\n")
    main = write(tmp_path / "main.frag", '  #  version 330 core\n#include "lib.glsl"\nvoid main() {}\n')
    b = ShaderBuilder([])
    b.add_file(main)
    program = b.build()
    assert program.code.count("#version") == 1 and program.code.startswith("#version 330 core\n")
    assert body(program) == ["", "", "float g();", "void main() {}"]
    check_line_mapping(program)


def test_directives_pass_through(tmp_path: Path) -> None:
    text = dedent("""\
        #define A 1
        #ifdef A
        float a;
        #else
        float b;
        #endif
        #extension GL_ARB_foo : enable
        #pragma optimize(off)
        // #include "nope.glsl"
        """)
    b = ShaderBuilder([])
    b.add_source(text, "<text>")
    assert body(b.build()) == text.splitlines()


def test_include_inside_block_comment_is_ignored() -> None:
    text = '/* old:\n#include "missing.glsl"\n*/\nfloat a; /* x */\n#include "also-missing.glsl" // comment\n'
    b = ShaderBuilder([])
    b.add_source(text, "<text>")
    with pytest.raises(ShaderError) as info:
        b.build()
    assert (info.value.path, info.value.line) == ("<text>", 5)  # only the real one is looked up


def test_crlf_and_missing_final_newline(tmp_path: Path) -> None:
    (tmp_path / "inc.glsl").write_bytes(b"float a;\r\nfloat b;")
    b = ShaderBuilder([tmp_path])
    b.add_source('#include "inc.glsl"\r\nfloat c;', "<text>")
    program = b.build()
    assert "\r" not in program.code
    assert body(program) == ["float a;", "float b;", "float c;"]


# --- includes -------------------------------------------------------------------


def test_include_resolution_order(tmp_path: Path) -> None:
    write(tmp_path / "src" / "common.glsl", "// src/common\n")
    write(tmp_path / "first" / "common.glsl", "// first/common\n")
    write(tmp_path / "first" / "only_first.glsl", "// first/only_first\n")
    write(tmp_path / "second" / "only_first.glsl", "// second/only_first\n")
    write(tmp_path / "second" / "only_second.glsl", "// second/only_second\n")
    main = write(
        tmp_path / "src" / "main.frag",
        '#include "common.glsl"\n#include <only_first.glsl>\n#include "only_second.glsl"\n',
    )
    b = ShaderBuilder([tmp_path / "first", tmp_path / "second"])
    b.add_file(main)
    program = b.build()
    # the includer's own directory wins, then the include dirs in order
    assert body(program) == ["// src/common", "// first/only_first", "// second/only_second"]
    assert program.sources[2:] == [
        os.path.normpath(tmp_path / "src" / "common.glsl"),
        os.path.normpath(tmp_path / "first" / "only_first.glsl"),
        os.path.normpath(tmp_path / "second" / "only_second.glsl"),
    ]
    assert program.files == [
        main,
        tmp_path / "src" / "common.glsl",
        tmp_path / "first" / "only_first.glsl",
        tmp_path / "second" / "only_second.glsl",
    ]
    check_line_mapping(program)


def test_nested_includes_resolve_relative_to_their_own_file(tmp_path: Path) -> None:
    write(tmp_path / "lib" / "sub" / "leaf.glsl", "float leaf();\n")
    write(tmp_path / "lib" / "mid.glsl", '#include "sub/leaf.glsl"\nfloat mid();\n')
    brd = write(tmp_path / "materials" / "m.brd", "x\n")
    b = ShaderBuilder([tmp_path / "lib"])
    b.add_source('#include "mid.glsl"\nvec3 BRDF();\n', str(brd), first_line=7)
    assert body(b.build()) == ["float leaf();", "float mid();", "vec3 BRDF();"]


def test_chunk_includes_next_to_its_file(tmp_path: Path) -> None:
    write(tmp_path / "materials" / "helpers.glsl", "float helper();\n")
    b = ShaderBuilder([])
    b.add_source('#include "helpers.glsl"\n', str(tmp_path / "materials" / "m.brd"))
    assert body(b.build()) == ["float helper();"]


def test_each_file_is_included_once(tmp_path: Path) -> None:
    write(tmp_path / "lib" / "common.glsl", "const float PI = 3.14159265;\n")
    write(tmp_path / "lib" / "a.glsl", '#include "common.glsl"\nfloat a();\n')
    write(tmp_path / "lib" / "b.glsl", '#include "./common.glsl"\nfloat b();\n')
    main = write(
        tmp_path / "main.frag",
        '#include "a.glsl"\n#include "b.glsl"\n#include "./lib/common.glsl"\nvoid main() {}\n',
    )
    (tmp_path / "sub").mkdir()
    b = ShaderBuilder([tmp_path / "lib", tmp_path])
    b.add_file(main)
    b.add_file(tmp_path / "lib" / "common.glsl")  # a whole file already included: nothing
    b.add_file(main)  # and the main file a second time: nothing either
    program = b.build()
    assert body(program) == ["const float PI = 3.14159265;", "float a();", "", "float b();", "", "void main() {}"]
    check_line_mapping(program)
    assert b.build() == program  # building again gives the same program


def test_include_cycles_terminate(tmp_path: Path) -> None:
    write(tmp_path / "a.glsl", '#include "b.glsl"\nfloat a;\n')
    write(tmp_path / "b.glsl", '#include "a.glsl"\nfloat b;\n')
    write(tmp_path / "self.glsl", '#include "self.glsl"\nfloat s;\n')
    b = ShaderBuilder([tmp_path])
    b.add_source('#include "a.glsl"\n#include "self.glsl"\n', "<main>")
    program = b.build()
    assert body(program) == ["", "float b;", "float a;", "", "float s;"]
    check_line_mapping(program)


def make_chain(root: Path, length: int) -> None:
    for i in range(length):
        nxt = f'#include "c{i + 1}.glsl"\n' if i + 1 < length else ""
        write(root / f"c{i}.glsl", f"{nxt}float c{i};\n")


def test_include_depth_limit(tmp_path: Path) -> None:
    make_chain(tmp_path, 17)  # main -> c0 -> ... -> c16: 17 levels
    ok = ShaderBuilder([tmp_path], max_depth=17)
    ok.add_source('#include "c0.glsl"\n', "<main>")
    assert len(body(ok.build())) == 17

    b = ShaderBuilder([tmp_path])  # default max_depth=16
    b.add_source('#include "c0.glsl"\n', "<main>")
    with pytest.raises(ShaderError) as info:
        b.build()
    err = info.value
    assert err.path == os.path.normpath(tmp_path / "c15.glsl") and err.line == 1
    assert "deeper than 16" in err.message


def test_missing_include_names_includer_and_dirs(tmp_path: Path) -> None:
    write(tmp_path / "lib" / "ok.glsl", "float ok;\n")
    main = write(tmp_path / "src" / "main.frag", 'float a;\n\n#include "ok.glsl"\n#include "lighting/nope.glsl"\n')
    b = ShaderBuilder([tmp_path / "lib", tmp_path / "more"])
    b.add_file(main)
    with pytest.raises(ShaderError) as info:
        b.build()
    err = info.value
    assert (err.path, err.line) == (str(main), 4)
    assert "cannot find include 'lighting/nope.glsl'" in err.message
    for d in ("src", "lib", "more"):
        assert os.path.normpath(tmp_path / d) in err.message
    assert str(err) == f"{main}:4: {err.message}" and "\n" not in str(err)


def test_missing_include_in_included_file(tmp_path: Path) -> None:
    write(tmp_path / "lib" / "a.glsl", "\n\n#include <gone.glsl>\n")
    b = ShaderBuilder([tmp_path / "lib"])
    b.add_source('#include "a.glsl"\n', "<main>")
    with pytest.raises(ShaderError) as info:
        b.build()
    assert (info.value.path, info.value.line) == (os.path.normpath(tmp_path / "lib" / "a.glsl"), 3)


@pytest.mark.parametrize(
    "line", ["#include common.glsl", '#include "unterminated.glsl', "#include", '#include "a.glsl" junk']
)
def test_malformed_include(line: str) -> None:
    b = ShaderBuilder([])
    b.add_source(f"float a;\n{line}\n", "<main>", first_line=10)
    with pytest.raises(ShaderError) as info:
        b.build()
    assert (info.value.path, info.value.line) == ("<main>", 11)
    assert "malformed #include" in info.value.message


def test_missing_file(tmp_path: Path) -> None:
    b = ShaderBuilder([])
    b.add_file(tmp_path / "nope.frag")
    with pytest.raises(ShaderError) as info:
        b.build()
    assert info.value.path == str(tmp_path / "nope.frag") and info.value.line is None
    assert "cannot read shader file" in info.value.message


def test_line_mapping_of_a_program_tree(tmp_path: Path) -> None:
    """Every emitted line maps back to the identical line of its real file."""
    lib = tmp_path / "shaders" / "lib"
    write(lib / "constants.glsl", dedent("""\
        #version 330 core
        const float PI = 3.14159265358979323846;

        /* block
           comment */
        """))
    write(lib / "fresnel.glsl", dedent("""\
        // Schlick
        #include "constants.glsl"

        float schlick(float f0, float u)
        {
            return f0 + (1-f0) * pow(1-u, 5);
        }
        """))
    write(lib / "brdf_common.glsl", dedent("""\
        #include "fresnel.glsl"
        #include "constants.glsl"
        float sqr(float x) { return x*x; }
        """))
    view = tmp_path / "shaders" / "views" / "sphere.frag"
    view.parent.mkdir(parents=True)
    view.write_bytes(dedent("""\
        #version 330 core
        #include "brdf_common.glsl"
        in vec3 normal;
        out vec4 color;

        #include "fresnel.glsl"
        void main()
        {
            color = vec4(BRDF(normal, normal, normal, normal, normal), 1);
        }
        """).replace("\n", "\r\n").encode())
    brd = write(tmp_path / "materials" / "m.brd", dedent("""\
        analytic
        ::begin shader
        #include "brdf_common.glsl"
        vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
        {
            return vec3(sqr(schlick(.04, dot(N, V))));
        }
        ::end shader
        """))
    shader = "".join(brd.read_text().splitlines(keepends=True)[2:7])
    uniforms = write(tmp_path / "uniforms.glsl", "uniform float n;\n")
    for stride in (LINE_STRIDE, 0):
        b = ShaderBuilder([lib], line_stride=stride)
        b.define("MAX_LIGHTS", 4)
        b.add_source(uniforms.read_text(), str(uniforms))
        b.add_source(shader, str(brd), first_line=3)
        b.add_file(view)
        program = b.build()
        assert check_line_mapping(program) > 15
        if stride == 0:
            assert all(int(m[1]) < 20 for m in LINE_RE.finditer(program.code))


def test_too_long_for_stride() -> None:
    b = ShaderBuilder([], line_stride=10)
    b.add_source("a\n" * 10, "<long>")
    with pytest.raises(ShaderError, match="too long"):
        b.build()


# --- compile logs ---------------------------------------------------------------

SOURCES = [PREAMBLE, "materials/thin_film.brd", "shaders/lib/fresnel.glsl"]


def test_map_log_mesa() -> None:
    log = (
        "0:12(3): error: `foo' undeclared\n"
        f"0:{2 * LINE_STRIDE + 7}(14): error: no matching function for call to `f(vec2)'; candidates are:\n"
        f"2:{2 * LINE_STRIDE + 9}(1): preprocessor error: Redefinition of macro X\n"
        "1:5(2): warning: `x' used uninitialized\n"
        "some other line"
    )
    assert map_log(log, SOURCES) == [
        "<preamble>:12:3: error: `foo' undeclared",
        "shaders/lib/fresnel.glsl:7:14: error: no matching function for call to `f(vec2)'; candidates are:",
        "shaders/lib/fresnel.glsl:9:1: preprocessor error: Redefinition of macro X",
        "materials/thin_film.brd:5:2: warning: `x' used uninitialized",
        "some other line",
    ]


def test_map_log_nvidia() -> None:
    log = (
        f'0({LINE_STRIDE + 42}) : error C1008: undefined variable "foo"\n'
        "2(8) : warning C7011: implicit cast from \"int\" to \"float\"\n"
    )
    assert map_log(log, SOURCES) == [
        'materials/thin_film.brd:42: error C1008: undefined variable "foo"',
        'shaders/lib/fresnel.glsl:8: warning C7011: implicit cast from "int" to "float"',
    ]
    assert compile_error_message(log, SOURCES) == 'materials/thin_film.brd:42: undefined variable "foo"'


def test_map_log_amd_intel() -> None:
    log = (
        f"ERROR: 0:{2 * LINE_STRIDE + 3}: 'foo' : undeclared identifier \n"
        "WARNING: 1:4: extension not supported\n"
        "ERROR: 1 compilation errors.  No code generated.\n"
    )
    assert map_log(log, SOURCES) == [
        "shaders/lib/fresnel.glsl:3: error: 'foo' : undeclared identifier",
        "materials/thin_film.brd:4: warning: extension not supported",
        "ERROR: 1 compilation errors.  No code generated.",
    ]
    assert compile_error_message(log, SOURCES) == "shaders/lib/fresnel.glsl:3: 'foo' : undeclared identifier"


def test_map_log_unknown_source_passes_through() -> None:
    assert map_log("7:3(1): error: x\n0:900000(1): error: y", SOURCES) == ["7:3(1): error: x", "0:900000(1): error: y"]
    assert compile_error_message("7:3(1): error: x", SOURCES) == "<source 7>:3: x"


def test_compile_error_message_picks_the_first_error() -> None:
    log = (
        "GLSL Compiler failed\n\nfragment_shader\n===============\n"
        "1:2(1): warning: unused\n"
        f"0:{LINE_STRIDE + 11}(23): error: `foo' undeclared\n"
        f"0:{LINE_STRIDE + 11}(18): error: cannot construct `vec4' from a non-numeric data type\n"
    )
    assert compile_error_message(log, SOURCES) == "materials/thin_film.brd:11: `foo' undeclared"
    err = compile_error(log, SOURCES)
    assert (err.path, err.line, err.message) == ("materials/thin_film.brd", 11, "`foo' undeclared")
    assert Program("", SOURCES).error_message(log) == compile_error_message(log, SOURCES)


def test_compile_error_message_without_locations() -> None:
    log = "GLSL Compiler failed\nsomething bad: error 7\n"
    assert compile_error_message(log, SOURCES) == "<shader>: something bad: error 7"
    assert compile_error_message("", SOURCES) == "<shader>: compilation failed (empty log)"


def test_shader_error_is_one_line_and_pickles() -> None:
    err = ShaderError("a.glsl", 3, "bad\nthing")
    assert str(err) == "a.glsl:3: bad thing"
    assert str(ShaderError("a.glsl", None, "x")) == "a.glsl: x"
    copy = pickle.loads(pickle.dumps(err))
    assert (copy.path, copy.line, copy.message) == ("a.glsl", 3, "bad\nthing")


# --- with a real driver ---------------------------------------------------------

VERTEX = "#version 330 core\nin vec2 position;\nvoid main() { gl_Position = vec4(position, 0.0, 1.0); }\n"


@pytest.mark.gl
def test_gl_compile_error_maps_to_included_file(tmp_path: Path, gl_renderer) -> None:
    # The session's context (tests/conftest.py): under CI=true a missing EGL fails, never skips.
    import moderngl

    ctx = gl_renderer.ctx
    try:
        lib = tmp_path / "lib"
        write(lib / "util.glsl", "float twice(float x)\n{\n    return 2.0 * x;\n}\n")
        # A semantic error: Mesa reports it with source string 0, whatever #line said.
        write(lib / "broken.glsl", dedent("""\
            #include "util.glsl"

            float broken(float x)
            {
                return twice(x) * undefined_thing;
            }
            """))
        main = write(tmp_path / "main.frag", dedent("""\
            #version 330 core
            out vec4 color;
            #include "broken.glsl"

            void main()
            {
                color = vec4(broken(0.5));
            }
            """))
        b = ShaderBuilder([lib])
        b.add_file(main)
        program = b.build()
        # and a syntax error, which Mesa reports with the real source number
        b2 = ShaderBuilder([lib])
        b2.add_source("float ok;\nfloat oops = 1.0 + ;\n", str(main), first_line=20)
        b2.add_source('#include "util.glsl"\nvoid main() {}\n', "<main>")
        program2 = b2.build()

        messages = []
        for prog in (program, program2):
            with pytest.raises(moderngl.Error) as info:
                ctx.program(vertex_shader=VERTEX, fragment_shader=prog.code)
            messages.append(compile_error_message(str(info.value), prog.sources))
        assert messages[0].startswith(f"{os.path.normpath(lib / 'broken.glsl')}:5: "), messages[0]
        assert "undefined_thing" in messages[0]
        assert messages[1].startswith(f"{main}:21: syntax error"), messages[1]
    finally:
        pass  # the session owns the context
