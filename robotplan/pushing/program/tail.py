"""The rest of a plan from one of its states on: what a closed loop re-plans (shrinking
horizon).

A plan of K phases of T steps, cut after state t (0 < t ≤ N), keeps the phases not yet
finished. The phase that t lies in, if t is not its end, is done again in full: its
remaining states t…end are stretched over T steps, so every phase keeps T steps and the
program's steps per phase stay those of the skeleton space. Contact points of push steps
are stretched with their phase.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from robotplan.pushing.program.skeleton import Skeleton
from robotplan.pushing.program.solution import Solution

__all__ = ["solution_tail"]


def _stretch(states: np.ndarray, count: int) -> np.ndarray:
    """``states (m+1, d)`` resampled to ``count + 1`` states, linear in the step index."""
    m = len(states) - 1
    if m == count:
        return states.copy()
    at = np.linspace(0.0, m, count + 1)
    return np.stack([np.interp(at, np.arange(m + 1), states[:, j])
                     for j in range(states.shape[1])], axis=1)


def _stretch_contacts(points: np.ndarray, count: int) -> np.ndarray:
    """Contact points ``(m, 2)`` of the last m push steps of a phase over ``count`` steps."""
    if len(points) == count:
        return points.copy()
    if len(points) == 1:
        return np.repeat(points, count, axis=0)
    at = np.linspace(0.0, len(points) - 1, count)
    return np.stack([np.interp(at, np.arange(len(points)), points[:, j])
                     for j in range(2)], axis=1)


def _tail_states(q: np.ndarray, t: int, T: int, first: int) -> np.ndarray:
    """States of the phases from ``first`` on, the first one stretched from state t."""
    head = _stretch(q[t:(first + 1) * T + 1], T)
    return np.concatenate((head, q[(first + 1) * T + 1:]))


def _tail_contacts(points: np.ndarray, phase_has_points: list[bool], t: int, T: int,
                   first: int) -> np.ndarray:
    """The contact rows (one per step of the phases flagged in ``phase_has_points``) of
    the phases from ``first`` on; the first one's rows after state t stretched to T."""
    out, row = [], 0
    for k, has in enumerate(phase_has_points):
        if not has:
            continue
        block = points[row:row + T]
        row += T
        if k == first:
            done = t - k * T
            out.append(_stretch_contacts(block[done:], T))
        elif k > first:
            out.append(block)
    return np.concatenate(out) if out else np.zeros((0, 2))


def solution_tail(sol: Solution, t: int) -> Solution | None:
    """The plan ``sol`` from state ``t`` on, as a solution of the remaining phases (None
    when every phase is done). Its state 0 is the plan's state t; the caller re-anchors it
    at the observed state (:func:`robotplan.pushing.program.solve.warm_guess`)."""
    phases = sol.skeleton.phases
    N = len(sol.q_obj) - 1
    T = N // len(phases)
    first = t // T  # the phase state t lies in (or the next, at its end)
    if first >= len(phases) or t >= N:
        return None
    pushing = [ph.mode == "push" for ph in phases]
    chained = [ph.mode == "push" and ph.chain is not None for ph in phases]
    skeleton = Skeleton(phases[first:])
    return replace(
        sol, skeleton=skeleton,
        q_obj=_tail_states(sol.q_obj, t, T, first),
        q_pusher=_tail_states(sol.q_pusher, t, T, first),
        contact=_tail_contacts(sol.contact, pushing, t, T, first),
        dynamics_mm2=np.zeros(0),
        q_joints={k: _tail_states(v, t, T, first) for k, v in sol.q_joints.items()},
        q_others={k: _tail_states(v, t, T, first) for k, v in sol.q_others.items()},
        contact_others={k: _tail_contacts(v, chained, t, T, first)
                        for k, v in sol.contact_others.items()})
