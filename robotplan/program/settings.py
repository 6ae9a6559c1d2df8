"""The settings of a push program (:class:`ProgramSettings`): functional constants, bounds,
solver options and the two-stage scheme, each with what measured it."""

from __future__ import annotations

from dataclasses import dataclass

from robotplan.functionals.dynamics import QUADRATURE_COARSE

__all__ = ["ProgramSettings"]


@dataclass(frozen=True)
class ProgramSettings:
    a_coll: float = 500.0
    a_goal: float = 100.0
    dynamics_rmse: float = 0.0015  # m: allowed RMSE of φ1_t against F(…) over X per step
    # H_F as a cost (weight per mm² of mean squared residual per step) when > 0, else as a
    # constraint ≤ dynamics_rmse² per step: the model's own error (~4.5 mm in contact) makes
    # the bound either infeasible or loose enough to move the object without contact
    dynamics_weight: float = 0.01
    hold_while_reaching: bool = True  # q_obj,t = q_obj,t−1 in reach phases
    guess_speed: float = 0.027  # m per step and axis in the initial guess (data: ≤ 2.9 cm)
    # optional hard limits per step and axis (m, rad); off by default: on box_push they
    # left SNOPT at violation 1.2 (coverage 0.997) instead of 7e-5 (coverage 1.0)
    max_step: float | None = None
    max_turn: float | None = None
    # allowed smoothed overlap: what a face contact pressed in by ``coll_depth`` costs (at
    # least ``coll_area``, m²); a fixed 2e-5 m² was below touching for pushers ≥ 2 cm, so
    # H_coll and H_PoC fought and SNOPT stopped with both violated by ~1 mm
    coll_area: float = 2e-5
    coll_depth: float = 0.0005
    # m² of smoothed overlap allowed between the object and an obstacle (a = 500, a 12 cm
    # box beside a wall: 8.5e-6 at 1 cm, 6e-8 at 2 cm, so ~1.3 cm of clearance)
    obstacle_overlap: float = 1e-6
    reach_clearance: float = 0.01  # m between pusher and object outside push steps
    # and at least −swept_tolerance (m) along each free move (SweptClearance, samples per
    # move): on 5 + 5 benchmark scenes 7 plans moved the pusher through the object between
    # two clear states (6 mm to 15 cm deep), and pybullet dragged the object along
    swept_samples: int = 7
    swept_tolerance: float = 0.002
    goal_tol: float = 0.003  # share of the object's area allowed outside the goal
    # plan into the region shrunk by this much (m), at most a third of the room the object
    # has when aligned (region inradius − half its longer side), so tight fits stay feasible
    goal_inset: float = 0.02
    accel_weight: float = 1.0  # larger weights kept SNOPT from certifying optimality
    contact_accel_weight: float = 0.1
    solver: str = "snopt"
    # hand SNOPT the per-step sparsity of the stepwise constraints. Off for free pushers: on
    # bench_box_003 (seed 0) push@0,push@1 the kinematic stage went from feasible (coverage
    # 0.998) to infeasible; on for arms (ARM_PROGRAM_SETTINGS), where the dense rows over
    # every joint made one kinematic stage 30 s instead of 11 s
    sparse_jacobians: bool = False
    optimality_tol: float = 2e-3
    feasibility_tol: float = 1e-4
    # SNOPT major iterations of the learned stage (it starts from the kinematic plan and keeps
    # it when it ends worse; 100 took 40–260 s a program and rarely beat 50; against 50, 30
    # gave the same plan on 9 of 10 bench scenes (seed 1) in 14 % less time; half of the
    # learned stages of the 20 + 20 benchmark ended at the limit and kept their start, 38 %
    # of all planning time). 15 gave the same coverage on 9 of those 10 scenes and a better
    # one on the tenth in 7.5 % less time, but on the first 10 + 10 scenes of the official
    # benchmark (seed 0) it was worse on 7 and better on 3 (L median 0.86 → 0.48) in the
    # same total time: kept at 30
    iterations: int = 30
    # SNOPT's limit on minor (QP) iterations over a whole solve: this many per constraint
    # row, at least SNOPT's default 10,000 (so programs of up to two free pushes, ≤ 666
    # rows, keep the default). The default ended the kinematic stage of a 60-step chained
    # push (1,781 rows; three objects pushed north) at violation 0.17 ("info 31"), 15,000 at
    # 0.14, 20,000 converged (info 1, 3.8e-5) in 10 s. Raising it for two-push programs
    # too (20,000) was no better on the first 5 + 5 official benchmark scenes (seed 0):
    # worse on 2, better on 1, 7 the same, plan time median 77 -> 104 s
    minor_iterations_per_row: int = 12
    quad_coarse: float = QUADRATURE_COARSE  # H_F quadrature (see phase_quadrature)
    # warm start: first solve the kinematic program (sticking contact, pushing direction,
    # no H_F: milliseconds per iteration) and start the learned program from its solution
    warm_start: bool = True
    warm_iterations: int = 300
    # a kinematic solve that ends above this violation (but usable, ≤ WARM_USABLE) is solved
    # again from where it ended (a fresh quasi-Newton model): SNOPT's "infeasibilities
    # minimized" (info 13) at 5e-3 went to 6e-6 in 0.7 s on tests/data/box_push_near.yaml;
    # from violations of 0.1–6.7 (5 of 25 bench candidates, seed 1) it never helped
    warm_restart_above: float = 1e-3
    warm_restarts: int = 1
    warm_max_step: float = 0.03  # m per push step and axis for the pusher (data: ≤ 2.9 cm)
    # rad per push step: sticking alone let the object spin about the pusher, its centre
    # sweeping faster than any push moves it
    warm_max_turn: float = 0.2
    object_motion_weight: float = 1.0  # kinematic stage: Σ|Δq_obj|² (yaw in turn_length m)
    turn_length: float = 0.3  # turning 1 rad costs like 0.3 m of travel
    # cost per cm² of the push's lever arm about the centroid (PushLever), both stages: an
    # off-centre push on a long face turned the box in pybullet, not in the plan
    lever_weight: float = 0.01
    # m between H_PoC's contact point and every convex corner of the object in push steps
    # (CornerClearance; at most a third of the shorter adjacent face), both stages; 0: off.
    # Off by default: 0.015 on 5 + 5 benchmark scenes (seed 1) won 3, lost 3, tied 4
    # (medians box 0.96 / 1.0, L 0.93 / 0.66), on the first 9 scenes of the official
    # benchmark (seed 0) won 1 and lost 4, and on
    # obstacle_push it removed the only plans of 2 or 3 pushes (corner pushes along the
    # diagonal route, which executed at coverage 0)
    corner_clearance: float = 0.0
    # quasi-static sticking pushes (QuasiStaticPush) with this pusher–object friction,
    # well inside pybullet's 0.5 × 0.3 = 0.15 (8.5°): the object arrives a few degrees off
    # the plan, and a push at the plan's cone edge then slides; ≤ 0 leaves the object's
    # motion free apart from sticking (two_arm_handover: 0.67 with 0.12, 1.0 with 0.08, 0.05
    # infeasible)
    push_friction: float = 0.08
    cone_in_learned: bool = True  # keep the friction cone in the learned stage too
    # and the limit surface's turning law (c² Δθ = r × Δc): the learned models predict
    # 9–16 % of the turning pybullet produces (`eval push --pose-fit`), the law (given the
    # true translation) 48–62 % with correlation 0.64–0.90. On 5 + 5 benchmark scenes
    # (seed 0, one worker, 100 s budget) with SweptClearance: box / L medians 0.985 / 1.0
    # (mean 0.70), against 0.872 / 0.464 (mean 0.52) with neither
    turn_in_learned: bool = True


DEFAULT_SETTINGS = ProgramSettings()  # the free pushers' settings
