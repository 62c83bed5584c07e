"""
Natural mirrors: the dispersion library and its files, and the exact spectra (``spectrum``) against
``tmm`` with complex, dispersive indices, a host, oblique and grazing incidence, many cells, and
thickness disorder (the mean of tmm over seeded realisations).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from tmm import coh_tmm

from explorer.cli.commands import main
from explorer.physics import dispersion, multilayer
from explorer.physics.natural import NaturalMirror, mirror_spectrum, wavelength_grid


def tmm_mirror(mirror: NaturalMirror, wavelength: float, theta_deg: float, d=None) -> tuple[float, float, float, float]:
    """``(Rs, Rp, Ts, Tp)`` of ``mirror`` by tmm: ``[nh] + [n2, n1] * N + [n1]`` at one wavelength."""
    n1 = complex(mirror.index_1(wavelength))
    n2 = complex(mirror.index_2(wavelength))
    nh = complex(mirror.index_host(wavelength)).real
    d = [mirror.d2, mirror.d1] * mirror.N if d is None else list(d)
    ns, ds = [nh] + [n2, n1] * mirror.N + [n1], [np.inf] + d + [np.inf]
    theta = np.radians(theta_deg)
    s, p = coh_tmm("s", ns, ds, theta, wavelength), coh_tmm("p", ns, ds, theta, wavelength)
    return s["R"], p["R"], s["T"], p["T"]


# --------------------------------------------------------------------------------------------------
# The library


def test_library_formulas_at_the_papers_wavelengths():
    # Leertouwer et al. (2011): chitin 1.572, 1.552, 1.541 and keratin 1.569, 1.556, 1.548 at 400, 500, 600 nm.
    chitin = dispersion.LIBRARY["chitin"].index([400.0, 500.0, 600.0])
    keratin = dispersion.LIBRARY["keratin"].index([400.0, 500.0, 600.0])
    np.testing.assert_allclose(chitin.real, [1.572, 1.552, 1.541], atol=1.5e-3)
    np.testing.assert_allclose(keratin.real, [1.569, 1.556, 1.548], atol=1.5e-3)
    # Stavenga et al. (2015): melanin 1.7-1.8 in the visible, absorbing, less so in the red.
    melanin = dispersion.LIBRARY["melanin"].index([400.0, 700.0])
    assert 1.79 < melanin[0].real < 1.81 and 1.69 < melanin[1].real < 1.71
    assert melanin[0].imag > melanin[1].imag > 0.0
    # Sellmeier media at the sodium D line: water 1.3330 (20 C), fused silica 1.4585, rutile (o) 2.613.
    at_589 = {name: dispersion.LIBRARY[name].index(589.3).real for name in ("water", "SiO2", "TiO2")}
    assert abs(at_589["water"] - 1.3330) < 5e-4 and abs(at_589["SiO2"] - 1.4585) < 5e-4 and abs(at_589["TiO2"] - 2.613) < 2e-3
    for entry in dispersion.LIBRARY.values():
        values = entry.index(np.arange(360.0, 831.0))
        assert np.all(np.isfinite(values)) and np.all(values.real >= 1.0) and np.all(values.imag >= 0.0), entry.name


def test_names_and_files(tmp_path):
    assert dispersion.dispersion_named("Chitin") is dispersion.LIBRARY["chitin"]
    table = tmp_path / "layer.csv"
    table.write_text("wavelength_nm,n,k\n350,1.6,0.1\n600,1.5,0.05\n850,1.4,0.0\n")
    entry = dispersion.dispersion_named(str(table))
    np.testing.assert_allclose(entry.index([350.0, 475.0, 725.0]), [1.6 + 0.1j, 1.55 + 0.075j, 1.45 + 0.025j])
    assert entry.step_nm == 250.0
    coefficients = tmp_path / "glass.toml"
    coefficients.write_text('formula = "sellmeier"\nunit = "um"\nterms = [[0.6961663, 0.00467914826], '
                            '[0.4079426, 0.0135120631], [0.8974794, 97.9340025]]\n')
    np.testing.assert_allclose(dispersion.dispersion_named(str(coefficients)).index(589.3),
                               dispersion.LIBRARY["SiO2"].index(589.3), rtol=1e-7)
    cauchy = tmp_path / "c.toml"
    cauchy.write_text('formula = "cauchy"\nA = 1.517\nB = 8800\n')
    np.testing.assert_allclose(dispersion.dispersion_named(str(cauchy)).index(500.0), dispersion.LIBRARY["chitin"].index(500.0))


@pytest.mark.parametrize("name, text, where", [
    ("bad.csv", "wavelength_nm,n,k\n360,1.5,0\n600,x,0\n", "bad.csv:3:"),
    ("short.csv", "wavelength_nm,n,k\n400,1.5,0\n700,1.5,0\n", "covers 400-700 nm"),
    ("order.csv", "360,1.5,0\n900,1.5,0\n800,1.5,0\n", "order.csv:3:"),
    ("neg.csv", "360,1.5,0\n900,1.5,-0.1\n", "neg.csv:2:"),
    ("bad.toml", 'formula = "cauchy"\nA = \n', "bad.toml:2:"),
    ("key.toml", 'formula = "cauchy"\nA = 1.5\nD = 3\n', "key.toml:3:"),
    ("pole.toml", 'formula = "sellmeier"\nterms = [[1.0, 250000.0]]\n', "pole.toml:1:"),
])
def test_bad_files_are_one_line_errors(tmp_path, name, text, where):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(dispersion.DispersionError) as error:
        dispersion.dispersion_named(str(path))
    assert where in str(error.value) and "\n" not in str(error.value)


def test_unknown_name_lists_the_library():
    with pytest.raises(dispersion.DispersionError, match="chitin, keratin"):
        dispersion.dispersion_named("unobtainium")


# --------------------------------------------------------------------------------------------------
# Exact spectra against tmm


MIRRORS = {
    "absorbing": NaturalMirror(n1=1.55, n2=1.68, k1=0.14, k2=0.03, Lambda=180.0, delta=0.5, N=12),
    "dispersive host": NaturalMirror(n1="chitin", n2="melanin", Lambda=190.0, delta=0.6, N=8, nh=1.0),
    "keratin in water": NaturalMirror(n1="keratin", n2="melanin", Lambda=300.0, delta=0.3, N=5, nh="water", k1=0.01),
}


def _resolve(mirror: NaturalMirror) -> NaturalMirror:
    named = {key: dispersion.LIBRARY[value] for key, value in vars(mirror).items() if isinstance(value, str)}
    return NaturalMirror(**{**vars(mirror), **named})


@pytest.mark.parametrize("name", list(MIRRORS))
@pytest.mark.parametrize("theta", [0.0, 40.0, 89.5])
def test_spectrum_equals_tmm(name, theta):
    mirror = _resolve(MIRRORS[name])
    wavelengths = np.array([360.0, 401.5, 455.0, 532.0, 610.25, 700.0, 830.0])
    ours = mirror_spectrum(mirror, wavelengths, [theta])
    reference = np.array([tmm_mirror(mirror, w, theta) for w in wavelengths])
    np.testing.assert_allclose(ours["Rs"][0], reference[:, 0], atol=1e-9, rtol=0)
    np.testing.assert_allclose(ours["Rp"][0], reference[:, 1], atol=1e-9, rtol=0)
    np.testing.assert_allclose(ours["T"][0], 0.5 * (reference[:, 2] + reference[:, 3]), atol=1e-9, rtol=0)
    assert np.all(ours["A"] >= -1e-12) and np.all(ours["R"] + ours["T"] <= 1.0 + 1e-12)


def test_spectrum_equals_tmm_for_a_thousand_cells():
    mirror = NaturalMirror(n1=dispersion.LIBRARY["chitin"], n2=1.7, k2=0.002, Lambda=170.0, delta=0.5, N=1000, nh=1.0)
    wavelengths = np.array([520.0, 545.0, 600.0])
    ours = mirror_spectrum(mirror, wavelengths, [20.0])
    reference = np.array([tmm_mirror(mirror, w, 20.0) for w in wavelengths])
    np.testing.assert_allclose(ours["Rs"][0], reference[:, 0], atol=1e-9, rtol=0)
    np.testing.assert_allclose(ours["Rp"][0], reference[:, 1], atol=1e-9, rtol=0)


def test_disorder_is_the_mean_of_tmm_over_realisations():
    """sigma > 0: within 3 standard errors (plus 1e-3) of tmm's mean over 2,000 independent seeded realisations."""
    mirror = NaturalMirror(n1=1.0, n2=dispersion.LIBRARY["chitin"], k2=0.02, Lambda=250.0, delta=0.5, N=6, nh=1.0, sigma=0.15)
    wavelengths = np.array([430.0, 560.0])
    ours = mirror_spectrum(mirror, wavelengths, [30.0])["R"][0]
    rng = np.random.default_rng(7)
    base = np.array([mirror.d2, mirror.d1] * mirror.N)
    eps = rng.standard_normal((2000, base.size))
    while np.any(np.abs(eps) > 3.0):  # truncation by rejection: independent of the inverse-CDF draw
        bad = np.abs(eps) > 3.0
        eps[bad] = rng.standard_normal(int(bad.sum()))
    samples = np.array([[0.5 * sum(tmm_mirror(mirror, w, 30.0, base * (1.0 + 0.15 * e))[:2]) for w in wavelengths] for e in eps])
    mean, se = samples.mean(axis=0), samples.std(axis=0, ddof=1) / np.sqrt(len(samples))
    assert np.all(np.abs(ours - mean) <= 3.0 * se + 1e-3), (ours, mean, se)
    # Disorder changes the spectrum (the test could fail): the ordered mirror is outside those bounds somewhere.
    ordered = mirror_spectrum(NaturalMirror(**{**vars(mirror), "sigma": 0.0}), wavelengths, [30.0])["R"][0]
    assert np.any(np.abs(ordered - mean) > 3.0 * se + 1e-3)


