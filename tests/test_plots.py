"""
BRDF Explorer's plots (explorer/views/plots.py, shaders/views/{theta_v,theta_h,theta_d,lobe3d,albedo}.glsl):
GL against the numpy twin, the geometry against closed forms, what a plot shows, the CLI's outputs.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli, run_cli_process
from twins import assert_twins_equal, render_both

SHADERS = REPO_ROOT / "shaders"
#: (material, overrides, light): rough lobes (the twin compares at 2e-3 of a value), a Dirac, a stack.
CASES = {
    "ggx_schlick": ("ggx_schlick.brd", {}),
    "thin_film": ("thin_film.brd", {"method": 2, "alpha": 0.3}),
    "bragg_layer": ("bragg_layer.brd", {"method": 3, "alpha": 0.3}),
    "bragg_mirror": ("bragg_mirror.brd", {"method": 1}),
}


def material(name):
    from explorer.materials.brd import load_material

    file, overrides = CASES[name]
    loaded = load_material(SHADERS / file)
    return loaded, loaded.resolve(overrides)


# -- geometry ------------------------------------------------------------------------------------------


def test_rusinkiewicz_directions_have_their_angles():
    """H = normalize(L + V) sits at theta_h in the xz plane and L.H = cos theta_d (phi_d = 90: L off the plane)."""
    from explorer.views.plots import rusinkiewicz_directions

    rng = np.random.default_rng(1)
    theta_h, theta_d = rng.uniform(0.0, 1.5, 50), rng.uniform(0.0, 1.5, 50)
    L, V = (a.astype(np.float64) for a in rusinkiewicz_directions(theta_h, theta_d))
    H = (L + V) / np.linalg.norm(L + V, axis=-1, keepdims=True)
    np.testing.assert_allclose(np.arccos(np.clip(H[:, 2], -1, 1)), theta_h, atol=2e-3)
    np.testing.assert_allclose(H[:, 1], 0.0, atol=1e-6)
    np.testing.assert_allclose(np.sum(L * H, axis=-1), np.cos(theta_d), atol=1e-6)


def test_the_slice_view_is_the_theta_h_plot_row_by_row():
    """The slice view's row at theta_d is the theta_h plot at that theta_d (the same construction)."""
    from explorer.views.geometry import brdf_view_geometry
    from explorer.views.plots import PlotSettings, plot_geometry

    width, height = 24, 12
    L, V = brdf_view_geometry("slice", width, height)[:2]
    row = 5
    theta_d = 90.0 * (row + 0.5) / height
    Lp, Vp = plot_geometry("theta_h", width, 1, np.array([0, 0, 1.0]), PlotSettings(theta_d=theta_d))
    np.testing.assert_allclose(Lp[0], L[row], atol=2e-6)
    np.testing.assert_allclose(Vp[0], V[row], atol=2e-6)


def test_theta_v_plot_peaks_at_the_mirror_direction():
    """A GGX lobe (alpha 0.1) in the plane of incidence peaks at theta_v = -theta_l; off the plane it is lower."""
    from explorer.materials.models import model_for
    from explorer.views.geometry import light_direction
    from explorer.views.plots import PlotSettings, abscissa, plot_numpy

    loaded, _ = material("ggx_schlick")
    model = model_for(loaded, loaded.resolve({"alpha": 0.1}))
    curve = plot_numpy(model, "theta_v", 360, 1, light_direction((35.0, 20.0)), PlotSettings(phi_v=20.0))[0, :, 1]
    assert abs(abscissa("theta_v", 360)[curve.argmax()] + 35.0) <= 0.5
    across = plot_numpy(model, "theta_v", 360, 1, light_direction((35.0, 20.0)), PlotSettings(phi_v=110.0))[0, :, 1]
    assert across.max() < 0.2 * curve.max()


