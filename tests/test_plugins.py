"""
Materials as plugins: every shipped material's twin declares what it can do (explorer/materials/twins.py),
nothing else in ``explorer/`` names a built-in material, and a ``.brd`` with its twin ``.py`` beside it
loads from any folder (docs/plugins.md, docs/plugin_example/).
"""

from __future__ import annotations

import ast
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli
from twins import Twins, assert_twins_equal
from explorer.materials.brd import load_material
from explorer.materials.methods import Method
from explorer.materials.models import model_for
from explorer.materials.plugins import PluginError
from explorer.materials.twins import CAPABILITY_FIELDS, Capabilities, DesignModel, registry, supporting

@pytest.fixture(autouse=True)
def _plugins_unloaded_afterwards():
    """A plugin a test loads in this process leaves the registry with it (another test loads its own copy)."""
    from explorer.materials import plugins, twins as registered

    registry()
    before, loaded = dict(registered.TWINS), dict(plugins._LOADED)
    yield
    registered.TWINS.clear()
    registered.TWINS.update(before)
    plugins._LOADED.clear()
    plugins._LOADED.update(loaded)


SHIPPED = sorted((REPO_ROOT / "shaders").glob("*.brd"))
EXAMPLE = REPO_ROOT / "docs" / "plugin_example"
#: The built-in materials' names: their files' stems and their twins' names.
BUILTIN_NAMES = tuple(sorted({p.stem for p in SHIPPED} | {load_material(p).model for p in SHIPPED}))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_every_shipped_material_declares_every_capability(path):
    """Its twin class states each field itself (none inherited), and what it states holds."""
    material = load_material(path)
    cls = registry()[material.model]
    assert "capabilities" in vars(cls), f"{cls.__name__} inherits its capabilities"
    declared = cls.capabilities
    assert isinstance(declared, Capabilities)
    assert {f: getattr(declared, f) for f in CAPABILITY_FIELDS}.keys() == set(CAPABILITY_FIELDS)
    has_method = any(p.name == "method" and p.type == "int" for p in material.parameters)
    assert (declared.methods is not None) == has_method
    if declared.methods is not None:
        assert issubclass(declared.methods, Method)
        method = material.parameter("method")
        assert {int(m) for m in declared.methods} == set(range(int(method.min), int(method.max) + 1))
    model = model_for(material, material.resolve())
    assert declared.numpy and callable(model.brdf) and callable(model.reflectance)
    if declared.bragg_spectrum:
        assert {"n1", "n2", "Lambda", "delta", "N", "nh"} <= {p.name for p in material.parameters}
    if declared.dirac:
        assert model.mirror_only and callable(model.spectral_reflectance)
    if "mitsuba" in declared.exports and not declared.dirac:
        alphas, weights, cosine = model.sampling_lobes(np.array([0.3, 0.9]))
        assert len(alphas) == len(weights) >= 1 and np.all(np.asarray(cosine) >= 0.0)
    if declared.supports("position-free"):
        assert model.stack.layers
    if declared.design is not None:
        _assert_design_declared(material, declared.design)


def _assert_design_declared(material, declared) -> None:
    """A twin's design model: its parameters are the file's floats, and its coarse model agrees with its converged one."""
    from explorer.design import design_model

    parameters = {p.name: p for p in material.parameters}
    assert isinstance(declared, DesignModel) and declared.parameters
    assert all(name in parameters and parameters[name].type in ("float", "int") for name in declared.parameters)
    assert design_model(material.model).parameters == declared.parameters  # what design asks of the registry
    values = {name: float(material.resolve()[name]) for name in declared.parameters}
    cos_theta = np.cos(np.radians([0.0, 45.0]))
    coarse = declared.batch({k: np.array([v]) for k, v in values.items()}, cos_theta)
    converged = declared.converged(values, cos_theta, final=True)
    assert coarse.shape == (1, 2, 3) and converged.shape == (2, 3)
    np.testing.assert_allclose(coarse[0], converged, atol=0.02)  # the coarse model screens for the converged one
    if declared.scale_parameter is not None:
        spectra = declared.spectra({k: np.array([v]) for k, v in values.items()}, cos_theta, np.array([450.0, 550.0]), 0.01)
        assert spectra.shape == (1, 2, 2) and np.all((spectra >= 0.0) & (spectra <= 1.0))


