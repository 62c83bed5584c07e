"""
``bench --position-free``: the position-free walk's albedo to a standard-error goal, and its time.
"""

from __future__ import annotations

import json
import os
import time

import numpy as np

from explorer.bench.common import _progress
from explorer.materials.brd import load_material
from explorer.resources import SHADER_DIR
from explorer.materials.models import BraggStackModel

#: The position-free benchmark: 9 incidence angles, a standard-error goal, a time goal (this 2-core machine).
POSITION_FREE_THETA = tuple(float(t) for t in np.linspace(0.0, 80.0, 9))
POSITION_FREE_TARGET = 2e-3
POSITION_FREE_GOAL_S = 30.0
#: Its configurations: bragg_stack.brd's three default layers (no shipped preset has three) over a black
#: base, and the same three over Figure 7's grey base under Figure 7's coating (the hard case: many bounces).
POSITION_FREE_CASES = (
    (f"{BraggStackModel.name} defaults, layers = 3 (rho_d = 0, nh = 1)", {"layers": 3}),
    ("figure7_A_prime's host and base with three layers (nh = 1.35, rho_d = 0.5)",
     {"preset": "figure7_A_prime", "layers": 3}),
)


def _cpu_seconds() -> float:
    """CPU seconds of this process and of its finished children (the position-free walk's workers)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def run_position_free_bench(as_json: bool = False, target: float = POSITION_FREE_TARGET,
                            budget_s: float = 4.0 * POSITION_FREE_GOAL_S, samples: int = 8192) -> list[dict]:
    """
    ``bragg-explorer bench --position-free``: the wall-clock time the position-free reference
    (:class:`explorer.physics.position_free.PositionFree`) takes for the directional albedo at the 9 angles of
    :data:`POSITION_FREE_THETA` to a standard error of ``target`` in every channel (progressive rounds of
    ``samples`` paths per angle, stopped at the target or after ``budget_s``), per configuration of
    :data:`POSITION_FREE_CASES`; the layer tables' build time apart.
    """
    from explorer.materials.models import model_for
    from explorer.materials.presets import presets_for
    from explorer.physics.position_free import PositionFree

    material = load_material(SHADER_DIR / f"{BraggStackModel.name}.brd")
    rows = []
    for name, spec in POSITION_FREE_CASES:
        spec = dict(spec)
        preset = spec.pop("preset", None)
        overrides = {**(presets_for(material.path).get(preset).values if preset else {}), **spec}
        start = time.perf_counter()
        model = model_for(material, material.resolve(overrides))
        tables_s = time.perf_counter() - start
        _progress(f"bench --position-free: {name}")
        cpu = _cpu_seconds()
        result = PositionFree(model.stack, model.tables).albedo(
            POSITION_FREE_THETA, samples=samples, seed=0, target_stderr=target, max_seconds=budget_s)
        cpu = _cpu_seconds() - cpu
        rows.append({
            "configuration": name, "values": overrides, "theta_deg": list(POSITION_FREE_THETA),
            "rgb": result.value.tolist(), "stderr": result.stderr.tolist(), "max_stderr": float(result.stderr.max()),
            "paths_per_angle": result.paths, "seconds": result.seconds, "cpu_seconds": cpu, "tables_seconds": tables_s,
            "target_stderr": target, "goal_seconds": POSITION_FREE_GOAL_S,
        })
    if as_json:
        print(json.dumps(rows, indent=2))
        return rows
    print(f"position-free directional albedo, {len(POSITION_FREE_THETA)} angles (0-80 deg), to a standard error of {target:g} per channel")
    print(f"{'configuration':<78} {'paths/angle':>11} {'max stderr':>10} {'seconds':>8} {'CPU s':>6}  goal")
    for row in rows:
        ok = row["max_stderr"] <= target and row["seconds"] <= POSITION_FREE_GOAL_S
        print(f"{row['configuration']:<78} {row['paths_per_angle']:>11} {row['max_stderr']:>10.2e} {row['seconds']:>8.1f} "
              f"{row['cpu_seconds']:>6.1f}  {'met' if ok else 'missed'} (<= {POSITION_FREE_GOAL_S:g} s wall)")
    return rows
