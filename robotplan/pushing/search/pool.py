"""A pool of forked processes that solves a search's programs as they come, and stops at a
deadline or when the collected results say so."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing import get_context
from queue import Empty, Queue

__all__ = ["Processes", "run_in_pool"]


@dataclass(frozen=True)
class Processes:
    """The pool of :func:`run_in_pool`: ``workers`` forked processes, each set up by
    ``setup()``, and the ``time.monotonic()`` instant ``deadline`` at which what still runs
    in them is dropped (None: none)."""

    workers: int
    setup: Callable[[], None] | None = None
    deadline: float | None = None


def run_in_pool(solve: Callable, items: list, processes: Processes,
                collect: Callable[[object], bool], may_start: Callable[[], bool]) -> None:
    """``solve`` each of ``items`` in order in ``processes``, handing every result to
    ``collect`` as it comes; stop when ``collect`` says so or at the processes' deadline
    (the programs still running are dropped), and start an item only while
    ``may_start()``. An error in a worker is raised here."""
    finished: Queue = Queue()
    pending, running = list(items), 0
    workers, deadline = processes.workers, processes.deadline
    with get_context("fork").Pool(min(workers, len(items)) or 1, processes.setup) as pool:
        while True:
            while pending and running < workers and may_start():
                pool.apply_async(solve, (pending.pop(0),), callback=finished.put,
                                 error_callback=finished.put)
                running += 1
            if running == 0:
                return
            try:
                result = finished.get(timeout=None if deadline is None or math.isinf(deadline)
                                      else max(0.0, deadline - time.monotonic()))
            except Empty:  # past the deadline: what still runs is dropped
                return
            running -= 1
            if isinstance(result, BaseException):
                raise result
            if collect(result):
                return
