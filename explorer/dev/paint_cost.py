"""
The cost per evaluation of what painting spends its time in (CPU seconds, ``time.process_time``, one process): the
coarse batch colours of the polish (:meth:`explorer.design.pixels.RowModel.rgb`) per 1000 rows, their Jacobian by the
free parameters per 1000 rows (:meth:`~explorer.design.pixels.RowModel.rgb_and_jacobian`: analytic, and by forward
differences for comparison), and the converged reference colour per structure (one at a time and all at once,
:meth:`explorer.materials.twins.DesignModel.converged_rows`), on the round trip's box (:mod:`explorer.bench.paint`).

    .venv/bin/python -m explorer.dev.paint_cost       # ~1 minute

With ``--round-trip SIZE``: instead, ``bench --paint``'s round trip at SIZE x SIZE painted in this one process (no Dask),
its CPU seconds (all threads), the stages' wall seconds and the share of pixels within CIEDE2000 1 at both angles.

    .venv/bin/python -m explorer.dev.paint_cost --round-trip 64       # ~3-8 minutes
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

ROWS = 1000
STRUCTURES = 200
REPEATS = 3


def _cpu(function) -> float:
    """The least CPU seconds of :data:`REPEATS` calls (a shared machine's interruptions only add)."""
    best = np.inf
    for _ in range(REPEATS):
        start = time.process_time()
        function()
        best = min(best, time.process_time() - start)
    return best


def main() -> None:
    from explorer.bench.paint import ANGLES, ROUND_TRIP_BOX
    from explorer.design import ranges_of
    from explorer.design.forward import design_model
    from explorer.design.pixels import RowModel
    from explorer.design.targets import parameter_box
    from explorer.materials.brd import load_material
    from explorer.materials.models import BraggMirrorModel
    from explorer.materials.twins import shipped_file

    material = load_material(shipped_file(BraggMirrorModel))
    model = design_model(material.model)
    defaults = material.resolve({})
    fixed = {name: float(defaults[name]) for name in model.parameters if name not in ROUND_TRIP_BOX}
    fixed.update({name: 0.0 for name in model.held})
    ranges = {**ranges_of(material), **ROUND_TRIP_BOX}
    free = [p for p in parameter_box(model, ranges) if p.name not in fixed]
    cos_theta = np.cos(np.radians(ANGLES))
    rows = RowModel(model, free, fixed, cos_theta)
    differenced = RowModel(replace(model, gradient=None), free, fixed, cos_theta)
    U = np.random.default_rng(0).random((ROWS, len(free)))
    columns = list(range(len(free)))
    print(f"box {ROUND_TRIP_BOX}, angles {ANGLES}, {len(free)} free parameters; CPU seconds, least of {REPEATS}")
    print(f"  RowModel.rgb, {ROWS} rows: {_cpu(lambda: rows.rgb(U)):.3f} s")
    print(f"  colours and Jacobian, {ROWS} rows: analytic {_cpu(lambda: rows.rgb_and_jacobian(U, columns)):.3f} s, "
          f"forward differences {_cpu(lambda: differenced.rgb_and_jacobian(U, columns)):.3f} s")
    values = rows.values(U[:STRUCTURES], whole=True)
    one = _cpu(lambda: [model.converged({k: float(v[i]) for k, v in values.items()}, cos_theta, final=True) for i in range(STRUCTURES)])
    many = _cpu(lambda: model.converged_rows(values, cos_theta))
    print(f"  reference colour ({len(ANGLES)} angles), {STRUCTURES} structures: {1e3 * one / STRUCTURES:.2f} ms each one at a time, "
          f"{1e3 * many / STRUCTURES:.2f} ms each all at once")


def round_trip(size: int, seed: int = 0) -> None:
    """``bench --paint``'s round trip painted here, in one process: CPU seconds and the share within 1 (re-rendered)."""
    from explorer.bench.paint import ANGLES, ROUND_TRIP_BOX, _targets, smooth_random_maps
    from explorer.design import ranges_of
    from explorer.design.forward import design_model
    from explorer.design.paint import paint
    from explorer.materials.brd import load_material
    from explorer.materials.models import BraggMirrorModel
    from explorer.materials.twins import shipped_file
    from explorer.physics.colorimetry import delta_E_2000
    from explorer.views.maps import map_colours

    material = load_material(shipped_file(BraggMirrorModel))
    model = design_model(material.model)
    defaults = material.resolve({})
    fixed = {name: float(defaults[name]) for name in model.parameters if name not in ROUND_TRIP_BOX}
    targets = _targets(model.name, fixed, smooth_random_maps(size, seed))
    start = time.process_time()
    result = paint(model.name, ranges_of(material), fixed, targets, seed=seed)
    cpu = time.process_time() - start
    again = np.stack([map_colours(model.name, result.fixed, result.maps, a) for a in ANGLES]).astype(np.float64)
    within = float(np.mean(np.all(delta_E_2000(again, targets.rgb) <= 1.0, axis=0)))
    print(f"round trip {size}x{size}, one process: {cpu:.1f} CPU s; {100 * within:.1f} % of pixels within ΔE2000 1 at "
          f"{' and '.join(f'{a:g}' for a in ANGLES)} degrees; {result.colours} colours, {result.clusters} clusters")
    print("  stages (wall s): " + ", ".join(f"{k} {v:.1f}" for k, v in result.stages.items()))


if __name__ == "__main__":
    import sys

    if len(sys.argv) == 3 and sys.argv[1] == "--round-trip":
        round_trip(int(sys.argv[2]))
    else:
        main()