def test_grid_includes_a_tables_step(tmp_path):
    table = tmp_path / "fine.csv"
    table.write_text("".join(f"{w:g},1.6,0\n" for w in np.arange(360.0, 830.5, 0.5)))
    mirror = NaturalMirror(n2=dispersion.load_dispersion(table))
    grid = wavelength_grid(mirror)
    assert grid[0] == 360.0 and grid[-1] == 830.0 and np.isclose(np.diff(grid).max(), 0.5)
    assert wavelength_grid(NaturalMirror()).size == 471


def test_truncated_normal_noise():
    eps = multilayer.disorder_noise(40)
    assert eps.shape == (multilayer.REALISATIONS, 40) and np.abs(eps).max() <= 3.0
    assert abs(eps.mean()) < 0.01 and abs(eps.std() - 0.986) < 0.01  # the truncated law's sd: 0.9866


# --------------------------------------------------------------------------------------------------
# The command


def test_spectrum_command_json(capsys):
    main(["spectrum", "bragg_mirror", "--set", "n2=chitin", "--set", "k1=0.05", "--set", "n1=1.2",
          "--set", "N=6", "--theta", "0,60", "--json"])
    document = json.loads(capsys.readouterr().out)
    assert list(document) == ["wavelength_nm", "theta_deg", "R", "Rs", "Rp", "T", "A"]
    assert document["theta_deg"] == [0.0, 60.0] and len(document["wavelength_nm"]) == 471
    assert np.asarray(document["R"]).shape == (2, 471)
    mirror = NaturalMirror(n1=1.2, n2=dispersion.LIBRARY["chitin"], k1=0.05, N=6, Lambda=500.0, delta=0.5)
    for row, theta in enumerate((0.0, 60.0)):
        Rs, Rp, Ts, Tp = tmm_mirror(mirror, document["wavelength_nm"][123], theta)
        assert abs(document["R"][row][123] - 0.5 * (Rs + Rp)) < 1e-9
        assert abs(document["T"][row][123] - 0.5 * (Ts + Tp)) < 1e-9


