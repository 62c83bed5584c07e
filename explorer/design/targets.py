"""
Target colours (checked, or read from a strip of a gradient), the design's result, and the box of the parameters
searched.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
from numpy.typing import ArrayLike

from explorer.design.base import REACHABLE_DELTA_E, DesignError, DesignModel, DesignParameter
from explorer.physics import colorimetry

#: The public names (re-exported by :mod:`explorer.design`).
__all__ = ["check_target_rgb", "targets_from_strip", "Target", "DesignResult", "ranges_of", "parameter_box"]


def check_target_rgb(rgb: ArrayLike, what: str = "colour") -> np.ndarray:
    """
    A target colour as linear RGB, or a :class:`DesignError`: non-finite values, or a luminance no passive
    reflector has (``Y > 1``: brighter than the flat reflectance of 1; ``Y < 0``). Channels outside [0, 1]
    are kept (vivid Bragg colours lie outside sRGB).
    """
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.shape != (3,) or not np.all(np.isfinite(rgb)):
        raise DesignError(f"{what}: expected three finite numbers")
    Y = float(colorimetry.rgb_to_xyz(rgb)[1])
    if Y > 1.0 + 1e-6:
        raise DesignError(f"{what}: luminance Y = {Y:.4g} > 1, brighter than a perfect mirror: no passive reflector has it")
    if Y < -1e-6:
        raise DesignError(f"{what}: luminance Y = {Y:.4g} < 0: no colour has it")
    return rgb


def targets_from_strip(image: np.ndarray, theta_a: float, theta_b: float, count: int = 5,
                       clipped: np.ndarray | None = None) -> list["Target"]:
    """
    ``count`` targets from a strip of linear RGB ``(H, W, 3)`` whose column ``i`` shows
    ``theta_a + (theta_b - theta_a)(i + 0.5) / W`` degrees (as the gradient view draws 0 to 90): evenly
    spaced columns, each the mean of its rows; columns at 90 degrees and beyond are skipped. ``clipped``
    ``(H, W, 3)``: -1 where an integer image holds its lowest code, +1 its highest, 0 elsewhere; a channel
    clipped in every row of its column becomes a bound (:class:`Target`), not a value.
    """
    if not (np.isfinite(theta_a) and np.isfinite(theta_b) and 0.0 <= min(theta_a, theta_b)
            and max(theta_a, theta_b) <= 90.0 and theta_a != theta_b):
        raise DesignError(f"theta range {theta_a:g},{theta_b:g}: the two angles must differ, within [0, 90]")
    width = image.shape[1]
    columns = np.unique(np.clip(np.round((np.arange(count) + 0.5) / count * width - 0.5).astype(int), 0, width - 1))
    targets = []
    for i in columns:
        theta = theta_a + (theta_b - theta_a) * (i + 0.5) / width
        if theta >= 90.0:
            continue
        rgb = check_target_rgb(np.asarray(image)[:, i, :3].mean(axis=0), f"strip column {i}")
        bounds = (0, 0, 0)
        if clipped is not None:
            column = np.asarray(clipped)[:, i, :3]
            bounds = tuple(int(column[0, c]) if np.all(column[:, c] == column[0, c]) else 0 for c in range(3))
        targets.append(Target(float(theta), tuple(float(c) for c in rgb), bounds))
    if not targets:
        raise DesignError("the strip has no column below 90 degrees")
    return targets


# --------------------------------------------------------------------------------------------------
# The search


@dataclass(frozen=True)
class Target:
    """
    A wanted colour (linear RGB of this convention) at an angle (degrees, in the outer medium). ``bounds``
    per channel: 0 the value itself; -1 at most it, +1 at least it (a channel an 8-bit image clipped at 0 or
    255: the true colour lies beyond). A bounded channel costs nothing on its side of the bound.
    """

    theta_deg: float
    rgb: tuple[float, float, float]
    bounds: tuple[int, int, int] = (0, 0, 0)

    @property
    def bounded(self) -> bool:
        return any(self.bounds)


@dataclass
class DesignResult:
    """
    The best structure found: every design value (``values``, free and fixed, ``N`` an integer), the
    converged colour at each target and its CIEDE2000, the time taken (wall and this process's CPU: on
    a shared machine the wall time measures the load as much as the search) and how many candidates
    were evaluated.
    """

    model: str
    values: dict[str, float]
    targets: list[Target]
    achieved_rgb: np.ndarray
    delta_e2000: np.ndarray
    seconds: float
    cpu_seconds: float = 0.0
    evaluations: int = 0
    #: Searches run (:func:`design`'s ``tries``: fewer when every target was reached early).
    tries: int = 1
    stages: dict[str, float] = field(default_factory=dict)

    @property
    def median_delta_e2000(self) -> float:
        return float(np.median(self.delta_e2000))

    @property
    def reachable(self) -> np.ndarray:
        """Per target: whether the design reaches it (CIEDE2000 at most :data:`REACHABLE_DELTA_E`)."""
        return self.delta_e2000 <= REACHABLE_DELTA_E

    def as_json(self, material: str) -> dict:
        """The ``design --json`` object; colours are linear RGB."""
        return {
            "material": material,
            "set": dict(self.values),
            "targets": [
                {"theta_deg": t.theta_deg, "target_rgb": [float(c) for c in t.rgb],
                 **({"target_bounds": ["at most" if b < 0 else "at least" if b > 0 else "equal" for b in t.bounds]}
                    if t.bounded else {}),
                 "achieved_rgb": [float(c) for c in a], "delta_e2000": float(d)}
                for t, a, d in zip(self.targets, self.achieved_rgb, self.delta_e2000)
            ],
            "median_delta_e2000": self.median_delta_e2000,
            "seconds": self.seconds,
        }


def ranges_of(material) -> dict[str, tuple[float, float]]:
    """The declared ``(min, max)`` of each parameter of a material file (an :class:`explorer.materials.brd.Material`)."""
    return {p.name: (float(p.min), float(p.max)) for p in material.parameters if p.min is not None}


def parameter_box(model: DesignModel, ranges: Mapping[str, tuple[float, float]]) -> list[DesignParameter]:
    """The design parameters of ``model`` over ``ranges`` (name -> (low, high), the material's declared ranges)."""
    box = []
    for name in model.parameters:
        if name not in ranges and name in model.held:  # an effect the caller's ranges leave off
            box.append(DesignParameter(name, 0.0, 0.0))
            continue
        if name not in ranges:
            raise DesignError(f"the material declares no range for {name}")
        low, high = (float(v) for v in ranges[name])
        if name in model.log_parameters:
            low = max(low, 1.0)
        box.append(DesignParameter(name, low, high, log=name in model.log_parameters, integer=name in model.integer_parameters))
    return box
