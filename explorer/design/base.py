"""
What the inverse design shares: the search's settings, its errors and a design parameter (its box and scale). A design
model (what the search reads of a material) is declared by the material's twin
(:class:`explorer.materials.twins.DesignModel`), re-exported here.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from explorer.materials.twins import DesignModel  # noqa: F401  (declared by each twin; re-exported)
from explorer.physics.colorimetry import COARSE_STEP  # noqa: F401  (the coarse model's wavelength step, nm)

#: The public names (re-exported by :mod:`explorer.design`).
__all__ = ["REACHABLE_DELTA_E", "REACHED_DELTA_E", "TRY_SEED_STRIDE", "COARSE_STEP", "SCREEN_STEP", "SCREEN_SMOOTH",
           "FIRST_PASS_SAMPLES", "SCAN_SHAPES", "SCAN_RELATIVE_STEP", "SCAN_SMOOTH", "SCAN_KEPT", "SCAN_BATCH",
           "SCAN_BATCH_SAMPLES", "POLISH_SECONDS", "DISORDERED_POLISH_SECONDS", "POLISHED_ENOUGH", "LOCAL_STARTS", "REFINE_NFEV", "POLISHED",
           "DISTINCT_STARTS", "POLISH_DISTINCT", "COARSE_DIFF_STEP", "FINE_DIFF_STEP", "SECOND_COUNTS", "SECOND_PERTURBED",
           "SECOND_SPREAD", "SECOND_STARTS", "GOOD_ENOUGH", "SCAN_THREADS", "DESCENT_STARTS", "DESCENT_SAMPLES",
           "DESCENT_SIGMAS", "DESCENT_SPAN", "BATCH", "DesignError", "DesignCancelled", "DesignParameter", "DesignModel"]

#: A target whose CIEDE2000 stays above this is reported as not reachable (about twice a just
#: noticeable difference).
REACHABLE_DELTA_E = 2.0
#: Tries (``design(..., tries=K)``) stop once every target is within this CIEDE2000 (about a just
#: noticeable difference).
REACHED_DELTA_E = 1.0
#: Successive tries' seeds this far apart: each a fresh scrambled Sobol first pass.
TRY_SEED_STRIDE = 1000
#: The first pass's and the scan's wavelength step (nm): screening only, about 4 times cheaper.
SCREEN_STEP = 4.0
#: The screening averages out fringes narrower than about this (nm): their ripples make the landscape
#: rugged where the bands' positions, which it keeps, decide the basin.
SCREEN_SMOOTH = 12.0
#: Candidates of the first pass (a power of two: Sobol's balance).
FIRST_PASS_SAMPLES = 2048
#: The scan: this many scrambled-Sobol shapes, each at every value of the scale parameter (the period, the
#: film's thickness) on a geometric grid. A mirror's spectrum shifts by about lambda dLambda / Lambda when
#: Lambda moves: its colour turns as fast in log Lambda everywhere, by several CIEDE2000 per percent at
#: high orders (Lambda ~ 1 um), whose basins in Lambda are narrow. Half the 1024 of a scan without the
#: descent: its time goes to the descent, which finds more (round trip of 50, median of the medians
#: 0.83 -> 0.24, share within 1: 52 -> 64 %, in one run each).
SCAN_SHAPES = 512
#: The scan's spectra: samples at this relative step in s / lambda (3 nm at 600 nm), also its scales' step.
SCAN_RELATIVE_STEP = 0.005
#: The scan's spectra average out fringes narrower than about this share of the wavelength (two of its steps:
#: point samples would alias; measured: 0.93 -> 0.71 median of the round trip's medians against 0.004).
SCAN_SMOOTH = 0.01
#: The scan's CIEDE2000 is evaluated at this many scales per shape, those nearest in CIELAB.
SCAN_KEPT = 48
#: Shapes per batch of the scan (memory: shapes x angles x ~1800 samples x 3, complex).
SCAN_BATCH = 8
#: ... at spectra this long (samples of the full range of scales).
SCAN_BATCH_SAMPLES = 1000
#: CPU seconds the polish on the converged model may take (a mirror with N ~ 1000 costs ~0.1 s a colour).
#: CPU time, not wall time: a design's result must not depend on how busy the machine is.
POLISH_SECONDS = 1.5
#: The polish stops below this RMS CIEDE2000 per target (a hundredth of a just-noticeable difference).
POLISHED_ENOUGH = 0.01
#: CPU seconds of the polish of a disordered mirror (``sigma > 0``): each of its colours averages seeded
#: realisations (~0.1-0.5 s a colour against ~0.01 s ordered).
DISORDERED_POLISH_SECONDS = 12.0
#: Distinct starts refined on the coarse model, and of those, how many are polished on the converged one.
LOCAL_STARTS = 6
#: Evaluations of each coarse refinement.
REFINE_NFEV = 40
POLISHED = 2
#: Two starts closer than this in the unit box (max norm) are the same basin.
DISTINCT_STARTS = 0.08
#: Two polished candidates closer than this are the same one.
POLISH_DISTINCT = 0.01
#: Finite-difference step in the unit box for the coarse Jacobians (the model is smooth there), and the
#: converged model's (its adaptive refinement moves colours by up to ~2e-4: a larger step).
COARSE_DIFF_STEP = 1e-4
FINE_DIFF_STEP = 1e-3
#: The second scan: counts tried, perturbed shapes, their spread, and the starts refined from them.
SECOND_COUNTS = 48
SECOND_PERTURBED = 48
SECOND_SPREAD = 0.05
SECOND_STARTS = 3
#: Above this median CIEDE2000 the coarse stage has not found the basin: more starts are refined.
GOOD_ENOUGH = 0.05
#: Threads of the scans (:func:`_threaded_scan`): this machine's cores, at most 4.
SCAN_THREADS = max(1, min(4, os.cpu_count() or 1))
#: The scan's descent (:func:`_scan_descent`): starts, moves per step, their spreads in the unit box, and
#: the window of scales around each. Measured against 8 starts (0.35, 62 %), three spreads (0.54, 58 %),
#: six (0.30, 64 %, 15 % slower) and 40 moves (0.44, 58 %).
DESCENT_STARTS = 16
DESCENT_SAMPLES = 48
DESCENT_SIGMAS = (0.08, 0.04, 0.02, 0.01)
DESCENT_SPAN = 0.06
#: Candidates evaluated per batch of the coarse model (memory: rows x angles x wavelengths complex).
BATCH = 32


class DesignError(ValueError):
    """A design request that cannot be met: one line (a bad colour, an impossible fix)."""


class DesignCancelled(Exception):
    """The caller's ``cancelled()`` said stop."""


# --------------------------------------------------------------------------------------------------
# The design parameters


@dataclass(frozen=True)
class DesignParameter:
    """
    One structural parameter: its name in the material file, its box (the file's declared range unless
    the caller narrows it), and whether the search walks it on a log scale or rounds it to an integer.
    """

    name: str
    low: float
    high: float
    log: bool = False
    integer: bool = False

    def from_unit(self, u):
        u = np.clip(np.asarray(u, dtype=np.float64), 0.0, 1.0)
        if self.log:
            return np.exp(math.log(self.low) + u * (math.log(self.high) - math.log(self.low)))
        return self.low + u * (self.high - self.low)

    def whole(self, value):
        """``value`` at the nearest whole number in the box for an integer parameter, as it is otherwise."""
        return np.maximum(np.round(value), self.low) if self.integer else value

    def to_unit(self, value):
        value = np.asarray(value, dtype=np.float64)
        if self.high == self.low:
            return np.zeros_like(value)
        if self.log:
            return (np.log(value) - math.log(self.low)) / (math.log(self.high) - math.log(self.low))
        return (value - self.low) / (self.high - self.low)