def test_spectrum_command_files_and_errors(tmp_path, capsys):
    csv_out, png = tmp_path / "s.csv", tmp_path / "s.png"
    main(["spectrum", "bragg_mirror", "--set", "n2=melanin", "--theta", "0,45", "--csv", str(csv_out), "--plot", str(png)])
    lines = csv_out.read_text().splitlines()
    assert lines[0].startswith("wavelength_nm,R@0,Rs@0,Rp@0,T@0,A@0,R@45") and len(lines) == 472
    assert png.stat().st_size > 10_000
    for argv, message in ((["--set", "n2=unobtainium"], "neither a number nor a dispersion"),
                          (["--set", "sigma=0.5"], "parameter 'sigma': value 0.5 is outside its range [0, 0.3]"),
                          (["--theta", "95"], "--theta"),
                          (["--set", f"n1={tmp_path / 'missing.csv'}"], "missing.csv: no such file")):
        with pytest.raises(SystemExit):
            main(["spectrum", "bragg_mirror", *argv])
        err = capsys.readouterr().err.strip()
        assert message in err and "\n" not in err and "Traceback" not in err


def test_info_dispersions(capsys):
    main(["info", "--dispersions"])
    out = capsys.readouterr().out
    for name in ("chitin", "keratin", "melanin", "guanine", "water", "air", "SiO2", "TiO2"):
        assert f"\n{name}: " in out
    assert "Leertouwer" in out and "Stavenga" in out


