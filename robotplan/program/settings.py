"""The settings of a push program (:class:`ProgramSettings`): functional constants, bounds,
solver options and the two-stage scheme, each with its reason; the measurements behind them
are in docs/experiments.md."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path

from robotplan.base.overlays import apply_overlays, parse_overrides, read_overlays
from robotplan.base.resources import skeletons_dir
from robotplan.functionals.dynamics import QUADRATURE_COARSE

__all__ = ["ARM_PROGRAM_SETTINGS", "DEFAULT_SETTINGS", "SCENE_CLASSES", "ProgramSettings",
           "load_overlays", "parse_program_overrides", "settings_for", "with_overrides"]


@dataclass(frozen=True)
class ProgramSettings:
    a_coll: float = 500.0
    a_goal: float = 100.0
    dynamics_rmse: float = 0.0015  # m: allowed RMSE of φ1_t against F(…) over X per step
    # H_F as a cost (weight per mm² of mean squared residual per step) when > 0, else as a
    # constraint ≤ dynamics_rmse² per step: the model's own error in contact makes the bound
    # either infeasible or loose enough to move the object without contact
    # (measured: docs/experiments.md#dynamics-residual)
    dynamics_weight: float = 0.01
    hold_while_reaching: bool = True  # q_obj,t = q_obj,t−1 in reach phases
    guess_speed: float = 0.027  # m per step and axis in the initial guess (data: ≤ 2.9 cm)
    # allowed smoothed overlap: what a face contact pressed in by ``coll_depth`` costs (at
    # least ``coll_area``, m²); a bound below what touching costs makes H_coll and H_PoC
    # fight (measured: docs/experiments.md#collision-bound)
    coll_area: float = 2e-5
    coll_depth: float = 0.0005
    # m² of smoothed overlap allowed between the object and an obstacle: ~1.3 cm of clearance
    # at a = 500 (measured: docs/experiments.md#obstacle-overlap)
    obstacle_overlap: float = 1e-6
    reach_clearance: float = 0.01  # m between pusher and object outside push steps
    # and at least −swept_tolerance (m) along each free move (SweptClearance, samples per
    # move): without it the pusher can pass through the object between two clear states,
    # and pybullet drags the object along (measured: docs/experiments.md#swept-clearance)
    swept_samples: int = 7
    swept_tolerance: float = 0.002
    # a solved plan's free moves are checked again at points ``swept_check_spacing`` (m)
    # apart, and a crossing deeper than ``swept_check_depth`` (m) fails the swept row: a long
    # reach step can cross the object between its samples, and pybullet drags it along; a
    # step bound in the program or rows added after the solve did worse
    # (measured: docs/experiments.md#swept-clearance)
    swept_check_spacing: float | None = 0.01
    swept_check_depth: float = 0.01
    # the same check on push steps, the pusher's move seen from the object (its start carried
    # by the object's step): a push step's rows hold at its end states only, so the pusher
    # can hop through the object between two faces; plans that executed well cross far less
    # (measured: docs/experiments.md#swept-clearance)
    push_check_depth: float = 0.02
    goal_tol: float = 0.003  # share of the object's area allowed outside the goal (or off its pose)
    # plan into the region shrunk by this much (m), at most a third of the room the object
    # has when aligned (region inradius − half its longer side), so tight fits stay feasible
    goal_inset: float = 0.02
    accel_weight: float = 1.0  # larger weights keep SNOPT from certifying optimality
    contact_accel_weight: float = 0.1
    solver: str = "snopt"
    # hand SNOPT the per-step sparsity of the stepwise constraints. Off for free pushers (it
    # can turn a feasible kinematic stage infeasible); on for arms (the `arms` overlay of
    # skeletons/settings.yaml),
    # whose dense rows over every joint are slow (measured: docs/experiments.md#sparse-jacobians)
    sparse_jacobians: bool = False
    optimality_tol: float = 2e-3
    feasibility_tol: float = 1e-4
    # SNOPT major iterations of the learned stage (it starts from the kinematic plan and keeps
    # it when it ends worse): more iterations cost time without better plans, fewer lose
    # plans (measured: docs/experiments.md#learned-iterations)
    iterations: int = 30
    # the search stops at the first solved plan whose learned-dynamics residual (RMS per
    # step, mm) is at most this: F_flow's own one-step error in contact; F_q's overlay
    # (`rigid`) stops at its first solved plan (measured: docs/experiments.md#dynamics-residual)
    good_rms_mm: float = 5.0
    # SNOPT's limit on minor (QP) iterations over a whole solve: this many per constraint
    # row, at least SNOPT's default 10,000 (so programs of up to two free pushes, ≤ 666
    # rows, keep the default): long chained pushes need more, short programs gain nothing
    # from it (measured: docs/experiments.md#minor-iterations)
    minor_iterations_per_row: int = 12
    quad_coarse: float = QUADRATURE_COARSE  # H_F quadrature (see phase_quadrature)
    # warm start: first solve the kinematic program (sticking contact, pushing direction,
    # no H_F: milliseconds per iteration) and start the learned program from its solution
    warm_start: bool = True
    # False: the kinematic program is the plan, its quasi-static model (sticking contact,
    # the limit surface's turning law) in place of the learned one: the analytic-model
    # baseline of the paper's Fig. 6
    learned_stage: bool = True
    # with a given guess (a re-plan from an earlier plan), the kinematic stage starts from it
    warm_from_guess: bool = True
    # and the learned stage is not run when its start (the repaired guess) already meets
    # every row with a residual of at most good_rms_mm: such a solve mostly keeps its start
    # (the `replan` overlay turns it on; measured: docs/experiments.md#good-start)
    accept_good_start: bool = False
    # nor when its start misses the constraints by more than this (scaled violation; None:
    # always run): from such a start the learned stage's few iterations ended where they
    # began (the `replan` overlay sets it; measured: docs/experiments.md#replan-learned-stage)
    learned_start_violation: float | None = None
    warm_iterations: int = 300
    # a kinematic solve that ends above this violation (but usable, ≤ WARM_USABLE) is solved
    # again from where it ended (a fresh quasi-Newton model): it rescues SNOPT's
    # "infeasibilities minimized" near a solution, never a far one
    # (measured: docs/experiments.md#warm-restart)
    warm_restart_above: float = 1e-3
    warm_restarts: int = 1
    warm_max_step: float = 0.03  # m per push step and axis for the pusher (data: ≤ 2.9 cm)
    # rad per push step: sticking alone lets the object spin about the pusher, its centre
    # sweeping faster than any push moves it
    warm_max_turn: float = 0.2
    object_motion_weight: float = 1.0  # kinematic stage: Σ|Δq_obj|² (yaw in turn_length m)
    turn_length: float = 0.3  # turning 1 rad costs like 0.3 m of travel
    # cost per cm² of the push's lever arm about the centroid (PushLever), both stages: an
    # off-centre push on a long face turns the box in pybullet, not in the plan
    lever_weight: float = 0.01
    # quasi-static sticking pushes (QuasiStaticPush) with this pusher–object friction,
    # well inside pybullet's 0.5 × 0.3 = 0.15 (8.5°): the object arrives a few degrees off
    # the plan, and a push at the plan's cone edge then slides; ≤ 0 leaves the object's
    # motion free apart from sticking (measured: docs/experiments.md#push-friction)
    push_friction: float = 0.08
    cone_in_learned: bool = True  # keep the friction cone in the learned stage too
    # and the limit surface's turning law (c² Δθ = r × Δc): the learned models predict little
    # of the turning pybullet produces, the law much more
    # (measured: docs/experiments.md#turn-in-learned)
    turn_in_learned: bool = True
    # the turning law's gain g (c² Δθ = g · r × Δc; 1: the ellipsoidal limit surface of the
    # support points); pybullet turns a box or T pushed along a face normal further, which
    # the `pose` overlay's gain follows (measured: docs/experiments.md#pose-goals)
    turn_gain: float = 1.0
    # arms (robotplan/program/arm_program.py)
    step_seconds: float = 1.0 / 12.0  # one planned step: 20 simulation steps, as the data
    reach_slowdown: float = 3.0  # reach steps last this many planned steps in execution
    idle_lift: float = 0.04  # m between an idle tip's bottom and the objects' tops
    flange_clearance: float = 0.01  # m between the flange and the objects' tops
    link_min: float = 0.12  # m: lowest allowed height of the other check links
    arm_gap: float = 0.10  # m between the two arms' check points
    # m per step and axis of the acting tip while reaching: H_coll sees the sampled states
    # only, and a long step between them can cut through the object in pybullet
    # (measured: docs/experiments.md#tip-reach-step)
    tip_reach_step: float = 0.04
    joint_step_weight: float = 0.01  # cost per rad² of joint motion per step
    # the paper's ablation (Fig. 11): off, the program has no H_coll (and no swept
    # clearance) between actor and object, or no H_PoC
    with_collision: bool = True
    with_contact: bool = True
    # a user's settings (``--program NAME=VALUE``) as (name, value) pairs: they win over
    # every scene class's overlay, also over those applied later (re-plans, routes)
    overrides: tuple[tuple[str, object], ...] = ()


DEFAULT_SETTINGS = ProgramSettings()  # the free pushers' settings
# "replan": a search warm started from an earlier plan (the closed loop's re-plans), last
SCENE_CLASSES = ("arms", "routes", "pose", "rigid", "replan")


@cache
def load_overlays(path: Path | None = None) -> dict[str, dict]:
    """The overlays of ``skeletons/settings.yaml``, checked against the fields."""
    return read_overlays(path or skeletons_dir() / "settings.yaml", DEFAULT_SETTINGS,
                         SCENE_CLASSES, "program setting")


def settings_for(*classes: str, base: ProgramSettings = DEFAULT_SETTINGS,
                 **changes: object) -> ProgramSettings:
    """``base`` with the overlays of the scene ``classes`` (``arms``, ``routes``) from
    ``skeletons/settings.yaml`` in order, then ``changes``, then the user's ``overrides``
    that ``base`` carries."""
    settings = replace(apply_overlays(base, load_overlays(), classes), **changes)
    return replace(settings, **dict(settings.overrides)) if settings.overrides else settings


def with_overrides(settings: ProgramSettings, overrides: Mapping[str, object] | None
                   ) -> ProgramSettings:
    """``settings`` with a user's ``overrides`` applied, and carried into every overlay
    applied after (:func:`settings_for`)."""
    if not overrides:
        return settings
    pairs = tuple(sorted(dict(overrides).items()))
    return replace(settings, **dict(pairs), overrides=pairs)


def parse_program_overrides(items: Sequence[str]) -> dict[str, object]:
    """``NAME=VALUE`` items (the CLI's ``--program``) as :class:`ProgramSettings` fields
    with values of their types (:func:`robotplan.base.overlays.parse_overrides`)."""
    return parse_overrides(DEFAULT_SETTINGS, items, "program setting")


ARM_PROGRAM_SETTINGS = settings_for("arms")
"""The program settings of scenes with arms."""
