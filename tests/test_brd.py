"""Tests for explorer.materials.brd, the parser of BRDF Explorer style material files."""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import numpy as np
import pytest

from explorer.materials.brd import (
    Material,
    MaterialError,
    Parameter,
    UnknownParameterError,
    load_material,
    parse_assignment,
    parse_material,
    round_integer,
)

DATA = Path(__file__).parent / "data" / "brdf"
GOOD = ["lambert", "blinn_phong", "colored_lambert", "ashikhmin_shirley"]

SHADER = """::begin shader
vec3 BRDF( vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y )
{
    return vec3(1);
}
::end shader
"""


def material(body: str, shader: str = SHADER) -> Material:
    """Parse `body` (header and parameters) followed by a trivial shader."""
    return parse_material(body + shader, "test.brd")


def raises(text: str) -> MaterialError:
    with pytest.raises(MaterialError) as info:
        parse_material(text, "test.brd")
    return info.value


# --- the test materials -------------------------------------------------------


@pytest.mark.parametrize("stem", GOOD)
def test_good_materials_load_cleanly(stem: str) -> None:
    path = DATA / f"{stem}.brdf"
    m = load_material(path)
    assert m.path == str(path)
    assert m.warnings == []
    assert m.model == stem
    assert "vec3 BRDF( vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y )" in m.shader
    # shader_line points at the shader text's first line, and the text is verbatim
    lines = path.read_text().splitlines()
    assert lines[m.shader_line - 2].strip() == "::begin shader"
    shader_lines = m.shader.splitlines()
    assert shader_lines == lines[m.shader_line - 1 : m.shader_line - 1 + len(shader_lines)]
    assert lines[m.shader_line - 1 + len(shader_lines)].strip() == "::end shader"


def test_lambert() -> None:
    m = load_material(DATA / "lambert.brdf")
    assert m.parameters == [Parameter("reflectance", "float", 0.0, 1.0, 0.8, 10)]
    assert m.parameter("reflectance").default == 0.8
    assert m.uniform_declarations() == "uniform float reflectance;\n"


def test_blinn_phong() -> None:
    m = load_material(DATA / "blinn_phong.brdf")
    n, divide = m.parameters
    assert (n.name, n.type, n.min, n.max, n.default) == ("n", "float", 1.0, 1000.0, 100.0)
    assert not n.is_integer()  # whole-number range and default, but declared float
    assert (divide.name, divide.type, divide.min, divide.max, divide.default) == (
        "divide_by_NdotL",
        "bool",
        None,
        None,
        True,
    )
    assert not divide.is_integer()
    assert m.uniform_declarations() == "uniform float n;\nuniform bool divide_by_NdotL;\n"


def test_colored_lambert() -> None:
    m = load_material(DATA / "colored_lambert.brdf")
    (albedo,) = m.parameters
    assert albedo.type == "color" and albedo.glsl_type == "vec3"
    assert albedo.default == (0.82, 0.67, 0.16)
    assert (albedo.min, albedo.max) == (0.0, 1.0)  # a colour without a declared range: COLOR_RANGE
    assert m.uniform_declarations() == "uniform vec3 albedo;\n"


def test_ashikhmin_shirley_is_anisotropic() -> None:
    m = load_material(DATA / "ashikhmin_shirley.brdf")
    assert [p.name for p in m.parameters] == ["Rs", "Rd", "nu", "nv"]
    assert "dot(H,X)" in m.shader and "dot(H,Y)" in m.shader


BAD = [
    ("bad_kind_measured", 3, "unsupported material kind 'measured'"),
    ("bad_missing_header", 2, "missing 'analytic' header"),
    ("bad_unterminated", 6, "section 'shader' is not terminated"),
    ("bad_unknown_type", 5, "unknown parameter type 'int'"),
    ("bad_field_count", 4, "has 4 fields (float NAME MIN MAX DEFAULT), got 3"),
    ("bad_not_a_number", 4, "max 'one' is not a number"),
    ("bad_min_gt_max", 4, "min 1 is greater than max 0"),
    ("bad_default_range", 5, "default 1.5 is outside [0, 1]"),
    ("bad_bool_default", 4, "default must be 0 or 1, got '2'"),
    ("bad_duplicate", 6, "duplicate parameter 'n' (first defined on line 4)"),
    ("bad_keyword_name", 4, "'sample' is a GLSL keyword"),
    ("bad_identifier", 4, "'2tone' is not a valid GLSL identifier"),
    ("bad_no_shader", None, "no shader section"),
    ("bad_mismatched_end", 5, "'::end shader' does not close section 'parameters' opened on line 3"),
    ("bad_nested", 5, "sections cannot nest"),
]


