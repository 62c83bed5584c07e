"""The env view: the environment map, the sampling functions and their GLSL twins, the progressive
Monte Carlo estimate against the numpy integral, and the command line's bad input.

The convergence tests compare, per pixel and channel, the GPU mean after N samples with the exact
integral (:func:`explorer.views.env.env_integral_numpy`) in units of the estimate's own standard error,
z = (mean - integral) / SE. Over an unbiased estimate with a Gaussian mean, z is standard normal: 99.73 %
within 3, none of a few hundred beyond 5, mean 0. The environment of these tests is smooth (a sky
gradient and a broad glow), so the mean is close to Gaussian after a few thousand samples and the
quadrature is accurate; under the default environment's sun the estimate is heavy-tailed (rare
samples that hit the sun) and z is not Gaussian at these sample counts. Seeds are fixed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli, run_cli_process
from explorer.physics import microfacet
from explorer.views.env import (
    DEFAULT_ENVIRONMENT, EnvironmentFileError, EnvironmentMap, direction_to_uv, env_integral_numpy,
    generate_default_environment, pcg4d, quadrature_subdivisions, sample_cosine_hemisphere, uniform_floats,
    uv_to_direction,
)
from explorer.gpu.env import ProgressiveEnvRender
from explorer.views.geometry import brdf_view_geometry, rim_distance
from explorer.views.twin_check import smooth_environment  # the env comparisons' sky, shared with check

GGX = REPO_ROOT / "shaders" / "ggx_schlick.brd"
LAYER = REPO_ROOT / "shaders" / "bragg_layer.brd"

#: Image size and samples per pixel of the convergence tests (about 200 pixels inside the disc).
CONVERGENCE_SIZE = 16
CONVERGENCE_SPP = 4096
#: Fraction of (pixel, channel) within 3 SE at least (99.73 % expected; 0.98 is > 4 binomial sigmas below).
WITHIN_3SE = 0.98
#: No |z| beyond this (P(|z| > 5.5) ~ 4e-8 per value).
MAX_Z = 5.5
#: |mean z| at most: a bias of a quarter of a standard error over ~200 pixels would show (~3.5 sigmas).
MEAN_Z = 0.25
#: Densities integrated over a 1000 x 2000 grid of the sphere: absolute tolerance (the midpoint rule is
#: first order where the density jumps to 0, where the half vector crosses the horizon: 1.4e-3 at alpha = 1).
QUADRATURE_ATOL = 2e-3
#: The quadrature's own error, relative (measured: < 2e-4 against twice the subdivisions).
QUADRATURE_RTOL = 1e-3
#: RGBE stores 8-bit mantissas: relative precision 2^-7 of a texel's largest channel.
RGBE_RTOL = 2.0**-7
#: The default environment file stays small.
DEFAULT_MAX_BYTES = 300_000
#: float32 GLSL against float64 numpy: sampled directions (absolute), densities (relative above 1e-3).
SAMPLE_ATOL = 2e-3
PDF_RTOL = 2e-3


@pytest.fixture(scope="module")
def smooth():
    return smooth_environment()


def load(path, overrides=None):
    from explorer.materials.brd import load_material

    material = load_material(path)
    return material, material.resolve(overrides or {})


def without_hook(path: Path, directory: Path):
    """A copy of a material whose sampling hook is off (the hook function stays, unused): cosine sampling."""
    from explorer.materials.brd import load_material

    text = path.read_text()
    assert "#define HAS_SAMPLING_LOBES" in text
    copy = directory / path.name
    copy.write_text(text.replace("#define HAS_SAMPLING_LOBES", "// (hook off)"))
    return load_material(copy)


def progressive_mean(renderer, material, values, environment, size, spp, **options):
    """The env view's mean and standard error (float64) after ``spp`` samples per pixel; ``options`` go to the render."""
    render = ProgressiveEnvRender(renderer, material, values, environment, size, size, **options)
    try:
        render.step(spp)
        return render.image().astype(np.float64), render.standard_error().astype(np.float64)
    finally:
        render.release()


