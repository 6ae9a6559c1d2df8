"""Skeletons: the discrete part of the plan (which phases, who pushes, which initialization).

A skeleton is a tuple of :class:`Phase` rows, KOMO-style declarative: ``reach`` moves a
pusher towards an initialization point without touching, ``push`` moves an object with it.
The choices come from ``skeletons/push.yaml``.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import yaml

__all__ = ["Phase", "Skeleton", "SkeletonSpace", "load_skeleton_space", "parse_skeleton"]

SKELETONS_DIR = Path(__file__).resolve().parents[1] / "skeletons"


@dataclass(frozen=True)
class Phase:
    """One phase of T steps: ``mode`` of ``actor`` (a pusher) on ``object``, initialised
    from the fixed point ``init`` around the object (index into the init directions)."""

    mode: Literal["reach", "push"]
    actor: str
    object: str
    init: int


@dataclass(frozen=True)
class Skeleton:
    phases: tuple[Phase, ...]

    @property
    def pushes(self) -> int:
        return sum(p.mode == "push" for p in self.phases)

    def describe(self) -> str:
        return " ".join(f"{p.mode}({p.actor}->{p.object}@{p.init})" for p in self.phases)

    def as_rows(self) -> list[dict]:
        return [{"phase": k, "mode": p.mode, "actor": p.actor, "object": p.object,
                 "init": p.init} for k, p in enumerate(self.phases)]


@dataclass(frozen=True)
class SkeletonSpace:
    steps_per_phase: int
    templates: dict[str, tuple[str, ...]]
    init_directions_deg: tuple[float, ...]
    init_clearance: float
    init_frame: Literal["table", "goal"] = "table"

    def init_angle(self, index: int, obj_xy, goal_xy) -> float:
        """Direction (rad, table frame) of init point ``index`` around an object at
        ``obj_xy``: the table frame (paper Fig. 17), or measured from the direction away
        from the goal (``init_frame: goal``, so init 0 is straight behind the object)."""
        base = 0.0
        if self.init_frame == "goal" and goal_xy is not None:
            base = math.atan2(obj_xy[1] - goal_xy[1], obj_xy[0] - goal_xy[0])
        return base + math.radians(self.init_directions_deg[index])

    def candidates(self, actor: str, obj: str, max_pushes: int = 2) -> list[Skeleton]:
        """Every template with up to ``max_pushes`` pushes × every init per push."""
        out = []
        inits = range(len(self.init_directions_deg))
        for modes in self.templates.values():
            n_push = sum(m == "push" for m in modes)
            if n_push > max_pushes:
                continue
            for choice in itertools.product(inits, repeat=n_push):
                phases, k = [], 0
                for mode in modes:
                    phases.append(Phase(mode, actor, obj, choice[k]))
                    if mode == "push":
                        k += 1
                out.append(Skeleton(tuple(phases)))
        return out


def load_skeleton_space(path: Path = SKELETONS_DIR / "push.yaml") -> SkeletonSpace:
    data = yaml.safe_load(path.read_text())
    return SkeletonSpace(int(data["steps_per_phase"]),
                         {k: tuple(v) for k, v in data["templates"].items()},
                         tuple(float(d) for d in data["init_directions_deg"]),
                         float(data["init_clearance"]), data.get("init_frame", "table"))


def parse_skeleton(text: str, actor: str, obj: str) -> Skeleton:
    """``"push@2"`` (one push from init 2) or ``"push@0,push@3"`` (two pushes)."""
    phases = []
    for item in text.replace(" ", "").split(","):
        mode, _, init = item.partition("@")
        if mode != "push" or not init.isdigit():
            raise ValueError(f"skeleton item {item!r}: expected push@<init index>")
        phases += [Phase("reach", actor, obj, int(init)), Phase("push", actor, obj, int(init))]
    return Skeleton(tuple(phases))