def test_info_json_lists_each_materials_capabilities_from_the_registry(tmp_path):
    """``info --json`` carries the twin's declaration: a built-in's, and a plugin's loaded from another folder."""
    import json

    for path in SHIPPED + [_example(tmp_path)]:
        run = run_cli("info", path, "--json")
        assert run.returncode == 0, run.stderr
        listed = json.loads(run.stdout)["capabilities"]
        declared = registry()[load_material(path).model].capabilities
        assert set(listed) == set(CAPABILITY_FIELDS)
        assert listed["albedo"] == list(declared.albedo) and listed["exports"] == list(declared.exports)
        assert (listed["dirac"], listed["bragg_spectrum"], listed["numpy"], listed["design"]) == \
            (declared.dirac, declared.bragg_spectrum, declared.numpy, declared.design is not None)
        assert listed["methods"] == (None if declared.methods is None else [m.name for m in declared.methods])


def test_design_asks_the_registry_and_refuses_a_twin_without_a_design_model():
    from explorer import design

    assert design.designable() == supporting("design") and len(design.designable()) >= 3
    for name, cls in registry().items():
        if cls.capabilities.design is None:
            with pytest.raises(design.DesignError, match=f"model {name} cannot be designed"):
                design.design_model(name)
        else:
            assert design.design_model(name).name == name


def test_design_on_a_plugin_without_a_design_model_is_one_line(tmp_path):
    line = one_line_error(run_cli("design", _example(tmp_path), "--target", "0:0.5,0.3,0.2"))
    assert "model tinted_phong cannot be designed" in line


#: A plugin that declares design: a grey Schlick reflector whose forward model is its reflectance at ``f0``.
GREY_BRD = """analytic
# model: grey_schlick
::begin parameters
float f0 0.01 0.9 0.04  # 1: reflectance at normal incidence
::end parameters
::begin shader
vec3 reflectance(float cos_theta) { float m = clamp(1.0 - cos_theta, 0.0, 1.0); return vec3(f0 + (1.0 - f0) * pow(m, 5.0)); }
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return reflectance(clamp(dot(normalize(L + V), L), 0.0, 1.0)) / 3.14159265; }
::end shader
"""
GREY_PY = """import numpy as np
from explorer.plugins import Capabilities, DesignModel, twin


def grey(f0, cos_theta):
    m = np.clip(1.0 - np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)
    return np.repeat((f0 + (1.0 - f0) * m**5)[..., None], 3, axis=-1)


@twin
class GreySchlick:
    name = "grey_schlick"
    capabilities = Capabilities(methods=None, dirac=False, bragg_spectrum=False, numpy=True, albedo=("numpy", "gl"),
                                exports=(), design=DesignModel(
                                    parameters=("f0",),
                                    batch=lambda values, cos_theta, step=None, smooth=None: grey(
                                        np.asarray(values["f0"], dtype=np.float64)[:, None], cos_theta),
                                    converged=lambda values, cos_theta, final=True: grey(float(values["f0"]), cos_theta)))

    def __init__(self, values):
        self.f0 = float(values["f0"])

    def reflectance(self, cos_theta):
        return grey(self.f0, cos_theta)

    def brdf(self, L, V, N, X, Y):
        H = np.asarray(L) + np.asarray(V)
        H = H / np.linalg.norm(H, axis=-1, keepdims=True)
        return self.reflectance(np.clip(np.sum(H * L, axis=-1), 0.0, 1.0)) / np.pi

    def textures(self):
        return {}
"""


def test_a_plugin_declares_its_design_model_and_design_finds_its_structure(tmp_path):
    import json

    (tmp_path / "grey_schlick.brd").write_text(GREY_BRD)
    (tmp_path / "grey_schlick.py").write_text(GREY_PY)
    wanted = 0.3 + 0.7 * (1.0 - np.cos(np.radians(60.0))) ** 5  # f0 = 0.3 at 60 degrees
    run = run_cli("design", tmp_path / "grey_schlick.brd", "--target", f"60:{wanted},{wanted},{wanted}", "--json")
    assert run.returncode == 0, run.stderr
    result = json.loads(run.stdout)
    assert abs(result["set"]["f0"] - 0.3) < 1e-3 and result["median_delta_e2000"] < 0.01, result
    assert "design yes" in run_cli("info", tmp_path / "grey_schlick.brd").stdout