def z_scores(renderer, material, values, environment, size, spp, seed=0, pixels=None):
    """z per (pixel, channel) inside the disc (or at ``pixels``), the within-tolerance mask, the mean and the integral."""
    from explorer.materials.models import model_for

    render = ProgressiveEnvRender(renderer, material, values, environment, size, size, seed=seed)
    try:
        render.step(spp)
        mean, se = render.image().astype(np.float64), render.standard_error().astype(np.float64)
        assert render.dropped_samples() == 0
    finally:
        render.release()
    inside = brdf_view_geometry("lit", size, size)[5]
    if pixels is not None:
        rows, columns = np.asarray(pixels).T
        mean, se, inside = mean[rows, columns], se[rows, columns], inside[rows, columns]
        exact = env_integral_numpy(model_for(material, values), environment, size, size, pixels)
    else:
        exact = env_integral_numpy(model_for(material, values), environment, size, size).astype(np.float64)
    tolerance = 3.0 * se + QUADRATURE_RTOL * np.abs(exact)
    z = (mean - exact) / np.maximum(se, 1e-30)
    return z[inside], (np.abs(mean - exact) <= tolerance)[inside], mean, exact


# -- directions and the environment ---------------------------------------------------------------------


def test_direction_convention():
    u, v = direction_to_uv(np.array([[0, 0, -1], [1, 0, 0], [0, 0, 1], [-1, 0, 0], [0, 1, 0]], float))
    np.testing.assert_allclose(u[:2], [0.5, 0.75])
    assert u[2] in (0.0, 1.0)  # the seam, behind the sphere's centre as seen from it: toward the viewer
    np.testing.assert_allclose(u[3], 0.25)
    np.testing.assert_allclose(v, [0.5, 0.5, 0.5, 0.5, 0.0], atol=1e-12)
    rng = np.random.default_rng(3)
    d = rng.normal(size=(1000, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    np.testing.assert_allclose(uv_to_direction(*direction_to_uv(d)), d, atol=1e-12)


def test_quadrature_solid_angles_and_constant_environment():
    environment = EnvironmentMap(np.ones((8, 16, 3), np.float32))
    directions, solid_angle, radiance = environment.quadrature(2)
    assert solid_angle.sum() == pytest.approx(4.0 * np.pi, rel=1e-12)
    np.testing.assert_allclose(radiance, 1.0)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=-1), 1.0)


def test_bilinear_lookup_matches_texels_at_their_centres():
    rng = np.random.default_rng(1)
    pixels = rng.random((6, 10, 3)).astype(np.float32)
    environment = EnvironmentMap(pixels)
    u = (np.arange(10) + 0.5) / 10
    v = (np.arange(6) + 0.5) / 6
    np.testing.assert_allclose(environment.radiance_uv(u[None, :], v[:, None]), pixels, atol=1e-7)
    # Wraps in u: halfway between the last and the first column.
    np.testing.assert_allclose(environment.radiance_uv(np.zeros(6), v), 0.5 * (pixels[:, 0] + pixels[:, -1]), atol=1e-7)
    # Clamps in v: above the first row's centre is the first row.
    np.testing.assert_allclose(environment.radiance_uv(u, np.zeros(10)), pixels[0], atol=1e-7)


def test_lambertian_integral_of_a_uniform_environment():
    """A white Lambertian sphere under radiance 1 everywhere reflects 1 at every pixel (the quadrature)."""

    class White:
        def brdf(self, L, V, N, X, Y):
            return np.full(np.shape(L)[:-1] + (3,), 1.0 / np.pi)

    environment = EnvironmentMap(np.ones((16, 32, 3), np.float32))
    values = env_integral_numpy(White(), environment, 8, 8, pixels=[(4, 4), (1, 3), (7, 7)])
    np.testing.assert_allclose(values[:2], 1.0, rtol=1e-3)
    np.testing.assert_array_equal(values[2], 0.0)  # outside the disc


def test_default_environment_is_its_generator():
    environment = EnvironmentMap.default()
    expected = generate_default_environment()
    assert environment.pixels.shape == expected.shape == (128, 256, 3)
    scale = expected.max(axis=-1, keepdims=True)
    assert (np.abs(environment.pixels - expected) <= RGBE_RTOL * scale).all()
    assert DEFAULT_ENVIRONMENT.stat().st_size < DEFAULT_MAX_BYTES


def test_exr_and_hdr_load_as_written(tmp_path):
    from explorer.views.env import _cv2

    cv2 = _cv2()
    image = smooth_environment(16, 8).pixels
    assert cv2.imwrite(str(tmp_path / "sky.exr"), image[:, :, ::-1])
    np.testing.assert_array_equal(EnvironmentMap.load(tmp_path / "sky.exr").pixels, image)
    assert cv2.imwrite(str(tmp_path / "sky.hdr"), image[:, :, ::-1])
    loaded = EnvironmentMap.load(tmp_path / "sky.hdr").pixels
    assert (np.abs(loaded - image) <= RGBE_RTOL * image.max(axis=-1, keepdims=True)).all()


