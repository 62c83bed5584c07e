"""
Absorption and disorder as design parameters (``design bragg_mirror --fix k2=0.05 --fix sigma=0.1``,
``--free k2``): seeded round trips of natural mirrors from their own exact colours
(:func:`explorer.physics.natural.natural_rgb`), and the search's held parameters (0 unless named).
"""

from __future__ import annotations

import json

import numpy as np

from conftest import run_cli

from explorer import design
from explorer.design.media import mirror_with_media
from explorer.physics.natural import natural_rgb

RANGES = dict(n1=(1, 2.5), n2=(1, 2.5), Lambda=(50, 1500), delta=(0, 1), N=(1, 1000), nh=(0, 2.5), k1=(0, 1), k2=(0, 1),
              sigma=(0, 0.3))
ANGLES = [0.0, 30.0, 60.0]


def _targets(truth):
    colours = natural_rgb(np.cos(np.radians(ANGLES)), mirror_with_media(truth, {}))
    return [design.Target(a, tuple(float(c) for c in rgb)) for a, rgb in zip(ANGLES, colours)]


def test_a_disordered_absorbing_mirror_is_recovered_with_k2_and_sigma_fixed():
    rng = np.random.default_rng(7)
    truth = dict(n1=1.0, n2=1.56, Lambda=float(rng.uniform(160, 260)), delta=float(rng.uniform(0.3, 0.7)), N=8, nh=0.0,
                 k1=0.0, k2=0.05, sigma=0.1)
    fixed = {k: truth[k] for k in ("n1", "n2", "nh", "N", "k2", "sigma")}
    result = design.design("bragg_mirror", _targets(truth), RANGES, fixed, seed=3)
    assert np.all(result.delta_e2000 < 1.0), result.delta_e2000
    assert abs(result.values["Lambda"] / truth["Lambda"] - 1.0) < 0.01, (result.values, truth)
    # The achieved colours are the disordered, absorbing mirror's (an independent recomputation).
    found = {**truth, **result.values}
    np.testing.assert_allclose(result.achieved_rgb, natural_rgb(np.cos(np.radians(ANGLES)), mirror_with_media(found, {})),
                               atol=1e-12)


def test_a_free_extinction_is_found():
    truth = dict(n1=1.0, n2=1.56, Lambda=210.0, delta=0.45, N=8, nh=0.0, k1=0.0, k2=0.08, sigma=0.0)
    # N fixed: with absorption a thicker stack's colours converge (light no longer reaches its last cells).
    fixed = {k: truth[k] for k in ("n1", "n2", "nh", "N")}
    result = design.design("bragg_mirror", _targets(truth), RANGES, fixed, seed=0, free=["k2"], tries=1)
    assert np.all(result.delta_e2000 < 1.0), (result.values, result.delta_e2000)
    assert abs(result.values["k2"] - 0.08) < 0.01, result.values


def test_held_parameters_stay_off_and_unreported():
    # Without --fix or --free, k1, k2 and sigma stay 0: the paper's mirror, reported as before.
    truth = dict(n1=1.0, n2=1.56, Lambda=210.0, delta=0.45, N=8, nh=0.0)
    fixed = {k: truth[k] for k in ("n1", "n2", "nh", "N")}
    result = design.design("bragg_mirror", _targets(truth), RANGES, fixed, seed=0, tries=1)
    assert not {"k1", "k2", "sigma"} & set(result.values) and result.median_delta_e2000 < 0.1, result


def test_the_cli_frees_an_extinction_by_name():
    truth = dict(n1=1.0, n2=1.56, Lambda=210.0, delta=0.45, N=8, nh=0.0, k1=0.0, k2=0.08, sigma=0.0)
    args = [f"--target={t.theta_deg:g}:{t.rgb[0]!r},{t.rgb[1]!r},{t.rgb[2]!r}" for t in _targets(truth)]
    run = run_cli("design", "bragg_mirror", *args, "--fix", "n1=1", "--fix", "n2=1.56", "--fix", "nh=0", "--fix", "N=8",
                  "--free", "Lambda,delta,k2", "--tries", "1", "--json")
    assert run.returncode == 0, run.stderr
    found = json.loads(run.stdout)["set"]
    assert abs(found["k2"] - 0.08) < 0.01 and "sigma" not in found, found  # held at 0: not reported


# --------------------------------------------------------------------------------------------------
# The same in a measured spectrum's fit (design --target-spectrum)


def _spectrum_file(tmp_path, mirror, name="m.csv"):
    from explorer.physics.natural import mirror_spectrum

    wavelengths = np.arange(380.0, 801.0, 10.0)
    R = mirror_spectrum(mirror, wavelengths, [0.0])["R"][0]
    path = tmp_path / name
    path.write_text("wavelength_nm,R\n" + "".join(f"{w:g},{r:.8f}\n" for w, r in zip(wavelengths, R)))
    return path, wavelengths, R


