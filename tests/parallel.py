"""
The suite's distribution over xdist workers: load balancing test by test, except that the tests sharing a
module's set-up form one unit (tests/conftest.py: shared_set_up_group, written by each worker at collection).

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


class SharedSetUpScheduling(LoadScopeScheduling):
    """
    xdist's scope scheduler whose scopes are the groups, and each other test alone. Larger units go first
    (its ``--loadscope-reorder``, on by default), so a group never waits for the tail of the run.
    """

    def __init__(self, config, log, folder: Callable[[], str | None]):
        super().__init__(config, log)
        self._folder, self._groups = folder, None

    def _split_scope(self, nodeid: str) -> str:
        if self._groups is None:  # read once, when the workers have collected
            self._groups = read_groups(self._folder())
        return unit_of(nodeid, self._groups)