@pytest.mark.parametrize("case", ["missing", "text", "png", "directory", "empty exr"])
def test_bad_environment_files_are_one_line_errors(tmp_path, case):
    path = {"missing": tmp_path / "missing.hdr", "text": tmp_path / "notes.hdr", "png": tmp_path / "grey.png",
            "directory": tmp_path / "folder.hdr", "empty exr": tmp_path / "empty.exr"}[case]
    if case == "text":
        path.write_text("not an image\n")
    elif case == "png":
        from PIL import Image

        Image.fromarray(np.zeros((4, 8), np.uint8)).save(path)
    elif case == "directory":
        path.mkdir()
    elif case == "empty exr":
        path.write_bytes(b"")
    with pytest.raises(EnvironmentFileError) as error:
        EnvironmentMap.load(path)
    assert str(path) in str(error.value) and "\n" not in str(error.value)


def test_non_finite_environment_is_refused():
    pixels = np.ones((4, 8, 3), np.float32)
    pixels[1, 2, 0] = np.inf
    with pytest.raises(EnvironmentFileError, match="non-finite"):
        EnvironmentMap(pixels)


# -- sampling in numpy -------------------------------------------------------------------------------


def sphere_grid(n: int = 1000):
    theta = (np.arange(n) + 0.5) / n * np.pi
    phi = (np.arange(2 * n) + 0.5) / (2 * n) * 2.0 * np.pi
    theta, phi = np.meshgrid(theta, phi, indexing="ij")
    directions = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    return directions, np.sin(theta) * (np.pi / n) ** 2


@pytest.mark.parametrize("alpha", [0.05, 0.3, 1.0])
@pytest.mark.parametrize("theta_v", [0.1, 1.0, 1.5])
def test_vndf_densities_integrate_to_one(alpha, theta_v):
    v = np.array([np.sin(theta_v) * np.cos(0.4), np.sin(theta_v) * np.sin(0.4), np.cos(theta_v)])
    directions, weights = sphere_grid()
    assert np.sum(microfacet.ggx_visible_normal_pdf(v, directions, alpha) * weights) == pytest.approx(1.0, abs=QUADRATURE_ATOL)
    assert np.sum(microfacet.ggx_reflection_pdf(directions, v, alpha) * weights) == pytest.approx(1.0, abs=QUADRATURE_ATOL)


@pytest.mark.parametrize("alpha", [0.1, 0.5])
def test_vndf_samples_follow_their_density(alpha):
    """A histogram of reflected directions over (cos theta, phi) bins against the density's integral per bin."""
    rng = np.random.default_rng(7)
    count = 400_000
    v = np.array([np.sin(0.9), 0.0, np.cos(0.9)])
    m = microfacet.sample_ggx_visible_normal(np.broadcast_to(v, (count, 3)), alpha, rng.random(count), rng.random(count))
    assert (m[:, 2] >= 0.0).all()
    np.testing.assert_allclose(np.linalg.norm(m, axis=-1), 1.0)
    assert (np.sum(m * v, axis=-1) >= -1e-12).all()  # visible normals only
    l = 2.0 * np.sum(m * v, axis=-1, keepdims=True) * m - v
    edges_z, edges_phi = np.linspace(-1.0, 1.0, 21), np.linspace(-np.pi, np.pi, 25)
    histogram, _, _ = np.histogram2d(l[:, 2], np.arctan2(l[:, 1], l[:, 0]), bins=(edges_z, edges_phi))
    # Expected counts: the density integrated over each bin (uniform in z and phi is uniform in solid angle).
    fine = 16
    z = edges_z[0] + (np.arange(20 * fine) + 0.5) * (2.0 / (20 * fine))
    phi = edges_phi[0] + (np.arange(24 * fine) + 0.5) * (2.0 * np.pi / (24 * fine))
    Z, P = np.meshgrid(z, phi, indexing="ij")
    s = np.sqrt(1.0 - Z * Z)
    pdf = microfacet.ggx_reflection_pdf(np.stack([s * np.cos(P), s * np.sin(P), Z], axis=-1), v, alpha)
    cell = (2.0 / (20 * fine)) * (2.0 * np.pi / (24 * fine))
    expected = count * (pdf * cell).reshape(20, fine, 24, fine).sum(axis=(1, 3))
    populated = expected > 50
    assert expected[populated].sum() > 0.95 * count
    # Poisson: within 5 standard deviations plus 1 % of the count (the midpoint rule's error per bin).
    assert (np.abs(histogram - expected)[populated] <= 5.0 * np.sqrt(expected[populated]) + 0.01 * expected[populated]).all()