@pytest.mark.parametrize("stem, line, fragment", BAD, ids=[b[0] for b in BAD])
def test_malformed_files(stem: str, line: int | None, fragment: str) -> None:
    path = DATA / f"{stem}.brdf"
    with pytest.raises(MaterialError) as info:
        load_material(path)
    err = info.value
    assert err.path == str(path)
    assert err.line == line
    assert fragment in err.message
    where = f"{path}:{line}" if line is not None else str(path)
    assert str(err) == f"{where}: {err.message}"
    assert "\n" not in str(err)


# --- format details -------------------------------------------------------------


def test_header_may_follow_comments_and_carry_words() -> None:
    m = material("\n# a comment first\n\n   analytic   extra words\n")
    assert m.warnings == ["test.brd:4: ignoring text after 'analytic': 'extra words'"]


def test_other_kinds_are_rejected() -> None:
    assert raises("bparam lambert.brdf\n" + SHADER).line == 1
    assert "parameter file" in raises("bparam lambert.brdf\n" + SHADER).message
    assert "only 'analytic'" in raises("# c\nmeasured\n" + SHADER).message
    assert raises("Analytic\n" + SHADER).line == 1  # case matters, as in BRDF Explorer
    empty = raises("\n# only a comment\n")
    assert empty.line is None and "missing 'analytic' header" in empty.message


def test_numbers_in_brdf_explorer_style() -> None:
    m = material(
        "analytic\n::begin parameters\n"
        "float a .5 1e3 +1.\nfloat b -2. 1E-3 -1e-1\ncolor c .1 1 0\n"
        "::end parameters\n"
    )
    a, b, c = m.parameters
    assert (a.min, a.max, a.default) == (0.5, 1000.0, 1.0)
    assert (b.min, b.max, b.default) == (-2.0, 0.001, -0.1)
    assert c.default == (0.1, 1.0, 0.0)
    assert a.is_integer() is False  # min .5


@pytest.mark.parametrize("token", ["nan", "inf", "1_0", "0x1", "1,5", "one", "1.2.3", "."])
def test_non_numbers_are_rejected(token: str) -> None:
    err = raises(f"analytic\n::begin parameters\nfloat k 0 2 {token}\n::end parameters\n{SHADER}")
    assert err.line == 3 and f"default {token!r} is not a number" in err.message


@pytest.mark.parametrize(
    "line, fragment",
    [
        ("bool flag true", "default must be 0 or 1"),
        ("bool flag", "has 2 fields"),
        ("bool flag 1 0", "has 2 fields"),
        ("color c 1 1", "has 4 or 6 fields (color NAME R G B [MIN MAX]), got 3"),
        ("color c 1 x 1", "green 'x' is not a number"),
        ("float k 0 1 .5 .6", "got 5"),
        ("float gl_k 0 1 .5", "reserved prefix 'gl_'"),
        ("float uniform 0 1 .5", "GLSL keyword"),
        ("float my-k 0 1 .5", "not a valid GLSL identifier"),
        ("vec3 k 0 0 0", "unknown parameter type 'vec3'"),
        ("float k 0 1 -0.5", "default -0.5 is outside [0, 1]"),
    ],
)
def test_parameter_errors(line: str, fragment: str) -> None:
    err = raises(f"analytic\n::begin parameters\nfloat ok 0 1 1\n{line}\n::end parameters\n{SHADER}")
    assert err.line == 4
    assert fragment in err.message