def test_a_disordered_absorbing_spectrum_is_fitted_with_sigma_and_k2_fixed(tmp_path):
    from explorer.physics.dispersion import LIBRARY
    from explorer.physics.natural import NaturalMirror

    rng = np.random.default_rng(11)
    truth = NaturalMirror(n1=1.0, n2=LIBRARY["chitin"], k2=0.05, sigma=0.1, Lambda=float(rng.uniform(180, 260)),
                          delta=float(rng.uniform(0.3, 0.7)), N=6, nh=1.0)
    path, _, _ = _spectrum_file(tmp_path, truth)
    run = run_cli("design", "bragg_mirror", "--target-spectrum", str(path), "--fix", "n1=1", "--fix", "n2=chitin",
                  "--fix", "nh=1", "--fix", "k2=0.05", "--fix", "sigma=0.1", "--fix", "N=6", "--fix", "k1=0", "--json")
    assert run.returncode == 0, run.stderr
    document = json.loads(run.stdout)
    assert document["rms"] < 0.01 and document["values"]["sigma"] == 0.1, document["values"]
    assert abs(document["values"]["Lambda"] / truth.Lambda - 1.0) < 0.02, (document["values"], truth)


def test_a_free_sigma_and_extinction_are_fitted_by_name(tmp_path):
    from explorer.physics.natural import NaturalMirror

    truth = NaturalMirror(n1=1.0, n2=1.56, k2=0.03, sigma=0.08, Lambda=220.0, delta=0.5, N=6, nh=1.0)
    path, _, _ = _spectrum_file(tmp_path, truth)
    run = run_cli("design", "bragg_mirror", "--target-spectrum", str(path), "--fix", "n1=1", "--fix", "n2=1.56",
                  "--fix", "nh=1", "--fix", "N=6", "--free", "Lambda,delta,k2,sigma", "--json")
    assert run.returncode == 0, run.stderr
    document = json.loads(run.stdout)
    values = document["values"]
    assert document["rms"] < 0.01 and abs(values["sigma"] - 0.08) < 0.04 and abs(values["k2"] - 0.03) < 0.02, document


def test_fit_refusals_are_one_line(tmp_path):
    from conftest import one_line_error
    from explorer.physics.natural import NaturalMirror

    path, _, _ = _spectrum_file(tmp_path, NaturalMirror(n1=1.0, n2=1.56, Lambda=220.0, delta=0.5, N=6))
    for args, message in ((["--fix", "sigma=0.5"], "sigma='0.5': a number in [0, 0.3]"),
                          (["--fix", "k2=-1"], "k2='-1': a number in"),
                          (["--free", "Lambda,kappa"], "'kappa' is not fitted"),
                          (["--fix", "N=6", "--free", "N"], "also fixed")):
        assert message in one_line_error(run_cli("design", "bragg_mirror", "--target-spectrum", str(path), *args))


def test_a_count_off_by_two_is_walked_back():
    # Keratin over melanin: its colours change little with N, so a polish may end at another count; the walk to
    # neighbouring counts (explorer.design.solve._neighbouring_counts) finds the truth's from two cells off.
    from explorer.design.media import with_media
    from explorer.design.search import _Problem
    from explorer.design.solve import _neighbouring_counts
    from explorer.design.targets import parameter_box
    from explorer.physics.dispersion import LIBRARY

    media = {"n1": LIBRARY["keratin"], "n2": LIBRARY["melanin"]}
    truth = dict(n1=1.5515, n2=1.7263, Lambda=173.9, delta=0.4536, N=6, nh=0.0)
    colours = natural_rgb(np.cos(np.radians(ANGLES)), mirror_with_media(truth, media))
    model = with_media(design.design_model("bragg_mirror"), media)
    fixed = {k: truth[k] for k in ("n1", "n2", "nh")}
    problem = _Problem(model, parameter_box(model, RANGES), fixed, [design.Target(a, tuple(c)) for a, c in zip(ANGLES, colours)], None)
    start = {**truth, "N": 8, "k1": 0.0, "k2": 0.0, "sigma": 0.0}
    cost = float(np.sum(problem.fine_residuals(problem.unit_row(start))[1] ** 2))
    assert cost > len(ANGLES), cost  # two cells off: above ΔE2000 1 per target
    found = _neighbouring_counts(problem, start, cost, 1.5)
    assert found["N"] == 6 and abs(found["Lambda"] - 173.9) < 0.5, found
