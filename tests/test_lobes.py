"""The layered lobes model (explorer.physics.lobes, shaders/layered_lobes.brd): Belcour 2018 as in Bati et al. 2021, Sec. 4.

Independent references: ``tmm.inc_tmm`` (incoherent multilayers) for smooth stacks, a brute-force
integration of the GGX BRDF over outgoing directions for the FGD table. GL against the numpy twin with
tests/twins.py's BRDF_TOLERANCE (2e-3 of a pixel's largest channel), the gradient included.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, seed, settings
from hypothesis import strategies as st

from conftest import REPO_ROOT
from explorer.dev.validation_studies import FURNACE_STACKS, GL_STACKS, brute_force_fgd, hemisphere
from explorer.dev.validation_studies import tmm_incoherent_reflectance as tmm_reflectance
from explorer.physics import lobes
from explorer.materials.brd import load_material
from explorer.views.env import EnvironmentMap, env_integral_numpy
from explorer.gpu.env import ProgressiveEnvRender
from explorer.materials.models import model_for
from explorer.views.geometry import brdf_view_geometry
from test_brdf_views import SIZE
from twins import BRDF_TOLERANCE, LIGHTS, assert_twins_equal, render_both

MATERIAL = REPO_ROOT / "shaders" / "layered_lobes.brd"
#: Smooth stacks against tmm's incoherent multilayer, every angle, within this.
TMM_TOLERANCE = 1e-3
#: The FGD table (trilinear, 48^2 quadrature) against a brute-force integral off the table's nodes, more
#: than alpha from a critical angle (within it, at alpha < 0.1, the table's alpha rows 0 and 1/15 miss the
#: sharp rise of TIR: up to 0.17 at alpha = 0.02, 0.07 at alpha = 0.05, eta = 0.8; and for
#: 0.92 < eta < 1, interpolated towards the all-zero eta = 1 row, up to 0.28 below the critical angle).
FGD_TOLERANCE = 5e-3
#: Just past a critical angle (alpha >= 0.1), where the table's coordinate follows sqrt(cos theta - cos theta_c):
#: linear in cos theta there, 0.3 (explorer.physics.lobes_fgd.fgd_cos_coordinate).
FGD_CRITICAL_TOLERANCE = 2e-2
#: White furnace: the albedo may not exceed 1 by more than the quadrature's error.
FURNACE_SLACK = 2e-3


THETAS = np.radians(np.linspace(0.0, 89.0, 46))


@pytest.mark.parametrize("etas, taus", [
    ([1.0, 1.5, 1.2, 2.0], [0.3, 0.1]),  # eta decreasing then increasing: TIR at the second interface
    ([1.0, 2.5, 1.0, 1.5], [0.0, 0.7]),  # an air gap
    ([1.0, 1.33], []),
])
@pytest.mark.parametrize("tir", [False, True])
def test_smooth_dielectric_stack_equals_incoherent_tmm(etas, taus, tir):
    stack = lobes.make_stack(etas[1:], [0.0] * (len(etas) - 1), tau=taus, tir=tir)
    ours = lobes.reflectance(stack, np.cos(THETAS))
    reference = np.array([tmm_reflectance(etas, taus, t) for t in THETAS])
    error = np.abs(ours - reference[:, None]).max()
    assert error <= TMM_TOLERANCE, f"max |lobes - inc_tmm| = {error:.2e}"
    assert np.ptp(ours, axis=-1).max() < 1e-12, "achromatic stack, coloured result"


def test_smooth_coated_conductor_equals_incoherent_tmm():
    eta, kappa, tau = [0.2, 0.4, 1.1], [3.5, 2.5, 2.0], [0.1, 0.2, 0.3]
    stack = lobes.make_stack([1.5, eta], [0.0, 0.0], tau=[tau], base_kappa=kappa)
    ours = lobes.reflectance(stack, np.cos(THETAS))
    for ch in range(3):
        reference = np.array([tmm_reflectance([1.0, 1.5, eta[ch]], [tau[ch]], t, kappa[ch]) for t in THETAS])
        error = np.abs(ours[:, ch] - reference).max()
        assert error <= TMM_TOLERANCE, f"channel {ch}: max |lobes - inc_tmm| = {error:.2e}"


@pytest.mark.parametrize("cos_theta, alpha, eta", [
    (0.93, 0.23, 1.37), (0.41, 0.55, 1.9), (0.77, 0.35, 0.71), (0.6, 0.1, 0.8), (0.3, 0.7, 0.5), (0.076, 0.28, 2.15),
])
def test_fgd_table_against_brute_force_integral(cos_theta, alpha, eta):
    """Unpolarised: the table corrects both polarisations alike (a microfacet's s and p are not the surface's)."""
    ours = lobes.fgd_dielectric(cos_theta, alpha, eta).mean(axis=0)
    reference = brute_force_fgd(cos_theta, alpha, eta).mean(axis=0)
    assert abs(ours - reference) <= FGD_TOLERANCE, (ours, reference)


@pytest.mark.parametrize("alpha, eta", [(0.1, 0.8), (0.2, 0.8), (0.15, 0.5)])
def test_fgd_table_just_past_the_critical_angle(alpha, eta):
    """From the denser side, within alpha of the critical angle: TIR's rise smoothed by the roughness."""
    c_c = np.sqrt(1.0 - eta**2)
    for cos_theta in (c_c - 0.3 * alpha, c_c + 0.01, c_c + 0.3 * alpha):
        ours = lobes.fgd_dielectric(cos_theta, alpha, eta).mean(axis=0)
        reference = brute_force_fgd(cos_theta, alpha, eta, count=300).mean(axis=0)
        assert abs(ours - reference) <= FGD_CRITICAL_TOLERANCE, (cos_theta, ours, reference)


