"""
A layered Bragg structure's dispersive host (bragg_stack's ``nh`` naming a medium: ``--set nh=chitin``, ``medium_nh``).

Under the coating each wavelength refracts its own way: its Snell angle, the coating's Fresnel terms, the
``1/nh^2`` radiance factor and the layers' tables (over the angle in the host, each column in the host's index at
its wavelength). Checked here against the same structure in a host of one index, wavelength by wavelength;
against closed forms written out here (the smooth limit, the coating's Dirac, a Lambertian base under the
coating in the position-free walk); GL against numpy; energy; and one-line errors for hosts that cannot be.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import one_line_error, run_cli
from explorer.errors import LocatedError
from explorer.materials.brd import load_material
from explorer.materials.models import BraggStackModel, model_for
from explorer.physics import colorimetry, dispersion, layered, position_free
from explorer.physics.layered import LayeredBragg, RoughBraggLayer
from explorer.physics.natural import NaturalMirror, mirror_spectrum
from explorer.resources import material_path
from test_energy import ALBEDO_TOLERANCE, SWEEP_SIZE, _albedo_values, _cheap, assert_passive, parameter_sets
from test_position_free import _within, fresnel_unpolarised
from twins import BRDF_TOLERANCE, assert_twins_equal, render_both

CHITIN = dispersion.LIBRARY["chitin"]
SEED = 20261129
#: Two layers in a chitin host (the first layer's n1 chitin too), a coloured base, an absorbing host.
VALUES = {"layers": "2", "nh": "chitin", "n1_1": "chitin", "n2_1": "1.7", "Lambda_1": "380", "N_1": "8", "alpha_1": "0.15",
          "n1_2": "1.3", "rho_d": "0.5,0.3,0.2", "tau_h": "0.1"}
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
#: Columns checked one by one: 360, 400, 550, 700 and 830 nm.
COLUMNS = [0, 40, 190, 340, 470]


@pytest.fixture(scope="module")
def stack_material():
    return load_material(material_path("bragg_stack"))


@pytest.fixture(scope="module")
def model(stack_material):
    return model_for(stack_material, stack_material.resolve(VALUES))


def _directions(seed: int, count: int = 7) -> np.ndarray:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(count, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.05
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def test_the_host_names_a_medium(stack_material, model):
    """nh=chitin selects the medium (the slider shows its n at 550 nm); Leertouwer et al.'s 1.572, 1.552, 1.541."""
    stack = model.stack
    assert stack.medium_n1 is CHITIN and stack.dispersive_host
    assert stack.n1 == pytest.approx(CHITIN.real_at(550.0))
    np.testing.assert_allclose(stack.host_index([400.0, 500.0, 600.0]), [1.572, 1.552, 1.541], atol=2e-3)
    assert stack.layers[0].medium_n1 is CHITIN and stack.layers[1].n1 == 1.3 and stack.layers[1].medium_n1 is None
    assert all(table.n1 is CHITIN for table in model.tables)
    np.testing.assert_allclose(model.textures()["stack_host"][:, 0], stack.host_index(), rtol=1e-7)
    # A number replaces the medium.
    plain = BraggStackModel.stack_of(stack_material.resolve({**VALUES, "nh": "1.5"}))
    assert plain.medium_n1 is None and not plain.dispersive_host


