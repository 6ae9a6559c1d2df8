"""Independent units of work (data shards, benchmark scenes) run in order of submission, in
local processes or as Ray tasks.

A unit is a module-level function of one picklable argument that builds what it needs
itself (a pybullet client, a Drake program: neither pickles) and returns its result; the
caller writes files. Results come back in the order of the jobs whatever ran them, so what
a command writes is the same with 1 or N workers and with or without Ray; where and how
long each unit ran is reported apart (:class:`UnitsReport`).

``ray``: ``None`` for local processes (``workers`` of them, forked), ``"local"`` to start a
Ray instance on this machine with ``workers`` CPUs, else the address of a running cluster
(``"auto"``: the one this machine belongs to; ``"HOST:PORT"``), where each unit asks for
``cpus_per_unit`` CPUs.
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from multiprocessing import get_context

__all__ = ["RayMissing", "UnitsReport", "check_ray", "run_units"]


class RayMissing(RuntimeError):
    """``--ray`` was asked for where the ``ray`` package is not installed."""


@dataclass
class UnitsReport:
    """Where and how long the units ran (kept apart from their results)."""

    executor: str = "processes"  # or "ray"
    workers: int = 1
    address: str | None = None
    units: int = 0
    wall_seconds: float = 0.0
    unit_seconds: float = 0.0  # summed over the units
    hosts: dict[str, int] = field(default_factory=dict)  # host name → units it ran

    def as_dict(self) -> dict:
        return {"executor": self.executor, "workers": self.workers, "address": self.address,
                "units": self.units, "wall_seconds": round(self.wall_seconds, 2),
                "unit_seconds": round(self.unit_seconds, 2), "hosts": dict(self.hosts)}


def check_ray(ray: str | None) -> None:
    """Raise :class:`RayMissing` where ``ray`` asks for Ray and the package is missing (call
    it before any work, so that nothing is written)."""
    if ray:
        try:
            import ray as _  # noqa: F401
        except ImportError as exc:
            raise RayMissing("--ray needs the ray package (pip install 'robotplan[ray]')"
                             ) from exc


def _timed(call: tuple[Callable, object]) -> tuple[object, str, float]:
    fn, job = call
    t0 = time.perf_counter()
    result = fn(job)
    return result, socket.gethostname(), time.perf_counter() - t0


def _ray_results(fn: Callable, jobs: Sequence, workers: int, address: str,
                 cpus_per_unit: int) -> Iterator[tuple[object, str, float]]:
    check_ray(address)
    import ray

    started = not ray.is_initialized()
    if started:
        if address == "local":
            ray.init(num_cpus=workers * cpus_per_unit, include_dashboard=False, log_to_driver=False,
                     logging_level="ERROR")
        else:
            ray.init(address=address, log_to_driver=False, logging_level="ERROR")
    try:
        task = ray.remote(num_cpus=cpus_per_unit)(_timed)
        refs = [task.remote((fn, job)) for job in jobs]
        for ref in refs:
            yield ray.get(ref)
    finally:
        if started:
            ray.shutdown()


def _local_results(fn: Callable, jobs: Sequence, workers: int
                   ) -> Iterator[tuple[object, str, float]]:
    calls = [(fn, job) for job in jobs]
    if workers <= 1:
        yield from map(_timed, calls)
        return
    with get_context("fork").Pool(workers) as pool:
        yield from pool.imap(_timed, calls)


def run_units(fn: Callable, jobs: Sequence, workers: int = 1, ray: str | None = None,
              report: UnitsReport | None = None, cpus_per_unit: int = 1) -> Iterator[object]:
    """``fn(job)`` for every job, yielded in the order of ``jobs`` (see the module
    docstring for ``ray``). ``workers``: units at once (local processes, or the Ray
    instance ``"local"`` starts); ``cpus_per_unit``: the CPUs a Ray task asks for (a unit
    that runs processes of its own). ``report``, if given, is filled in as the units
    finish."""
    report = report if report is not None else UnitsReport()
    report.executor, report.workers, report.address = ("ray" if ray else "processes",
                                                       workers, ray)
    t0 = time.perf_counter()
    results = (_ray_results(fn, jobs, workers, ray, cpus_per_unit) if ray
               else _local_results(fn, jobs, workers))
    for result, host, seconds in results:
        report.units += 1
        report.unit_seconds += seconds
        report.hosts[host] = report.hosts.get(host, 0) + 1
        report.wall_seconds = time.perf_counter() - t0
        yield result
