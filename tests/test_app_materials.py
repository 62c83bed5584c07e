"""
Several materials at once (issue 18 item 1), in scripted sessions under Xvfb (see test_app.py): ``open A
B``, File > Open... answered by the script and by its path field, the Materials list's Visible, Solo,
Close and selection, the plots overlaying the visible materials, two materials compared side by side
(a Bragg layer and a Disney principled BRDF), the Slice window's phi_d against the numpy twin, and a
stack's disabled layer sliders.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from conftest import REPO_ROOT
from test_app import run_session
from twins import Twins, assert_twins_equal

from explorer.app.dialogs import native_dialog_available, split_paths
from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.views.render import render_numpy

LAYER = REPO_ROOT / "shaders" / "bragg_layer.brd"
GGX = REPO_ROOT / "shaders" / "ggx_schlick.brd"
STACK = REPO_ROOT / "shaders" / "bragg_stack.brd"
THIN_FILM = REPO_ROOT / "shaders" / "thin_film.brd"
#: Our own writing of Burley's principled BRDF with BRDF Explorer's parameter names (no numpy twin: not in tests/data/brdf).
DISNEY = REPO_ROOT / "tests" / "data" / "brdf_explorer" / "disney.brdf"
VIEW = 128


def names(report, key="materials"):
    return [entry["path"].rsplit("/", 1)[-1] for entry in report[key]]


def test_materials_list_overlays_dialog_and_compare(x_display, tmp_path, gl_renderer):
    from explorer.physics.colorimetry import delta_E_2000
    from explorer.views.geometry import view_cos_theta

    actions = [
        {"wait": 3}, {"view_size": VIEW}, {"focus": "Polar"}, {"wait": 3}, {"wait_complete": True}, {"wait": 6},
        {"mark": "two"}, {"wait": 1}, {"mark": None},
        # File > Open..., answered by the script: a Disney BRDF and a thin film beside the two.
        {"dialog": [str(DISNEY), str(THIN_FILM)]}, {"click": "menu_file"}, {"wait": 1}, {"click": "menu_open"}, {"wait": 3},
        # Visible off for the GGX; then the overlays are the layer, the Disney BRDF and the film.
        {"click": "material:1:visible"}, {"focus": "Polar"}, {"wait": 3}, {"wait_complete": True}, {"wait": 6},
        {"mark": "three visible"}, {"wait": 1}, {"mark": None},
        # Compare: the layer (selected) | the Disney BRDF, lit; the heat-map with its colour bar.
        {"click": "material:0"}, {"wait": 1}, {"focus": "Compare"}, {"wait": 2}, {"click": "compare_on"}, {"wait": 1},
        {"click": "compare_materials"}, {"wait": 1}, {"click": "compare_b"}, {"wait": 1}, {"click": "compare_b:2"}, {"wait": 2},
        {"wait_complete": True, "timeout": 1500}, {"wait": 3}, {"click": "compare_heat"}, {"wait": 3},
        # Solo the layer, close the film.
        {"click": "material:0:solo"}, {"wait": 1}, {"click": "material:3:close"}, {"wait": 2}, {"quit": True},
    ]
    _, report = run_session(x_display, LAYER, actions, tmp_path, GGX)
    log = report["script_log"]
    assert not any("no item" in line or "timed out" in line for line in log), log
    assert report["dialog"] == ["scripted: 2 paths"], report["dialog"]
    assert names(report) == ["bragg_layer.brd", "ggx_schlick.brd", "disney.brdf"], report["materials"]
    colours = [tuple(entry["colour"]) for entry in report["materials"]]
    assert len(set(colours)) == 3
    # Solo: the layer alone visible, and shown.
    assert [entry["visible"] for entry in report["materials"]] == [True, False, False] and report["selected"] == 0
    # The plots' overlays at the marks: both materials, then the three visible ones (the film in place of the GGX).
    frames = {f["mark"]: f for f in report["frames"] if f["mark"]}
    assert "two" in frames and "three visible" in frames
    plotted = report["plotted_log"]
    assert plotted["two"]["Polar"] == ["bragg_layer.brd", "ggx_schlick.brd"], plotted
    assert plotted["three visible"]["Polar"] == ["bragg_layer.brd", "disney.brdf", "thin_film.brd"], plotted
    assert plotted["two"]["Spectrum"] == ["bragg_layer.brd"]  # the GGX has no Bragg spectrum
    from explorer.app.state import has_reflectance

    strips = [p.name for p in (LAYER, DISNEY, THIN_FILM) if has_reflectance(load_material(p))]  # a gradient needs one
    assert plotted["two"]["Strips"] == ["bragg_layer.brd", "ggx_schlick.brd"]
    shown = plotted["three visible"]["Strips"]  # the shown material's methods first (the film, opened last), then the others
    assert shown[0] == "thin_film.brd" and sorted(shown) == sorted(strips), shown
    # Side by side: the layer | the Disney BRDF, each its own material, lit; the mean ΔE is theirs.
    assert "compare_colour_bar" in report["items"]
    from explorer.views.fill import DEFAULT_FILL

    layer, disney = load_material(LAYER), load_material(DISNEY)
    values = {entry["path"]: entry["values"] for entry in report["materials"]}
    size = VIEW
    fill = {"fill": DEFAULT_FILL}  # the app's lit view: the default environment fill
    a = gl_renderer.render(layer, layer.resolve(values[str(LAYER)]), "lit", size, size, light=(45.0, 0.0), uniforms=fill)
    b = gl_renderer.render(disney, disney.resolve(values[str(DISNEY)]), "lit", size, size, light=(45.0, 0.0), uniforms=fill)
    inside = view_cos_theta("sphere", size, size)[1]
    expected = float(np.mean(delta_E_2000(a[inside].astype(np.float64), b[inside].astype(np.float64))))
    assert report["mean_delta_e"] == pytest.approx(expected, rel=1e-3) and expected > 1.0


def test_open_dialog_field_slice_phi_d_and_disabled_layers(x_display, tmp_path):
    """
    Without a dialog program: File > Open... shows a path field (two paths typed); the Slice window of the
    GGX (chosen in the Sphere window's combo) at phi_d dragged from 90 deg is its numpy twin's; a stack's
    Lambda_3 slider (layers = 1) does not move.
    """
    if native_dialog_available():
        pytest.skip("a native file dialog program is installed here: the field is for machines without one")
    slice_npy = tmp_path / "slice.npy"
    actions = [
        {"wait": 3}, {"view_size": VIEW}, {"click": "menu_file"}, {"wait": 1}, {"click": "menu_open"}, {"wait": 2},
        {"type": "open_dialog:paths", "text": f"{STACK}; {THIN_FILM}"}, {"wait": 3},
        {"click": "shown"}, {"wait": 1}, {"click": "shown:0"}, {"wait": 1}, {"focus": "Slice"}, {"wait": 2},  # the sphere's own choice
        {"drag": "slice_phi_d", "from": 0.5, "to": 0.3, "frames": 3}, {"click": "slice_chroma"}, {"wait": 2},
        {"save_slice": str(slice_npy)}, {"wait": 1},
        {"click": "material:1"}, {"wait": 2},
        {"drag": "param:Lambda_3", "from": 0.3, "to": 0.6, "frames": 3}, {"drag": "param:Lambda_1", "from": 0.3, "to": 0.6, "frames": 3},
        {"wait": 2}, {"quit": True},
    ]
    _, report = run_session(x_display, GGX, actions, tmp_path)
    log = report["script_log"]
    assert not any("no item" in line or "timed out" in line for line in log), log
    assert report["dialog"] == ["field: 2 paths"] and split_paths(" a b ; c;; ") == ["a b", "c"]
    assert names(report) == ["ggx_schlick.brd", "bragg_stack.brd", "thin_film.brd"]
    # The slice at the dragged phi_d, chroma on: the linear image is the twin's, the shown one chroma.
    phi_d = report["slice"]["phi_d"]
    assert 20.0 < phi_d < 85.0 and report["slice"]["chroma"], report["slice"]
    ggx = load_material(GGX)
    gl = np.load(slice_npy)
    reference = render_numpy(model_for(ggx, ggx.resolve({})), "slice", *gl.shape[1::-1], slice_phi_d=phi_d)
    assert_twins_equal(Twins.of(gl, reference, "slice"), f"slice at phi_d {phi_d:.1f}")
    at_90 = render_numpy(model_for(ggx, ggx.resolve({})), "slice", *gl.shape[1::-1])
    assert np.abs(at_90 - reference).max() > 1e-2, "phi_d changes the slice"
    # The stack (selected last): Lambda_3 is beyond layers = 1, its slider disabled; Lambda_1 moved.
    stack = load_material(STACK)
    values = report["values"]
    assert report["material"] == str(STACK)
    assert values["Lambda_3"] == stack.parameter("Lambda_3").default
    assert values["Lambda_1"] != stack.parameter("Lambda_1").default


@pytest.mark.parametrize("view", ["lit", "slice", "scatter"])
def test_disney_brdf_matches_its_numpy_twin(gl_renderer, view):
    """The principled BRDF the comparison uses is what Burley's equations give (DisneyTwin in tests/brdf_twins.py)."""
    import brdf_twins
    from twins import render_both

    disney = load_material(DISNEY)
    # A glossier clearcoat (GTR1 at alpha 0.001) is float32-limited at the scatter view's exact mirror pixel.
    cases = [{}, {"metallic": 0.7, "roughness": 0.3, "anisotropic": 0.6, "sheen": 0.5, "clearcoat": 0.8, "clearcoatGloss": 0.3, "subsurface": 0.4,
                  "specularTint": 0.5}]
    with brdf_twins.registered():
        for case in cases:
            twins = render_both(gl_renderer, disney, disney.resolve(case), view, (48, 48))
            assert_twins_equal(twins, f"disney {view} {case}")
            assert np.abs(twins.reference).max() > 0.05


def test_materials_list_logic_without_a_window(tmp_path):
    """Open (one file failing), select (each keeps its values), Solo, Close (Compare's B follows its material)."""
    from explorer.app import App

    app = App(LAYER, more_paths=[GGX])
    state = app.state
    assert [e.name for e in state.materials] == ["bragg_layer.brd", "ggx_schlick.brd"] and state.view_size_auto
    assert app.open_materials([DISNEY, tmp_path / "missing.brd"]) == 1
    assert "missing.brd" in state.error and "1 failed" in state.status
    assert state.selected == 2 and state.material_path == DISNEY and state.material is state.materials[2].material
    state.values = state.material.resolve({**state.values, "roughness": 0.9})  # an edit of the shown material
    app.select(0)
    assert state.materials[2].values["roughness"] == 0.9 and state.material_path == LAYER
    state.compare.material_b = 2
    app.close(1)
    assert [e.name for e in state.materials] == ["bragg_layer.brd", "disney.brdf"] and state.compare.material_b == 1
    app.solo(1)
    assert [e.visible for e in state.materials] == [False, True] and state.selected == 1
    assert state.values["roughness"] == 0.9
    assert len({e.colour for e in state.materials}) == 2
    app.close(1)
    assert [e.name for e in state.materials] == ["bragg_layer.brd"] and state.material_path == LAYER
    app.close(0)  # the last one stays
    assert len(state.materials) == 1


def test_native_file_dialog_through_portable_file_dialogs(x_display, tmp_path, monkeypatch):
    """File > Open... starts portable-file-dialogs' zenity (a stand-in here, on PATH) and opens what it answers."""
    fake = tmp_path / "bin" / "zenity"
    fake.parent.mkdir()
    fake.write_text(f'#!/bin/sh\necho "$@" > {tmp_path / "args.txt"}\nprintf "%s\\n" "{THIN_FILM}" "{DISNEY}"\n')
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", f"{fake.parent}:{os.environ['PATH']}")
    actions = [{"wait": 3}, {"click": "menu_file"}, {"wait": 1}, {"click": "menu_open"}, {"wait": 30}, {"quit": True}]
    _, report = run_session(x_display, GGX, actions, tmp_path)
    assert report["dialog"] == ["native: 2 paths"], (report["dialog"], report["script_log"])
    assert names(report) == ["ggx_schlick.brd", "thin_film.brd", "disney.brdf"] and report["selected"] == 2
    arguments = (tmp_path / "args.txt").read_text()
    assert "--multiple" in arguments and "*.brd *.brdf" in arguments