def test_hosts_that_cannot_be_are_one_line(stack_material, tmp_path):
    """An absorbing host, a medium with n < 1 somewhere and a bad file: one line each (the file's own line)."""
    with pytest.raises(LocatedError, match="melanin absorbs") as error:
        stack_material.resolve({"nh": "melanin"})
    assert "\n" not in str(error.value)
    (tmp_path / "thin.csv").write_text("wavelength_nm,n,k\n360,1.2,0\n600,0.98,0\n830,1.1,0\n")
    with pytest.raises(LocatedError, match="below the host's minimum 1") as error:
        stack_material.resolve({"nh": str(tmp_path / "thin.csv")})
    assert "\n" not in str(error.value)
    (tmp_path / "bad.csv").write_text("wavelength_nm,n,k\n360,1.5,0\n600,1.4;0\n830,1.3,0\n")
    with pytest.raises(LocatedError) as error:
        stack_material.resolve({"nh": str(tmp_path / "bad.csv")})
    assert str(error.value).startswith(f"{tmp_path / 'bad.csv'}:3:") and "\n" not in str(error.value)
    line = one_line_error(run_cli("albedo", "bragg_stack", "--set", f"nh={tmp_path / 'bad.csv'}", "--theta", "0"))
    assert "bad.csv:3:" in line
    with pytest.raises(ValueError, match="absorbs"):
        LayeredBragg(layers=(RoughBraggLayer(),), n1=1.7, medium_n1=dispersion.LIBRARY["melanin"])


def test_a_file_medium_is_a_host(stack_material, tmp_path):
    (tmp_path / "host.csv").write_text("wavelength_nm,n,k\n360,1.45,0\n600,1.40,0\n830,1.38,0\n")
    stack = BraggStackModel.stack_of(stack_material.resolve({"nh": str(tmp_path / "host.csv")}))
    assert stack.dispersive_host and stack.medium_n1.name == str(tmp_path / "host.csv")
    np.testing.assert_allclose(stack.host_index([360.0, 600.0]), [1.45, 1.40])


def test_tables_are_the_exact_multilayer_in_the_host_at_each_wavelength(model):
    """Layer 1's rows are the spectrum command's multilayer with the chitin host (and chitin n1) at every wavelength."""
    table = model.tables[0]
    mirror = NaturalMirror(n1=CHITIN, n2=1.7, Lambda=380.0, delta=0.5, N=8, nh=CHITIN)
    rows = [0, 120, 240]  # 0, 30 and 60 degrees in the host
    exact = mirror_spectrum(mirror, colorimetry.WAVELENGTHS, np.degrees(table.theta[rows]))
    np.testing.assert_allclose(table.reflectance[rows], exact["R"], atol=1e-6)
    np.testing.assert_allclose(table.transmittance[rows], exact["T"], atol=1e-6)


