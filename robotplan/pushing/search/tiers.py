"""The tier table of the skeleton search (``skeletons/tiers.yaml``): which candidates are
tried, in which order, for which tasks, under which program settings and budget, and when a
tier ends the search. One loop reads it
(:func:`robotplan.pushing.search.scene_search.search_scene`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Literal

import yaml

from robotplan.base.overlays import check_overlays
from robotplan.base.resources import skeletons_dir
from robotplan.pushing.program.settings import DEFAULT_SETTINGS, ProgramSettings
from robotplan.pushing.search.request import SearchRequest
from robotplan.scene.reader import read

__all__ = ["Tier", "TierCondition", "budget_settings", "load_budgets", "load_tiers"]


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
    budgets: list[str] = field(default_factory=lambda: ["own"])
    ends: Literal["never", "candidates", "settled", "solved"] = "never"
    charged: bool = True


@dataclass(frozen=True)
class TierTable:
    tiers: list[Tier]


@cache
def load_tiers(path: Path | None = None) -> tuple[Tier, ...]:
    """The tiers of ``path`` (default ``skeletons/tiers.yaml``), in order."""
    path = path or skeletons_dir() / "tiers.yaml"
    data = yaml.safe_load(path.read_text())
    tiers = read(TierTable, {"tiers": (data or {}).get("tiers")} if isinstance(data, dict)
                 else data).tiers
    budgets = set(load_budgets(path)) | {"own"}
    for i, tier in enumerate(tiers):
        for name in tier.budgets:
            if name not in budgets:
                raise ValueError(f"{path}: tiers[{i}].budgets: {name!r} is not a budget; one "
                                 f"of {sorted(budgets)}")
    return tuple(tiers)


@cache
def load_budgets(path: Path | None = None) -> dict[str, dict]:
    """The named budgets of ``path`` (``budgets:`` of ``skeletons/tiers.yaml``): program
    settings a tier applies over the task's, checked against the settings' names."""
    path = path or skeletons_dir() / "tiers.yaml"
    data = yaml.safe_load(path.read_text()) or {}
    budgets = data.get("budgets", {}) if isinstance(data, dict) else {}
    if isinstance(budgets, dict) and "own" in budgets:
        raise ValueError(f"{path}: budgets.own: 'own' is the task's settings, not a budget")
    return check_overlays(budgets, DEFAULT_SETTINGS.values(), None, "program setting",
                          f"{path}: budgets")


def budget_settings(name: str, base: ProgramSettings) -> ProgramSettings:
    """``base`` with the budget ``name`` applied, then the user's overrides ``base``
    carries (they win over every budget)."""
    settings = base.with_values(load_budgets()[name])
    return settings.with_values(dict(settings.overrides)) if settings.overrides else settings