def test_fgd_conductor_moment_approximation():
    """E F(cbar_d) against the brute-force integral: a rough gold-like conductor at three angles."""
    for cos_theta in (0.95, 0.6, 0.3):
        ours = lobes.fgd_conductor(cos_theta, 0.4, 0.4, 2.5).mean(axis=0)
        reference = brute_force_fgd(cos_theta, 0.4, 0.4, 2.5).mean(axis=0)
        assert abs(ours - reference) <= FGD_TOLERANCE, (cos_theta, ours, reference)


def test_roughness_variance_mapping_inverts():
    alpha = np.linspace(0.0, 0.99, 50)
    np.testing.assert_allclose(lobes.roughness_from_variance(lobes.variance_from_roughness(alpha)), alpha, atol=1e-12)


def test_two_interfaces_follow_eq5_at_normal_incidence():
    """Lobe 2's variance at theta = 0 is Eq. 5 with the unitary operators of Eq. 6, written out here."""
    eta_1, eta_2, alpha_1, alpha_2, tau_1 = 1.6, 1.2, 0.2, 0.35, 0.25
    stack = lobes.make_stack([eta_1, eta_2], [alpha_1, alpha_2], tau=[tau_1])
    energies, variances = lobes.lobes(stack, 1.0)
    f = lobes.variance_from_roughness
    s_t01, s_t10, s_r10 = f(0.5 * abs(1 - 1 / eta_1) * alpha_1), f(0.5 * abs(1 - eta_1) * alpha_1), f(alpha_1)
    R_01 = lobes.fgd_dielectric(1.0, alpha_1, eta_1).mean(axis=0)
    R_12 = lobes.fgd_dielectric(1.0, lobes.roughness_from_variance(f(alpha_2) + s_t01), eta_2 / eta_1).mean(axis=0)
    R_12_attenuated = R_12 * np.exp(-2 * tau_1)
    sigma_02 = s_t10 + eta_1 * (s_t01 + (f(alpha_2) + R_12_attenuated * R_01 * s_r10) / (1 - R_12_attenuated * R_01))
    energy_2 = (1 - R_01) ** 2 * R_12_attenuated / (1 - R_12_attenuated * R_01)  # Eq. 2's second term
    np.testing.assert_allclose(variances[1], sigma_02, rtol=1e-9)  # (lobes, RGB) at one angle
    np.testing.assert_allclose(energies[1], energy_2, rtol=1e-9)
    np.testing.assert_allclose(variances[0], f(alpha_1), rtol=1e-12)


