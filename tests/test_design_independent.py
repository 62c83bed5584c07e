"""
The achieved colours that ``bragg-explorer design --json`` reports, recomputed from nothing but its JSON
with references the explorer did not write: ``tmm``'s transfer matrices (both polarisations, averaged) for
the reflectance spectrum, colour-science for the CMFs, the XYZ integral, the RGB matrices and CIEDE2000.

What is shared is only the documented convention (docs/design.md, explorer/physics/colorimetry.py): CIE
1931 2° CMFs over 360-830 nm, illuminant E with Y(flat 1) = 1, linear sRGB by a Bradford adaptation
E -> D65 scaled per channel so that a flat reflectance of 1 is (1, 1, 1); a mirror is ``N`` cells of
``(n2, (1 - delta) Lambda), (n1, delta Lambda)`` on ``n1`` under the host ``nh`` (``nh`` below 1: the
host is ``n1``), THETA in the host; a film is ``eta1 | (eta2, d) | eta3 + i kappa3``.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from tmm import coh_tmm

from conftest import run_cli

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    import colour

#: The independent integral's wavelength step (nm): trapezoids of tmm's spectrum against colour-science's
#: CMFs interpolated to it, where the explorer integrates its spectrum exactly against the 1-nm CMFs
#: interpolated linearly. With fringes a few nm wide at the thickest structures drawn here, the two agree
#: to ~0.003 ΔE2000 (measured); this leaves room for the CMFs' two interpolations and nothing more.
STEP_NM = 0.5
#: Achieved against recomputed colour, CIEDE2000 per target.
INDEPENDENT_DELTA_E = 0.02
#: The reported CIEDE2000 against its recomputation from the reported colours (relative): here the white
#: that scales RGB is the 0.5-nm integral of a flat spectrum, the explorer's the 1-nm sum.
REPORTED_RTOL = 1e-3

OBSERVER = "CIE 1931 2 Degree Standard Observer"
WAVELENGTHS = np.arange(360.0, 830.0 + STEP_NM / 2, STEP_NM)
CMFS = colour.MSDS_CMFS[OBSERVER]
XY_E = colour.CCS_ILLUMINANTS[OBSERVER]["E"]
ILLUMINANT_E = colour.sd_constant(1.0, colour.SpectralShape(360.0, 830.0, STEP_NM))


def xyz_of(reflectance: np.ndarray) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sd = colour.SpectralDistribution(reflectance, WAVELENGTHS)
        return colour.sd_to_XYZ(sd, CMFS, ILLUMINANT_E, method="Integration") / 100.0


def unscaled_rgb(xyz: np.ndarray) -> np.ndarray:
    return colour.XYZ_to_RGB(xyz, "sRGB", XY_E, chromatic_adaptation_transform="Bradford")


WHITE_RGB = unscaled_rgb(xyz_of(np.ones_like(WAVELENGTHS)))


def lab_of_rgb(rgb) -> np.ndarray:
    xyz = colour.RGB_to_XYZ(np.asarray(rgb) * WHITE_RGB, "sRGB", XY_E, chromatic_adaptation_transform="Bradford")
    return colour.XYZ_to_Lab(xyz, XY_E)


def tmm_unpolarised(indices, thicknesses, theta_deg: float) -> np.ndarray:
    theta = np.radians(theta_deg)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.array([0.5 * (coh_tmm("s", indices, thicknesses, theta, lam)["R"] + coh_tmm("p", indices, thicknesses, theta, lam)["R"])
                         for lam in WAVELENGTHS])


def mirror_layers(s: dict) -> tuple[list, list]:
    host = s["nh"] if s["nh"] >= 1.0 else s["n1"]
    N = s["N"]
    assert N == int(N)
    cell = [(s["n2"], (1.0 - s["delta"]) * s["Lambda"]), (s["n1"], s["delta"] * s["Lambda"])]
    return [host] + [n for n, _ in cell] * int(N) + [s["n1"]], [np.inf] + [d for _, d in cell] * int(N) + [np.inf]


def film_layers(s: dict) -> tuple[list, list]:
    return [s["eta1"], s["eta2"], s["eta3"] + 1j * s["kappa3"]], [np.inf, s["d"], np.inf]


CASES = {
    # A mirror under a host (N held small, so that tmm's stacks stay short).
    "mirror under a host": ("bragg_mirror", ["--target", "0:#2a8a3a", "--target", "30:#2a6a8a", "--target", "60:#3a3a9a",
                                             "--fix", "N=10", "--fix", "nh=1.33"], mirror_layers),
    # Air layers and no separate host (nh = 0: the host is n1).
    "air-layer mirror": ("bragg_mirror", ["--target", "0:0.02,0.3,0.05", "--target", "45:0.02,0.1,0.35",
                                          "--fix", "n1=1", "--fix", "N=6", "--fix", "nh=0"], mirror_layers),
    # A rough Bragg layer: its smooth mirror's (specular) colour.
    "rough layer's mirror": ("bragg_layer", ["--target", "0:#c03a5a", "--target", "50:#5a8a3a", "--fix", "N=4"], mirror_layers),
    "film on a metal": ("thin_film", ["--target", "0:#b07a3a", "--target", "40:#8a5aa0", "--target", "70:#5a7ac0",
                                      "--free", "d,eta2,eta3,kappa3"], film_layers),
}


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.slow
def test_achieved_colours_equal_tmm_and_colour_science(case):
    material, args, layers = CASES[case]
    run = run_cli("design", material, *args, "--tries", "1", "--json")  # one search: its colours are what is checked
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    indices, thicknesses = layers(report["set"])
    errors = []
    for target in report["targets"]:
        xyz = xyz_of(tmm_unpolarised(indices, thicknesses, target["theta_deg"]))
        delta = float(colour.delta_E(colour.XYZ_to_Lab(xyz, XY_E), lab_of_rgb(target["achieved_rgb"]), method="CIE 2000"))
        errors.append(delta)
        # The reported CIEDE2000 is the achieved colour's against the target, recomputed the same way.
        reported = float(colour.delta_E(lab_of_rgb(target["target_rgb"]), lab_of_rgb(target["achieved_rgb"]), method="CIE 2000"))
        assert reported == pytest.approx(target["delta_e2000"], rel=REPORTED_RTOL, abs=1e-6)
    assert max(errors) <= INDEPENDENT_DELTA_E, (report["set"], errors)
