"""
MERL ``.binary`` measured BRDFs: the half/difference angles and bins against their inverse, the file's
layout and scales from bytes written here by hand, analytic BRDFs tabulated into MERL files (MERL's own
data cannot be shipped), the GL lookup against its numpy twin, and the one-line errors of files that are
not MERL tables.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import one_line_error, run_cli, run_cli_process
from twins import BRDF_TOLERANCE, LIGHTS, compared_pixels

from explorer.materials.brd import MaterialError, load_material
from explorer.materials.merl import FILE_BYTES, tabulate, write_merl
from explorer.materials.models import model_for
from explorer.physics.merl import (
    CHANNEL_SCALES, merl_bin_centres, merl_directions, merl_half_diff, merl_index,
)
from explorer.views.geometry import brdf_view_geometry

#: Of the compared pixels, at most this fraction may show a neighbouring bin's value (float32 angles in
#: GLSL, float64 in the twin: a direction within ~1e-6 rad of a bin edge may land on either side).
NEIGHBOUR_BIN_FRACTION = 0.02


def rng():
    return np.random.default_rng(18)


def random_pairs(count):
    """Random local (L, V) pairs above the surface."""
    generator = rng()
    def hemisphere():
        d = generator.normal(size=(count, 3))
        d[:, 2] = np.abs(d[:, 2]) + 1e-3
        return d / np.linalg.norm(d, axis=-1, keepdims=True)
    return hemisphere(), hemisphere()


def analytic(L, V):
    """A coloured Lambertian plus a broad Blinn-Phong-like lobe, anisotropic in phi_d: every angle matters."""
    H = L + V
    H = H / np.linalg.norm(H, axis=-1, keepdims=True)
    theta_h, theta_d, phi_d = merl_half_diff(L, V)
    lobe = np.exp(-8.0 * (1.0 - H[..., 2])) * (1.0 + 0.5 * np.cos(theta_d)) * (1.0 + 0.3 * np.cos(2.0 * phi_d))
    return np.array([0.12, 0.08, 0.05]) / np.pi + lobe[..., None] * np.array([0.9, 0.6, 0.3])


@pytest.fixture(scope="module")
def analytic_file(tmp_path_factory):
    return write_merl(tmp_path_factory.mktemp("merl") / "analytic.binary", tabulate(analytic))


@pytest.fixture(scope="module")
def analytic_material(analytic_file):
    return load_material(analytic_file)


# -- angles and bins ----------------------------------------------------------------------------------


def test_half_diff_angles_invert_their_directions():
    generator = rng()
    theta_h = generator.uniform(0.0, np.pi / 2 * 0.99, 500)
    theta_d = generator.uniform(0.0, np.pi / 2 * 0.99, 500)
    phi_d = generator.uniform(-np.pi * 0.99, np.pi * 0.99, 500)
    phi_h = generator.uniform(-np.pi, np.pi, 500)
    L, V = merl_directions(theta_h, theta_d, phi_d, phi_h)
    np.testing.assert_allclose(np.linalg.norm(L, axis=-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(V, axis=-1), 1.0, atol=1e-12)
    H = (L + V) / np.linalg.norm(L + V, axis=-1, keepdims=True)
    np.testing.assert_allclose(np.arccos(np.clip(np.sum(L * H, axis=-1), -1, 1)), theta_d, atol=1e-7)  # theta_d is L's angle to H
    back = merl_half_diff(L, V)
    for got, want in zip(back, (theta_h, theta_d, phi_d)):
        np.testing.assert_allclose(got, want, atol=1e-9)


def test_bin_centres_fall_in_their_bins_and_edges_follow_the_sqrt_mapping():
    centres = merl_bin_centres()
    grid = np.meshgrid(*centres, indexing="ij")
    indices = merl_index(*grid)
    for axis, index in enumerate(indices):
        np.testing.assert_array_equal(index, np.indices(grid[0].shape)[axis])
    # theta_h bin i spans [i^2 / 90, (i + 1)^2 / 90) degrees: just below and above an edge.
    for i in (1, 2, 10, 45, 89):
        edge = np.radians(i * i / 90.0)
        assert merl_index(edge * (1 - 1e-9), 0.1, 0.1)[0] == i - 1
        assert merl_index(edge * (1 + 1e-9), 0.1, 0.1)[0] == i
    # phi_d's reciprocity fold: phi_d and phi_d - pi share a bin; out-of-range angles clamp.
    assert merl_index(0.1, 0.1, 0.4)[2] == merl_index(0.1, 0.1, 0.4 - np.pi)[2] == int(0.4 / np.pi * 180)
    assert [int(i) for i in merl_index(np.pi, np.pi, np.pi)] == [89, 89, 179]
    assert [int(i) for i in merl_index(-0.1, 0.0, 0.0)] == [0, 0, 0]


def test_lookup_reads_the_bin_of_any_direction(tmp_path):
    """A table whose value encodes its bin: every lookup returns the bin of its own half/difference angles."""
    i_h, i_d, i_phi = np.indices((90, 90, 180))
    table = np.stack([i_h, i_d, i_phi], axis=-1).astype(np.float64) * CHANNEL_SCALES  # raw value = index
    material = load_material(write_merl(tmp_path / "indices.binary", table))
    L, V = random_pairs(2000)
    eye = np.eye(3)
    got = model_for(material, {}).brdf(L, V, eye[2], eye[0], eye[1]) / CHANNEL_SCALES.astype(np.float32)
    want = np.stack(merl_index(*merl_half_diff(L, V)), axis=-1)
    np.testing.assert_allclose(got, want, atol=1e-3)
    # The frame counts: the same pair in a rotated frame (X, Y, N) reads the same bins.
    rotation = np.linalg.qr(rng().normal(size=(3, 3)))[0]
    X, Y, N = rotation.T
    world = lambda d: d[..., 0:1] * X + d[..., 1:2] * Y + d[..., 2:3] * N  # noqa: E731
    rotated = model_for(material, {}).brdf(world(L), world(V), N, X, Y) / CHANNEL_SCALES.astype(np.float32)
    np.testing.assert_allclose(rotated, want, atol=1e-3)


# -- the file -----------------------------------------------------------------------------------------


def test_layout_and_scales_from_bytes_written_by_hand(tmp_path):
    """Header 90 90 180, then R, G, B blocks of C-ordered float64: raw 1500 reads as (1, 1.15, 1.66); negative as 0."""
    raw = np.full((3, 90, 90, 180), 1500.0)
    raw[1, 3, 4, 5] = 3000.0  # green of bin (3, 4, 5): index 5 + 4 x 180 + 3 x 180 x 90 of its block
    raw[:, 89, 89, 179] = -1.0  # MERL's "not measured"
    path = tmp_path / "hand.binary"
    path.write_bytes(np.array([90, 90, 180], "<i4").tobytes() + raw.astype("<f8").tobytes())
    assert path.stat().st_size == FILE_BYTES
    table = load_material(path).measured.rgb
    np.testing.assert_allclose(table[0, 0, 0], [1.0, 1.15, 1.66], rtol=1e-6)
    np.testing.assert_allclose(table[3, 4, 5], [1.0, 2.30, 1.66], rtol=1e-6)
    np.testing.assert_array_equal(table[89, 89, 179], 0.0)


def test_an_analytic_brdf_comes_back_at_its_bin_centres(analytic_material):
    """A tabulated analytic BRDF: exact at the bins' middles (float32), close to the function between them."""
    model = model_for(analytic_material, {})
    eye = np.eye(3)
    theta_h, theta_d, phi_d = (c[::7] for c in merl_bin_centres())
    L, V = merl_directions(theta_h[:, None, None], theta_d[None, :, None], phi_d[None, None, :], phi_h=0.7)
    L, V = L.reshape(-1, 3), V.reshape(-1, 3)
    np.testing.assert_allclose(model.brdf(L, V, eye[2], eye[0], eye[1]), analytic(L, V), rtol=1e-6)
    L, V = random_pairs(3000)
    above = (L[:, 2] > 0.05) & (V[:, 2] > 0.05)
    got, want = model.brdf(L, V, eye[2], eye[0], eye[1])[above], analytic(L, V)[above]
    assert np.median(np.abs(got - want) / want) < 0.02  # nearest bin: a step function's error


