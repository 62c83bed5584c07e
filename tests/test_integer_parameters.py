"""Integer parameters (``int`` in our .brd files): one rounding rule from values to physics.

``method``, ``N``, ``s``, ``layers`` and ``N_k`` may arrive as any float (a typed field, a JSON or
.bparam file, a script, a caller's dict). The GL host (uniforms and the ``# specialise:`` constant) and
the numpy twins must turn ``2.5`` into the same integer, :func:`explorer.materials.brd.round_integer`'s 3, where
they used to disagree (Python's ``round`` halves to even: 0.5 compiled method 0 while numpy ran method 1).
Values here bypass :meth:`~explorer.materials.brd.Material.resolve` (which rounds already), to test the host and
the twins themselves; the tolerances are the named ones of the GL-vs-numpy tests.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import BRAGG_MATERIAL, BRDF_DATA, REPO_ROOT
from explorer.app.parameter_files import widget_kind
from explorer.materials.brd import load_material, round_integer
from explorer.gpu.programs import specialisation
from explorer.materials.models import model_for
from explorer.views.render import render_numpy
from test_gl_views import SWEEP_SIZES
from twins import GL_ATOL, Twins, assert_twins_equal, render_both

SHADERS = REPO_ROOT / "shaders"
#: Halves, and values either side of one.
FRACTIONS = (0.5, 1.5, 2.5, 3.5, 2.4999, 2.5001)
#: The BRDF views' image (small: the spectral reference and the stack cost ~1 s per 256² on llvmpipe).
BRDF_SIZE = (16, 12)

#: (material, base values, parameter, its fractional values, views).
SWEEPS = {
    "mirror method": ("bragg_mirror.brd", {"N": 8}, "method", FRACTIONS, ("gradient", "sphere")),
    "mirror N": ("bragg_mirror.brd", {"method": 4}, "N", (1.5, 2.4999, 2.5001, 10.5), ("gradient",)),
    "mirror s": ("bragg_mirror.brd", {"method": 2}, "s", (1.5, 2.4999, 2.5, 2.5001, 4.5), ("gradient",)),
    "film method": ("thin_film.brd", {}, "method", FRACTIONS + (4.5,), ("gradient", "sphere")),
    "layer method": ("bragg_layer.brd", {"N": 6, "rho_d": 0.3}, "method", FRACTIONS, ("lit",)),
    "layer N": ("bragg_layer.brd", {"method": 4}, "N", (2.4999, 2.5001), ("lit",)),
    "layer s": ("bragg_layer.brd", {"method": 4}, "s", (1.5, 2.5), ("lit",)),
    "stack layers": ("bragg_stack.brd", {"rho_d": 0.3}, "layers", (1.5, 2.4999, 2.5001), ("lit",)),
    "stack N_k": ("bragg_stack.brd", {"layers": 2}, "N_1", (1.5, 2.4999, 2.5001), ("lit",)),
    "stack N_2": ("bragg_stack.brd", {"layers": 2}, "N_2", (9.5,), ("lit",)),
}


def sweep_cases():
    for name, (material, _, parameter, fractions, views) in SWEEPS.items():
        for value in fractions:
            for view in views:
                yield pytest.param(name, value, view, id=f"{name}={value}-{view}")


def render_pair(renderer, material, values, view):
    """GL and numpy images of ``material`` at ``values`` (not resolved: fractional ints stay fractional)."""
    return render_both(renderer, material, values, view, SWEEP_SIZES.get(view, BRDF_SIZE))


@pytest.mark.gl
@pytest.mark.parametrize("name, value, view", list(sweep_cases()))
def test_gl_equals_numpy_at_fractional_integer_values(gl_renderer, name, value, view):
    material_file, base, parameter, _, _ = SWEEPS[name]
    material = load_material(SHADERS / material_file)
    values = {**material.resolve(base), parameter: value}
    twins = render_pair(gl_renderer, material, values, view)
    assert_twins_equal(twins, f"{material_file} {parameter}={value} {view}")
    gl = twins.gl
    # Both are the image of the rounded integer (halves up), not of any other rounding.
    rounded = {**values, parameter: float(round_integer(value))}
    gl_rounded, _, _ = render_pair(gl_renderer, material, rounded, view)
    np.testing.assert_allclose(gl, gl_rounded, rtol=0, atol=GL_ATOL * 1e-3)
    model = model_for(material, values)
    if "method" in material.specialised:
        (constant,) = specialisation(material, values)
        assert constant == ("method", model.method) and model.method == round_integer(values["method"])


@pytest.mark.gl
@pytest.mark.parametrize("material_file, parameter, value, other", [
    ("bragg_mirror.brd", "method", 0.5, 0.0),
    ("bragg_mirror.brd", "method", 2.5, 2.0),
    ("thin_film.brd", "method", 4.5, 4.0),  # naive RGB against Gaussian fits (methods 0 and 1 now agree to 6e-3)
    ("bragg_stack.brd", "layers", 1.5, 1.0),
])
def test_halves_round_up_not_to_even(gl_renderer, material_file, parameter, value, other):
    """Non-vacuous: the halves above do change the image, so banker's rounding would fail the sweep."""
    material = load_material(SHADERS / material_file)
    base = {"rho_d": 0.3} if material_file == "bragg_stack.brd" else {}
    view = "lit" if material_file == "bragg_stack.brd" else "gradient"
    values = {**material.resolve(base), parameter: value}
    image, _, compared = render_pair(gl_renderer, material, values, view)
    below, _, _ = render_pair(gl_renderer, material, {**values, parameter: other}, view)
    assert np.abs(image - below).max() > 10 * GL_ATOL