@pytest.mark.parametrize("overrides", FURNACE_STACKS)  # the brightest, a bare conductor at alpha = 0.2: 0.89
def test_white_furnace_at_most_one(overrides):
    material = load_material(MATERIAL)
    model = model_for(material, material.resolve(overrides))
    o, d_omega = hemisphere(96)
    for cos_theta in (1.0, 0.7, 0.3, 0.05):
        L = np.array([np.sqrt(1 - cos_theta**2), 0.0, cos_theta])
        albedo = (model.brdf(L, o, np.array([0.0, 0.0, 1.0]), None, None) * (o[:, 2] * d_omega)[:, None]).sum(axis=0)
        assert albedo.max() <= 1.0 + FURNACE_SLACK, f"cos theta {cos_theta}: albedo {albedo}"
        assert lobes.reflectance(model.stack, cos_theta).max() <= 1.0 + 1e-12


def test_reciprocal_where_the_model_is():
    """Eq. 3 takes R_k, sigma_k at the light's angle: it is reciprocal for pairs of equal polar angle only."""
    material = load_material(MATERIAL)
    model = model_for(material, material.resolve({"layers": 3, "tau_1": "0.3,0.1,0", "alpha_2": 0.5}))
    rng = np.random.default_rng(4)
    cos_theta, phi_l, phi_v = rng.uniform(0.05, 1, 32), rng.uniform(0, 2 * np.pi, 32), rng.uniform(0, 2 * np.pi, 32)
    sin_theta = np.sqrt(1 - cos_theta**2)
    L = np.stack([sin_theta * np.cos(phi_l), sin_theta * np.sin(phi_l), cos_theta], axis=-1)
    V = np.stack([sin_theta * np.cos(phi_v), sin_theta * np.sin(phi_v), cos_theta], axis=-1)
    N = np.array([0.0, 0.0, 1.0])
    forward, backward = model.brdf(L, V, N, None, None), model.brdf(V, L, N, None, None)
    assert forward.max() > 0.0
    np.testing.assert_allclose(forward, backward, rtol=1e-10)


def test_bad_stack_is_one_line():
    with pytest.raises(lobes.StackError, match=r"^alpha_2 = 1.5 is outside \[0, 1\]$"):
        lobes.make_stack([1.5, 1.2], [0.1, 1.5])
    with pytest.raises(lobes.StackError, match="tau_1"):
        lobes.make_stack([1.5, 1.2], [0.1, 0.1], tau=[-0.1])


# --------------------------------------------------------------------------------------------------
# GL against numpy

CASES = GL_STACKS


@pytest.fixture(scope="module")
def material():
    return load_material(MATERIAL)


@pytest.mark.gl
@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("view", ["lit", "slice", "scatter", "gradient"])
def test_gl_equals_numpy_twin(gl_renderer, material, case, view):
    twins = render_both(gl_renderer, material, material.resolve(CASES[case]), view, SIZE)
    assert_twins_equal(twins, f"layered_lobes {case}, {view}", BRDF_TOLERANCE)
    assert np.abs(twins.reference).max() > 0.05, "an empty image"


#: Two rough interfaces of eta < 1 facing each other (tir): NaN from 63 to 76 degrees, numpy and GL, when the
#: FGD's s part was scaled past 1 (the hypothesis sweep below found it).
TIR_FACING = {"layers": 2, "eta_1": 4, "alpha_1": 0.5, "eta_2": 1, "alpha_2": 0, "tir": 1}


def test_fgd_polarisations_stay_albedos():
    """FGD_s and FGD_p in [0, 1] with the unpolarised table's mean, on both sides of 1 and of the critical angle."""
    cos_theta, alpha, eta = np.meshgrid(np.linspace(0.0, 1.0, 101), np.linspace(0.0, 1.0, 31), [0.25, 0.5, 0.8, 0.97, 1.03, 1.5, 4.0])
    fgd = lobes.fgd_dielectric(cos_theta, alpha, eta)
    assert fgd.min() >= 0.0 and fgd.max() <= 1.0
    unpolarised = fgd.mean(axis=0)
    with_s_scaled = lobes.fresnel_sp(cos_theta, eta) * unpolarised / np.maximum(lobes.fresnel_sp(cos_theta, eta).mean(axis=0), 1e-300)
    assert with_s_scaled.max() > 1.0 + 0.1, "the grid no longer reaches the case (F_s ~ 1, F_p ~ 0, FGD > F)"
    stack = lobes.make_stack([4.0, 1.0], [0.5, 0.0], tir=True)
    energies = lobes.reflectance(stack, np.cos(np.radians(np.linspace(0.0, 90.0, 181))))
    assert np.isfinite(energies).all() and energies.max() <= 1.0


