"""Units of work in order, in local processes; Ray asked for where it is missing."""

from __future__ import annotations

import os
import sys

import pytest

from robotplan.base.units import RayMissing, UnitsReport, run_units


def _square_and_pid(x: int) -> tuple[int, int]:
    return x * x, os.getpid()


@pytest.mark.parametrize("workers", [1, 3])
def test_results_come_back_in_the_order_of_the_jobs(workers):
    report = UnitsReport("", 0)
    out = list(run_units(_square_and_pid, list(range(9)), workers, report=report))
    assert [r[0] for r in out] == [x * x for x in range(9)]
    pids = {r[1] for r in out}
    assert (pids == {os.getpid()}) if workers == 1 else (os.getpid() not in pids)
    assert report.executor == "processes" and report.workers == workers
    assert report.units == 9 and sum(report.hosts.values()) == 9
    assert report.wall_seconds > 0 and report.unit_seconds > 0


def test_ray_without_the_package_says_so(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    with pytest.raises(RayMissing, match="ray package"):
        list(run_units(_square_and_pid, [1], 1, ray="local"))