def test_plotted_channel_log_and_ndotl():
    from explorer.physics.colorimetry import rgb_to_xyz
    from explorer.views.plots import PlotSettings, plotted

    values = np.array([[0.2, 0.5, 1.0], [3.0, 0.0, -0.1]])
    cos_l = np.array([0.5, 1.0])
    np.testing.assert_allclose(plotted(values, PlotSettings()), values)
    np.testing.assert_allclose(plotted(values, PlotSettings(channel="g"))[:, 0], values[:, 1])
    np.testing.assert_allclose(plotted(values, PlotSettings(channel="luminance"))[:, 0], rgb_to_xyz(values)[:, 1])
    np.testing.assert_allclose(plotted(values, PlotSettings(ndotl=True, channel="r"), cos_l), [[0.1], [3.0]])
    np.testing.assert_allclose(plotted(values, PlotSettings(log=True, channel="r")), [[np.log10(1.2)], [np.log10(4.0)]])
    assert plotted(values, PlotSettings(log=True, channel="b"))[1, 0] == 0.0  # out of gamut: clipped at log10(1)


def test_bad_plot_settings_are_one_line():
    from explorer.views.plots import PlotSettings

    for kwargs in ({"theta_d": 95.0}, {"theta_h": -1.0}, {"phi_v": float("nan")}, {"channel": "alpha"}):
        with pytest.raises(ValueError) as error:
            PlotSettings(**kwargs)
        assert "\n" not in str(error.value)


def test_albedo_plot_of_the_mirror_is_its_reflectance():
    """A smooth mirror's albedo is its reflectance at the incidence angle (explorer.views.albedo)."""
    from explorer.materials.models import model_for
    from explorer.views.plots import PlotSettings, abscissa, plot_numpy

    loaded, values = material("bragg_mirror")
    model = model_for(loaded, values)
    curve = plot_numpy(model, "albedo", 9, 1, np.array([0, 0, 1.0]), PlotSettings())
    np.testing.assert_allclose(curve[0], model.reflectance(np.cos(np.radians(abscissa("albedo", 9)))), rtol=1e-6)


# -- GL = numpy ------------------------------------------------------------------------------------------


@pytest.mark.gl
@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("view", ["theta_v", "theta_h", "theta_d", "lobe3d"])
def test_plot_gl_equals_numpy(gl_renderer, case, view):
    from explorer.views.plots import PlotSettings

    loaded, values = material(case)
    settings = PlotSettings(theta_d=20.0, theta_h=15.0, phi_v=30.0)
    size = (40, 12) if view == "lobe3d" else (61, 2)
    twins = render_both(gl_renderer, loaded, values, view, size, light=(40.0, 10.0), plot=settings)
    assert np.abs(twins.reference).max() > 1e-3, f"{case} {view}: nothing to compare"
    assert_twins_equal(twins, f"{case} {view}")
    if view != "lobe3d":
        np.testing.assert_array_equal(twins.gl[0], twins.gl[1])  # every row the same


@pytest.mark.gl
@pytest.mark.parametrize("case", ["ggx_schlick", "bragg_layer", "bragg_mirror"])
def test_albedo_plot_gl_equals_numpy(gl_renderer, case):
    loaded, values = material(case)
    twins = render_both(gl_renderer, loaded, values, "albedo", (6, 1))
    assert np.abs(twins.reference).max() > 1e-2
    assert_twins_equal(twins, f"{case} albedo")


# -- the command line --------------------------------------------------------------------------------------