def test_eq34_is_each_wavelengths_own_host(model):
    """Column j of Eq. 34 equals the same structure in a host of the one index n(lambda_j) (same tables)."""
    i, o = _directions(1), _directions(2)
    spectra = layered.single_reflection_spectra(model.stack, i, o, model.tables)
    n = model.stack.host_index()
    worst_550 = 0.0
    for j in COLUMNS:
        fixed = LayeredBragg(layers=model.stack.layers, n1=float(n[j]), rho_d=model.stack.rho_d, tau_h=model.stack.tau_h)
        one = layered.single_reflection_spectra(fixed, i, o, model.tables)
        np.testing.assert_allclose(spectra.layers[..., j], one.layers[..., j], rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(spectra.base[..., j], one.base[..., j], rtol=1e-6, atol=1e-9)
        at_550 = layered.single_reflection_spectra(
            LayeredBragg(layers=model.stack.layers, n1=model.stack.n1, rho_d=model.stack.rho_d, tau_h=model.stack.tau_h),
            i, o, model.tables)
        worst_550 = max(worst_550, float(np.abs(at_550.layers[..., j] - spectra.layers[..., j]).max()))
    assert worst_550 > 1e-3  # the per-wavelength directions matter (the test could fail)


def test_smooth_limit_and_the_coatings_dirac_are_per_wavelength(stack_material):
    """One layer: F(lambda) + (1 - F)^2 exp(-2 tau / cos theta') R(theta'_lambda), and the Dirac F(lambda), in RGB."""
    values = stack_material.resolve({"layers": "1", "nh": "chitin", "n2_1": "1.8", "N_1": "6", "tau_h": "0.2"})
    model = model_for(stack_material, values)
    n = model.stack.host_index()
    cos_theta = np.cos(np.radians([0.0, 35.0, 70.0]))
    F = fresnel_unpolarised(cos_theta[:, None], 1.0, n)
    cos_host = np.sqrt(1.0 - (1.0 - cos_theta[:, None] ** 2) / n**2)
    R = layered.lookup_columns(model.tables[0].reflectance.astype(np.float64), np.arccos(cos_host))
    expected = colorimetry.spectrum_to_rgb(F + (1.0 - F) ** 2 * np.exp(-0.4 / cos_host) * R)
    np.testing.assert_allclose(model.reflectance(cos_theta), expected, atol=1e-6)
    normal = np.array([0.0, 0.0, 1.0])
    V = np.stack([np.sqrt(1.0 - cos_theta**2), 0.0 * cos_theta, cos_theta], axis=-1)
    np.testing.assert_allclose(model.mirror_reflection(V, normal), colorimetry.spectrum_to_rgb(F), atol=1e-9)
    assert np.ptp(model.mirror_reflection(V, normal)[0]) > 1e-4  # the coating is bluer than white (n falls with lambda)


def test_energy_and_reciprocity(stack_material, model):
    """Eq. 34 is reciprocal with a dispersive host; the albedo (white base, with the multiple-scattering lobe at the
    host's 550-nm index, and without) is at most 1; the smooth limit is passive."""
    from explorer.views.albedo import albedo_numpy

    i, o = _directions(3), _directions(4)
    np.testing.assert_allclose(layered.single_reflection_brdf(model.stack, i, o, model.tables),
                               layered.single_reflection_brdf(model.stack, o, i, model.tables), rtol=1e-9, atol=1e-12)
    assert np.all(model.reflectance(np.linspace(0.0, 1.0, 33)) @ LUMINANCE <= 1.0 + 1e-3)
    white = {**VALUES, "layers": "1", "rho_d": "1", "alpha_1": "0.4"}
    single = albedo_numpy(model_for(stack_material, stack_material.resolve(white)), [40.0])
    multiple = albedo_numpy(model_for(stack_material, stack_material.resolve({**white, "multiple_scattering": "1"})), [40.0])
    for rgb in (single, multiple):
        assert np.all(np.isfinite(rgb)) and np.all(rgb @ LUMINANCE <= 1.0 + 1e-3), rgb
    assert np.all(multiple @ LUMINANCE > single @ LUMINANCE + 1e-3)


@pytest.mark.gl
@pytest.mark.parametrize("view, size", [("gradient", (64, 2)), ("sphere", (24, 24))])
def test_gl_specular_colours_equal_numpy(gl_renderer, stack_material, view, size):
    twins = render_both(gl_renderer, stack_material, stack_material.resolve(VALUES), view, size)
    assert_twins_equal(twins, f"bragg_stack in chitin, {view}", BRDF_TOLERANCE)
    assert np.abs(twins.reference).max() > 0.02


@pytest.mark.gl
def test_gl_albedo_equals_numpy(gl_renderer, stack_material):
    """The albedo command's GL engine (the scatter view summed, plus the coating's Dirac) equals its numpy one."""
    from explorer.views.albedo import albedo_gl, albedo_numpy

    values = stack_material.resolve({**VALUES, "alpha_1": "0.3", "alpha_2": "0.3"})
    model = model_for(stack_material, values)
    gl = albedo_gl(stack_material, values, [20.0], gl_renderer, size=256, model=model)
    numpy_ = albedo_numpy(model, [20.0])
    np.testing.assert_allclose(gl, numpy_, atol=5e-3)


def _invisible_in(medium) -> RoughBraggLayer:
    """A smooth layer of the host's own medium: no reflection, no loss."""
    return RoughBraggLayer(n2=1.5, Lambda=500.0, delta=0.5, N=10, alpha=0.0, medium_n2=medium)


def _fbar(n: np.ndarray, steps: int = 4000) -> np.ndarray:
    """The interface's hemispherical reflectance from inside, per index (midpoint rule in cos^2)."""
    mu2 = (np.arange(steps) + 0.5) / steps
    return np.mean(fresnel_unpolarised(np.sqrt(mu2)[None, :], n[:, None], 1.0), axis=1)


def _per_channel(spectra: np.ndarray) -> np.ndarray:
    """``spectra`` (3, ..., 471), one per RGB channel: channel c of the RGB of spectrum c."""
    return np.stack([colorimetry.spectrum_to_rgb(spectra[c])[..., c] for c in range(3)], axis=-1)


def test_position_free_lambertian_under_a_chitin_coating():
    """
    The closed forms of tests/test_position_free.py per wavelength, in the chitin host: the albedo
    ``F + (1 - F) rho (1 - Fbar) / (1 - rho Fbar)`` and the BRDF ``(1 - F(i)) (1 - F(o)) rho / (pi n^2 (1 - rho Fbar))``,
    each wavelength with its own n (the walk carries one wavelength per path there); within 3 standard errors.
    """
    rho = np.array([0.8, 0.5, 0.3])
    stack = LayeredBragg(layers=(_invisible_in(CHITIN),), n1=CHITIN.real_at(550.0), rho_d=rho, medium_n1=CHITIN)
    n = stack.host_index()
    Fbar = _fbar(n)
    theta = np.radians([0.0, 50.0, 80.0])
    result = position_free.directional_albedo(stack, np.degrees(theta), samples=4096, seed=SEED)
    F = fresnel_unpolarised(np.cos(theta)[:, None], 1.0, n)
    spectra = np.stack([F + (1.0 - F) * r * (1.0 - Fbar) / (1.0 - r * Fbar) for r in rho])
    _within(result, _per_channel(spectra), 1e-5)
    t_i, t_o = np.radians([10.0, 60.0]), np.radians([55.0, 25.0])
    i = np.stack([np.sin(t_i), 0 * t_i, np.cos(t_i)], -1)
    o = np.stack([-np.sin(t_o) * 0.6, np.sin(t_o) * 0.8, np.cos(t_o)], -1)
    result = position_free.brdf(stack, i, o, samples=4096, seed=SEED)
    Fi, Fo = (fresnel_unpolarised(np.cos(t)[:, None], 1.0, n) for t in (t_i, t_o))
    spectra = np.stack([(1.0 - Fi) * (1.0 - Fo) * r / (np.pi * n**2 * (1.0 - r * Fbar)) for r in rho])
    _within(result, _per_channel(spectra), 1e-5)
    # With one index (550 nm) for every wavelength the albedo's Dirac alone would be off by more than the noise.
    flat = fresnel_unpolarised(np.cos(theta), 1.0, stack.n1)[:, None]
    assert np.abs(colorimetry.spectrum_to_rgb(F) - flat).max() > 1e-4


#: The library's media a host may be (lossless), by their medium_nh numbers.
LOSSLESS_HOSTS = [number for number, name in enumerate(dispersion.LIBRARY, start=1) if not dispersion.LIBRARY[name].absorbing]


@pytest.mark.gl
@settings(max_examples=3, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_energy_sweep_with_a_dispersive_host(gl_renderer, data):
    """tests/test_energy.py's sweep of the stack's box with the host a drawn lossless medium: the smooth limit
    passive in GL and numpy and equal in both, and the numpy albedo at most 1."""
    from explorer.views.albedo import albedo_numpy

    mat, values = data.draw(parameter_sets("bragg_stack"))
    values = _cheap("bragg_stack", {**values, "medium_nh": float(data.draw(st.sampled_from(LOSSLESS_HOSTS)))})
    twins = render_both(gl_renderer, mat, values, "gradient", SWEEP_SIZE)
    assert_passive(twins.reference, f"numpy {values}")
    assert_passive(twins.gl, f"GL {values}")
    assert_twins_equal(twins, f"{values}")
    model = model_for(mat, mat.resolve(_albedo_values("bragg_stack", values)))
    assert model.stack.dispersive_host
    assert_passive(albedo_numpy(model, [50.0]), f"numpy albedo {values}", ALBEDO_TOLERANCE)