@pytest.mark.gl
def test_float32_sweep_is_finite(gl_renderer, material):
    """Extremes of every parameter, grazing angles included (the gradient runs to 90 degrees), TIR, opaque media."""
    sweeps = [
        {"layers": 3, "alpha_1": 0, "alpha_2": 0, "alpha_3": 0, "eta_1": 4, "eta_2": 1, "eta_3": 4},
        {"layers": 3, "alpha_1": 1, "alpha_2": 1, "alpha_3": 1, "tau_1": "20", "tau_2": "0,5,50"},
        {"layers": 2, "conductor": 1, "eta_base": "0.01", "kappa_base": "10", "alpha_1": 1, "alpha_2": 0},
        {"layers": 1, "conductor": 1, "eta_base": "4", "kappa_base": "0,0,1e-4", "alpha_1": 0.001},
        {"layers": 2, "eta_1": 1, "eta_2": 1, "alpha_1": 0.5},
        {"layers": 4, "eta_1": 4, "eta_2": 1, "eta_3": 4, "eta_4": 1, "alpha_1": 0.05, "alpha_2": 0.9, "alpha_3": 0.02, "tir": 1},
        TIR_FACING,
    ]
    for overrides in sweeps:
        values = material.resolve(overrides)
        for view in ("gradient", "slice", "scatter"):
            image = gl_renderer.render(material, values, view, 24, 16, light=LIGHTS.get(view))
            assert np.isfinite(image).all(), f"{overrides}, {view}: non-finite"
            assert image.min() >= 0.0, f"{overrides}, {view}: negative"


@pytest.mark.gl
def test_env_view_matches_its_exact_integral(gl_renderer, material):
    """The env view (importance-sampled through sampling_lobes) against the numpy quadrature on a few pixels."""
    values = material.resolve({"alpha_1": 0.3, "alpha_2": 0.5})
    environment = EnvironmentMap.default()
    render = ProgressiveEnvRender(gl_renderer, material, values, environment, 12, 12, seed=2)
    try:
        render.step(1024)
        image, error = render.image(), render.standard_error()
    finally:
        render.release()
    inside = brdf_view_geometry("lit", 12, 12)[5]
    pixels = [(6, 6), (3, 5), (8, 3)]
    assert all(inside[p] for p in pixels)
    exact = env_integral_numpy(model_for(material, values), environment, 12, 12, pixels=pixels)
    for k, p in enumerate(pixels):
        assert np.isfinite(image[p]).all()
        assert np.all(np.abs(image[p] - exact[k]) <= 4 * error[p] + 1e-3 * np.abs(exact[k]).max()), (p, image[p], exact[k], error[p])


def test_tir_term_keeps_the_lobe_beyond_the_critical_angle_inside():
    """With tir, light going up a rough interface into a rarer medium is reflected by that side's FGD, which
    holds the lobe's part beyond the critical angle: at normal incidence more is reflected back down and less
    leaves (Fig. 6: FGD for eta < 1 exceeds Fresnel once alpha > 0.1). At grazing incidence Belcour's
    symmetric R_21 = R_12 is the larger one instead, so the two differ both ways there."""
    plain = lobes.make_stack([2.0, 1.0], [0.5, 0.0])
    with_tir = lobes.make_stack([2.0, 1.0], [0.5, 0.0], tir=True)
    assert np.all(lobes.stack_statistics(with_tir, 1).R_n0 > lobes.stack_statistics(plain, 1).R_n0 + 0.05)
    assert np.all(lobes.reflectance(with_tir, 1.0) < lobes.reflectance(plain, 1.0) - 1e-3)


def test_cli_negative_optical_depth_is_one_line(tmp_path):
    from conftest import one_line_error, run_cli

    run = run_cli("render", MATERIAL, "--set", "tau_1=0,-1,0", "--view", "lit", "--size", "8", "--engine", "numpy",
                  "--out", tmp_path / "unused.png")
    assert not (tmp_path / "unused.png").exists()
    assert "parameter 'tau_1': component -1 is outside its range [0, 100]" in one_line_error(run)  # the declared range


# --------------------------------------------------------------------------------------------------
# The smooth limit: exact Fresnel at every angle (numpy and GL), and the albedo over the declared box