def test_min_equal_max_and_edge_defaults_are_fine() -> None:
    m = material("analytic\n::begin parameters\nfloat a 2 2 2\nfloat b 0 1 0\nfloat c 0 1 1\n::end parameters\n")
    assert [p.default for p in m.parameters] == [2.0, 0.0, 1.0]


def test_comments_and_blank_lines_inside_parameters() -> None:
    m = material(
        "analytic\n::begin parameters\n# a comment\n\n   float k 0 1 .5   # trailing comment\n"
        "\tbool  b\t1\n::end parameters\n"
    )
    assert [(p.name, p.line) for p in m.parameters] == [("k", 5), ("b", 6)]


def test_crlf_and_bom() -> None:
    text = (DATA / "blinn_phong.brdf").read_text()
    lf = parse_material(text, "x.brdf")
    crlf = parse_material("\ufeff" + text.replace("\n", "\r\n"), "x.brdf")
    assert crlf == lf
    assert "\r" not in crlf.shader


def test_unknown_sections_are_skipped_with_a_warning() -> None:
    m = material(
        "analytic\n::begin notes\nanything at all: float 1 2\n::end notes\n"
        "::begin isFunc\nvec3 sampleBRDF() {}\n::end isFunc\n"
    )
    assert m.parameters == []
    assert m.warnings[0] == "test.brd:2: skipping unknown section 'notes'"
    assert m.warnings[1].startswith("test.brd:5: skipping section 'isFunc'")
    assert "sampleBRDF" not in m.shader


def test_text_outside_sections_warns() -> None:
    m = material("analytic\nstray words\n")
    assert m.warnings == ["test.brd:2: ignoring text outside any section: 'stray words'"]


def test_section_marker_errors() -> None:
    assert raises("analytic\n::end parameters\n").line == 2
    assert "without a matching '::begin'" in raises("analytic\n::end parameters\n").message
    assert raises("analytic\n::begin\n").line == 2
    unterminated = raises("analytic\n::begin parameters\nfloat k 0 1 1\n")
    assert unterminated.line == 2 and "missing '::end parameters'" in unterminated.message


def test_second_shader_section_replaces_the_first() -> None:
    m = material("analytic\n::begin shader\nfloat old;\n::end shader\n")
    assert "old" not in m.shader and m.shader_line == 6
    assert m.warnings == ["test.brd:5: second shader section replaces the one on line 2"]


def test_model_comment() -> None:
    assert material("analytic\n").model is None
    assert material("# model: thin_film.bragg\nanalytic\n").model == "thin_film.bragg"
    m = material("analytic\n::begin parameters\n#model:lambert\n::end parameters\n")
    assert m.model == "lambert"
    after = parse_material("analytic\n" + SHADER + "#   Model :  late  \n")
    assert after.model == "late"
    twice = material("analytic\n# model: a\n# model: b\n")
    assert twice.model == "a" and "ignoring second model 'b'" in twice.warnings[0]
    bad = material("analytic\n# model: not a name\n")
    assert bad.model is None and bad.warnings


def test_shader_text_and_hash_lines() -> None:
    shader = (
        "::begin shader\n"
        "#define TWO 2.0\n"  # a directive: kept
        "# model: inside\n"  # BRDF Explorer drops '#' lines: blanked
        "\n"
        "#include \"lib/common.glsl\"\n"
        "# just a note\n"
        "   #  ifdef TWO\n"
        "vec3 BRDF( vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y ) { return vec3(TWO); }\n"
        "#endif\n"
        "::end shader\n"
    )
    m = parse_material("analytic\n" + shader, "s.brd")
    assert m.shader_line == 3
    assert m.shader.split("\n") == [
        "#define TWO 2.0",
        "",
        "",
        '#include "lib/common.glsl"',
        "",
        "   #  ifdef TWO",
        "vec3 BRDF( vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y ) { return vec3(TWO); }",
        "#endif",
        "",
    ]
    assert m.model is None
    assert m.warnings == ["s.brd:4: '# model:' inside the shader section is ignored"]


def test_empty_shader_section() -> None:
    m = parse_material("analytic\n::begin shader\n::end shader\n")
    assert m.shader == "" and m.shader_line == 3