def test_a_merl_table_under_another_name_loads(tmp_path, analytic_file):
    other = tmp_path / "measured.dat"
    other.write_bytes(analytic_file.read_bytes())
    assert load_material(other).model == "merl"


BAD_FILES = {
    "wrong header": (np.array([90, 90, 360], "<i4").tobytes() + bytes(64), "header 90 90 360"),
    "truncated": (np.array([90, 90, 180], "<i4").tobytes() + bytes(800), "truncated or padded MERL .binary file: 812 bytes"),
    "too short": (b"\x88(", "2 bytes, no header"),
}


@pytest.mark.parametrize("case", list(BAD_FILES))
def test_a_binary_that_is_not_merl_is_one_line_saying_what_is_expected(tmp_path, case):
    data, expected = BAD_FILES[case]
    path = tmp_path / "bad.binary"
    path.write_bytes(data)
    with pytest.raises(MaterialError, match="34992012 bytes") as error:
        load_material(path)
    assert expected in str(error.value)
    line = one_line_error(run_cli("render", path, "--view", "lit", "--out", tmp_path / "x.png"))
    assert str(path) in line and expected in line and "\\x" not in line


def test_unknown_binary_data_says_what_is_supported(tmp_path):
    path = tmp_path / "image.brd"
    path.write_bytes(b"\x88(\x00\x01garbage" * 10)
    line = one_line_error(run_cli("info", path))
    assert "binary data (110 bytes), not a material file" in line and "MERL" in line and ".brdf" in line and "\\x88" not in line


