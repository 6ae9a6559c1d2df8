"""The tier table of the skeleton search (``skeletons/tiers.yaml``): which candidates are
tried, in which order, for which tasks, under which program settings and budget, and when a
tier ends the search. One loop reads it (:func:`robotplan.search.scene_search.search_scene`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Literal

import yaml

from robotplan.base.resources import skeletons_dir
from robotplan.scene.reader import read
from robotplan.search.request import SearchRequest

__all__ = ["Tier", "TierCondition", "load_tiers"]


@dataclass(frozen=True)
class TierCondition:
    """What the task and the request must be for a tier to be tried (None: either)."""

    goal: list[Literal["region", "pose", "touch"]] | None = None
    actors: list[Literal["pusher", "arms", "chain"]] | None = None
    obstacles: bool | None = None
    given: bool | None = None
    warm: bool | None = None
    replan: bool | None = None

    def holds(self, request: SearchRequest) -> bool:
        task = request.task
        actors = "arms" if task.arms else "chain" if task.chained is not None else "pusher"
        facts = {"goal": task.goal, "actors": actors, "obstacles": task.obstacles,
                 "given": request.skeleton is not None, "warm": bool(request.guesses),
                 "replan": request.replan}
        for name, fact in facts.items():
            wanted = getattr(self, name)
            if wanted is not None and (fact not in wanted if isinstance(wanted, list)
                                       else fact != wanted):
                return False
        return True


@dataclass(frozen=True)
class Tier:
    """One row of the tier table (its fields are explained in ``skeletons/tiers.yaml``)."""

    name: str
    candidates: Literal["pose_fits", "region_fits", "plain", "routes"]
    when: TierCondition = field(default_factory=TierCondition)
    runs: Literal["always", "unsolved", "unsolved_in_budget"] = "always"
    budgets: list[Literal["own", "replan"]] = field(default_factory=lambda: ["own"])
    ends: Literal["never", "candidates", "settled", "solved"] = "never"
    charged: bool = True


@dataclass(frozen=True)
class TierTable:
    tiers: list[Tier]


@cache
def load_tiers(path: Path | None = None) -> tuple[Tier, ...]:
    """The tiers of ``path`` (default ``skeletons/tiers.yaml``), in order."""
    path = path or skeletons_dir() / "tiers.yaml"
    return tuple(read(TierTable, yaml.safe_load(path.read_text())).tiers)