def test_brdf_explorer_stock_style() -> None:
    """The shapes found in BRDF Explorer's own src/brdfs files."""
    text = (
        "analytic\n\n# Copyright line\n#\n\n# variables go here...\n"
        "# [type] [name] [min val] [max val] [default val]\n"
        "::begin parameters\n"
        "color baseColor .82 .67 .16\nfloat metallic 0 1 0\nfloat roughness 0.0001 .1 0.01\n"
        "bool _x 0\nbool show_thetaH 0\nfloat sigma 0.0 90 30\n"
        "::end parameters\n::begin shader\nconst float PI = 3.14159265358979323846;\n"
        "vec3 BRDF( vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y ) { return baseColor/PI; }\n"
        "::end shader\n\n\n"
    )
    m = parse_material(text, "disney.brdf")
    assert [p.type for p in m.parameters] == ["color", "float", "float", "bool", "bool", "float"]
    assert not any(p.is_integer() for p in m.parameters)  # metallic 0 1 0 and sigma 0 90 30 stay floats
    assert m.warnings == []


def test_double_underscore_warns() -> None:
    m = material("analytic\n::begin parameters\nfloat a__b 0 1 0\n::end parameters\n")
    assert m.parameters[0].name == "a__b"
    assert "reserves" in m.warnings[0]


# --- loading --------------------------------------------------------------------


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.brd"
    with pytest.raises(MaterialError) as info:
        load_material(path)
    assert info.value.path == str(path) and info.value.line is None
    assert str(info.value).startswith(f"{path}: cannot read material file")


def test_directory_is_unreadable(tmp_path: Path) -> None:
    with pytest.raises(MaterialError, match="cannot read"):
        load_material(tmp_path)


def test_latin1_file(tmp_path: Path) -> None:
    path = tmp_path / "old.brd"
    path.write_bytes(b"analytic\n# Caf\xe9 material\n" + SHADER.encode())
    m = load_material(path)
    assert m.warnings == [f"{path}:1: file is not UTF-8; read as Latin-1"]


def test_error_is_one_line_and_pickles() -> None:
    err = MaterialError("a.brd", 3, "two\nlines")
    assert str(err) == "a.brd:3: two lines"
    assert str(MaterialError("a.brd", None, "x")) == "a.brd: x"
    copy = pickle.loads(pickle.dumps(err))
    assert (copy.path, copy.line, copy.message) == ("a.brd", 3, "two\nlines")


# --- values ---------------------------------------------------------------------

MIXED = (
    "analytic\n::begin parameters\nfloat n 1 1000 100\nfloat rough 0 1 .5\n"
    "bool flag 1\ncolor tint .8 .6 .4\n::end parameters\n"
)


def test_resolve_defaults() -> None:
    m = material(MIXED)
    assert m.resolve() == {"n": 100.0, "rough": 0.5, "flag": True, "tint": (0.8, 0.6, 0.4)}
    assert list(m.resolve()) == ["n", "rough", "flag", "tint"]


def test_resolve_strings_as_from_the_cli() -> None:
    m = material(MIXED)
    values = m.resolve({"n": "250", "rough": "1e-3", "flag": "off", "tint": "0.1, 0.2,0.3"})
    assert values == {"n": 250.0, "rough": 0.001, "flag": False, "tint": (0.1, 0.2, 0.3)}
    assert m.resolve({"tint": ".5"})["tint"] == (0.5, 0.5, 0.5)
    assert m.parameter("tint").default == (0.8, 0.6, 0.4)  # defaults untouched


@pytest.mark.parametrize(
    "word, value",
    [(w, True) for w in ("1", "true", "YES", "On")] + [(w, False) for w in ("0", "False", "no", "off")],
)
def test_bool_words(word: str, value: bool) -> None:
    assert material(MIXED).resolve({"flag": word})["flag"] is value


def test_resolve_python_values() -> None:
    m = material(MIXED)
    values = m.resolve({"n": 3, "rough": 0.25, "flag": 0, "tint": np.array([1, 0, 0.5])})
    assert values == {"n": 3.0, "rough": 0.25, "flag": False, "tint": (1.0, 0.0, 0.5)}
    assert type(values["n"]) is float and type(values["tint"]) is tuple
    assert m.resolve({"tint": 0.25})["tint"] == (0.25, 0.25, 0.25)
    assert m.resolve({"n": np.int64(5), "flag": np.int64(1)}) == m.resolve({"n": 5.0, "flag": True})


