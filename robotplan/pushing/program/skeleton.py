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
from typing import TYPE_CHECKING, Literal

import yaml

from robotplan.base.resources import skeletons_dir

if TYPE_CHECKING:
    from robotplan.scene.task import PushTask

__all__ = ["Phase", "Skeleton", "SkeletonSpace", "actor_candidates", "chain_candidates",
           "load_skeleton_space", "parse_skeleton", "space_for"]

SKELETONS_DIR = skeletons_dir()


@dataclass(frozen=True)
class Phase:
    """One phase of T steps: ``mode`` of ``actor`` (a pusher) on ``object``, initialised
    from the fixed point ``init`` around the object (index into the init directions). In a
    push phase with a ``chain``, ``object`` pushes the object named ``chain`` in turn (the
    pairs actor–object and object–chain interact, paper Fig. 9). ``via``: where the initial
    guess leaves the object's centre at the end of a push (table frame, m), e.g. a corner of
    a route around obstacles (robotplan.pushing.search.route)."""

    mode: Literal["reach", "push"]
    actor: str
    object: str
    init: int
    chain: str | None = None
    via: tuple[float, float] | None = None


@dataclass(frozen=True)
class Skeleton:
    phases: tuple[Phase, ...]

    @property
    def pushes(self) -> int:
        return sum(p.mode == "push" for p in self.phases)

    @property
    def chained(self) -> str | None:
        """The object that another object pushes in some phase (one per skeleton), if any."""
        return next((p.chain for p in self.phases if p.chain), None)

    def describe(self) -> str:
        return " ".join(f"{p.mode}({p.actor}->{p.object}{'->' + p.chain if p.chain else ''}"
                        f"@{p.init}{' to ({:.2f}, {:.2f})'.format(*p.via) if p.via else ''})"
                        for p in self.phases)

    def as_rows(self) -> list[dict]:
        rows = []
        for k, p in enumerate(self.phases):
            row = {"phase": k, "mode": p.mode, "actor": p.actor, "object": p.object,
                   "init": p.init}
            if p.chain:
                row["pushes"] = p.chain
            if p.via:
                row["via"] = [round(v, 4) for v in p.via]
            rows.append(row)
        return rows


@dataclass(frozen=True)
class SkeletonSpace:
    steps_per_phase: int
    templates: dict[str, tuple[str, ...]]
    init_directions_deg: tuple[float, ...]
    init_clearance: float
    init_frame: Literal["table", "goal", "object"] = "table"

    def init_angle(self, index: int, obj_xy, goal_xy, yaw: float = 0.0) -> float:
        """Direction (rad, table frame) of init point ``index`` around an object at
        ``obj_xy`` with orientation ``yaw``: the table frame (paper Fig. 17), measured from
        the direction away from the goal (``init_frame: goal``, so init 0 is straight
        behind the object), or the object's own frame (``object``: for a box, the four
        face normals at its start pose)."""
        base = 0.0
        if self.init_frame == "goal" and goal_xy is not None:
            base = math.atan2(obj_xy[1] - goal_xy[1], obj_xy[0] - goal_xy[0])
        elif self.init_frame == "object":
            base = yaw
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


def chain_candidates(space: SkeletonSpace, actor: str, obj: str, target: str,
                     max_pushes: int = 2, min_alone: int = 0) -> list[Skeleton]:
    """Skeletons in which ``actor`` may touch ``obj`` only and ``obj`` pushes ``target``:
    every template with up to ``max_pushes`` pushes, each push either ``obj`` alone or the
    chain ``obj`` → ``target``; once the chain is in contact it stays so (alone pushes come
    first, at least ``min_alone`` of them, then at least one chained push), × every init per
    push."""
    out = []
    for base in space.candidates(actor, obj, max_pushes):
        n = base.pushes
        for alone in range(min_alone, n):  # the first ``alone`` pushes move obj by itself
            phases, k = [], 0
            for ph in base.phases:
                chain = target if ph.mode == "push" and k >= alone else None
                phases.append(Phase(ph.mode, ph.actor, ph.object, ph.init, chain))
                k += ph.mode == "push"
            out.append(Skeleton(tuple(phases)))
    return out


def actor_candidates(space: SkeletonSpace, actors: list[str], obj: str, max_pushes: int = 2,
                     touch_actor: str | None = None) -> list[Skeleton]:
    """Every template with up to ``max_pushes`` pushes, every choice of the actor of each
    push (its reach phase goes with it) and every init; with a ``touch_actor`` (touch goal)
    a final reach phase of that actor, from each init, ends on the object, and zero pushes
    is a template too."""
    templates = list(space.templates.values())
    if touch_actor is not None:
        templates = [(), *templates]
    out = []
    inits = range(len(space.init_directions_deg))
    for modes in templates:
        n_push = sum(m == "push" for m in modes)
        if n_push > max_pushes:
            continue
        extra = 1 if touch_actor is not None else 0
        for who in itertools.product(actors, repeat=n_push):
            for choice in itertools.product(inits, repeat=n_push + extra):
                phases = []
                for i, mode in enumerate(modes):
                    # a reach belongs to the push after it
                    k_push = sum(m == "push" for m in modes[:i + (mode == "reach")])
                    phases.append(Phase(mode, who[k_push], obj, choice[k_push]))
                if touch_actor is not None:
                    phases.append(Phase("reach", touch_actor, obj, choice[-1]))
                out.append(Skeleton(tuple(phases)))
    return out


def load_skeleton_space(path: Path = SKELETONS_DIR / "push.yaml") -> SkeletonSpace:
    data = yaml.safe_load(path.read_text())
    return SkeletonSpace(int(data["steps_per_phase"]),
                         {k: tuple(v) for k, v in data["templates"].items()},
                         tuple(float(d) for d in data["init_directions_deg"]),
                         float(data["init_clearance"]), data.get("init_frame", "table"))


def space_for(task: PushTask) -> SkeletonSpace:
    """The skeleton choices of a task: ``arms.yaml`` when robot arms push, else
    ``push.yaml``."""
    return load_skeleton_space(SKELETONS_DIR / ("arms.yaml" if task.arms else "push.yaml"))


def parse_skeleton(text: str, actor: str, obj: str) -> Skeleton:
    """``"push@2"`` (one push from init 2), ``"push@0,push@3"`` (two pushes); an item may
    name its actor, ``"left:push@1,right:push@3"``, a touch goal ends with
    ``"right:touch@2"`` (the arm reaches the object from init 2), and ``"push@0>blue"`` is a
    push in which the object pushes ``blue``."""
    phases = []
    for item in text.replace(" ", "").split(","):
        item, _, chain = item.partition(">")
        who, _, rest = item.rpartition(":")
        mode, _, init = rest.partition("@")
        if mode not in ("push", "touch") or not init.isdigit():
            raise ValueError(f"skeleton item {item!r}: expected [actor:]push@<init index> "
                             "or [actor:]touch@<init index>")
        name = who or actor
        if mode == "touch":
            phases.append(Phase("reach", name, obj, int(init)))
        else:
            phases += [Phase("reach", name, obj, int(init)),
                       Phase("push", name, obj, int(init), chain or None)]
    return Skeleton(tuple(phases))