# --------------------------------------------------------------------------------------------------
# Fitting a measured spectrum


@pytest.mark.slow
def test_fit_recovers_random_absorbing_dispersive_mirrors(tmp_path, capsys):
    """Seeded random mirrors (chitin and an absorbing layer) from their own spectra: median RMS <= 0.01."""
    rng = np.random.default_rng(35)
    wavelengths = np.arange(380.0, 801.0, 20.0)
    rms = []
    for k in range(3):
        truth = NaturalMirror(n1=dispersion.LIBRARY["chitin"], n2=float(rng.uniform(1.6, 1.9)), k2=float(rng.uniform(0.0, 0.1)),
                              Lambda=float(rng.uniform(150.0, 400.0)), delta=float(rng.uniform(0.2, 0.8)), N=int(rng.integers(3, 16)), nh=1.0)
        R = mirror_spectrum(truth, wavelengths, [0.0])["R"][0]
        measured = tmp_path / f"m{k}.csv"
        measured.write_text("wavelength_nm,R (%)\n" + "".join(f"{w:g},{100 * r:.6f}\n" for w, r in zip(wavelengths, R)))
        main(["design", "bragg_mirror", "--target-spectrum", str(measured), "--fix", "n1=chitin", "--fix", "nh=1", "--json"])
        document = json.loads(capsys.readouterr().out)
        assert document["reading"] == "R in percent (header)"
        rms.append(document["rms"])
        # The reported fit is the spectrum of the reported values (tmm at one wavelength).
        v = document["values"]
        fitted = NaturalMirror(n1=dispersion.LIBRARY["chitin"], n2=v["n2"], k1=v["k1"], k2=v["k2"], Lambda=v["Lambda"],
                               delta=v["delta"], N=v["N"], nh=1.0)
        Rs, Rp, _, _ = tmm_mirror(fitted, wavelengths[7], 0.0)
        assert abs(document["fitted"][7] - 0.5 * (Rs + Rp)) < 1e-9
    assert np.median(rms) <= 0.01, rms


def test_fit_file_errors(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("wavelength_nm,R\n400,0.1\n410,oops\n")
    with pytest.raises(SystemExit):
        main(["design", "bragg_mirror", "--target-spectrum", str(bad)])
    err = capsys.readouterr().err.strip()
    assert "bad.csv:3:" in err and "\n" not in err
