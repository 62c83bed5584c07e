"""
What the design studies ask of it: a structure's forward colours, the reachable structures and chromaticities, random
structures and the round trip.
"""

from __future__ import annotations

from typing import Callable, Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

from explorer.design.forward import design_model
from explorer.design.search import _Problem
from explorer.design.solve import design
from explorer.design.targets import DesignResult, Target, parameter_box
from explorer.physics import colorimetry

#: The public names (re-exported by :mod:`explorer.design`).
__all__ = ["forward_rgb", "reachable_structures", "reachable_chromaticities", "ROUND_TRIP_ANGLES", "random_structure",
           "round_trip"]


def forward_rgb(model_name: str, values: Mapping[str, float], theta_deg: ArrayLike) -> np.ndarray:
    """The converged colours of a structure at angles (degrees): what :func:`design` reports as achieved."""
    model = design_model(model_name)
    return model.converged(values, np.cos(np.radians(np.asarray(theta_deg, dtype=np.float64))), final=True)


def _reachable(model_name: str, theta_deg: float, ranges: Mapping[str, tuple[float, float]],
               fixed: Mapping[str, float] | None, samples: int, seed: int) -> tuple[_Problem, np.ndarray]:
    """The problem at one angle and its ``samples`` scrambled-Sobol unit rows (:func:`reachable_structures`)."""
    from scipy.stats import qmc

    model = design_model(model_name)
    problem = _Problem(model, parameter_box(model, ranges), dict(fixed or {}), [Target(float(theta_deg), (0.5, 0.5, 0.5))], None)
    return problem, qmc.Sobol(max(len(problem.free), 1), scramble=True, seed=seed).random(samples)[:, : len(problem.free)]


def reachable_structures(model_name: str, ranges: Mapping[str, tuple[float, float]], fixed: Mapping[str, float] | None = None,
                         samples: int = 4096, seed: int = 0) -> dict[str, np.ndarray]:
    """
    ``samples`` structures spread over the box (scrambled Sobol over the free parameters, the search's unit
    box), as arrays of design values; integer parameters (``N``) whole, since a fractional count has
    colours no stack has.
    """
    problem, U = _reachable(model_name, 0.0, ranges, fixed, samples, seed)
    return problem.values(U, whole=True)


def reachable_chromaticities(model_name: str, theta_deg: float, ranges: Mapping[str, tuple[float, float]],
                             fixed: Mapping[str, float] | None = None, samples: int = 4096, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """
    The chromaticities ``(x, y)`` and luminances ``Y`` of structures spread over the box
    (:func:`reachable_structures`, coarse model) at one angle: the colours a Bragg mirror (or film) can
    make there.

    Returns
    -------
    xy : ndarray (M, 2)
    Y : ndarray (M,)
    """
    problem, U = _reachable(model_name, theta_deg, ranges, fixed, samples, seed)
    rgb = problem.coarse_rgb(U, whole=True)[:, 0]
    xyz = colorimetry.rgb_to_xyz(rgb)
    total = np.maximum(xyz.sum(axis=-1), 1e-12)
    return np.stack([xyz[:, 0] / total, xyz[:, 1] / total], axis=-1), xyz[:, 1]


#: The round trip's target angles (degrees).
ROUND_TRIP_ANGLES = (0.0, 15.0, 30.0, 45.0, 60.0)


def random_structure(model_name: str, ranges: Mapping[str, tuple[float, float]], rng: np.random.Generator) -> dict[str, float]:
    """
    A structure drawn from the declared ranges: uniform in each, except the parameters the search walks on
    a log scale (``N``: log-uniform, so that thin stacks are drawn as often as thick ones) and integers
    rounded.
    """
    model = design_model(model_name)
    values = {}
    for p in parameter_box(model, ranges):
        if p.name in model.held:  # the round trip's mirrors are the paper's (absorption and disorder off)
            values[p.name] = 0.0
            continue
        value = float(p.from_unit(rng.uniform())) if p.name in model.integer_parameters else float(rng.uniform(*ranges[p.name]))
        values[p.name] = float(p.whole(value))
    return values


def round_trip(model_name: str, ranges: Mapping[str, tuple[float, float]], count: int, seed: int = 0,
               angles: Sequence[float] = ROUND_TRIP_ANGLES, report: Callable[[int, dict, DesignResult], None] | None = None,
               draw_ranges: Mapping[str, tuple[float, float]] | None = None, tries: int = 1) -> list[DesignResult]:
    """
    Designs for ``count`` reachable targets: random structures (:func:`random_structure`, seeded, from
    ``draw_ranges``, default ``ranges``), their converged colours at ``angles`` as targets, each designed
    back from its colours alone over ``ranges`` (in at most ``tries`` searches, :func:`design`).
    """
    rng = np.random.default_rng(seed)
    results = []
    for k in range(count):
        truth = random_structure(model_name, {**ranges, **(draw_ranges or {})}, rng)
        colours = forward_rgb(model_name, truth, angles)
        targets = [Target(float(a), tuple(float(c) for c in rgb)) for a, rgb in zip(angles, colours)]
        result = design(model_name, targets, ranges, seed=seed + k, tries=tries)
        results.append(result)
        if report is not None:
            report(k, truth, result)
    return results