def test_cosine_samples():
    rng = np.random.default_rng(2)
    d = sample_cosine_hemisphere(rng.random(200_000), rng.random(200_000))
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0)
    assert (d[:, 2] >= 0).all()
    assert d[:, 2].mean() == pytest.approx(2.0 / 3.0, abs=3e-3)  # E[cos] under cos / pi


def test_pcg4d_is_uniform():
    grid = np.stack(np.meshgrid(np.arange(64), np.arange(64), [3], [5], indexing="ij"), axis=-1).reshape(-1, 4)
    u = uniform_floats(pcg4d(grid))
    assert ((u >= 0.0) & (u < 1.0)).all()
    histogram = np.histogram(u, bins=16, range=(0.0, 1.0))[0]
    expected = u.size / 16
    assert (np.abs(histogram - expected) < 5.0 * np.sqrt(expected)).all()


# -- the GLSL twins ----------------------------------------------------------------------------------

PROBE_SIZE = 32
PROBE = """#include "lib/sampling.glsl"
uniform vec3 view;
uniform float alpha;
layout(location = 0) out vec4 sample_out;
layout(location = 1) out vec4 pdf_out;
layout(location = 2) out vec4 hash_out;
void main() {
    vec2 u = gl_FragCoord.xy / SIZE;  // pixel centres: (i + 0.5) / SIZE
    vec3 m = sample_ggx_visible_normal(view, alpha, u);
    vec3 c = sample_cosine_hemisphere(u);
    float theta = radians(179.0) * u.x, phi = 6.2831853 * u.y;
    vec3 l = vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
    sample_out = vec4(m, c.z);
    pdf_out = vec4(ggx_reflection_pdf(l, view, vec3(0.0, 0.0, 1.0), alpha), ggx_visible_normal_pdf(view, l, alpha), c.xy);
    hash_out = uniform_floats(pcg4d(uvec4(uvec2(gl_FragCoord.xy), 7u, 11u)));
}
"""


def run_probe(renderer, view, alpha):
    from explorer.materials.glsl import ShaderBuilder
    from explorer.gpu.context import VERTEX_SHADER
    from explorer.resources import SHADER_DIR

    ctx = renderer.ctx

    builder = ShaderBuilder(include_dirs=[SHADER_DIR])
    builder.define("SIZE", f"{PROBE_SIZE:.1f}")
    builder.add_source(PROBE, "probe")
    program = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=builder.build().code)
    targets = [ctx.renderbuffer((PROBE_SIZE, PROBE_SIZE), 4, dtype="f4") for _ in range(3)]
    framebuffer = ctx.framebuffer(color_attachments=targets)
    try:
        renderer.draw(program, framebuffer, uniforms={"view": tuple(float(c) for c in view), "alpha": alpha})
        return [np.frombuffer(framebuffer.read(components=4, attachment=k, dtype="f4"), np.float32)
                .reshape(PROBE_SIZE, PROBE_SIZE, 4).astype(np.float64) for k in range(3)]
    finally:
        for target in targets:
            target.release()
        framebuffer.release()
        program.release()


@pytest.mark.gl
@pytest.mark.parametrize("alpha", [0.02, 0.2, 0.8])
@pytest.mark.parametrize("theta_v", [0.0, 0.7, 1.5])
def test_sampling_glsl_equals_numpy(gl_renderer, alpha, theta_v):
    view = np.array([np.sin(theta_v) * np.cos(1.1), np.sin(theta_v) * np.sin(1.1), np.cos(theta_v)], np.float32)
    samples, pdfs, hashes = run_probe(gl_renderer, view, alpha)
    centre = (np.arange(PROBE_SIZE) + 0.5) / PROBE_SIZE
    u1, u2 = np.meshgrid(centre, centre)  # row = gl_FragCoord.y
    v = view.astype(np.float64)
    m = microfacet.sample_ggx_visible_normal(np.broadcast_to(v, u1.shape + (3,)), alpha, u1, u2)
    assert np.abs(samples[..., :3] - m).max() < SAMPLE_ATOL
    c = sample_cosine_hemisphere(u1, u2)
    assert np.abs(np.concatenate([pdfs[..., 2:], samples[..., 3:]], axis=-1) - c).max() < SAMPLE_ATOL
    theta, phi = np.radians(179.0) * u1, 2.0 * np.pi * u2
    l = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    expected = np.stack([microfacet.ggx_reflection_pdf(l, v, alpha), microfacet.ggx_visible_normal_pdf(v, l, alpha)], axis=-1)
    error = np.abs(pdfs[..., :2] - expected) / np.maximum(np.abs(expected), 1e-3)
    assert error.max() < PDF_RTOL
    x, y = np.meshgrid(np.arange(PROBE_SIZE), np.arange(PROBE_SIZE))
    words = np.stack([x, y, np.full_like(x, 7), np.full_like(x, 11)], axis=-1)
    np.testing.assert_array_equal(hashes, uniform_floats(pcg4d(words)))  # bit for bit (24 bits a word)


