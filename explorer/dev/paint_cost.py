"""
The cost per evaluation of what painting spends its time in (CPU seconds, ``time.process_time``, one process): the
coarse batch colours of the polish (:meth:`explorer.design.pixels.RowModel.rgb`) per 1000 rows, their Jacobian by the
free parameters per 1000 rows (:meth:`~explorer.design.pixels.RowModel.rgb_and_jacobian`: analytic, and by forward
differences for comparison), and the converged reference colour per structure (one at a time and all at once,
:meth:`explorer.materials.twins.DesignModel.converged_rows`), on the round trip's box (:mod:`explorer.bench.paint`).

    .venv/bin/python -m explorer.dev.paint_cost       # ~1 minute
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


if __name__ == "__main__":
    main()