@pytest.mark.gl
def test_cli_plot_npy_gl_equals_numpy_and_png_is_a_chart(tmp_path):
    """The .npy holds (angle, plotted values) per sample, equal on both engines; the PNG is a chart."""
    from PIL import Image

    args = ["--view", "theta_h", "--size", "45", "--theta-d", "25", "--channel", "luminance", "--log", "--ndotl", "--set", "alpha=0.3"]
    outputs = {}
    for engine in ("gl", "numpy"):
        outputs[engine] = tmp_path / f"{engine}.npy"
        run = run_cli_process("render", SHADERS / "ggx_schlick.brd", *args, "--engine", engine, "--out", outputs[engine])
        assert run.returncode == 0, run.stderr
    gl, reference = np.load(outputs["gl"]), np.load(outputs["numpy"])
    assert gl.shape == reference.shape == (45, 2)
    np.testing.assert_allclose(gl[:, 0], 90.0 * (np.arange(45) + 0.5) / 45, rtol=1e-6)
    np.testing.assert_allclose(gl[:, 1], reference[:, 1], rtol=2e-3, atol=2e-6)
    png = tmp_path / "plot.png"
    run = run_cli_process("render", SHADERS / "ggx_schlick.brd", *args, "--out", png)
    assert run.returncode == 0, run.stderr
    with Image.open(png) as image:
        pixels = np.asarray(image.convert("RGB"))
    assert pixels.shape[0] >= 200 and pixels.shape[1] >= 300
    assert len(np.unique(pixels.reshape(-1, 3), axis=0)) > 10  # axes, text and a curve, not a blank image


def test_cli_plot_options_belong_to_their_views(tmp_path):
    out = tmp_path / "out.png"
    cases = {
        "theta-d on lit": ["--view", "lit", "--theta-d", "10"],
        "phi-v on theta_h": ["--view", "theta_h", "--phi-v", "10"],
        "log on sphere": ["--view", "sphere", "--log"],
        "bad channel": ["--view", "theta_v", "--channel", "alpha"],
        "theta-h out of range": ["--view", "theta_d", "--theta-h", "120"],
        "exposure on a plot": ["--view", "albedo", "--exposure", "2"],
        "exr plot": ["--view", "theta_v", "--out", str(tmp_path / "plot.exr")],
    }
    for name, args in cases.items():
        args = args if "--out" in args else [*args, "--out", out]
        line = one_line_error(run_cli("render", SHADERS / "ggx_schlick.brd", *args, "--engine", "numpy"))
        assert line, name
        assert not out.exists(), name


def test_polar_window_draws_the_light_where_the_curve_puts_its_angle():
    """The Polar window's incident segment lies at the light's signed theta of the curve (x toward phi = 0)."""
    from explorer.app.data import polar_incident
    from explorer.views.geometry import light_direction

    for theta, phi, signed in ((30.0, 0.0, 30.0), (50.0, 180.0, -50.0), (0.0, 0.0, 0.0)):
        xs, ys = polar_incident(light_direction((theta, phi)), 2.0)
        assert xs[0] == ys[0] == 0.0
        assert np.hypot(xs[1], ys[1]) == pytest.approx(2.0)
        assert np.degrees(np.arctan2(xs[1], ys[1])) == pytest.approx(signed, abs=1e-4)


def test_cli_chart_names_a_smooth_mirrors_curve_as_the_app_does(tmp_path, monkeypatch):
    """A smooth mirror's plotted value is its reflectance R(theta_d), not a BRDF: the CLI's chart says it in the app's words."""
    from explorer.app.panels.brdf_views import slice_quantity
    from explorer.views import plot_images
    from explorer.views.mirror import BRDF_QUANTITY, MIRROR_QUANTITY, plotted_quantity

    labels = {}
    drawn = plot_images.chart

    def recording(*args, **kwargs):
        figure = drawn(*args, **kwargs)
        labels[args[3]] = figure.axes[0].get_ylabel()
        return figure

    monkeypatch.setattr(plot_images, "chart", recording)
    for name in ("bragg_mirror", "ggx_schlick"):
        run = run_cli("render", name, "--view", "theta_d", "--engine", "numpy", "--size", "16", "--out", tmp_path / f"{name}.png")
        assert run.returncode == 0, run.stderr
    (mirror,), (rough,) = ([label for title, label in labels.items() if name in title] for name in ("bragg_mirror", "ggx_schlick"))
    assert mirror == MIRROR_QUANTITY == plotted_quantity([True]) and rough == BRDF_QUANTITY, labels
    loaded, _ = material("bragg_mirror")
    assert slice_quantity(loaded).startswith(MIRROR_QUANTITY) and slice_quantity(material("ggx_schlick")[0]) == BRDF_QUANTITY