# -- the Monte Carlo estimate ------------------------------------------------------------------------

CONVERGENCE_CASES = {
    "ggx alpha 0.3": (GGX, {"alpha": 0.3, "F0": 0.5}),
    "ggx alpha 0.1": (GGX, {"alpha": 0.1, "F0": 0.9}),
    "bragg layer": (LAYER, {"alpha": 0.2, "method": 3, "rho_d": (0.5, 0.3, 0.2)}),
}


@pytest.mark.gl
@pytest.mark.parametrize("case", list(CONVERGENCE_CASES))
def test_env_converges_to_the_numpy_integral(gl_renderer, smooth, case):
    path, overrides = CONVERGENCE_CASES[case]
    material, values = load(path, overrides)
    z, within, mean, exact = z_scores(gl_renderer, material, values, smooth, CONVERGENCE_SIZE, CONVERGENCE_SPP)
    assert z.size > 500
    assert np.isfinite(mean).all()
    assert within.mean() >= WITHIN_3SE, f"{within.mean():.4f} within 3 SE; |z| quantiles {np.quantile(np.abs(z), [0.5, 0.99])}"
    assert np.abs(z).max() <= MAX_Z, f"max |z| = {np.abs(z).max():.2f}"
    assert abs(z.mean()) <= MEAN_Z, f"mean z = {z.mean():.3f}"


#: The layered stack's BRDF is spectral: ~50 us a sample on llvmpipe (40 s for 4096 spp at 16^2) and
#: ~0.2 s a pixel for the quadrature, so an 8^2 image, 2048 spp, and a handful of its pixels (rows,
#: columns) across the disc, four near its rim.
STACK_SIZE, STACK_SPP = 8, 2048
HANDFUL = [(4, 4), (1, 3), (2, 1), (2, 6), (5, 1), (5, 6), (6, 4), (3, 7), (0, 3), (3, 0), (6, 2), (1, 5)]
#: Over a handful of values, every |z| below this (P(|z| > 4.5) ~ 7e-6 per value).
HANDFUL_MAX_Z = 4.5


@pytest.mark.gl
def test_env_converges_for_the_layered_stack(gl_renderer, smooth):
    """bragg_stack.brd (Eq. 34; two layers under a coating, over a base) and its Eq. 35 sampling hook."""
    overrides = {"layers": 2, "nh": 1.4, "coating": True, "rho_d": (0.3, 0.3, 0.3), "alpha_1": 0.2, "alpha_2": 0.3}
    material, values = load(REPO_ROOT / "shaders" / "bragg_stack.brd", overrides)
    z, within, mean, exact = z_scores(gl_renderer, material, values, smooth, STACK_SIZE, STACK_SPP, pixels=HANDFUL)
    assert z.shape == (len(HANDFUL), 3) and np.abs(exact).max() > 0.05
    assert within.mean() >= 0.9 and np.abs(z).max() <= HANDFUL_MAX_Z, f"z = {z.round(2).tolist()}"


@pytest.mark.gl
def test_env_converges_without_a_hook_for_brdf_explorer_files(gl_renderer, smooth):
    """BRDF Explorer's own files (which define PI and have no sampling hook) render by cosine sampling."""
    from brdf_twins import registered

    from conftest import BRDF_DATA

    with registered():
        # Ashikhmin-Shirley made broad (its default nu = 100, nv = 1000 is too sharp for cosine sampling to
        # reach a Gaussian mean at this sample count): still anisotropic, so X and Y matter.
        for name, overrides in (("colored_lambert.brdf", {}), ("ashikhmin_shirley.brdf", {"nu": 5, "nv": 30})):
            material, values = load(BRDF_DATA / name, overrides)
            z, within, _, _ = z_scores(gl_renderer, material, values, smooth, CONVERGENCE_SIZE, CONVERGENCE_SPP)
            assert within.mean() >= WITHIN_3SE and np.abs(z).max() <= MAX_Z and abs(z.mean()) <= MEAN_Z, name


def test_quadrature_is_converged(smooth):
    from explorer.materials.models import model_for

    pixels = [(8, 8), (3, 9), (12, 4), (8, 1)]
    for path, overrides in CONVERGENCE_CASES.values():
        material, values = load(path, overrides)
        model = model_for(material, values)
        s = quadrature_subdivisions(model, smooth)
        coarse = env_integral_numpy(model, smooth, CONVERGENCE_SIZE, CONVERGENCE_SIZE, pixels, subdivisions=s)
        fine = env_integral_numpy(model, smooth, CONVERGENCE_SIZE, CONVERGENCE_SIZE, pixels, subdivisions=2 * s)
        np.testing.assert_allclose(coarse, fine, rtol=QUADRATURE_RTOL / 2)


