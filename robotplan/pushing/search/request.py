"""What one skeleton search is asked: the task, the learned model, the candidates' limits,
the budget and how it reports; frozen, so a tier or a helper process narrows it with
:meth:`SearchRequest.but` and never changes the caller's."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from robotplan.scene.task import PushTask

if TYPE_CHECKING:
    from robotplan.pushing.program.skeleton import Skeleton

__all__ = ["SearchRequest"]


@dataclass(frozen=True, eq=False)
class SearchRequest:
    """``task``: the push task. ``model_dir``: the learned dynamics' folder. ``skeleton``:
    one skeleton (the CLI's notation, or a ``Skeleton``) instead of the search.
    ``max_pushes``: the most pushes a candidate has. ``workers``: processes that solve
    programs at once. ``time_budget``: seconds after which no further tier starts once a
    plan is in hand. ``guesses``: the learned program's initial guesses by skeleton (a warm
    start). ``program``: a user's program settings
    (:func:`~robotplan.pushing.program.settings.with_overrides`). ``replan``: a fresh search during
    execution. ``last_resort``: the violation within which the caller adopts an unsolved
    plan that meets the constraints. ``exhaustive``: solve every candidate. ``deadline``: the
    instant (``time.monotonic()``, one clock for every process) after which no tier and no
    program starts, the best plan so far (or none) being the search's result; a program
    running then runs to its end. ``candidate_kinds``: the kinds of candidates the search
    may try (``skeletons/tiers.yaml``: pose_fits, region_fits, plain, routes; None: every
    kind); ``("plain",)`` is the paper's search, the optimiser from the skeleton space's
    initializations, without pushes fitted in closed form."""

    task: PushTask
    model_dir: Path
    solver: str = "snopt"
    workers: int = 2
    skeleton: str | Skeleton | None = None
    max_pushes: int = 2
    time_budget: float | None = None
    guesses: Mapping[Skeleton, dict] | None = None
    program: Mapping[str, object] | None = None
    replan: bool = False
    last_resort: float | None = None
    exhaustive: bool = False
    deadline: float | None = None
    progress: bool = True
    quiet: bool = False
    candidate_kinds: tuple[str, ...] | None = None

    def but(self, **changes: object) -> SearchRequest:
        """This request with ``changes``."""
        return replace(self, **changes)

    def left(self, spent: float) -> float | None:
        """The seconds of ``time_budget`` left after ``spent`` (None: no budget)."""
        return None if self.time_budget is None else max(0.0, self.time_budget - spent)

    def past_deadline(self) -> bool:
        """Whether ``deadline`` has passed (never without one)."""
        return self.deadline is not None and time.monotonic() > self.deadline

    def say(self, line: str) -> None:
        """Print ``line`` unless quiet."""
        if not self.quiet:
            print(line)
