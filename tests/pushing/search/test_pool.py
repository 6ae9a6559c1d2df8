"""The search's pool of processes: programs collected as they come, none started once told
not to, what runs dropped at a stop or the deadline."""

import math
import time

import pytest

from robotplan.pushing.search.pool import Processes, run_in_pool


def _nap(item: tuple[int, float]) -> int:
    """A pool task: sleep ``item[1]`` s, return ``item[0]`` (negative: raise)."""
    if item[0] < 0:
        raise ValueError("a worker's error")
    time.sleep(item[1])
    return item[0]


def test_past_the_budget_the_pool_starts_nothing_but_collects_what_runs():
    """Once ``may_start`` says no, the programs already running are still collected and no
    other starts; a stop from ``collect`` drops what runs; a worker's error reaches the
    caller; a deadline never reached waits for every result, one passed drops what runs."""
    started, got = [], []

    def may_start() -> bool:
        started.append(len(started))
        return len(started) <= 2  # the first two only

    def collect_all(result: int) -> bool:
        got.append(result)
        return False

    run_in_pool(_nap, [(0, 0.3), (1, 0.6), (2, 0.0), (3, 0.0)], Processes(2), collect_all,
                may_start)
    assert sorted(got) == [0, 1]

    got.clear()
    run_in_pool(_nap, [(0, 0.0), (1, 30.0), (2, 0.0)], Processes(2),
                lambda r: got.append(r) or True, lambda: True)
    assert got == [0]

    with pytest.raises(ValueError, match="a worker's error"):
        run_in_pool(_nap, [(-1, 0.0)], Processes(1), collect_all, lambda: True)

    got.clear()  # a deadline never reached
    run_in_pool(_nap, [(0, 0.0), (1, 0.2)], Processes(2, deadline=math.inf), collect_all,
                lambda: True)
    assert sorted(got) == [0, 1]

    got.clear()  # at the deadline what still runs is dropped
    t0 = time.monotonic()
    run_in_pool(_nap, [(0, 0.0), (1, 30.0), (2, 30.0)], Processes(2, deadline=t0 + 1.0),
                collect_all, lambda: True)
    assert got == [0] and time.monotonic() - t0 < 10.0
