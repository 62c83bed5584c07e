"""
Natural layers in the layered Bragg structure (bragg_stack): per layer k1_l, k2_l, sigma_l and media
medium_n1_l, medium_n2_l. Each natural layer's tables are its exact multilayer's (R, Eq. 28 over its exact T),
GL equals numpy, the position-free reference reads the same layers, energy holds, and the defaults are unchanged.
"""

from __future__ import annotations

import numpy as np
import pytest

from explorer.errors import LocatedError
from explorer.materials.brd import load_material
from explorer.materials.models import BraggStackModel, model_for
from explorer.physics import colorimetry, dispersion, layered, position_free
from explorer.physics.natural import NaturalMirror, mirror_spectrum
from explorer.resources import material_path
from twins import assert_twins_equal, render_both

#: Two layers: the first absorbing with a chitin n2 (dispersive), the second lossless (the paper's).
ABSORBING = {"layers": "2", "nh": "1.4", "n1_1": "1.4", "n2_1": "chitin", "k2_1": "0.05", "Lambda_1": "320", "N_1": "6",
             "alpha_1": "0.2", "Lambda_2": "400", "N_2": "4", "alpha_2": "0.3", "rho_d": "0.5"}
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


@pytest.fixture(scope="module")
def stack_material():
    return load_material(material_path("bragg_stack"))


def test_the_parameters_make_natural_layers(stack_material):
    stack = BraggStackModel.stack_of(stack_material.resolve({**ABSORBING, "sigma_2": "0.1", "n1_2": "melanin"}))
    first, second = stack.layers
    assert first.natural and first.k2 == 0.05 and first.medium_n2 is dispersion.LIBRARY["chitin"] and first.medium_n1 is None
    assert second.natural and second.sigma == 0.1 and second.medium_n1 is dispersion.LIBRARY["melanin"]
    assert not any(layer.natural for layer in BraggStackModel.stack_of(stack_material.resolve({"layers": "3"})).layers)


def test_defaults_are_the_papers_tables(stack_material):
    """k = 0, sigma = 0 and no media, given or not: the same tables bit for bit, the smooth T is 1 - R."""
    plain = model_for(stack_material, stack_material.resolve({"layers": "2"}))
    zeros = model_for(stack_material, stack_material.resolve({"layers": "2", "k1_1": "0", "k2_2": "0", "sigma_1": "0"}))
    assert all(t.transmittance is None for t in plain.tables)
    a, b = plain.textures(), zeros.textures()
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    np.testing.assert_array_equal(a["stack_transmittance"][..., :2], 1.0 - a["stack_reflectance"][..., :2])


def test_a_natural_layers_tables_are_its_exact_spectra(stack_material):
    """R and T of the table rows equal the spectrum command's exact multilayer (n2 chitin, k2 = 0.05, host 1.4)."""
    model = model_for(stack_material, stack_material.resolve(ABSORBING))
    table = model.tables[0]
    mirror = NaturalMirror(n1=1.4, n2=dispersion.LIBRARY["chitin"], Lambda=320.0, delta=0.5, N=6, nh=1.4, k2=0.05)
    rows = [0, 120, 240]  # 0, 30 and 60 degrees in the host
    exact = mirror_spectrum(mirror, colorimetry.WAVELENGTHS, np.degrees(table.theta[rows]))
    np.testing.assert_allclose(table.reflectance[rows], exact["R"], atol=1e-6)
    np.testing.assert_allclose(table.transmittance[rows], exact["T"], atol=1e-6)
    assert exact["A"].min() > 1e-3  # it absorbs: T < 1 - R
    assert np.all(table.reflectance + table.transmittance <= 1.0 + 1e-6)
    # Eq. 28 over the exact T: the rough layer lets through less than over 1 - R.
    lossless = model_for(stack_material, stack_material.resolve({**ABSORBING, "k2_1": "0"})).tables[0]
    assert table.transmissivity.mean() < lossless.transmissivity.mean() - 0.01
    # The second layer is the paper's: its tables as before.
    assert model.tables[1].transmittance is None


@pytest.mark.gl
@pytest.mark.parametrize("view, size, brightest", [("gradient", (48, 4), 0.02), ("lit", (32, 32), 1e-3)])
def test_gl_equals_numpy(gl_renderer, stack_material, view, size, brightest):
    # A disordered second layer too (two cells: its realisations cost seconds per cell).
    values = stack_material.resolve({**ABSORBING, "sigma_2": "0.2", "N_2": "2", "k1_2": "0.1"})
    twins = render_both(gl_renderer, stack_material, values, view, size)
    assert_twins_equal(twins, f"natural stack, {view}")
    assert np.abs(twins.reference).max() > brightest


def test_absorption_darkens_and_energy_holds(stack_material):
    """The smooth limit's colour through absorbing layers is darker than through lossless ones, and passive."""
    cos_theta = np.linspace(0.0, 1.0, 33)
    absorbing = model_for(stack_material, stack_material.resolve(ABSORBING)).reflectance(cos_theta) @ LUMINANCE
    lossless = model_for(stack_material, stack_material.resolve({**ABSORBING, "k2_1": "0"})).reflectance(cos_theta) @ LUMINANCE
    assert np.all(np.isfinite(absorbing)) and absorbing.max() <= 1.0 + 1e-3
    assert np.all(absorbing <= lossless + 1e-6) and (lossless - absorbing).max() > 1e-3