@pytest.mark.gl
def test_standard_error_shrinks_as_one_over_root_spp(gl_renderer, smooth):
    material, values = load(GGX, {"alpha": 0.3, "F0": 0.5})
    inside = brdf_view_geometry("lit", 16, 16)[5]
    errors = []
    for spp in (256, 4096):
        render = ProgressiveEnvRender(gl_renderer, material, values, smooth, 16, 16, seed=3)
        render.step(spp)
        errors.append(render.standard_error()[inside])
        render.release()
    ratio = np.median(errors[0] / errors[1])
    assert 3.6 <= ratio <= 4.4, f"SE(256) / SE(4096) = {ratio:.2f}, expected 4"


@pytest.mark.gl
@pytest.mark.parametrize("path, overrides, least", [
    (GGX, {"alpha": 0.1, "F0": 0.9}, 20.0),
    (LAYER, {"alpha": 0.1, "method": 3, "rho_d": (0.5, 0.3, 0.2)}, 3.0),
])
def test_importance_sampling_lowers_the_variance(gl_renderer, smooth, tmp_path, path, overrides, least):
    """The hook against cosine sampling alone, same material and samples: median variance ratio."""
    material, values = load(path, overrides)
    plain = without_hook(path, tmp_path)
    inside = brdf_view_geometry("lit", 16, 16)[5]
    variances = []
    for which in (material, plain):
        render = ProgressiveEnvRender(gl_renderer, which, values, smooth, 16, 16, seed=5)
        render.step(1024)
        variances.append(render.standard_error()[inside].astype(np.float64) ** 2)
        render.release()
    ratio = np.median(variances[1].mean(axis=-1) / variances[0].mean(axis=-1))
    assert ratio >= least, f"cosine / importance variance = {ratio:.1f}"


@pytest.mark.gl
@pytest.mark.parametrize("path, overrides", [
    (GGX, {"alpha": 0.0}), (GGX, {"alpha": 0.02}), (GGX, {"alpha": 1.0}),
    (LAYER, {"alpha": 0.05, "method": 4, "rho_d": 0.8}), (LAYER, {"alpha": 0.0, "method": 3}),
])
def test_no_nan_at_grazing_pixels(gl_renderer, path, overrides):
    """
    The default environment (its sun included), 64^2: every pixel finite and bounded, none dropped, the rim
    included. For alpha -> 0 the BRDF's D and the sampling density's D must round alike (a factor 1e10 apart
    otherwise). The bound: these materials reflect at most about all they receive (Bragg RGB may exceed
    1 a little per channel, out of gamut).
    """
    material, values = load(path, overrides)
    render = ProgressiveEnvRender(gl_renderer, material, values, EnvironmentMap.default(), 64, 64, seed=1)
    render.step(32)
    image, se = render.image(), render.standard_error()
    assert np.isfinite(image).all() and np.isfinite(se).all()
    assert render.dropped_samples() == 0
    inside = brdf_view_geometry("lit", 64, 64)[5]
    rim = inside & (rim_distance("env", 64, 64) < 0.1)
    assert rim.sum() > 20
    assert np.abs(image).max() <= 2.0 * float(EnvironmentMap.default().pixels.max())
    assert (image[~inside] == 0.0).all()
    render.release()


@pytest.mark.gl
def test_progressive_bookkeeping(gl_renderer, smooth):
    material, values = load(GGX, {"alpha": 0.3})
    render = ProgressiveEnvRender(gl_renderer, material, values, smooth, 12, 12, seed=9, pass_budget_ms=0.0)
    render.step(5)
    assert render.samples == 5 and render.passes == 5  # a zero budget: one sample per pass
    _, _, count, dropped = render.sums()
    assert (count == 5).all() and (dropped == 0).all()
    first = render.image()
    render.reset()
    assert render.samples == 0 and (render.image() == 0).all()
    render.samples_per_pass = 5
    render.step(5)
    assert render.passes == 1
    np.testing.assert_allclose(render.image(), first, rtol=1e-5, atol=1e-7)  # same numbers, another split
    render.reset({**values, "F0": 1.0})
    render.step(5)
    assert not np.allclose(render.image(), first)
    other = ProgressiveEnvRender(gl_renderer, material, values, smooth, 12, 12, seed=10)
    other.step(5)
    assert not np.allclose(other.image(), first)  # another seed, other numbers
    other.release()
    render.release()