def test_models_and_specialisation_share_the_rule():
    """Without GL: the specialised constant and every numpy model's integers for the sweep's values."""
    mirror = load_material(BRAGG_MATERIAL)
    stack = load_material(SHADERS / "bragg_stack.brd")
    film = load_material(SHADERS / "thin_film.brd")
    for value in FRACTIONS + (0.49999999999999994, 4.5):
        expected = round_integer(value)
        values = {**mirror.resolve(), "method": min(value, 4.0), "N": 1.0 + value, "s": 1.0 + value}
        model = model_for(mirror, values)
        assert specialisation(mirror, values) == (("method", round_integer(min(value, 4.0))),)
        assert model.method == round_integer(min(value, 4.0))
        assert model.s == model.mirror.N == int(np.floor(1.0 + value + 0.5))  # (1 + 0.49999999999999994 is 1.5)
        film_values = {**film.resolve(), "method": value}
        assert specialisation(film, film_values) == (("method", expected),) and model_for(film, film_values).method == expected
        if value <= 2.0:
            stack_model = model_for(stack, {**stack.resolve(), "layers": 1.0 + value, "N_1": 5.0 + value})
            assert len(stack_model.stack.layers) == int(np.floor(1.0 + value + 0.5))
            assert stack_model.stack.layers[0].N == int(np.floor(5.0 + value + 0.5))


def test_resolve_rounds_what_the_cli_and_presets_pass():
    """``--set method=2.5`` and a preset's ``N = 10.5`` resolve to the integers the renderers use."""
    mirror = load_material(BRAGG_MATERIAL)
    values = mirror.resolve({"method": "2.5", "N": 10.5, "s": "2.4999"})
    assert (values["method"], values["N"], values["s"]) == (3.0, 11.0, 2.0)
    assert mirror.typed_values(values) is values


def test_resolved_values_are_typed_and_frozen():
    """resolve() returns the one typed set every consumer reads: ints exact, nothing changes it after."""
    import pickle

    from explorer.materials.brd import Values

    mirror = load_material(BRAGG_MATERIAL)
    values = mirror.resolve({"N": "10.5"})
    assert isinstance(values, Values) and values.integer("N") == 11 and values["N"] == 11.0
    with pytest.raises(TypeError, match="frozen"):
        values["N"] = 3.0
    with pytest.raises(TypeError, match="frozen"):
        values.update(N=3.0)
    assert pickle.loads(pickle.dumps(values)) == values and {**values, "N": 4.0}["N"] == 4.0
    typed = mirror.typed_values({**values, "N": 2.5})  # a caller's mapping: ints rounded, not range-checked
    assert isinstance(typed, Values) and typed["N"] == 3.0