def test_position_free_reads_the_natural_layers(stack_material):
    """
    One absorbing layer over a white base: the position-free walk's albedo is below the lossless layer's
    (its facets transmit T < 1 - R), both within [0, 1]; the microsurface walk (facets transmitting 1 - R)
    refuses natural layers.
    """
    one = {**ABSORBING, "layers": "1", "rho_d": "1", "k2_1": "0.2"}
    results = []
    for k2 in ("0.2", "0"):
        model = model_for(stack_material, stack_material.resolve({**one, "k2_1": k2}))
        walker = position_free.PositionFree(model.stack, model.tables)
        results.append(walker.albedo([20.0], samples=3000, seed=1))
    absorbing, lossless = (r.value[0] @ LUMINANCE for r in results)
    error = np.hypot(results[0].stderr[0] @ LUMINANCE, results[1].stderr[0] @ LUMINANCE)
    assert 0.0 <= absorbing and lossless <= 1.0 + 3 * error
    assert absorbing < lossless - 3 * error - 0.01, (absorbing, lossless, error)
    natural = model_for(stack_material, stack_material.resolve(one))
    with pytest.raises(ValueError, match="natural"):
        position_free.PositionFree(natural.stack, natural.tables, microsurface="walk")


def test_a_layers_natural_checks_are_one_line():
    with pytest.raises(ValueError, match="k1 and k2"):
        layered.RoughBraggLayer(k1=-0.1)


def test_a_file_medium_names_a_layers_index(stack_material, tmp_path):
    """``--set n2_2=my_layer.csv``: the second layer's n2 is the file's medium; a bad file is refused naming its line."""
    (tmp_path / "layer.csv").write_text("wavelength_nm,n,k\n360,1.9,0.02\n600,1.8,0.01\n830,1.75,0.0\n")
    values = stack_material.resolve({"layers": "2", "n2_2": str(tmp_path / "layer.csv")})
    layer = BraggStackModel.stack_of(values).layers[1]
    assert layer.natural and layer.medium_n2.name == str(tmp_path / "layer.csv") and layer.medium_n1 is None
    np.testing.assert_allclose(layer.natural_mirror(1.0).index_2([600.0]), [1.8 + 0.01j])
    (tmp_path / "bad.csv").write_text("wavelength_nm,n,k\n360,1.9,0.02\n600,x,0.01\n")
    with pytest.raises(LocatedError) as error:
        stack_material.resolve({"layers": "2", "n2_2": str(tmp_path / "bad.csv")})
    assert str(error.value).startswith(f"{tmp_path / 'bad.csv'}:3:") and "\n" not in str(error.value)


def test_two_smooth_absorbing_layers_bounce_incoherently():
    """
    Two smooth natural layers in air over black: the position-free walk is the incoherent pair
    ``R1 + T1^2 R2 / (1 - R1 R2)`` per wavelength with each layer's exact T (< 1 - R: they absorb), within 3
    standard errors; with 1 - R in place of T it would be brighter by many. (A layer reflects its table's R from
    below as from above: exact for lossless layers, the model's choice for absorbing ones.)
    """
    chitin = dispersion.LIBRARY["chitin"]
    top = layered.RoughBraggLayer(n2=1.55, Lambda=330.0, delta=0.5, N=6, alpha=0.0, k2=0.05, medium_n2=chitin)
    bottom = layered.RoughBraggLayer(n2=1.7, Lambda=420.0, delta=0.5, N=5, alpha=0.0, k1=0.03)
    stack = layered.LayeredBragg(layers=(top, bottom), n1=1.0, rho_d=0.0)
    theta = np.array([0.0, 30.0, 60.0])
    result = position_free.directional_albedo(stack, theta, samples=4096, seed=20261129)
    tables = layered.stack_tables(stack)
    R1, R2 = (layered.lookup(t.reflectance.astype(np.float64), np.radians(theta)) for t in tables)
    T1 = layered.lookup(tables[0].transmittance.astype(np.float64), np.radians(theta))
    pair = colorimetry.spectrum_to_rgb(R1 + T1**2 * R2 / (1.0 - R1 * R2))
    error = np.abs(result.value - pair)
    assert np.all(error <= 3.0 * result.stderr + 1e-4), (error, result.stderr)
    lossless = colorimetry.spectrum_to_rgb(R1 + (1.0 - R1) ** 2 * R2 / (1.0 - R1 * R2))
    assert (lossless - pair).max() > 10 * result.stderr.max()


def test_mitsubas_spectral_hook_reads_the_natural_tables(stack_material):
    """The spectral BRDF Mitsuba evaluates (one natural layer, over black, at normal incidence both ways) is
    Eq. 17's lobe times the layer's exact R at the path's wavelengths (the table's 1-nm samples interpolated)."""
    from explorer.physics import microfacet

    model = model_for(stack_material, stack_material.resolve({**ABSORBING, "layers": "1", "rho_d": "0", "nh": "1",
                                                              "n1_1": "1", "coating": "0"}))
    wavelengths = np.array([[420.0, 510.0, 600.0, 700.0]])
    i = np.array([[0.0, 0.0, 1.0]])
    value = model.spectral_brdf(i, i, wavelengths, lambda rgb, w: np.zeros(w.shape))  # a black base
    mirror = NaturalMirror(n1=1.0, n2=dispersion.LIBRARY["chitin"], Lambda=320.0, delta=0.5, N=6, nh=1.0, k2=0.05)
    exact = mirror_spectrum(mirror, wavelengths[0], [0.0])["R"][0]
    lobe = microfacet.microfacet_lobe(i, i, np.array([0.0, 0.0, 1.0]), 0.2)[0]
    np.testing.assert_allclose(value[0], lobe[0] * exact, rtol=1e-5)