# -- the command line --------------------------------------------------------------------------------




def test_cli_bad_environment_input(tmp_path):
    text = tmp_path / "notes.hdr"
    text.write_text("not an image\n")
    grey = tmp_path / "grey.png"
    from PIL import Image

    Image.fromarray(np.zeros((4, 8), np.uint8)).save(grey)
    out = tmp_path / "out.png"
    cases = {
        "missing": (["--env", tmp_path / "missing.hdr"], str(tmp_path / "missing.hdr")),
        "not an image": (["--env", text], str(text)),
        "not HDR": (["--env", grey], str(grey)),
        "spp 0": (["--spp", "0"], "--spp"),
        "spp not a number": (["--spp", "many"], "--spp"),
    }
    runs = {name: run_cli("render", GGX, "--view", "env", "--size", "8", "--engine", "numpy", "--out", out, *args)
            for name, (args, _) in cases.items()}
    runs["--spp on lit"] = run_cli("render", GGX, "--view", "lit", "--size", "8", "--spp", "4", "--out", out)
    cases["--spp on lit"] = ([], "--view")
    for name, (_, named) in cases.items():
        line = one_line_error(runs[name])
        assert named in line, f"{name}: {line}"
        assert not out.exists(), name
    assert sorted(p.name for p in tmp_path.iterdir()) == ["grey.png", "notes.hdr"]


@pytest.mark.gl
def test_cli_env_with_an_exr(gl_renderer, tmp_path):
    from explorer.views.env import _cv2

    environment = tmp_path / "sky.exr"
    assert _cv2().imwrite(str(environment), smooth_environment(32, 16).pixels[:, :, ::-1])
    out = tmp_path / "env.npy"
    run = run_cli_process("render", GGX, "--view", "env", "--env", environment, "--spp", "16", "--size", "20", "--out", out)
    assert run.returncode == 0, run.stderr
    image = np.load(out)
    assert image.shape == (20, 20, 3) and np.isfinite(image).all()
    inside = brdf_view_geometry("lit", 20, 20)[5]
    assert (image[inside].max(axis=-1) > 0).all() and (image[~inside] == 0).all()