def test_a_design_model_names_only_its_parameters():
    with pytest.raises(ValueError, match="design names 'd'"):
        DesignModel(parameters=("f0",), paint_free=("d",), batch=len, converged=len)
    with pytest.raises(TypeError, match="needs spectra"):
        DesignModel(parameters=("d",), scale_parameter="d", batch=len, converged=len)
    with pytest.raises(TypeError, match="must be a DesignModel"):
        Capabilities(methods=None, dirac=False, bragg_spectrum=False, numpy=True, albedo=("numpy",), exports=(), design=True)


def test_capabilities_refuse_an_unknown_engine_or_export():
    with pytest.raises(ValueError, match="povray"):
        Capabilities(methods=None, dirac=False, bragg_spectrum=False, numpy=True, albedo=("numpy",), exports=("povray",),
                     design=False)
    with pytest.raises(TypeError):
        Capabilities(methods=None, dirac=False)  # every field, no default


#: Where a built-in name may stand as a string literal: its own plugin files, and the one default material.
PLUGIN_FILES = {"explorer/materials/models.py", "explorer/materials/thinfilm_model.py",
                "explorer/materials/lobes_model.py", "explorer/materials/lobes_presets.py"}
DEFAULT_FILE = "explorer/resources.py"
NAME_RE = re.compile(r"(?<![A-Za-z0-9_])(" + "|".join(map(re.escape, BUILTIN_NAMES)) + r")(?![A-Za-z0-9_])")


def _docstrings(tree) -> set[int]:
    ids = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            ids.add(id(node.value))  # module, class and function docstrings, attribute notes
    return ids


def builtin_name_literals(root: Path) -> dict[str, list[tuple[int, str]]]:
    """Every string literal (docstrings aside) under ``root/explorer`` that holds a built-in material's name."""
    found: dict[str, list[tuple[int, str]]] = {}
    for path in sorted((root / "explorer").rglob("*.py")):
        relative = path.relative_to(root).as_posix()
        tree = ast.parse(path.read_text(encoding="utf-8"))
        skip = _docstrings(tree)
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in skip \
                    and NAME_RE.search(node.value):
                found.setdefault(relative, []).append((node.lineno, node.value))
    return found


def test_no_builtin_material_name_outside_its_plugin_files():
    found = builtin_name_literals(REPO_ROOT)
    default = found.pop(DEFAULT_FILE, [])
    assert len(default) == 1, f"{DEFAULT_FILE}: one default material, found {default}"
    stray = {path: hits for path, hits in found.items() if path not in PLUGIN_FILES}  # study scripts included
    assert not stray, "built-in material names as string literals: " + "; ".join(
        f"{path}:{line} {text[:50]!r}" for path, hits in stray.items() for line, text in hits)


def test_the_scan_finds_a_planted_name(tmp_path):
    (tmp_path / "explorer").mkdir()
    (tmp_path / "explorer" / "x.py").write_text('"""Docstrings may say thin_film."""\nNAME = "bragg_stack"\n')
    assert builtin_name_literals(tmp_path) == {"explorer/x.py": [(2, "bragg_stack")]}


# ---- plugins from any folder ------------------------------------------------------------------------


def _example(tmp_path) -> Path:
    folder = tmp_path / "plugin"
    shutil.copytree(EXAMPLE, folder)
    return folder / "tinted_phong.brd"


def test_a_plugin_loads_from_any_folder_and_renders_in_numpy(tmp_path):
    from explorer.views.render import render_numpy

    material = load_material(_example(tmp_path))
    assert material.model == "tinted_phong" and "tinted_phong" in supporting("brdf")
    image = render_numpy(model_for(material, material.resolve()), "lit", 16, 16)
    assert np.isfinite(image).all() and image.max() > 0.0


@pytest.mark.parametrize("edit, line, message", [
    (("self.exponent = float(values[\"exponent\"])", "self.exponent = float(values[\"exponent\"]) +"), None, "SyntaxError"),
    (("exports=(\"brdf\", \"table\")", "exports=(\"brdf\", \"povray\")"), 17, "unknown engine or export 'povray'"),
    (("name = \"tinted_phong\"", "name = \"bragg_mirror\""), 12, "registered twice"),
    (("design=None", "design=True"), 17, "must be a DesignModel"),
    (("@twin\n", ""), None, "registers no twin"),
])
def test_a_broken_plugin_is_one_error_with_its_file_and_line(tmp_path, edit, line, message):
    path = _example(tmp_path)
    source = path.with_suffix(".py")
    source.write_text(source.read_text().replace(*edit))
    with pytest.raises(PluginError) as error:
        load_material(path)
    text = str(error.value)
    assert "\n" not in text and message in text and text.startswith(str(source.resolve()))
    if line is not None:
        assert error.value.line == line, text
    else:
        assert message == "registers no twin" or error.value.line is not None


