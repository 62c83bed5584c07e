"""
Spatially varying film thickness (Belcour & Barla 2017, Section 5, Figures 12-15): the
``textured`` view, its numpy twin, the pre-filtered Fourier table, the removal of aliasing, bad input.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli, run_cli_process
from twins import Twins, assert_twins_equal, render_both

THIN_FILM = REPO_ROOT / "shaders" / "thin_film.brd"
#: Not square, so that a swapped width and height or flipped rows show.
SIZE = (36, 28)
#: The aliasing test: 32^2 with prefiltering must be this many times closer (RMS) to the box-filtered
#: 256^2 render than 32^2 without (measured: 4.6 on a 256^2 texture of iid texel noise over [0, 1125] nm).
ALIASING_MARGIN = 3.0


@pytest.fixture(scope="module")
def film():
    from explorer.materials.brd import load_material

    return load_material(THIN_FILM)


def noise_texture(size: int = 256, low: float = 0.0, high: float = 1125.0, seed: int = 0):
    rng = np.random.default_rng(seed)
    return (low + (high - low) * rng.random((size, size))).astype(np.float32)


# -- physics -------------------------------------------------------------------------------------------


def test_prefiltered_table_level_zero_is_the_table():
    from explorer.tables import luts
    from explorer.physics import thinfilm

    table = thinfilm.sensitivity_fourier_prefiltered()
    plain = luts.load("sensitivity_fourier")
    assert np.abs(table[0] - plain[0]).max() < 1e-6
    assert np.abs(table[thinfilm.PREFILTER_LEVELS] - plain[1]).max() < 1e-6


@pytest.mark.parametrize("sigma", [10.0, 40.0, 120.0])
def test_prefiltered_transform_is_the_gaussian_average(sigma):
    """The table at (mu, sigma) = S^ averaged over OPDs ~ N(mu, sigma^2), by quadrature of the exact transform."""
    from explorer.physics import thinfilm

    mu = np.linspace(0.0, 4000.0, 41)
    z = np.linspace(-7.0, 7.0, 2801)
    weights = np.exp(-0.5 * z**2)
    weights /= weights.sum()
    average = (thinfilm.sensitivity_fourier_transform_exact(mu[:, None] + sigma * z[None, :]) * weights[None, :, None]).sum(axis=1)
    assert np.abs(thinfilm.sensitivity_fourier_transform_prefiltered(mu, sigma) - average).max() < 2e-3


def test_prefiltered_without_variance_is_fourier_rgb():
    from explorer.physics import thinfilm

    cos_theta = np.linspace(0.05, 1.0, 30)
    for method in (1, 2, 3):
        plain = thinfilm.fourier_rgb(1.0, 1.5, 1.09, 0.0, cos_theta, 300.0, m_max=method)
        prefiltered = thinfilm.fourier_rgb_prefiltered(1.0, 1.5, 1.09, 0.0, cos_theta, 300.0, 0.0, m_max=method)
        np.testing.assert_allclose(prefiltered, plain, atol=1e-6)


def test_large_variance_leaves_the_fringe_average():
    """sigma -> infinity: every harmonic averages out, R -> C_0 (the colourless fringe average)."""
    from explorer.physics import thinfilm

    cos_theta = np.linspace(0.1, 1.0, 10)
    rgb = thinfilm.fourier_rgb_prefiltered(1.0, 1.5, 1.09, 0.0, cos_theta, 300.0, 1000.0, m_max=3)
    c0 = thinfilm.fourier_rgb(1.0, 1.5, 1.09, 0.0, cos_theta, 300.0, m_max=0, remainder=False)
    np.testing.assert_allclose(rgb, c0, atol=1e-6)


def test_default_texture_is_its_generator():
    from explorer.views.thickness import DEFAULT_TEXTURE, generate_default_texture, load_grey

    # To one grey level: a value that rounds on .5 may go either way on another machine's arithmetic.
    shipped = np.round(load_grey(DEFAULT_TEXTURE) * 255.0)
    np.testing.assert_allclose(shipped, generate_default_texture(), rtol=0, atol=1)


def test_footprint_moments_of_a_constant_and_of_a_checkerboard():
    from explorer.views.thickness import ThicknessTexture

    constant = ThicknessTexture(np.full((8, 8), 400.0, np.float32), prefilter=True).moments(4, 4)
    np.testing.assert_allclose(constant[..., 0], 400.0)
    np.testing.assert_allclose(constant[..., 1], 0.0, atol=1e-6)
    checker = (np.indices((64, 64)).sum(axis=0) % 2 * 1000.0).astype(np.float32)
    moments = ThicknessTexture(checker, prefilter=True).moments(16, 16)  # 4 texels a pixel, 16 samples
    # The bilinear checkerboard 500 + 500 (1 - 2 fx)(1 - 2 fy) over whole cells: mean 500 nm, variance
    # 500^2 / 9; the midpoint rule at 4 samples per texel gives 500^2 (5/16)^2, 12 % less.
    np.testing.assert_allclose(moments[1:-1, 1:-1, 0], 500.0, rtol=1e-3)
    np.testing.assert_allclose(moments[1:-1, 1:-1, 1], 500.0**2 * (5.0 / 16.0) ** 2, rtol=1e-3)


# -- GL = numpy ------------------------------------------------------------------------------------------


@pytest.mark.gl
@pytest.mark.parametrize("method", [0, 1, 2, 3, 4, 5])
def test_textured_gl_equals_numpy(gl_renderer, film, method):
    from explorer.views.thickness import ThicknessTexture

    thickness = ThicknessTexture.from_file(dinc_range=(0.0, 1125.0))
    twins = render_both(gl_renderer, film, film.resolve({"method": method, "alpha": 0.3}), "textured", SIZE,
                        light=None, thickness=thickness)
    assert np.abs(twins.reference).max() > 0.01
    assert_twins_equal(twins, f"textured method {method}")


@pytest.mark.gl
@pytest.mark.parametrize("method", [1, 2, 3])
@pytest.mark.parametrize("texture", ["default", "noise"])
def test_textured_prefiltered_gl_equals_numpy(gl_renderer, film, method, texture):
    from explorer.views.thickness import ThicknessTexture

    if texture == "noise":
        thickness = ThicknessTexture(noise_texture(), prefilter=True)
    else:
        thickness = ThicknessTexture.from_file(dinc_range=(0.0, 1125.0), prefilter=True)
    values = film.resolve({"method": method, "alpha": 0.3, "eta3": 1.5, "kappa3": 0.8})
    twins = render_both(gl_renderer, film, values, "textured", SIZE, light=None, thickness=thickness)
    assert np.abs(twins.reference).max() > 0.01
    assert_twins_equal(twins, f"prefiltered method {method}, {texture}")


@pytest.mark.gl
def test_prefiltering_removes_aliasing(gl_renderer, film):
    """
    Figure 15: a texture of iid texel noise (256^2, D_inc over [0, 1125] nm) on the sphere at 32^2. With
    prefiltering, the image is much closer to the 256^2 render box-filtered to 32^2 than without.
    """
    from explorer.views.thickness import ThicknessTexture

    overrides = {"method": 3, "alpha": 0.3}
    d_inc = noise_texture()
    values = film.resolve(overrides)

    def render(size, prefilter):
        thickness = ThicknessTexture(d_inc, prefilter=prefilter)
        return gl_renderer.render(
            film, values, "textured", size, size,
            inputs=thickness.gl_inputs(size, size), uniforms={"prefilter": prefilter},
        )

    reference = render(256, False).reshape(32, 8, 32, 8, 3).mean(axis=(1, 3))
    x = (np.arange(256) + 0.5) / 128.0 - 1.0
    whole = ((x[None, :] ** 2 + x[:, None] ** 2) < 1.0).reshape(32, 8, 32, 8).all(axis=(1, 3))  # no rim pixels

    def rms(image):
        return float(np.sqrt(np.mean((image - reference)[whole] ** 2)))

    aliased, prefiltered = rms(render(32, False)), rms(render(32, True))
    assert aliased > ALIASING_MARGIN * prefiltered, f"RMS without {aliased:.5f}, with {prefiltered:.5f}"


# -- the command line --------------------------------------------------------------------------------------


def bad_cases(tmp_path):
    text = tmp_path / "notes.png"
    text.write_text("not an image\n")
    return {
        "not an image": (["--texture", text], str(text)),
        "missing texture": (["--texture", tmp_path / "missing.png"], str(tmp_path / "missing.png")),
        "one number": (["--dinc-range", "400"], "--dinc-range"),
        "not numbers": (["--dinc-range", "a,b"], "--dinc-range"),
        "negative": (["--dinc-range", "-10,400"], "--dinc-range"),
        "reversed": (["--dinc-range", "800,400"], "--dinc-range"),
        "not finite": (["--dinc-range", "0,inf"], "--dinc-range"),
        "prefilter method 0": (["--prefilter", "on", "--set", "method=0"], "--prefilter"),
    }


def test_cli_bad_thickness_input(tmp_path):
    out = tmp_path / "out.png"
    cases = bad_cases(tmp_path)
    runs = {name: run_cli("render", THIN_FILM, "--view", "textured", "--size", "8", "--engine", "numpy", "--out", out, *args)
            for name, (args, _) in cases.items()}
    for name, (args, named) in cases.items():
        line = one_line_error(runs[name])
        assert named in line, f"{name}: {line}"
        assert not out.exists(), name
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.png"]


@pytest.mark.gl
def test_cli_textured_npy_equals_numpy(gl_renderer, tmp_path):
    texture = tmp_path / "stripes.png"
    from PIL import Image

    Image.fromarray((np.indices((40, 40))[1] * 6 % 256).astype(np.uint8), mode="L").save(texture)
    outputs = {}
    for engine in ("gl", "numpy"):
        outputs[engine] = tmp_path / f"{engine}.npy"
        run = run_cli_process(
            "render", THIN_FILM, "--view", "textured", "--size", "36x28", "--set", "method=2", "--set", "alpha=0.3",
            "--texture", texture, "--dinc-range", "100,900", "--prefilter", "on", "--engine", engine, "--out", outputs[engine],
        )
        assert run.returncode == 0, run.stderr
    assert_twins_equal(Twins.of(np.load(outputs["gl"]), np.load(outputs["numpy"]).astype(np.float32), "textured"),
                       "CLI textured")