#: A smooth interface (alpha = 0) against exact Fresnel (tmm), theta in [0, 89.9] degrees: the FGD tables'
#: alpha = 0 rows are the closed-form smooth limit (explorer.physics.lobes_fgd.smooth_lobe_moments), so
#: only rounding remains in numpy (before, 8e-3 at 89.9 degrees for eta = 4, kappa = 1e-4); float32 in GL.
SMOOTH_TOLERANCE = 1e-6
SMOOTH_GL_TOLERANCE = 1e-3
SMOOTH_THETAS = np.radians(np.linspace(0.0, 89.9, 400))
#: Bare smooth interfaces: (eta_0, eta_1, kappa_1) per RGB channel; eta_0 > eta_1 is seen from the denser
#: side (eta < 1: total internal reflection beyond the critical angle).
SMOOTH_INTERFACES = {
    "gold-like conductor": (1.0, [0.2, 0.4, 1.1], [3.5, 2.5, 2.0]),
    "near-dielectric conductor": (1.0, [4.0, 1.5, 0.05], [1e-4, 0.5, 6.0]),
    "dielectric eta 1.5": (1.0, 1.5, None),
    "dielectric eta 4": (1.0, 4.0, None),
    "dielectric eta 1 / 1.5": (1.5, 1.0, None),
    "dielectric eta 1.2 / 1.33": (1.33, 1.2, None),
    "dielectric eta 1 / 4": (4.0, 1.0, None),
}


def smooth_interface(name: str) -> lobes.Stack:
    eta_0, eta_1, kappa = SMOOTH_INTERFACES[name]
    return lobes.make_stack([eta_1], [0.0], base_kappa=kappa, eta_0=eta_0)


def exact_fresnel(name: str, thetas: np.ndarray) -> np.ndarray:
    """``(len(thetas), 3)``: tmm's unpolarised reflectance of the bare interface, channel by channel."""
    eta_0, eta_1, kappa = SMOOTH_INTERFACES[name]
    eta_1, kappa = np.broadcast_to(eta_1, 3), np.broadcast_to(0.0 if kappa is None else kappa, 3)
    return np.array([[tmm_reflectance([eta_0, eta_1[ch]], [], t, kappa[ch]) for ch in range(3)] for t in thetas])


@pytest.mark.parametrize("name", list(SMOOTH_INTERFACES))
def test_smooth_interface_is_exact_fresnel(name):
    """The alpha -> 0 limit of layered_lobes is Fresnel's at every angle, grazing and TIR included."""
    ours = lobes.reflectance(smooth_interface(name), np.cos(SMOOTH_THETAS))
    error = np.abs(ours - exact_fresnel(name, SMOOTH_THETAS))
    worst = np.unravel_index(error.argmax(), error.shape)
    assert error.max() <= SMOOTH_TOLERANCE, f"{name}: {error.max():.2e} at {np.degrees(SMOOTH_THETAS[worst[0]]):.2f} deg"


GL_PROBE = """#include "lib/lobes.glsl"
uniform sampler2D lobes_fgd;
uniform sampler2D lobes_ggx_moments;
uniform float eta_0, eta_1;
uniform bool conductor;
uniform vec3 eta_base, kappa_base;
out vec4 result;
void main() {
    LobeStack s;
    s.count = 1;
    for (int i = 0; i <= LOBES_MAX; ++i) { s.eta[i] = 1.0; s.alpha[i] = 0.0; s.tau[i] = vec3(0.0); }
    s.eta[0] = eta_0;
    s.eta[1] = eta_1;
    s.conductor = conductor;
    s.tir = false;
    s.eta_base = eta_base;
    s.kappa_base = kappa_base;
    result = vec4(lobes_reflectance(s, lobes_fgd, lobes_ggx_moments, texelFetch(cos_thetas, ivec2(gl_FragCoord.xy), 0).r), 1.0);
}
"""