@pytest.mark.gl
def test_advance_in_bands_equals_whole_passes(gl_renderer):
    """advance() with a budget below one sample's cost works in bands of rows: same samples, same image."""
    from explorer.materials.brd import load_material
    from explorer.views.env import EnvironmentMap
    from explorer.gpu.env import ProgressiveEnvRender

    material = load_material(REPO_ROOT / "shaders" / "ggx_schlick.brd")
    values = material.resolve({"alpha": 0.3})
    environment = EnvironmentMap.default()
    whole = ProgressiveEnvRender(gl_renderer, material, values, environment, 24, 20, seed=3)
    whole.step(3)
    banded = ProgressiveEnvRender(gl_renderer, material, values, environment, 24, 20, seed=3)
    real_pass = banded._pass

    def slow_pass(bindings, count, rows=None):  # pretend each row costs 5 ms: a sample, 100 ms
        real_pass(bindings, count, rows)
        return 5.0 * ((rows[1] - rows[0]) if rows is not None else banded.height) * count

    banded._pass = slow_pass
    calls = 0
    while banded.samples < 3:
        banded.advance(10.0)
        calls += 1
        assert calls < 500
    assert calls > 3, "advance did not split samples into bands"
    np.testing.assert_allclose(banded.image(), whole.image(), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(banded.standard_error(), whole.standard_error(), rtol=1e-4, atol=1e-6)
    whole.release()
    banded.release()


@pytest.mark.gl
def test_advance_keeps_every_frame_to_its_budget(gl_renderer):
    """
    A sample's cost lies in the disc's pixels, not its rows: advance() sizes its bands by them, so that no
    call (the first, a probe, included) overruns its budget by more than one row, however cheap the top rows.
    """
    from explorer.materials.brd import load_material
    from explorer.views.env import EnvironmentMap
    from explorer.views.geometry import disc
    from explorer.gpu.env import ProgressiveEnvRender

    material = load_material(REPO_ROOT / "shaders" / "ggx_schlick.brd")
    size, per_pixel, budget = 64, 0.05, 10.0  # a sample: ~160 ms of pretended work
    render = ProgressiveEnvRender(gl_renderer, material, material.resolve({}), EnvironmentMap.default(), size, size)
    inside = (disc(size, size)[2] < np.float32(1.0)).sum(axis=1)
    real_pass, spent = render._pass, []

    def costly_pass(bindings, count, rows=None):
        real_pass(bindings, count, rows)
        top, bottom = rows if rows is not None else (0, size)
        spent.append(per_pixel * count * float(inside[top:bottom].sum()))
        return spent[-1]

    render._pass = costly_pass
    calls = 0
    while render.samples < 2:
        spent.clear()
        render.advance(budget)
        calls += 1
        assert sum(spent) <= budget + per_pixel * size, (calls, spent)
        assert calls < 200
    assert calls >= 2 * per_pixel * inside.sum() / budget  # no frame did more than its budget's share
    render.release()


@pytest.mark.gl
def test_coating_mirror_reflection_is_added_exactly(gl_renderer):
    """A coated stack whose layer is invisible (n2 = n1 = nh) and base black shows only the coating's Dirac: F Le(R)."""
    from explorer.materials.brd import load_material
    from explorer.views.env import EnvironmentMap
    from explorer.gpu.env import ProgressiveEnvRender
    from explorer.materials.models import model_for
    from explorer.views.geometry import brdf_view_geometry

    material = load_material(REPO_ROOT / "shaders" / "bragg_stack.brd")
    values = material.resolve({"nh": 1.5, "n1_1": 1.5, "n2_1": 1.5, "rho_d": 0})
    environment = EnvironmentMap.default()
    render = ProgressiveEnvRender(gl_renderer, material, values, environment, 16, 16)
    render.step(2)
    image = render.image()
    render.release()
    _, V, N, _, _, inside, _ = brdf_view_geometry("lit", 16, 16)
    v, n = V[inside].astype(np.float64), N[inside].astype(np.float64)
    expected = model_for(material, values).mirror_reflection(v, n) * environment.radiance(2.0 * np.sum(v * n, -1, keepdims=True) * n - v)
    assert expected.max() > 0.01
    np.testing.assert_allclose(image[inside], expected, rtol=2e-3, atol=1e-5)
    uncoated = material.resolve({**values, "coating": False})
    render = ProgressiveEnvRender(gl_renderer, material, uncoated, environment, 16, 16)
    render.step(2)
    assert np.abs(render.image()).max() < 1e-6  # no coating, an invisible layer, a black base: black
    render.release()


@pytest.mark.gl
@pytest.mark.parametrize("method", [1, 3])
def test_smooth_mirror_is_a_dirac_in_the_env_view(gl_renderer, method):
    """A smooth Bragg mirror under an environment shows R(V.N) Le(reflect(-V, N)) and nothing else, in GL and numpy."""
    from explorer.materials.brd import load_material
    from explorer.views.env import EnvironmentMap, env_integral_numpy
    from explorer.materials.models import model_for

    material = load_material(REPO_ROOT / "shaders" / "bragg_mirror.brd")
    values = material.resolve({"method": method})
    environment = EnvironmentMap.default()
    render = ProgressiveEnvRender(gl_renderer, material, values, environment, 16, 16)
    render.step(2)
    image = render.image()
    render.release()
    model = model_for(material, values)
    _, V, N, _, _, inside, _ = brdf_view_geometry("lit", 16, 16)
    v, n = V[inside].astype(np.float64), N[inside].astype(np.float64)
    expected = model.reflectance(np.sum(v * n, -1)) * environment.radiance(2.0 * np.sum(v * n, -1, keepdims=True) * n - v)
    assert expected.max() > 0.05
    np.testing.assert_allclose(image[inside], expected, rtol=3e-3, atol=2e-4)
    np.testing.assert_allclose(env_integral_numpy(model, environment, 16, 16)[inside], expected, rtol=1e-6, atol=1e-7)


@pytest.mark.gl
@pytest.mark.parametrize("declaration", ["const float PI = 3.14159265358979323846;", "#define PI 3.14159265358979323846"])
def test_brdf_explorer_pi_does_not_clash_with_the_library(gl_renderer, tmp_path, declaration):
    """BRDF Explorer files declare PI (a const or a macro) before the env view includes the GGX library."""
    from conftest import BRDF_DATA
    from explorer.views.env import EnvironmentMap

    text = (BRDF_DATA / "lambert.brdf").read_text()
    assert "const float PI = 3.14159265358979323846;" in text
    path = tmp_path / "lambert_pi.brdf"
    path.write_text(text.replace("const float PI = 3.14159265358979323846;", declaration))
    material, values = load(path)
    render = ProgressiveEnvRender(gl_renderer, material, values, EnvironmentMap.default(), 8, 8)
    render.step(4)
    image = render.image()
    render.release()
    assert np.isfinite(image).all() and image.max() > 0.0