@pytest.mark.parametrize(
    "name, value, fragment",
    [
        ("n", "5000", "parameter 'n': value 5000 is outside its range [1, 1000]"),
        ("rough", -0.1, "value -0.1 is outside its range [0, 1]"),
        ("rough", "nan", "'nan' is not a number"),
        ("rough", float("nan"), "outside its range"),
        ("rough", True, "expected a number"),
        ("flag", "maybe", "'maybe' is not a boolean"),
        ("flag", 2, "is not a boolean"),
        ("tint", "1,2", "is not a color"),
        ("tint", (1, 2), "needs 3 components"),
        ("tint", "1,x,2", "is not a color"),
    ],
)
def test_resolve_errors(name: str, value: object, fragment: str) -> None:
    with pytest.raises(MaterialError) as info:
        material(MIXED).resolve({name: value})
    assert fragment in info.value.message
    # The error names the line that declares the parameter (and its range).
    declared = material(MIXED).parameter(name).line
    assert info.value.line == declared
    assert str(info.value).startswith(f"test.brd:{declared}: parameter")


def test_unknown_parameter_lists_valid_names() -> None:
    m = material(MIXED)
    with pytest.raises(MaterialError) as info:
        m.resolve({"roughness": "0.5"})
    assert "unknown parameter 'roughness' (did you mean 'rough'?); valid names: n, rough, flag, tint" in str(info.value)
    with pytest.raises(KeyError):  # parameter() also behaves like a mapping lookup
        m.parameter("roughness")
    assert isinstance(info.value, UnknownParameterError)


def test_parse_assignment() -> None:
    assert parse_assignment("n=250") == ("n", "250")
    assert parse_assignment(" tint = 1,0,0 ") == ("tint", "1,0,0")
    assert parse_assignment("a=b=c") == ("a", "b=c")
    for bad in ("n", "=3", "n=", "n=  "):
        with pytest.raises(MaterialError) as info:
            parse_assignment(bad)
        assert str(info.value).startswith("--set: ")


def test_is_integer() -> None:
    m = material(
        "analytic\n::begin parameters\nfloat a 1 1000 100\nfloat b 0 1 .5\nint c 0 10 2\n"
        "int d -3 3 0\nbool e 1\ncolor f 1 1 1\n::end parameters\n"
    )
    assert [p.is_integer() for p in m.parameters] == [False, False, True, True, False, False]
    assert [p.type for p in m.parameters] == ["float", "float", "int", "int", "bool", "color"]


def test_int_parameter_is_a_float_uniform_holding_an_integer() -> None:
    m = material("analytic\n::begin parameters\nint N 1 1000 20\nint method 0 4 0\n::end parameters\n")
    N = m.parameter("N")
    assert (N.type, N.min, N.max, N.default, N.line) == ("int", 1.0, 1000.0, 20.0, 3)
    assert N.glsl_type == "float"
    assert m.uniform_declarations() == "uniform float N;\nuniform float method;\n"
    assert N.info() == {"name": "N", "type": "int", "min": 1.0, "max": 1000.0, "default": 20.0, "unit": "", "doc": ""}


@pytest.mark.parametrize(
    "value, expected",
    [(0.5, 1), (1.5, 2), (2.4999, 2), (2.5, 3), (2.5001, 3), (0.49999999999999994, 0), (3, 3), ("2.5", 3), ("7", 7)],
)
def test_int_values_round_halves_up(value, expected) -> None:
    """One rule, floor(x + 0.5) as GLSL computes it, not Python's round() (halves to even)."""
    m = material("analytic\n::begin parameters\nint method 0 8 0\n::end parameters\n")
    resolved = m.resolve({"method": value})["method"]
    assert resolved == float(expected) and isinstance(resolved, float)
    assert round_integer(float(value)) == expected
    assert m.typed_values({"method": float(value), "other": 0.5}) == {"method": float(expected), "other": 0.5}


