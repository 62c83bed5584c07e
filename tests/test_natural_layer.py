"""
Natural layers in the rough Bragg layer (bragg_layer): k1, k2, sigma and media as on bragg_mirror. Every method
shows the exact table, GL equals numpy, the base is seen through the layer's exact transmittance, and energy holds.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from explorer.materials.brd import load_material
from explorer.materials.models import model_for
from explorer.physics import colorimetry, dispersion
from explorer.physics.natural import NaturalMirror, mirror_spectrum, transmittance_table, unpolarised_reflectance
from explorer.resources import material_path
from twins import assert_twins_equal, render_both

ABSORBING = {"n1": "chitin", "n2": "1.8", "k2": "0.05", "Lambda": "300", "N": "6", "nh": "1", "alpha": "0.2",
             "rho_d": "0.5"}


@pytest.fixture(scope="module")
def layer_material():
    return load_material(material_path("bragg_layer"))


@pytest.mark.parametrize("method", ["1", "3"])
def test_every_method_shows_the_mirrors_exact_table(layer_material, method):
    mirror_material = load_material(material_path("bragg_mirror"))
    values = layer_material.resolve({**ABSORBING, "method": method})
    layer = model_for(layer_material, values)
    assert layer.natural is not None and layer.natural.k2 == 0.05
    mirror = model_for(mirror_material, mirror_material.resolve({k: v for k, v in ABSORBING.items() if k not in ("alpha", "rho_d")}))
    cos_theta = np.linspace(0.05, 1.0, 7)
    np.testing.assert_array_equal(layer.reflectance(cos_theta), mirror.reflectance(cos_theta))


@pytest.mark.gl
@pytest.mark.parametrize("view, size", [("gradient", (48, 4)), ("lit", (32, 32))])
def test_gl_equals_numpy(gl_renderer, layer_material, view, size):
    values = layer_material.resolve({**ABSORBING, "method": "1"})
    twins = render_both(gl_renderer, layer_material, values, view, size)
    assert_twins_equal(twins, f"natural rough layer, {view}")
    assert np.abs(twins.reference).max() > 0.02


def test_the_base_is_seen_through_the_exact_transmittance(layer_material):
    """Absorbing layers transmit less than 1 - R: the base term darkens; lossless ones transmit exactly 1 - R."""
    absorbing = model_for(layer_material, layer_material.resolve(ABSORBING))
    lossless = model_for(layer_material, layer_material.resolve({**ABSORBING, "k2": "0"}))
    assert np.all(absorbing.transmission_table <= lossless.transmission_table + 1e-6)
    assert absorbing.transmission_table.mean() < lossless.transmission_table.mean() - 0.01
    mirror = lossless.natural
    theta = np.radians([0.0, 30.0, 60.0, 85.0])
    T = transmittance_table(mirror, theta)
    R = unpolarised_reflectance(mirror, np.broadcast_to(colorimetry.WAVELENGTHS, (4, 471)), np.cos(theta))
    np.testing.assert_allclose(R + T, 1.0, atol=1e-9)
    # Against the spectrum command's exact T at 30 degrees (its own stack and grid).
    np.testing.assert_allclose(T[1], mirror_spectrum(mirror, colorimetry.WAVELENGTHS, [30.0])["T"][0], atol=1e-12)


@settings(max_examples=8, deadline=None)
@given(k1=st.floats(0.0, 1.0), k2=st.floats(0.0, 1.0), n2=st.sampled_from(["melanin", 1.8, 2.5]),
       N=st.integers(1, 30), Lambda=st.floats(80.0, 1000.0), sigma=st.sampled_from([0.0, 0.2]))
def test_energy_of_the_layers_tables(k1, k2, n2, N, Lambda, sigma):
    """R + T <= 1 at every angle and wavelength of the tables a rough layer integrates (and no NaN)."""
    mirror = NaturalMirror(n1=dispersion.LIBRARY["keratin"], n2=dispersion.LIBRARY.get(n2, n2) if isinstance(n2, str) else n2,
                           nh=1.0, k1=k1, k2=k2, N=N if sigma == 0.0 else min(N, 4), Lambda=Lambda, sigma=sigma)
    theta = np.radians([0.0, 45.0, 89.0])
    T = transmittance_table(mirror, theta)
    R = unpolarised_reflectance(mirror, np.broadcast_to(colorimetry.WAVELENGTHS[::10], (3, 48)), np.cos(theta))
    assert np.all(np.isfinite(T)) and np.all(T >= -1e-12) and np.all(R >= -1e-12)
    assert np.all(R + T[:, ::10] <= 1.0 + 1e-9)


def test_albedo_is_passive_with_a_white_base(layer_material):
    from explorer.materials.accuracy import accuracy_badge

    values = layer_material.resolve({**ABSORBING, "rho_d": "1", "method": "4"})
    model = model_for(layer_material, values)
    # The directional albedo by quadrature over the hemisphere at three view angles.
    theta, phi = np.meshgrid(np.linspace(0.0, np.pi / 2, 181)[1:], np.linspace(0.0, 2 * np.pi, 96, endpoint=False), indexing="ij")
    L = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    weight = np.sin(theta) * np.cos(theta) * (np.pi / 2 / 180) * (2 * np.pi / 96)
    frame = (np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    for theta_v in (0.0, 40.0, 75.0):
        V = np.array([np.sin(np.radians(theta_v)), 0.0, np.cos(np.radians(theta_v))])
        albedo = (model.brdf(L, V, *frame) * weight[..., None]).sum(axis=(0, 1))
        assert np.all(albedo <= 1.0) and np.all(albedo > 0.0), (theta_v, albedo)
    badge = accuracy_badge(layer_material, values)
    assert badge.natural and "exact table" in badge.text()


def test_spectral_reflectance_is_the_exact_multilayer(layer_material):
    """What Mitsuba's spectral variants evaluate (the twins' spectral hooks) is the natural mirror's exact R."""
    mirror_material = load_material(material_path("bragg_mirror"))
    values = {k: v for k, v in ABSORBING.items() if k not in ("alpha", "rho_d")}
    model = model_for(mirror_material, mirror_material.resolve(values))
    wavelengths = np.array([[420.0, 510.0, 600.0, 700.0]] * 2)
    cos_theta = np.cos(np.radians([0.0, 40.0]))
    R = model.spectral_reflectance(cos_theta, wavelengths)
    expected = mirror_spectrum(model.natural, wavelengths[0], [0.0, 40.0])["R"]
    np.testing.assert_allclose(R, expected, atol=1e-12)
    # The rough layer's spectral BRDF at the specular direction: the lobe times that R.
    layer = model_for(layer_material, layer_material.resolve({**ABSORBING, "rho_d": "0"}))
    i = np.array([[0.0, 0.0, 1.0]] * 2)
    value = layer.spectral_brdf(i, i, wavelengths, None)
    from explorer.physics import microfacet

    lobe = microfacet.microfacet_lobe(i, i, np.array([0.0, 0.0, 1.0]), layer.alpha)[0]
    np.testing.assert_allclose(value, lobe[:, None] * expected[0], rtol=1e-9)


def test_the_mitsuba_plugin_reads_the_natural_layers():
    """The RGB plugin's model is the numpy twin with k, the medium and sigma (its Dirac's colours are the twin's)."""
    pytest.importorskip("mitsuba")
    from explorer.mitsuba import register
    from explorer.mitsuba.scene import bsdf_properties

    mi = register("scalar_rgb")
    material = load_material(material_path("bragg_mirror"))
    values = material.resolve({**{k: v for k, v in ABSORBING.items() if k not in ("alpha", "rho_d")}, "sigma": "0.05"})
    bsdf = mi.load_dict(bsdf_properties(material, values, "scalar_rgb"))
    assert bsdf.model.natural == model_for(material, values).natural and bsdf.model.natural.sigma == 0.05
    cos_theta = np.array([1.0, 0.7, 0.3])
    np.testing.assert_array_equal(bsdf.model.reflectance(cos_theta), model_for(material, values).reflectance(cos_theta))
