"""
The colour design with media (``design bragg_mirror --fix n2=chitin --target ...``): the batch model with
dispersive, absorbing indices against the exact spectra and colours of natural mirrors
(:mod:`explorer.physics.natural`), and a round trip of a natural mirror from its own colours.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import one_line_error, run_cli

from explorer.design import design_model
from explorer.physics.bragg import bragg_reflectance_batch
from explorer.design.media import _indices, mirror_with_media, with_media
from explorer.physics.dispersion import LIBRARY
from explorer.physics.natural import mirror_spectrum, natural_rgb

WAVELENGTHS = np.linspace(360.0, 830.0, 236)
#: Natural mirrors: (media by parameter, the other design values); melanin absorbs (k ~ 0.15 at 400 nm).
MIRRORS = [
    ({"n2": LIBRARY["chitin"]}, dict(n1=1.0, n2=0.0, Lambda=300.0, delta=0.5, N=8, nh=0.0)),
    ({"n1": LIBRARY["keratin"], "n2": LIBRARY["melanin"]}, dict(n1=0.0, n2=0.0, Lambda=250.0, delta=0.6, N=5, nh=0.0)),
    ({"n1": LIBRARY["melanin"]}, dict(n1=0.0, n2=1.56, Lambda=220.0, delta=0.4, N=12, nh=1.0)),
    ({"n2": LIBRARY["melanin"], "nh": LIBRARY["water"]}, dict(n1=1.56, n2=0.0, Lambda=400.0, delta=0.5, N=30, nh=0.0)),
]
IDS = ["-".join(f"{k}={d.name}" for k, d in media.items()) for media, _ in MIRRORS]
ANGLES = np.array([0.0, 30.0, 60.0, 85.0])


@pytest.mark.parametrize("media, values", MIRRORS, ids=IDS)
def test_batch_spectra_equal_the_exact_natural_mirror(media, values):
    rows = {k: np.array([float(v)]) for k, v in values.items()}
    n = _indices(rows, media, WAVELENGTHS)
    R = bragg_reflectance_batch(n["n1"], n["n2"], rows["Lambda"], rows["delta"], rows["N"], n["nh"],
                                np.cos(np.radians(ANGLES)), WAVELENGTHS)[0]
    exact = mirror_spectrum(mirror_with_media(values, media), WAVELENGTHS, ANGLES)["R"]
    np.testing.assert_allclose(R, exact, rtol=0.0, atol=1e-9)


@pytest.mark.parametrize("media, values", MIRRORS, ids=IDS)
def test_batch_colours_equal_the_exact_colours(media, values):
    model = with_media(design_model("bragg_mirror"), media)
    cos_theta = np.cos(np.radians(ANGLES[:3]))
    exact = natural_rgb(cos_theta, mirror_with_media(values, media))
    coarse = model.batch({k: np.array([float(v)]) for k, v in values.items()}, cos_theta)[0]
    polish = model.converged(values, cos_theta, final=False)
    # The coarse nodes every 2 nm, the polish's every 1 nm: linear interpolation of resolved spectra.
    np.testing.assert_allclose(coarse, exact, atol=2e-4)
    np.testing.assert_allclose(polish, exact, atol=1e-4)
    np.testing.assert_array_equal(model.converged(values, cos_theta, final=True), exact)


def test_real_indices_take_the_same_path_bit_for_bit():
    # A medium of constant real index is the number: the same batch colours, bit for bit.
    values = {k: np.array([v]) for k, v in dict(n1=1.0, n2=1.83, Lambda=250.0, delta=0.5, N=6.0, nh=0.0).items()}
    cos_theta = np.cos(np.radians([0.0, 45.0]))
    plain = design_model("bragg_mirror").batch(values, cos_theta)
    media = with_media(design_model("bragg_mirror"), {"n2": LIBRARY["guanine"]}).batch(values, cos_theta)
    np.testing.assert_array_equal(plain, media)


def test_design_recovers_a_chitin_mirror_from_its_colours():
    # A chitin-air multilayer (a butterfly scale's, its count known): the period and the share from 5 colours.
    media = {"n2": LIBRARY["chitin"]}
    truth = dict(n1=1.0, n2=0.0, Lambda=190.0, delta=0.55, N=7, nh=0.0)
    angles = [0.0, 20.0, 40.0, 60.0, 75.0]
    colours = natural_rgb(np.cos(np.radians(angles)), mirror_with_media(truth, media))
    args = [f"--target={a:g}:{c[0]!r},{c[1]!r},{c[2]!r}" for a, c in zip(angles, colours)]
    run = run_cli("design", "bragg_mirror", *args, "--fix", "n2=chitin", "--fix", "n1=1", "--fix", "nh=0",
                  "--fix", "N=7", "--tries", "1", "--json")
    assert run.returncode == 0, run.stderr
    result = json.loads(run.stdout)
    assert result["set"]["n2"] == "chitin" and result["set"]["n1"] == 1.0, result["set"]
    assert result["median_delta_e2000"] < 0.1, result
    assert abs(result["set"]["Lambda"] - 190.0) < 1.0 and abs(result["set"]["delta"] - 0.55) < 0.01, result["set"]
    found = {**truth, **{k: v for k, v in result["set"].items() if k != "n2"}}
    # The reported colours are the exact natural mirror's (an independent recomputation).
    achieved = np.array([t["achieved_rgb"] for t in result["targets"]])
    np.testing.assert_allclose(achieved, natural_rgb(np.cos(np.radians(angles)), mirror_with_media(found, media)), atol=1e-12)


def test_design_with_an_absorbing_medium_reports_it_by_name():
    # Keratin over melanin (k > 0), the search's other parameters free: the text report and its render line.
    media = {"n1": LIBRARY["keratin"], "n2": LIBRARY["melanin"]}
    truth = dict(n1=0.0, n2=0.0, Lambda=170.0, delta=0.6, N=4, nh=1.0)
    colours = natural_rgb(np.cos(np.radians([0.0, 45.0])), mirror_with_media(truth, media))
    args = [f"--target={a:g}:{c[0]!r},{c[1]!r},{c[2]!r}" for a, c in zip([0.0, 45.0], colours)]
    run = run_cli("design", "bragg_mirror", *args, "--fix", "n1=keratin", "--fix", "n2=melanin", "--fix", "nh=1",
                  "--fix", "N=4", "--tries", "1")
    assert run.returncode == 0, run.stderr
    assert "--set n1=keratin --set n2=melanin" in run.stdout, run.stdout
    assert "render: " in run.stdout and " render " in run.stdout.split("render: ")[1], run.stdout
    median = float(run.stdout.split("median ΔE2000 ")[1].split(",")[0])
    assert median < 0.1, run.stdout


@pytest.mark.parametrize("args, message", [
    (["--fix", "n2=unobtainium"], "unobtainium"),
    (["--fix", "nh=melanin"], "absorbs"),
    (["--fix", "n2=chitin", "--fix", "n2=1.5"], "given twice"),
    (["--fix", "n2=chitin", "--free", "n2"], "also fixed"),
    (["--fix", "sigma=0.5"], "outside its range"),
    (["--fix", "k2=-0.1"], "outside its range"),
    (["--free", "Lambda,kappa"], "not a design parameter"),
])
def test_media_refusals_are_one_line(args, message):
    assert message in one_line_error(run_cli("design", "bragg_mirror", "--target", "0:#3f9f4f", *args))


def test_a_thin_film_takes_no_medium():
    assert "not a design parameter" in one_line_error(run_cli("design", "thin_film", "--target", "0:#3f9f4f", "--fix", "n2=chitin"))


def test_a_guessed_absorbing_mirror_survives_the_scan():
    # The scan screens with melanin's real index at 550 nm; the shapes it places are ranked again on the
    # absorbing model, so a guessed truth is refined rather than lost to a lossless look-alike (N = 6 with a host).
    from explorer import design
    from explorer.design.media import reference_value

    media = {"n2": LIBRARY["melanin"]}
    truth = dict(n1=1.56, n2=reference_value(media["n2"]), Lambda=210.0, delta=0.45, N=5, nh=0.0)
    angles = [0.0, 20.0, 40.0, 60.0, 75.0]
    colours = natural_rgb(np.cos(np.radians(angles)), mirror_with_media(truth, media))
    ranges = dict(n1=(1, 2.5), n2=(1, 2.5), Lambda=(50, 1500), delta=(0, 1), N=(1, 1000), nh=(0, 2.5))
    result = design.design("bragg_mirror", [design.Target(a, tuple(c)) for a, c in zip(angles, colours)], ranges,
                           media=media, guesses=[truth])
    assert result.median_delta_e2000 < 0.05 and result.values["N"] == 5, result


def test_painting_refuses_a_medium_in_one_line(tmp_path):
    assert "painting takes an index as a number" in one_line_error(run_cli(
        "design", "bragg_mirror", "--target-image", str(tmp_path / "a.png"), "--out-maps", str(tmp_path / "maps"),
        "--fix", "n2=chitin"))