def _cli(*args, cwd, module: str = "explorer") -> subprocess.CompletedProcess:
    """``python -m explorer ARGS`` from ``cwd`` (a folder outside the repository), the checkout on the path;
    ``module="explorer.cli.commands"``: the CLI without the checkout's set-up step (whose notes go to stderr)."""
    env = {**os.environ, "PYTHONWARNINGS": "ignore", "PYTHONPATH": str(REPO_ROOT)}
    return subprocess.run([sys.executable, "-m", module, *map(str, args)], cwd=cwd, capture_output=True, text=True,
                          timeout=600, env=env)


def test_the_broken_plugin_error_reaches_the_cli_as_one_line(tmp_path):
    path = _example(tmp_path)
    source = path.with_suffix(".py")
    source.write_text(source.read_text().replace("return {}", "return {}\n  oops"))
    line = one_line_error(_cli("info", path.name, cwd=path.parent, module="explorer.cli.commands"))
    assert f"{source.name}:" in line and "IndentationError" in line


@pytest.mark.gl
@pytest.mark.parametrize("name", ["ggx_schlick", "bragg_layer"])
def test_check_passes_a_builtin_material_in_every_view_it_supports(gl_renderer, name):
    """``check``'s comparisons are the harness's: a built-in twin is within the named tolerance in each view."""
    from explorer.gpu.twin_check import check_material
    from explorer.views.twin_check import CHECK_SIZES, check_views

    material = load_material(REPO_ROOT / "shaders" / f"{name}.brd")
    images = [v for v in CHECK_SIZES if v not in ("textured", "env", "albedo")]
    assert check_views(material) == tuple(images) + ("env", "albedo")  # no '# texture:' line
    results = check_material(gl_renderer, material, material.resolve({"method": 3} if name == "bragg_layer" else {}), images)
    assert [r.view for r in results] == images
    for result in results:
        assert result.passed and 0.0 < result.max_difference, result.message()


@pytest.mark.gl
@pytest.mark.parametrize("name, view", [("ggx_schlick", "env"), ("ggx_schlick", "albedo"), ("thin_film", "textured")])
def test_check_compares_the_env_textured_and_albedo_views(gl_renderer, name, view):
    """The env view (Monte Carlo against the twin's exact integral), the albedo and the textured view, each within its tolerance."""
    from explorer.gpu.twin_check import check_material
    from explorer.views.twin_check import CHECK_SIZES, ENV_PIXELS, check_views, tolerance_for

    material = load_material(REPO_ROOT / "shaders" / f"{name}.brd")
    assert view in check_views(material)
    (result,) = check_material(gl_renderer, material, material.resolve({}), [view])
    assert result.view == view and result.tolerance == tolerance_for(view)
    assert result.passed and 0.0 < result.max_difference, result.message()
    if view == "env":
        assert result.tolerance.standard_errors > 0.0 and CHECK_SIZES["env"][0] ** 2 > ENV_PIXELS


@pytest.mark.gl
def test_check_fails_a_plugin_whose_twin_disagrees_with_its_shader(tmp_path):
    path = _example(tmp_path)
    source = path.with_suffix(".py")
    # The twin's Fresnel off by 1 %: beyond the colour views' 2e-3 absolute.
    source.write_text(source.read_text().replace("return self.F0 + (1.0 - self.F0) * m**5",
                                                 "return 1.01 * (self.F0 + (1.0 - self.F0) * m**5)"))
    run = _cli("check", path.name, "--views", "gradient,lit,albedo", cwd=path.parent)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "OVER" in run.stdout and "over: gradient, lit, albedo" in run.stdout, run.stdout


