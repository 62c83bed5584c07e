"""
Natural mirrors in the renderer: an index naming a medium (n2=chitin), k1, k2 and sigma on bragg_mirror;
every method shows the exact table, GL equals numpy, the colour is the spectrum's, and energy holds.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from explorer.materials.brd import MaterialError, load_material
from explorer.materials.media import MEDIA
from explorer.materials.models import model_for
from explorer.physics import colorimetry, dispersion
from explorer.physics.natural import NaturalMirror, mirror_spectrum
from explorer.resources import material_path
from twins import assert_twins_equal, render_both


@pytest.fixture(scope="module")
def mirror_material():
    return load_material(material_path("bragg_mirror"))


def test_an_index_may_name_a_medium(mirror_material):
    values = mirror_material.resolve({"n2": "chitin", "n1": "1.2"})
    assert values["medium_n2"] == 1 + MEDIA.index("chitin") and abs(values["n2"] - dispersion.LIBRARY["chitin"].real_at(550.0)) < 1e-12
    assert mirror_material.resolve({"n2": "chitin", **{"n2": "1.6"}})["medium_n2"] == 0  # a number replaces it
    with pytest.raises(MaterialError, match="neither a number nor a dispersion"):
        mirror_material.resolve({"n2": "unobtainium"})
    assert mirror_material.parameter("medium_n2").max == len(MEDIA)  # the .brd's range is the library


def _colour_of_spectrum(mirror: NaturalMirror, theta: float, K: int = 8) -> np.ndarray:
    """The spectrum's hat averages (K samples per nm) against the CMFs: what the exact table holds."""
    fine = colorimetry.fine_wavelengths(K)
    R = mirror_spectrum(mirror, fine, [theta])["R"]
    return colorimetry.spectrum_to_rgb(colorimetry.hat_average(R, K))[0]


@pytest.mark.parametrize("method", [0, 1, 3])
def test_every_method_shows_the_spectrums_colour(mirror_material, method):
    values = mirror_material.resolve({"n2": "melanin", "n1": "chitin", "nh": "1", "Lambda": "180", "N": "8", "k1": "0.01",
                                      "method": str(method)})
    model = model_for(mirror_material, values)
    mirror = NaturalMirror(n1=dispersion.LIBRARY["chitin"], n2=dispersion.LIBRARY["melanin"], Lambda=180.0, N=8, nh=1.0, k1=0.01)
    for theta in (0.0, 35.0, 70.0):
        rgb = model.reflectance(np.cos(np.radians(theta)))
        # The table's linear interpolation over cos theta (129 entries) plus the sampling: within 2e-3.
        np.testing.assert_allclose(rgb, _colour_of_spectrum(mirror, theta), atol=2e-3)
    assert np.abs(rgb).max() > 0.02


@pytest.mark.gl
@pytest.mark.parametrize("overrides", [
    {"n2": "chitin", "n1": "1.2", "k1": "0.05", "N": "10", "Lambda": "300", "method": "3"},
    {"n2": "melanin", "n1": "keratin", "nh": "1", "N": "6", "Lambda": "190", "method": "0"},
])
def test_gl_equals_numpy(gl_renderer, mirror_material, overrides):
    twins = render_both(gl_renderer, mirror_material, mirror_material.resolve(overrides), "gradient", (48, 4))
    assert_twins_equal(twins, f"natural mirror {overrides}")
    assert np.abs(twins.reference).max() > 0.05


@settings(max_examples=25, deadline=None)
@given(k1=st.floats(0.0, 1.0), k2=st.floats(0.0, 1.0), n1=st.sampled_from(["chitin", 1.0, 1.33]),
       n2=st.sampled_from(["melanin", "TiO2", 1.8, 2.5]), nh=st.sampled_from([None, 1.0, "water"]),
       N=st.integers(1, 40), Lambda=st.floats(50.0, 1500.0), delta=st.floats(0.0, 1.0), theta=st.floats(0.0, 90.0))
def test_energy(k1, k2, n1, n2, nh, N, Lambda, delta, theta):
    """R + T + A = 1 with R, T, A in [0, 1] over the box of k, media, structure and angle."""
    lib = dispersion.LIBRARY
    mirror = NaturalMirror(n1=lib.get(n1, n1) if isinstance(n1, str) else n1, n2=lib.get(n2, n2) if isinstance(n2, str) else n2,
                           nh=lib.get(nh, nh) if isinstance(nh, str) else nh, k1=k1, k2=k2, N=N, Lambda=Lambda, delta=delta)
    out = mirror_spectrum(mirror, np.array([360.0, 555.5, 830.0]), [theta])
    for key in ("R", "Rs", "Rp", "T", "A"):
        assert np.all(np.isfinite(out[key])) and np.all(out[key] >= -1e-12) and np.all(out[key] <= 1.0 + 1e-12), key
    np.testing.assert_allclose(out["R"] + out["T"] + out["A"], 1.0, atol=1e-12)
    if k1 == 0.0 and k2 == 0.0 and not isinstance(n2, str) and n1 != "chitin":
        np.testing.assert_allclose(out["A"], 0.0, atol=1e-9)  # lossless layers absorb nothing


@settings(max_examples=6, deadline=None)
@given(sigma=st.floats(0.0, 0.3), k2=st.floats(0.0, 0.3), theta=st.floats(0.0, 89.0))
def test_energy_with_disorder(sigma, k2, theta):
    mirror = NaturalMirror(n1=1.0, n2=dispersion.LIBRARY["chitin"], k2=k2, N=4, Lambda=250.0, sigma=sigma)
    out = mirror_spectrum(mirror, np.array([420.0, 640.0]), [theta])
    assert np.all(out["A"] >= -1e-12) and np.all(out["R"] + out["T"] <= 1.0 + 1e-12)


def test_the_badge_names_the_exact_table(mirror_material):
    from explorer.materials.accuracy import accuracy_badge

    badge = accuracy_badge(mirror_material, mirror_material.resolve({"n2": "chitin", "method": "1", "N": "4"}))
    assert badge.natural and badge.accurate and "exact table" in badge.text() and badge.note() is None
    assert not accuracy_badge(mirror_material, mirror_material.resolve({"method": "1", "N": "4"})).natural