@pytest.mark.gl
def test_cli_set_and_engines_agree_on_a_half(gl_renderer, tmp_path):
    """``render --set method=0.5`` (GL, specialised) and ``--engine numpy``: both method 1, to GL_ATOL."""
    from conftest import run_cli_process

    images = {}
    for engine in ("gl", "numpy"):
        out = tmp_path / f"{engine}.npy"
        run = run_cli_process("render", BRAGG_MATERIAL, "--view", "gradient", "--size", "48x1", "--set", "method=0.5",
                  "--set", "N=8.5", "--engine", engine, "--out", out)
        assert run.returncode == 0, run.stderr
        images[engine] = np.load(out)
    material = load_material(BRAGG_MATERIAL)
    method_1 = render_numpy(model_for(material, material.resolve({"method": 1, "N": 9})), "gradient", 48, 1)
    assert_twins_equal(Twins.of(images["gl"], images["numpy"], "gradient"), "CLI gl and numpy at method=0.5")
    assert np.abs(images["numpy"] - method_1).max() <= 1e-6


# -- which parameters are integers, and the app's slider for each -----------------------------------

#: Every integer parameter of the shipped materials: declared ``int``.
SHIPPED_INTEGERS = {
    "bragg_mirror.brd": {"N", "method", "s", "medium_n1", "medium_n2", "medium_nh"},
    "bragg_layer.brd": {"N", "method", "s", "medium_n1", "medium_n2", "medium_nh"},
    "bragg_stack.brd": {"layers", "medium_nh", "N_1", "N_2", "N_3", *(f"medium_{n}_{k}" for n in ("n1", "n2") for k in (1, 2, 3))},
    "thin_film.brd": {"method"},
    "layered_lobes.brd": {"layers"},
    "ggx_schlick.brd": set(),
    "schlick_fresnel.brd": set(),
}


def test_every_shipped_material_is_listed():
    assert {p.name for p in SHADERS.glob("*.brd")} == set(SHIPPED_INTEGERS)


@pytest.mark.parametrize("material_file", list(SHIPPED_INTEGERS))
def test_shipped_integers_are_declared_int_and_get_integer_sliders(material_file):
    material = load_material(SHADERS / material_file)
    kinds = {p.name: widget_kind(p) for p in material.parameters}
    assert {name for name, kind in kinds.items() if kind == "int"} == SHIPPED_INTEGERS[material_file]
    for p in material.parameters:
        assert kinds[p.name] == p.type  # float -> float slider, bool -> checkbox, color -> colour editor
        if p.type == "int":
            assert p.glsl_type == "float" and float(p.default).is_integer()
    # Every preset's value of an integer is an integer (presets are checked against these declarations).
    from explorer.materials.presets import PresetError, presets_for

    try:
        presets = presets_for(SHADERS / material_file).presets
    except PresetError:
        presets = {}
    for preset in presets.values():
        for name, value in preset.values.items():
            if name in SHIPPED_INTEGERS[material_file]:
                assert float(value).is_integer(), (preset.name, name, value)


DISNEY_STYLE = """analytic
::begin parameters
color baseColor .82 .67 .16
float metallic 0 1 0
float subsurface 0 1 0
float sheen 0 1 0
float kappa3 0 10 0
float n 1 1000 100
bool flag 1
::end parameters
::begin shader
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return baseColor; }
::end shader
"""


def test_brdf_explorer_floats_with_whole_number_ranges_get_float_sliders(tmp_path):
    """Disney's metallic 0 1 0, a kappa3 0 10 0, Blinn-Phong's n 1 1000 100: float sliders, not 0/1 integers."""
    path = tmp_path / "disney.brdf"
    path.write_text(DISNEY_STYLE)
    kinds = {p.name: widget_kind(p) for p in load_material(path).parameters}
    assert kinds == {"baseColor": "color", "metallic": "float", "subsurface": "float", "sheen": "float",
                     "kappa3": "float", "n": "float", "flag": "bool"}
    for name in ("lambert.brdf", "blinn_phong.brdf", "ashikhmin_shirley.brdf", "app_all_kinds.brdf"):
        assert all(widget_kind(p) != "int" for p in load_material(BRDF_DATA / name).parameters), name


def test_cli_reports_a_bad_int_declaration_in_one_line(tmp_path):
    """``info`` on a .brd whose int has a fractional default: one line naming file:line, non-zero exit."""
    from conftest import one_line_error, run_cli

    path = tmp_path / "bad_int.brd"
    path.write_text("analytic\n::begin parameters\nfloat k 0 1 .5\nint N 1 1000 20.5\n::end parameters\n"
                    "::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(k); }\n::end shader\n")
    line = one_line_error(run_cli("info", path))
    assert line.endswith(f"{path}:4: int 'N': default '20.5' is not an integer"), line