@pytest.mark.gl
@pytest.mark.slow
def test_the_recipe_the_plugin_example_works_outside_the_repository(tmp_path):
    """docs/architecture.md's recipe, followed: the example copied out works with every command."""
    import json

    path = _example(tmp_path)
    folder = path.parent
    run = _cli("check", path.name, "--json", cwd=folder)
    assert run.returncode == 0, run.stdout + run.stderr
    report = json.loads(run.stdout)
    assert report["passed"] and {v["view"] for v in report["views"]} >= {"gradient", "sphere", "lit", "slice", "scatter", "env", "albedo"}
    run = _cli("info", path.name, cwd=folder)
    assert run.returncode == 0 and "model tinted_phong" in run.stdout, run.stderr
    run = _cli("albedo", path.name, "--theta", "0,60", "--json", cwd=folder)
    assert run.returncode == 0, run.stderr
    albedo = np.array(json.loads(run.stdout)["rgb"])
    assert albedo.shape == (2, 3) and np.all((albedo > 0.0) & (albedo <= 1.0))
    run = _cli("export", path.name, "--to", "brdf", "out.brdf", cwd=folder)
    assert run.returncode == 0, run.stderr
    exported = (folder / "out.brdf").read_text()
    shader = exported.split("::begin shader", 1)[1]
    assert exported.startswith("analytic") and not any(line.lstrip().startswith("#") for line in shader.splitlines())
    for engine in ("gl", "numpy"):
        run = _cli("render", path.name, "--view", "lit", "--size", "24", "--engine", engine, "--out", f"{engine}.npy", cwd=folder)
        assert run.returncode == 0, run.stderr
    twins = Twins.of(np.load(folder / "gl.npy"), np.load(folder / "numpy.npy"), "lit")
    assert twins.gl.max() > 0.0
    assert_twins_equal(twins, "the example's lit view, GL against numpy")


#: Run in a subprocess (Mitsuba's scalar variant, no LLVM in this process): a plugin loaded after register() gets its
#: BSDF, evaluated as its twin's brdf x cos; an edit to its file replaces the BSDF.
MITSUBA_LATE = r"""
import json, math, sys
import numpy as np
from explorer.mitsuba import register
from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.mitsuba.bsdfs import plugin_names

mi = register("scalar_rgb")
before = "tinted_phong" in plugin_names()
material = load_material(sys.argv[1])
bsdf = mi.load_dict({"type": "tinted_phong", "exponent": 20.0})
si = mi.SurfaceInteraction3f()
si.wi = mi.Vector3f(math.sin(0.4), 0.0, math.cos(0.4))
wo = [math.sin(0.5) * math.cos(2.8), math.sin(0.5) * math.sin(2.8), math.cos(0.5)]
value = np.ravel(np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*wo)), np.float64))
twin = model_for(material, material.resolve({"exponent": 20.0}))
expected = twin.brdf(np.array(wo), np.array([math.sin(0.4), 0.0, math.cos(0.4)]), np.array([0.0, 0.0, 1.0]),
                     np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])) * wo[2]
print(json.dumps({"before": before, "variant": mi.variant(), "value": value.tolist(), "expected": np.ravel(expected).tolist()}))
"""

#: What the example's twin adds to declare a Mitsuba export: its spectral BRDF and its sampling lobes (cosine only).
MITSUBA_HOOKS = '''
    def spectral_brdf(self, i, o, wavelengths, rgb_upsample):
        n = np.zeros_like(i); n[:, 2] = 1.0
        x = np.zeros_like(i); x[:, 0] = 1.0
        return rgb_upsample(self.brdf(i, o, n, x, np.cross(n, x)), wavelengths)

    def sampling_lobes(self, cos_o):
        return [], [], np.ones_like(np.asarray(cos_o, dtype=np.float64))
'''


def test_a_plugin_loaded_after_mitsuba_register_gets_its_bsdf(tmp_path):
    """Plugin registration reaches Mitsuba whenever it happens: here after ``register()`` set the variant."""
    import json

    pytest.importorskip("mitsuba")
    path = _example(tmp_path)
    source = path.with_suffix(".py")
    text = source.read_text().replace('exports=("brdf", "table")', 'exports=("brdf", "table", "mitsuba")')
    source.write_text(text + MITSUBA_HOOKS)
    env = {**os.environ, "PYTHONWARNINGS": "ignore", "PYTHONPATH": str(REPO_ROOT)}
    run = subprocess.run([sys.executable, "-c", MITSUBA_LATE, str(path)], capture_output=True, text=True, timeout=600, env=env)
    assert run.returncode == 0, run.stderr[-2000:]
    result = json.loads(run.stdout.strip().splitlines()[-1])
    assert result["before"] is False and result["variant"] == "scalar_rgb"
    assert max(result["expected"]) > 0.01
    np.testing.assert_allclose(result["value"], result["expected"], rtol=1e-5, atol=1e-7)