def test_round_integer_is_not_bankers_rounding() -> None:
    halves = np.arange(-3, 1001) + 0.5
    assert [round_integer(x) for x in halves] == list(np.floor(halves + 0.5).astype(int))
    assert round_integer(0.5) == 1 and round(0.5) == 0  # the rule the GL host used to apply


@pytest.mark.parametrize(
    "line, fragment",
    [
        ("int N 1 1000 20.5", "int 'N': default '20.5' is not an integer"),
        ("int N 1.5 1000 20", "int 'N': min '1.5' is not an integer"),
        ("int N 1 1e3 20", None),  # 1e3 is an integer
        ("int N 1 1000 2000", "int 'N': default 2000 is outside [1, 1000]"),
        ("int N 10 1 5", "int 'N': min 10 is greater than max 1"),
        ("int N 1 1000", "an int parameter has 4 fields (int NAME MIN MAX DEFAULT), got 3"),
        ("int N 1 many 20", "int 'N': max 'many' is not a number"),
        ("int 2N 1 10 2", "'2N' is not a valid GLSL identifier"),
    ],
)
def test_bad_int_declarations_are_one_line_with_file_and_line(line: str, fragment: str | None) -> None:
    text = f"analytic\n::begin parameters\nfloat k 0 1 .5\n{line}\n::end parameters\n" + SHADER
    if fragment is None:
        assert parse_material(text, "m.brd").parameter("N").max == 1000.0
        return
    with pytest.raises(MaterialError) as info:
        parse_material(text, "m.brd")
    assert str(info.value) == f"m.brd:4: {info.value.message}" and "\n" not in str(info.value)
    assert fragment in info.value.message, info.value.message


def test_int_is_refused_in_brdf_explorer_files() -> None:
    """BRDF Explorer's own .brdf format has float, bool and color only: an int there is an error (file:line)."""
    text = "analytic\n::begin parameters\nint N 1 1000 20\n::end parameters\n" + SHADER
    assert parse_material(text, "ours.brd").parameter("N").type == "int"
    with pytest.raises(MaterialError) as info:
        parse_material(text, "theirs.BRDF")
    assert str(info.value).startswith("theirs.BRDF:3: unknown parameter type 'int' in BRDF Explorer's .brdf files")


def test_info_is_json_ready() -> None:
    info = material(MIXED).info()
    assert json.loads(json.dumps(info)) == {
        "parameters": [
            {"name": "n", "type": "float", "min": 1.0, "max": 1000.0, "default": 100.0, "unit": "", "doc": ""},
            {"name": "rough", "type": "float", "min": 0.0, "max": 1.0, "default": 0.5, "unit": "", "doc": ""},
            {"name": "flag", "type": "bool", "min": None, "max": None, "default": True, "unit": "", "doc": ""},
            {"name": "tint", "type": "color", "min": 0.0, "max": 1.0, "default": [0.8, 0.6, 0.4], "unit": "", "doc": ""},
        ]
    }


def test_uniform_declarations_order_and_empty() -> None:
    assert material(MIXED).uniform_declarations() == (
        "uniform float n;\nuniform float rough;\nuniform bool flag;\nuniform vec3 tint;\n"
    )
    assert material("analytic\n").uniform_declarations() == ""


SPECIALISED = """analytic
# specialise: method
::begin parameters
int method 0 4 0
float alpha 0 1 0.5
float count 0 4 0
::end parameters
::begin shader
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(alpha); }
::end shader
"""


def test_specialise_directive_lists_integer_parameters() -> None:
    assert parse_material(SPECIALISED, "s.brd").specialised == ("method",)
    assert parse_material(SPECIALISED.replace("# specialise: method\n", ""), "s.brd").specialised == ()


@pytest.mark.parametrize("name", ["alpha", "count", "missing"])  # count: whole numbers, but a float
def test_specialise_directive_rejects_non_integer_or_unknown_parameters(name: str) -> None:
    with pytest.raises(MaterialError) as info:
        parse_material(SPECIALISED.replace("specialise: method", f"specialise: {name}"), "s.brd")
    assert info.value.line == 2
    assert name in info.value.message
