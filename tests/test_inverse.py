"""The inverse method (explorer.physics.inverse; Bati, Barla & Pacanowski 2021, Secs. 5-6) against the forward model.

forward(inverse(lobes)) must reproduce each requested lobe at normal incidence: its energy on every
channel, its variance on the channel that sets the roughness (Sec. 5.2.3: the brightest R'; on every
channel when the lobes are achromatic). Closed forms of the paper (Eqs. 1, 7-10) check the 1-layer
classes independently of the forward model's tables.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import REPO_ROOT, one_line_error, run_cli
from explorer.dev.validation_studies import INVERSE_CASES, brightest_channel_below
from explorer.physics import inverse, lobes, lobes_fgd
from explorer.physics.inverse import InverseError, Lobe

#: The bound for forward(inverse(lobes)) at normal incidence.
ROUND_TRIP_TOLERANCE = 1e-3
#: The colour channels other than the one that sets a roughness keep their own variance (Sec. 5.2.3);
#: measured up to 1.2e-3 on the cases below.
OTHER_CHANNEL_VARIANCE = 5e-3

CASES = INVERSE_CASES


@pytest.mark.parametrize("case", list(CASES))
def test_forward_of_inverse_reproduces_the_lobes(case):
    lobe_list = CASES[case]
    stack = inverse.invert_lobes(lobe_list)
    energies, variances = inverse.forward_lobes(stack, [lobe.layers for lobe in lobe_list])
    for k, lobe in enumerate(lobe_list):
        np.testing.assert_allclose(energies[k], lobe.energy, atol=ROUND_TRIP_TOLERANCE, err_msg=f"{case}: lobe {k + 1} energy")
        c = brightest_channel_below(stack, lobe_list, k)
        assert abs(variances[k][c] - lobe.variance) <= ROUND_TRIP_TOLERANCE, f"{case}: lobe {k + 1} sigma {variances[k]} != {lobe.variance}"
        assert np.abs(variances[k] - lobe.variance).max() <= OTHER_CHANNEL_VARIANCE
    # Within the constraints, each interface's lobes merged at normal incidence: 2-layer lobes are one lobe.
    raw_energies, raw_variances = lobes.lobes(stack, 1.0)
    i = 0
    for lobe in lobe_list:
        if lobe.layers == 2:
            assert np.abs(raw_variances[i] - raw_variances[i + 1]).max() <= OTHER_CHANNEL_VARIANCE
        i += lobe.layers
    for i in range(1, stack.count + 1):
        assert 0.0 <= stack.alpha[i] <= 1.0
        if not (i == stack.count and stack.conductor):
            assert 1.0 <= stack.eta[i].mean() <= lobes.ETA_MAX + 1e-12
        else:
            assert np.all(stack.kappa[i] >= stack.eta[i] - 1e-9), "kappa >= eta (Sec. 5.1.2)"
    assert np.all(stack.tau >= 0.0)


def test_round_trip_with_the_tir_term():
    lobe_list = CASES["fig20_haze_colour"]
    stack = inverse.invert_lobes(lobe_list, tir=True)
    assert stack.tir
    energies, variances = inverse.forward_lobes(stack, [2, 1])
    for k, lobe in enumerate(lobe_list):
        np.testing.assert_allclose(energies[k], lobe.energy, atol=ROUND_TRIP_TOLERANCE)
        assert abs(variances[k][brightest_channel_below(stack, lobe_list, k)] - lobe.variance) <= ROUND_TRIP_TOLERANCE
    assert not np.allclose(stack.eta, inverse.invert_lobes(lobe_list).eta), "the TIR term changes the stack"


def test_achromatic_round_trip_is_exact_on_every_channel():
    lobe_list = CASES["fig10c_two_layer_rough"]
    energies, variances = inverse.forward_lobes(inverse.invert_lobes(lobe_list), [2])
    np.testing.assert_allclose(variances[0], 0.02, atol=1e-9)
    np.testing.assert_allclose(energies[0], 0.15, atol=1e-9)


def test_smooth_one_layer_dielectric_is_eq7():
    for R in (0.01, 0.04, 0.2, 0.35):
        lower, upper = inverse.dielectric_roots(R, 0.0, eta_0=1.0)
        np.testing.assert_allclose(upper, (1 + np.sqrt(R)) / (1 - np.sqrt(R)), rtol=1e-9)
        assert np.isnan(lower) or lower < 1.0  # only one root above 1 in air (Sec. 5.1.1)
    lower, upper = inverse.dielectric_roots(0.04, 0.0, eta_0=1.6)
    np.testing.assert_allclose([lower, upper], [1.6 * 0.8 / 1.2, 1.6 * 1.2 / 0.8], rtol=1e-9)


def test_smooth_conductor_class_is_eqs_8_to_10():
    R, eta_0 = 0.6, 1.5
    eta_min, eta_max = inverse.conductor_bounds(R, eta_0)
    np.testing.assert_allclose(eta_min, eta_0 * (1 - R) / (1 + R))
    for eta in np.linspace(eta_min, eta_max, 5):
        kappa = inverse.conductor_kappa(R, 0.0, eta, eta_0)
        ratio = eta / eta_0
        eq8 = eta_0 * np.sqrt((R * (ratio + 1) ** 2 - (ratio - 1) ** 2) / (1 - R))
        np.testing.assert_allclose(kappa, eq8, rtol=1e-8)
    np.testing.assert_allclose(inverse.conductor_kappa(R, 0.0, eta_max, eta_0), eta_max, rtol=1e-8)  # kappa = eta at Eq. 9
    assert np.isnan(inverse.conductor_bounds(0.16, 1.0)[1]) and np.isfinite(inverse.conductor_bounds(0.18, 1.0)[1])


def test_highest_reflectances_are_the_papers():
    """Sec. 5.2.1: with eta_max = 4, 0.36 for a 1-layer and 0.53 for a 2-layer dielectric lobe in air."""
    assert lobes_fgd.normal_reflectance(1.0, 4.0) == pytest.approx(0.36)
    assert inverse.two_layer_class(0.52, 0.0, samples=31).valid.any()
    assert not inverse.two_layer_class(0.54, 0.0, samples=31).valid.any()
    with pytest.raises(InverseError, match=r"achievable energy in \[0, 0.36\]$"):
        inverse.invert_lobes([Lobe(0.37, 0.0)])


def test_two_layer_class_points_are_stacks_with_the_lobe():
    """Every valid (eta_1, eta_2) of the sampled class, as a stack, gives the lobe back (a few of them)."""
    energy, variance = np.array([0.09, 0.09, 0.15]), 0.01
    cls = inverse.two_layer_class(energy, variance, samples=24)
    points = np.argwhere(cls.valid)
    assert len(points) > 5
    for i, j in points[:: max(1, len(points) // 5)]:
        stack = inverse.two_layer_point_stack(cls, i, j)
        energies, variances = inverse.forward_lobes(stack, [2])
        np.testing.assert_allclose(energies[0], energy, atol=ROUND_TRIP_TOLERANCE)
        assert abs(variances[0][2] - variance) <= ROUND_TRIP_TOLERANCE
    assert np.all(cls.tau_1[cls.valid] >= 0.0)
    i, j = np.argwhere(~cls.valid)[0]
    with pytest.raises(InverseError, match="outside the constrained class"):
        inverse.two_layer_point_stack(cls, i, j)


def test_choices_pick_other_points_of_the_class():
    lobe_list = [Lobe(0.04, 0.0), Lobe([0.1, 0.2, 0.1], 0.03, layers=2)]
    first = inverse.invert_lobes(lobe_list)
    second = inverse.invert_lobes(lobe_list, [{}, {"eta_top": 1.2, "tau_top": 0.05}])
    assert abs(second.eta[2].mean() - 1.2) < 1e-12 and np.allclose(second.tau[1], 0.05)
    assert not np.allclose(first.eta, second.eta)
    for stack in (first, second):
        energies, _ = inverse.forward_lobes(stack, [1, 2])
        np.testing.assert_allclose(energies[1], [0.1, 0.2, 0.1], atol=ROUND_TRIP_TOLERANCE)


@pytest.mark.parametrize("lobe_list, message", [
    ([Lobe(0.5, 0.0)], r"^lobe 1: energy 0.5 is not achievable by a 1-layer dielectric lobe \(eta in \[1, 4\]\): achievable energy in \[0, 0.36\]$"),
    ([Lobe(0.1, -0.01)], r"^lobe 1: variance sigma = -0.01 must lie in \[0, 1e\+06\)$"),
    ([Lobe(0.1, 0.0, base="conductor")], r"conductors with kappa >= eta reach \[0.1716"),
    ([Lobe([0.1, 0.2, 0.1], 0.0)], r"1-layer dielectric lobe in air is achromatic"),
    ([Lobe(0.04, 0.07), Lobe([0.6, 0.25, 0.25], 0.03, base="conductor")], r"^lobe 2: variance is below what the layers above give \(constraint sigma\^R >= 0, Eq. 19\): achievable sigma >= 0.03"),
    ([Lobe(0.04, 0.0)], None),
    ([Lobe(0.3, 0.0), Lobe(0.75, 0.02, base="conductor")], r"^lobe 2: energies sum to 1.05: the lobes' energies must sum below 1$"),
])
def test_bad_lobes_say_which_constraint_fails(lobe_list, message):
    choices = None
    if message is None:  # a chosen eta in air that is not a root of Eq. 7
        choices, message = [{"eta": 1.3}], r"^lobe 1: in air the energy fixes eta \(Eq. 7, no absorbing medium above\): eta in \{1.5\}, not 1.3$"
    with pytest.raises(InverseError, match=message) as error:
        inverse.invert_lobes(lobe_list, choices)
    assert "\n" not in str(error.value)


def test_cli_inverse_json_prints_a_stack_that_renders():
    run = run_cli("inverse", "--lobe", "R=0.04 sigma=0", "--lobe", "R=0.9,0.7,0.5 sigma=0.03 base=conductor", "--json")
    assert run.returncode == 0, run.stderr
    result = json.loads(run.stdout)
    assert len(result["stack"]["interfaces"]) == 2 and result["values"]["conductor"] == 1
    for entry in result["lobes"]:
        np.testing.assert_allclose(entry["forward"]["R"], entry["requested"]["R"], atol=ROUND_TRIP_TOLERANCE)
    from explorer.materials.brd import load_material
    from explorer.materials.models import model_for

    material = load_material(REPO_ROOT / "shaders" / "layered_lobes.brd")
    model = model_for(material, material.resolve(result["values"]))
    np.testing.assert_allclose(model.reflectance(1.0), 0.04 + np.array([0.9, 0.7, 0.5]), atol=ROUND_TRIP_TOLERANCE)


def test_cli_bad_lobe_is_one_line():
    line = one_line_error(run_cli("inverse", "--lobe", "R=0.5 sigma=0"))
    assert "achievable energy in [0, 0.36]" in line
    line = one_line_error(run_cli("inverse", "--lobe", "R=0.1 sigma=oops"))
    assert "sigma" in line


def test_cli_figure_writes_png(tmp_path):
    out = tmp_path / "class.png"
    run = run_cli("figure", "--lobe", "R=0.09,0.09,0.15 sigma=0 layers=2", "--out", str(out), "--samples", "24")
    assert run.returncode == 0, run.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_presets_reproduce_their_figures_lobes():
    """Every preset's stack (shaders/presets/layered_lobes.toml, as written) gives its figure's lobes back."""
    from explorer.materials.lobes_model import stack_from_values
    from explorer.materials.lobes_presets import FIGURES, PRESET_FILE
    from explorer.materials.presets import load_presets

    presets = load_presets(PRESET_FILE).presets
    assert len(presets) >= 25
    for name, preset in presets.items():
        _, _, lobe_list, _ = FIGURES[name]
        stack = stack_from_values(preset.resolve())
        energies, _ = inverse.forward_lobes(stack, [lobe.layers for lobe in lobe_list])
        for k, lobe in enumerate(lobe_list):
            # The TOML keeps 6 significant digits.
            np.testing.assert_allclose(energies[k], lobe.energy, atol=2e-5, err_msg=f"{name}: lobe {k + 1}")


def test_tau_0_range_is_eq16():
    """T_0 = 1/2 log([R_min, R_max] / R_02) with R_max the 2-layer maximum (0.53 smooth in air, Sec. 5.2.1)."""
    R_min, R_max = inverse.two_layer_energy_bounds(0.0, samples=16)
    assert R_min == pytest.approx(0.0, abs=1e-12) and R_max == pytest.approx(2 * 0.36 / 1.36, rel=1e-9)  # the 1|4|1 slab
    low, high = inverse.tau_0_range(0.2, 0.0)
    assert low == 0.0 and high == pytest.approx(0.5 * np.log(R_max / 0.2), rel=1e-6)
    assert np.isnan(inverse.tau_0_range(0.6, 0.0)[0])
    # Rough: the bounds are the forward model's (the slab 1 | 4 | 1 at alpha = f^-1(0.02) on both interfaces).
    alpha = float(lobes.roughness_from_variance(0.02))
    slab = lobes.make_stack([4.0, 1.0], [alpha, alpha])
    assert inverse.two_layer_energy_bounds(0.02, samples=16)[1] == pytest.approx(float(lobes.reflectance(slab, 1.0)[0]), rel=1e-9)


@pytest.mark.parametrize("lobe_list, k", [
    (CASES["fig14b_coated"], 2),
    (CASES["fig19b_haze"], 2),
    (CASES["three_lobes"], 3),
])
def test_stacked_lobe_class_points_reproduce_the_lobes(lobe_list, k):
    """A few valid points of lobe k's class under the lobes above, as choices of invert_lobes, give the lobes back."""
    cls = inverse.lobe_class(lobe_list, k, samples=16)
    points = np.argwhere(cls.valid)
    assert len(points) > 0, cls.kind
    for point in points[:: max(1, len(points) // 3)]:
        if cls.kind == "two_layer":
            choice = {"eta_top": cls.eta_top[point[0]], "eta": cls.eta[point[1]]}
        elif cls.kind == "conductor":
            choice = {"eta": cls.eta[point[0]]} if cls.valid[point[0]].all() else None
        else:
            choice = {"eta": cls.eta[point[0]]}
        if choice is None:
            continue
        choices = [{}] * len(lobe_list)
        choices[k - 1] = choice
        stack = inverse.invert_lobes(lobe_list, choices)
        energies, _ = inverse.forward_lobes(stack, [lobe.layers for lobe in lobe_list])
        np.testing.assert_allclose(energies[k - 1], lobe_list[k - 1].energy, atol=ROUND_TRIP_TOLERANCE)
    # Outside the class, the same choice is refused.
    if cls.kind == "dielectric" and (~cls.valid).any():
        choices = [{}] * len(lobe_list)
        choices[k - 1] = {"eta": cls.eta[np.argwhere(~cls.valid)[0][0]]}
        with pytest.raises(InverseError, match="tau >= 0"):
            inverse.invert_lobes(lobe_list, choices)
