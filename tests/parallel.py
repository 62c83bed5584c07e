"""
The suite's distribution over xdist workers: load balancing test by test, except that the tests sharing a
module's set-up form one unit (tests/conftest.py: shared_set_up_group, written by each worker at collection).
Units are handed out in the workers' collection order, which :func:`schedule_order` sets: the units holding
a test marked ``slow`` (tens of seconds) first, then the larger units, so the run does not end on one worker
still busy with a long test while the other idles.

xdist's own ``--dist loadgroup`` marks do the same through the test's node id, which pytest 9.2 no longer lets
a plugin rewrite: this scheduler asks the workers instead.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

from xdist.scheduler import LoadScopeScheduling


def read_groups(folder: str | None) -> dict[str, str]:
    """Node id -> group, as the first worker wrote them in ``folder`` (every worker collects the same tests)."""
    files = sorted(Path(folder).glob("*.json")) if folder else []
    return json.loads(files[0].read_text()) if files else {}


def unit_of(nodeid: str, groups: dict[str, str]) -> str:
    """The unit a test is scheduled in: its group, or itself."""
    return groups.get(nodeid, nodeid)


def schedule_order(nodeids: list[str], groups: dict[str, str], slow: set[str]) -> list[str]:
    """
    ``nodeids`` with each unit's tests together: units holding a ``slow`` test first, then by size (larger
    first: a group never waits for the tail of the run), then in collection order; tests keep their order.
    """
    units: dict[str, list[str]] = {}
    for nodeid in nodeids:
        units.setdefault(unit_of(nodeid, groups), []).append(nodeid)
    ranked = sorted(enumerate(units.values()), key=lambda unit: (not slow.intersection(unit[1]), -len(unit[1]), unit[0]))
    return [nodeid for _, tests in ranked for nodeid in tests]


class SharedSetUpScheduling(LoadScopeScheduling):
    """
    xdist's scope scheduler whose scopes are the groups, and each other test alone, handed out in the
    collection's order (:func:`schedule_order`, applied by each worker) rather than re-sorted by size.
    """

    def __init__(self, config, log, folder: Callable[[], str | None]):
        super().__init__(config, log)
        self._folder, self._groups = folder, None
        config.option.loadscopereorder = False  # the workers' order already puts larger units first

    def _split_scope(self, nodeid: str) -> str:
        if self._groups is None:  # read once, when the workers have collected
            self._groups = read_groups(self._folder())
        return unit_of(nodeid, self._groups)
