"""
:func:`design`: the three stages of one search, and further tries from fresh first passes.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Callable, Mapping, Sequence

import numpy as np

from explorer.physics.dispersion import Dispersion

from explorer.design.base import (
    DESCENT_STARTS,
    FIRST_PASS_SAMPLES,
    GOOD_ENOUGH,
    LOCAL_STARTS,
    POLISH_DISTINCT,
    DISORDERED_POLISH_SECONDS,
    POLISH_SECONDS,
    POLISHED,
    REACHED_DELTA_E,
    REFINE_NFEV,
    SCAN_SHAPES,
    SECOND_STARTS,
    TRY_SEED_STRIDE,
    DesignError,
    DesignModel,
)
from explorer.design.forward import design_model
from explorer.design.media import reference_value, with_media
from explorer.design.search import _distinct, _distinct_indices, _polish, _Problem, _refine_coarse, _scan_best, _scan_descent, _variants
from explorer.design.targets import DesignResult, Target, check_target_rgb, parameter_box

#: The public names (re-exported by :mod:`explorer.design`).
__all__ = ["design"]


def design(
    model_name: str,
    targets: Sequence[Target],
    ranges: Mapping[str, tuple[float, float]],
    fixed: Mapping[str, float] | None = None,
    seed: int = 0,
    samples: int = FIRST_PASS_SAMPLES,
    starts: int = LOCAL_STARTS,
    progress: Callable[[float, str], None] | None = None,
    cancelled: Callable[[], bool] | None = None,
    guesses: Sequence[Mapping[str, float]] = (),
    tries: int = 1,
    media: Mapping[str, Dispersion] | None = None,
    free: Sequence[str] = (),
) -> DesignResult:
    """
    The structure whose converged colours come closest (least squares of CIEDE2000) to ``targets``.

    Parameters
    ----------
    model_name : str
        The material's ``# model:``, whose twin declares a design model (:func:`explorer.design.design_model`).
    targets : sequence of Target
        Colours at angles in [0, 90) degrees.
    ranges : mapping
        Each design parameter's box (the material's declared ``min``, ``max``).
    fixed : mapping, optional
        Parameters held at a value inside their range; the others are searched.
    seed : int
        The first pass's Sobol scrambling: the same seed gives the same design.
    samples, starts : int
        Candidates of the first pass; distinct starts refined on the coarse model.
    progress : callable, optional
        ``progress(fraction, stage)``, for a UI.
    cancelled : callable, optional
        Polled between batches; ``True`` raises :class:`DesignCancelled`.
    guesses : sequence of mapping, optional
        Structures (every design parameter by name; fixed ones take their fixed values; clipped to the
        box) that join the first pass's shapes, each at its best scale like them: a structure known to be
        close, such as the material's current one.
    tries : int
        Searches at most: after one that leaves a target above :data:`REACHED_DELTA_E`, another from a
        fresh first pass (seed + :data:`TRY_SEED_STRIDE` k) with the best structure so far among its
        guesses, so that each try also walks on from the last (an iterated search with restarts); the best
        result is returned, its times and evaluations summed over the tries.
    media : mapping, optional
        Index parameters (``n1``, ``n2``, ``nh`` of a Bragg mirror) held at a medium of
        :mod:`explorer.physics.dispersion` (dispersive, absorbing where ``k > 0``): :mod:`explorer.design.media`.
        The result reports such a parameter at the medium's real index at :data:`explorer.design.media.REFERENCE_NM`.
    free : sequence of str, optional
        The model's held parameters (a mirror's ``k1``, ``k2``, ``sigma``: 0 unless fixed) to search as well.

    Returns
    -------
    DesignResult
        Achieved colours from :func:`explorer.physics.bragg.reference_rgb` (or the film's), whatever the
        search used.
    """
    if not (isinstance(tries, int) and tries >= 1):
        raise DesignError(f"tries = {tries!r}: give a whole number of searches, at least 1")
    start_time, start_cpu = time.perf_counter(), time.process_time()
    best: DesignResult | None = None
    evaluations = 0
    for k in range(tries):
        def report(fraction, stage, k=k):
            if progress is not None:
                progress((k + fraction) / tries, stage if tries == 1 else f"try {k + 1} of {tries}: {stage}")

        carried = [] if best is None else [best.values]
        result = _design_once(model_name, targets, ranges, fixed, seed + TRY_SEED_STRIDE * k, samples, starts, report,
                              cancelled, [*guesses, *carried], media, free)
        evaluations += result.evaluations
        if best is None or np.sum(result.delta_e2000 ** 2) < np.sum(best.delta_e2000 ** 2):
            best = result
        if np.all(best.delta_e2000 <= REACHED_DELTA_E):
            break
    if progress is not None:
        progress(1.0, "done")
    return replace(best, seconds=time.perf_counter() - start_time, cpu_seconds=time.process_time() - start_cpu,
                   evaluations=evaluations, tries=k + 1)


def _design_once(model_name, targets, ranges, fixed, seed, samples, starts, progress, cancelled, guesses, media=None,
                 free=()) -> DesignResult:
    """One search of :func:`design` (its parameters), from the first pass on."""
    start_time, start_cpu = time.perf_counter(), time.process_time()
    model = design_model(model_name)
    fixed = dict(fixed or {})
    media = dict(media or {})
    unknown = [name for name in free if name not in model.held]
    if unknown:
        raise DesignError(f"free {unknown[0]}: not one of {model.name}'s held parameters ({', '.join(model.held) or 'none'})")
    # Absorbing or disordered layers (held parameters free, or fixed above 0): the natural mirror's models.
    natural = any(name in free or fixed.get(name, 0.0) != 0.0 for name in model.held)
    disordered = "sigma" in model.held and ("sigma" in free or fixed.get("sigma", 0.0) != 0.0)
    if media or natural:
        model = with_media(model, media, natural)
        for name, medium in media.items():
            if name in fixed:
                raise DesignError(f"cannot fix {name} twice (a number and {medium.name})")
            fixed[name] = reference_value(medium)
    if not targets:
        raise DesignError("give at least one target colour")
    for t in targets:
        if not (np.isfinite(t.theta_deg) and 0.0 <= t.theta_deg < 90.0):
            raise DesignError(f"target angle {t.theta_deg:g}: must be in [0, 90) degrees")
        check_target_rgb(t.rgb, f"target at {t.theta_deg:g} degrees")
    box = parameter_box(model, ranges)
    names = {p.name for p in box}
    for name, value in fixed.items():
        if name not in names:
            raise DesignError(f"cannot fix {name}: not a design parameter of {model.name} ({', '.join(model.parameters)})")
        p = next(p for p in box if p.name == name)
        low = float(ranges[name][0])
        if not (np.isfinite(value) and low <= value <= p.high):
            raise DesignError(f"cannot fix {name} = {value:g}: outside its range [{low:g}, {p.high:g}]")
        if p.integer and value != round(value):
            raise DesignError(f"cannot fix {name} = {value:g}: {name} is a whole number")
    problem = _Problem(model, box, fixed, targets, cancelled, free)
    guessed = np.array([np.clip(problem.unit_row(_guess_values(model, g, problem.fixed)), 0.0, 1.0) for g in guesses]).reshape(len(guesses), len(problem.free))
    report = progress or (lambda fraction, stage: None)
    stages: dict[str, float] = {}
    P = len(problem.free)

    if P == 0:
        values = problem.fine_values(np.zeros((1, 0)))
    else:
        from scipy.stats import qmc

        report(0.0, "first pass")
        scale = problem.scale_index
        chunk = 256
        if scale is not None:
            # 1-2. Space-filling shapes (Sobol), each at every value of its scale (the scale scan).
            # The first SCAN_SHAPES points of the next power of two (its balance, without scipy's warning).
            U = qmc.Sobol(P, scramble=True, seed=seed).random_base2(math.ceil(math.log2(SCAN_SHAPES)))[:SCAN_SHAPES]
            U = np.concatenate([guessed, U])
            U, scores = _scan_best(problem, U, lambda f: report(0.5 * f, "scale scan"))
            stages["scan"] = time.perf_counter() - start_time
            # 2b. The best distinct shapes walked downhill by the windowed scan.
            tops = _distinct_indices(U, scores, DESCENT_STARTS)
            U[tops], scores[tops] = _scan_descent(problem, U[tops], scores[tops], np.random.default_rng(seed),
                                                  lambda f: report(0.5 + 0.1 * f, "descent"))
            stages["descent"] = time.perf_counter() - start_time
            if model.rescreen:
                found = np.isfinite(scores)
                for start in range(0, len(U), chunk):
                    rows = slice(start, start + chunk)
                    scores[rows] = np.where(found[rows], problem.screen(U[rows]), np.inf)
        else:
            # 1. Space-filling first pass (Sobol) on the screening model.
            U = np.concatenate([guessed, qmc.Sobol(P, scramble=True, seed=seed).random(samples)])
            scores = np.empty(len(U))
            for start in range(0, len(U), chunk):
                scores[start : start + chunk] = problem.screen(U[start : start + chunk])
                report(0.6 * min(1.0, (start + chunk) / len(U)), "first pass")
            stages["first pass"] = time.perf_counter() - start_time
        # 3. Distinct starts, refined on the coarse model.
        chosen = _distinct(U, scores, starts)
        refined = []
        for k, u0 in enumerate(chosen):
            report(0.6 + 0.2 * k / len(chosen), "local refinement")
            u, cost = _refine_coarse(problem, u0, max_nfev=REFINE_NFEV)
            refined.append((cost, k, u))
            # A start that already matches every target to a small fraction of a unit needs no others.
            if k >= 1 and math.sqrt(cost / len(targets)) < GOOD_ENOUGH:
                break
        refined.sort(key=lambda item: item[0])
        if scale is not None and math.sqrt(refined[0][0] / len(targets)) >= GOOD_ENOUGH:
            # 3b. A second scan around the best: its integer count on a grid and perturbed shapes, each at
            # its best scale. Fringes make the count's basins narrow: a neighbouring count rarely wins by
            # refinement alone.
            report(0.75, "second scan")
            variants = _variants(problem, refined[0][2], np.random.default_rng(seed))
            variants, variant_scores = _scan_best(problem, variants)
            for k, u0 in enumerate(_distinct(variants, variant_scores, SECOND_STARTS, spacing=0.005)):
                u, cost = _refine_coarse(problem, u0, max_nfev=REFINE_NFEV)
                refined.append((cost, len(refined), u))
            refined.sort(key=lambda item: item[0])
        stages["coarse refinement"] = time.perf_counter() - start_time
        # 4. Polish the best on the converged model, within a time budget: the best as that model ranks
        # them, the coarse refinements' ends and the descent's shapes. The coarse model misjudges thick
        # stacks (their narrow bands fall between its samples): a shape the scan placed in the right basin
        # was refined out of it (the truth among the scan's shapes, explorer/dev/design_ceiling.py: 84 % of round
        # trips within 1 without this ranking, 90 % with it).
        best = None
        deadline = time.process_time() + (DISORDERED_POLISH_SECONDS if disordered else POLISH_SECONDS)
        pool = np.array([u for _, _, u in refined] + (list(U[tops]) if scale is not None else []))
        # Distinct ones: the second scan's refinements often end in the first's basin.
        polished = _distinct(pool, np.array([problem.fine_cost(u) for u in pool]), POLISHED, spacing=POLISH_DISTINCT)
        for k, u in enumerate(polished):
            report(0.8 + 0.2 * k / POLISHED, "polish")
            values, cost = _polish(problem, u, max_nfev=20, deadline=deadline)
            if best is None or cost < best[1]:
                best = (values, cost)
            if time.process_time() > deadline or best[1] < problem.polished_cost:
                break
        values = best[0]
        if best[1] > REACHED_DELTA_E**2 * len(targets):
            # 4b. Neighbouring counts: an absorbing stack's colours change little with N (light no longer reaches
            # its last cells), so the coarse stages may settle on a count whose basin holds no exact match.
            values = _neighbouring_counts(problem, values, best[1], POLISH_SECONDS)
        stages["polish"] = time.perf_counter() - start_time
    achieved = problem.fine_rgb(values, final=True)
    report(1.0, "done")
    return DesignResult(
        model=model.name,
        values=_reported_values(problem, values),
        targets=list(targets),
        achieved_rgb=achieved,
        delta_e2000=problem.delta_e(achieved),
        seconds=time.perf_counter() - start_time,
        cpu_seconds=time.process_time() - start_cpu,
        evaluations=problem.evaluations,
        stages=stages,
    )


#: The counts tried beside a polished count that leaves a target above REACHED_DELTA_E.
COUNT_NEIGHBOURS = (-2, -1, 1, 2)
COUNT_WALKS = 3


def _neighbouring_counts(problem: _Problem, values: Mapping[str, float], cost: float, seconds: float) -> dict[str, float]:
    """
    ``values`` polished again at each count of :data:`COUNT_NEIGHBOURS` around its own (the other parameters as
    they are), each within ``seconds`` of CPU, walking on from a better count while one is found (at most
    :data:`COUNT_WALKS` times): the best of these and ``values``.
    """
    k = next((j for j, p in enumerate(problem.free) if p.integer), None)
    if k is None:
        return dict(values)
    p = problem.free[k]
    best = (dict(values), cost)
    tried = {int(round(float(values[p.name])))}
    for _ in range(COUNT_WALKS):
        centre, u = best[0], problem.unit_row(best[0])
        for step in COUNT_NEIGHBOURS:
            count = int(round(float(centre[p.name]))) + step
            if not p.low <= count <= p.high or count in tried:
                continue
            tried.add(count)
            trial = u.copy()
            trial[k] = p.to_unit(float(count))
            found, found_cost = _polish(problem, np.clip(trial, 0.0, 1.0), max_nfev=20, deadline=time.process_time() + seconds)
            if found_cost < best[1]:
                best = (found, found_cost)
        if best[0] is centre or best[1] < problem.polished_cost:
            break
    return best[0]


def _reported_values(problem: _Problem, values: Mapping[str, float]) -> dict[str, float]:
    """
    The design values as reported: integers whole, and a free host found below its threshold (any value
    there means "the host is n1", the same colours) at its range's lower end, the file's canonical "no
    host", rather than an arbitrary number that reads like an index.
    """
    model = problem.model
    # A held parameter left at 0 (an effect off that the caller did not name) is not reported.
    out = {k: (int(round(values[k])) if problem.box[k].integer else float(values[k])) for k in model.parameters
           if k not in problem.held}
    host = model.host_parameter
    if host is not None and host not in problem.fixed and out[host] < model.host_threshold:
        out[host] = float(min(problem.box[host].low, out[host]))
    return out


def _guess_values(model: DesignModel, guess: Mapping[str, float], fixed: Mapping[str, float]) -> dict[str, float]:
    """A guessed structure's design values (fixed ones override), checked: every parameter, finite."""
    missing = [name for name in model.parameters if name not in guess and name not in fixed]
    if missing:
        raise DesignError(f"a guessed structure lacks {', '.join(missing)}")
    values = {name: float(guess[name]) for name in model.parameters if name in guess}
    bad = [name for name, value in values.items() if not np.isfinite(value)]
    if bad:
        raise DesignError(f"a guessed structure's {bad[0]} is not a finite number")
    return {**values, **fixed}
