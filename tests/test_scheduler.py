"""The app's frame scheduler (:class:`explorer.app.scheduler.Scheduler`): which views get GL time while a slider moves."""

from __future__ import annotations

from types import SimpleNamespace

import pytest


class _Job:
    """A view that records the budgets it was given."""

    def __init__(self):
        self.budgets = []

    def work(self, budget_ms: float) -> float:
        self.budgets.append(budget_ms)
        return 0.0


class _Panel:
    def __init__(self, order: int, jobs: list):
        self.gl_order, self._jobs = order, jobs

    def gl_jobs(self) -> list:
        return self._jobs

    def after_gl(self) -> None:
        pass


@pytest.mark.gl
@pytest.mark.parametrize("mode", ["sphere", "lit", "env"])
def test_while_dragging_only_the_sphere_gets_a_budget(gl_renderer, mode):
    """
    While a slider moves, the first view (the sphere's) gets the drag budget and the side views none; in the
    env mode the sphere is the env render, so no view leads (a side view's bind would build its tables on
    the spot, hundreds of ms for a stack). Released, every view shares the frame's budget.
    """
    from explorer.app.scheduler import DRAG_BUDGET_MS, Scheduler

    scheduler = Scheduler(gl_renderer)
    main, side = _Job(), _Job()
    panels = [_Panel(5, [side]), _Panel(0, [main] if mode != "env" else [])]
    state = SimpleNamespace(mode=mode, pending_screenshot=None, exposure=1.0, gamut=False)
    scheduler.work(state, panels, dragging=True)
    assert side.budgets == []
    assert main.budgets == ([] if mode == "env" else [pytest.approx(DRAG_BUDGET_MS, abs=1.0)])
    scheduler.work(state, panels, dragging=False)
    assert len(side.budgets) == 1 and side.budgets[0] > 0.0