@pytest.mark.gl
def test_smooth_interface_is_exact_fresnel_in_gl(gl_renderer):
    """The GLSL twin (lib/lobes.glsl's lobes_reflectance on a one-interface LobeStack, the shader's tables) at
    the same float32 cosines, eta < 1 included (the material's ambient is air: a probe sets eta_0)."""
    from explorer.gpu.context import VERTEX_SHADER
    from explorer.materials.glsl import ShaderBuilder
    from explorer.materials.lobes_model import fgd_texture, moments_texture
    from explorer.resources import SHADER_DIR

    ctx, resources = gl_renderer.ctx, gl_renderer.resources
    builder = ShaderBuilder(include_dirs=[SHADER_DIR])
    builder.add_source("uniform sampler2D cos_thetas;\n" + GL_PROBE, "probe")
    program = ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=builder.build().code)
    cos_theta = np.cos(SMOOTH_THETAS).astype(np.float32)
    textures = {"lobes_fgd": resources.texture(fgd_texture()), "lobes_ggx_moments": resources.texture(moments_texture()),
                "cos_thetas": resources.texture(cos_theta.reshape(1, -1, 1), components=1)}
    framebuffer = ctx.framebuffer(color_attachments=[ctx.renderbuffer((cos_theta.size, 1), 4, dtype="f4")])
    try:
        for name, (eta_0, eta_1, kappa) in SMOOTH_INTERFACES.items():
            uniforms = {"eta_0": eta_0, "eta_1": float(np.mean(eta_1)), "conductor": kappa is not None,
                        "eta_base": tuple(np.broadcast_to(eta_1, 3).tolist()),
                        "kappa_base": tuple(np.broadcast_to(0.0 if kappa is None else kappa, 3).tolist())}
            gl_renderer.draw(program, framebuffer, uniforms=uniforms, textures=textures)
            gl = np.frombuffer(framebuffer.read(components=4, dtype="f4"), dtype=np.float32).reshape(-1, 4)[:, :3]
            error = np.abs(gl - exact_fresnel(name, np.arccos(cos_theta.astype(np.float64))))
            worst = np.unravel_index(error.argmax(), error.shape)
            assert error.max() <= SMOOTH_GL_TOLERANCE, f"{name}: {error.max():.2e} at cos theta {cos_theta[worst[0]]}"
    finally:
        framebuffer.color_attachments[0].release()
        framebuffer.release()
        resources.release(*textures.values())
        program.release()


#: Per RGB channel (each an independent spectral sample): the albedo's numpy quadrature error
#: (tests/test_energy.py's ALBEDO_TOLERANCE: the half-vector rule resolves lobes down to alpha ~ 1e-3).
BOX_ALBEDO_TOLERANCE = 3e-3
BOX_THETAS_DEG = (0.0, 60.0, 89.0)




def _box_value(p, draw):
    """A value of parameter ``p`` in its declared range, its ends drawn as often as the rest; log-uniform where
    the range spans decades (tau up to 100, eta_base and kappa_base up to 1e10)."""
    if p.type == "bool":
        return draw(st.booleans())
    if p.type == "int":
        return float(draw(st.integers(int(p.min), int(p.max))))
    if p.max > 1e3 * max(p.min, 1e-3):
        inside = st.floats(np.log10(max(p.min, 1e-3)), np.log10(p.max)).map(lambda x: float(10.0**x))
    else:
        inside = st.floats(p.min, p.max)
    value = st.one_of(st.sampled_from([p.min, p.max]), inside)
    return tuple(draw(value) for _ in range(3)) if p.type == "color" else draw(value)


@st.composite
def declared_box(draw, material):
    return {p.name: _box_value(p, draw) for p in material.parameters}


@settings(max_examples=25, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@seed(20261125)
@given(data=st.data())
def test_albedo_over_the_declared_box_is_at_most_one(data):
    """Any point of layered_lobes.brd's declared box (corners drawn as often as the rest, eta < 1 inside stacks,
    TIR, opaque media, eta_base and kappa_base up to 1e10): sum_k R_k(theta) in [0, 1] and finite from 0 to
    90 degrees, and the directional albedo of Eq. 3 finite and at most 1 per channel."""
    from explorer.views.albedo import albedo_numpy

    material = load_material(MATERIAL)
    values = data.draw(declared_box(material))
    assume(not (values["conductor"] and max(values["kappa_base"]) == 0.0))  # a one-line error (test_cli_outputs)
    model = model_for(material, material.resolve(values))
    energy = model.reflectance(np.cos(np.radians(np.linspace(0.0, 90.0, 91))))
    assert np.isfinite(energy).all() and energy.min() >= 0.0, values
    assert energy.max() <= 1.0 + 1e-12, (energy.max(), values)
    albedo = albedo_numpy(model, BOX_THETAS_DEG)
    assert np.isfinite(albedo).all(), values
    assert albedo.max() <= 1.0 + BOX_ALBEDO_TOLERANCE, (albedo.max(axis=-1), values)