def test_not_finite_values_are_refused(tmp_path):
    raw = np.zeros((3, 90, 90, 180))
    raw[2, 1, 1, 1] = np.nan
    path = tmp_path / "nan.binary"
    path.write_bytes(np.array([90, 90, 180], "<i4").tobytes() + raw.astype("<f8").tobytes())
    with pytest.raises(MaterialError, match="1 NaN or infinite"):
        load_material(path)


# -- GL against numpy ---------------------------------------------------------------------------------


def assert_lookup_twins(gl, reference, material, view, light):
    """
    GL equals the numpy twin (:data:`twins.BRDF_TOLERANCE`) except at most :data:`NEIGHBOUR_BIN_FRACTION`
    of the pixels, and each of those shows the value of a neighbouring bin (one index apart on each axis).
    """
    height, width = gl.shape[:2]
    compared = compared_pixels(view, width, height)
    L, V, N, X, Y, inside, factor = brdf_view_geometry(view, width, height, light)
    allowed = BRDF_TOLERANCE.allowed(reference)
    off = compared & (np.abs(gl - reference).max(axis=-1) > allowed)
    assert off.mean() <= NEIGHBOUR_BIN_FRACTION, f"{view}: {off.mean():.3%} of the pixels differ"
    if not off.any():
        return
    local = lambda d: np.stack([np.sum(d * a, axis=-1) for a in (X[off], Y[off], N[off])], axis=-1)  # noqa: E731
    index = np.stack(merl_index(*merl_half_diff(local(L[off].astype(np.float64)), local(V[off].astype(np.float64)))), axis=-1)
    table = material.measured.rgb.astype(np.float64)
    best = np.full(index.shape[0], np.inf)
    for step in np.stack(np.meshgrid(*[(-1, 0, 1)] * 3, indexing="ij"), axis=-1).reshape(-1, 3):
        i = np.clip(index + step, 0, np.array(table.shape[:3]) - 1)
        candidate = table[i[:, 0], i[:, 1], i[:, 2]] * factor[off][:, None]
        best = np.minimum(best, np.abs(gl[off] - candidate).max(axis=-1))
    assert (best <= allowed[off]).all(), f"{view}: a pixel matches no neighbouring bin"


@pytest.mark.gl
@pytest.mark.parametrize("view", ["lit", "slice", "scatter"])
def test_gl_lookup_equals_the_numpy_twin(gl_renderer, analytic_material, view):
    from explorer.views.render import render_numpy

    light = LIGHTS.get(view)
    gl = gl_renderer.render(analytic_material, {}, view, 96, 96, light=light)
    reference = render_numpy(model_for(analytic_material, {}), view, 96, 96, light=light)
    assert np.abs(reference).max() > 0.1
    assert_lookup_twins(gl.astype(np.float64), reference.astype(np.float64), analytic_material, view, light)


@pytest.mark.gl
def test_env_view_converges_to_the_numpy_integral(gl_renderer, analytic_material):
    from test_env import HANDFUL, HANDFUL_MAX_Z, STACK_SIZE, smooth_environment, z_scores

    z, within, mean, exact = z_scores(gl_renderer, analytic_material, {}, smooth_environment(), STACK_SIZE, 1024, pixels=HANDFUL)
    assert np.abs(exact).max() > 0.05
    assert within.mean() >= 0.9 and np.abs(z).max() <= HANDFUL_MAX_Z, f"z = {z.round(2).tolist()}"


def test_cli_numpy_render_and_colour_views(tmp_path, analytic_file):
    out = tmp_path / "lit.npy"
    run = run_cli("render", analytic_file, "--view", "lit", "--size", "24", "--engine", "numpy", "--out", out)
    assert run.returncode == 0, run.stderr
    assert np.load(out).max() > 0.1
    line = one_line_error(run_cli("render", analytic_file, "--view", "sphere", "--out", tmp_path / "s.png"))
    assert "measured BRDF" in line and "lit" in line


@pytest.mark.gl
def test_cli_gl_render_equals_numpy(tmp_path, analytic_file, analytic_material):
    out = tmp_path / "lit.npy"
    # The light alone (--fill 0): each pixel is then one bin's value, as assert_lookup_twins matches them.
    run = run_cli_process("render", analytic_file, "--view", "lit", "--size", "48", "--fill", "0", "--out", out)
    assert run.returncode == 0, run.stderr
    from explorer.views.render import render_numpy

    reference = render_numpy(model_for(analytic_material, {}), "lit", 48, 48)
    assert_lookup_twins(np.load(out).astype(np.float64), reference.astype(np.float64), analytic_material, "lit", None)
