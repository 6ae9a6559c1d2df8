"""The decision variables of a push program and the sets of states its rows hold at.

Over N = K·T steps (states 0…N, K phases of T steps), :class:`ProgramVariables` holds the
arrays a row of ``skeletons/rows.yaml`` names in its ``bodies``; :class:`StepSets` the
state indices its ``steps`` names."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from pydrake.solvers import MathematicalProgram

from robotplan.pushing.program.skeleton import Skeleton

__all__ = ["ProgramVariables", "StepSets"]


def _states(skeleton: Skeleton, T: int, chained: bool = False) -> np.ndarray:
    """The states of the push phases (with ``chained``: of the chained push phases)."""
    return np.array([k * T + s + 1 for k, ph in enumerate(skeleton.phases)
                     if ph.mode == "push" and (ph.chain is not None or not chained)
                     for s in range(T)], dtype=int)


def _pairs(steps: np.ndarray, T: int) -> np.ndarray:
    """Indices i ≥ 1 into ``steps`` whose step follows step i − 1 in the same phase."""
    i = np.arange(1, len(steps))
    return i[(steps[i] == steps[i - 1] + 1) & ((steps[i] - 1) % T != 0)]


@dataclass(frozen=True)
class StepSets:
    """The states of one skeleton of K phases of ``T`` steps, by the table's names."""

    skeleton: Skeleton
    T: int
    touch_actor: str | None = None

    @property
    def N(self) -> int:
        return self.T * len(self.skeleton.phases)

    def mode(self, t: int) -> str:
        """The mode of the phase that step t ≥ 1 belongs to."""
        return self.skeleton.phases[(t - 1) // self.T].mode

    def actor(self, t: int) -> str:
        """The actor of state t (state 0: the first phase's)."""
        return self.skeleton.phases[max(t - 1, 0) // self.T].actor

    def named(self, name: str, arm: str | None = None) -> np.ndarray:
        """The states of the table's step set ``name`` (per-arm sets of ``arm``)."""
        N, T = self.N, self.T
        push = _states(self.skeleton, T)
        if name in ("acting", "arm_push", "arm_reach", "idle", "tip_steps"):
            return np.array(self._arm_states(name, arm), dtype=int)
        chain = _states(self.skeleton, T, chained=True)
        every = np.arange(N + 1)
        sets = {
            "start": every[:1], "every": every, "all": every[1:], "push": push,
            "reach": np.array([t for t in range(1, N + 1) if self.mode(t) == "reach"],
                              dtype=int),
            "free": np.setdiff1d(every[1:], push), "final": every[N:],
            "push_pairs": _pairs(push, T), "chain_push": chain,
            "chain_pairs": _pairs(chain, T), "unchained": np.setdiff1d(every[1:], chain)}
        return sets[name]

    def _arm_states(self, name: str, arm: str | None) -> list[int]:
        N, T = self.N, self.T
        if name == "tip_steps":
            return [t for t in range(1, N + 1) if self.actor(t) == self.actor(t - 1)]
        acting = [t for t in range(1, N + 1) if self.actor(t) == arm]
        low: set[int] = set()
        for k, ph in enumerate(self.skeleton.phases):
            if ph.mode == "push" and ph.actor == arm:
                low.update(range(max(k * T, 1), (k + 1) * T + 1))
        if self.touch_actor == arm:
            low.add(N)
        if name == "acting":
            return acting
        if name == "arm_push":
            return sorted(low)
        if name == "arm_reach":
            return [t for t in acting if t not in low]
        return [t for t in range(2, N + 1) if arm not in (self.actor(t), self.actor(t - 1))]


@dataclass
class ProgramVariables:
    """The decision variables, made in this order (SNOPT sees them so): the pushed object's
    poses ``q_obj (N+1, 3)``, the actor's positions ``q_actor (N+1, 2)`` (a free pusher's
    centre or the acting arm's tip), the contact points of push steps ``contact (P, 2)``;
    with a chain the chained object's poses ``chained (N+1, 3)`` and its contact points
    ``chain_contact (C, 2)``; with a touch goal its point ``touch (1, 2)``; with arms, once
    the arms' rows come, each arm's joint angles ``joints[name] (N+1, dof)``."""

    q_obj: np.ndarray
    q_actor: np.ndarray
    contact: np.ndarray
    chained: np.ndarray | None = None
    chain_contact: np.ndarray | None = None
    touch: np.ndarray | None = None
    goal_chained: bool = False  # the goal is the chained object's
    joints: dict[str, np.ndarray] = field(default_factory=dict)

    @classmethod
    def make(cls, prog: MathematicalProgram, steps: StepSets, chain: bool, touch: bool,
             goal_chained: bool = False) -> ProgramVariables:
        N = steps.N
        new = prog.NewContinuousVariables
        out = cls(new(N + 1, 3, "q_obj"), new(N + 1, 2, "q_pusher"),
                  new(len(steps.named("push")), 2, "p"))
        if chain:
            out.chained = new(N + 1, 3, "q_chain")
            out.chain_contact = new(len(steps.named("chain_push")), 2, "p_chain")
        if touch:
            out.touch = new(1, 2, "p_touch")
        out.goal_chained = goal_chained
        return out

    def add_joints(self, prog: MathematicalProgram, dofs: dict[str, int]) -> None:
        """Each arm's joint angles ``(N+1, dof)``."""
        N = len(self.q_obj) - 1
        for name, dof in dofs.items():
            self.joints[name] = prog.NewContinuousVariables(N + 1, dof, f"q_{name}")

    def body(self, name: str, arm: str | None = None) -> np.ndarray:
        """The variables of the table's body ``name`` (``joints``: those of ``arm``;
        ``goal``: the poses of the object the goal is about)."""
        if name == "joints":
            return self.joints[arm]
        if name == "goal":
            name = "chained" if self.goal_chained else "object"
        out = {"object": self.q_obj, "actor": self.q_actor, "contact": self.contact,
               "chained": self.chained, "chain_contact": self.chain_contact,
               "touch": self.touch}[name]
        if out is None:
            raise KeyError(f"the program has no {name} variables")
        return out
