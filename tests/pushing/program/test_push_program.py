"""The Drake program of a skeleton: variables, the start fixed, constraints evaluable with
exact gradients at the initial guess (the solve itself is exercised by the planner tests)."""

from dataclasses import replace

import numpy as np
import pytest
import torch
from pydrake.autodiffutils import ExtractGradient, ExtractValue, InitializeAutoDiff

from robotplan.functionals.collision import crossing_depth
from robotplan.pushing.models.dynamics import DynamicsSpec, PushDynamics
from robotplan.pushing.models.rigid import RigidMotion
from robotplan.pushing.program.push_program import PushProgram
from robotplan.pushing.program.rows_push import swept_shortfall
from robotplan.pushing.program.settings import ProgramSettings
from robotplan.pushing.program.skeleton import load_skeleton_space, parse_skeleton
from robotplan.scene.task import load_task
from tests.conftest import DATA, TASKS

TINY = {"channels": (2, 2, 2), "sdf_features": 8, "point_features": 8, "hidden": (16, 16)}


def build(text="push@2", kinematic=False, scene_file=TASKS / "box_push.yaml", rigid=False,
          **settings):
    torch.manual_seed(0)
    task = load_task(scene_file)
    space = replace(load_skeleton_space(), init_frame="table")  # init 2: west of the box
    model = None if kinematic else PushDynamics(DynamicsSpec(**TINY)).double()  # float64
    if rigid:
        model = RigidMotion(DynamicsSpec(kind="rigid", encoder="joint", **TINY)).double()
    # a row's constant ROW.NAME is given as ROW__NAME
    values = {name.replace("__", "."): value for name, value in settings.items()}
    return PushProgram(task, parse_skeleton(text, "pusher", "box"), model, space,
                       ProgramSettings().with_values(values))


def test_program_shape_and_initial_guess():
    prog = build()
    assert prog.N == 20 and prog.variables.q_obj.shape == (21, 3)
    assert prog.variables.q_actor.shape == (21, 2)
    assert prog.variables.contact.shape == (10, 2) and list(prog.push_steps) == list(range(11, 21))
    g = prog.guess
    assert np.allclose(g["q_obj"][0], prog.obj.pose)
    assert np.allclose(g["q_pusher"][0], prog.pusher.pose[:2])
    # the reach phase ends at init point 2 (180° in the table frame): west of the object
    assert g["q_pusher"][10, 0] < prog.obj.pose[0] - prog.obj.shape.bound_radius
    names = {b.evaluator().get_description() for b in prog.prog.GetAllConstraints()}
    assert {"H_coll", "H_PoC", "goal", "swept"} <= names and "H_F" not in names
    assert "H_F" in {b.evaluator().get_description() for b in prog.prog.GetAllCosts()}
    # the pusher pushes in contact with the box (φ_box = radius − 1 mm)
    X = torch.tensor(g["q_obj"][20])
    gap = prog.obj.sdf(torch.tensor(g["q_pusher"][20])[None], X).item()
    assert abs(gap - (prog.pusher.shape.radius - 0.001)) < 1e-6


def test_learned_program_keeps_the_quasi_static_rows_asked_for():
    def cone_rows(**settings) -> int:
        """The friction cone's rows per push step (10 push steps)."""
        return sum(b.evaluator().num_constraints()
                   for b in build(**settings).prog.GetAllConstraints()
                   if b.evaluator().get_description() == "friction_cone") // 10

    # the default: the cone and the limit surface's turning law in the learned stage too
    assert cone_rows() == 3
    assert cone_rows(friction_cone__turn=False) == 2  # the cone's two edges alone
    assert cone_rows(friction_cone__active=False) == 0
    assert cone_rows(quasi_static__friction=0.0) == 0


def test_the_ablations_leave_out_h_coll_or_h_poc_in_both_stages():
    """The paper's Fig. 11: without H_coll (and the swept clearance), without H_PoC."""
    for kinematic in (False, True):
        def constraints(kinematic=kinematic, **settings):
            prog = build(kinematic=kinematic, **settings).prog
            return {b.evaluator().get_description() for b in prog.GetAllConstraints()}

        full = constraints()
        assert {"H_coll", "swept", "H_PoC"} <= full
        assert constraints(with_collision=False) == full - {"H_coll", "swept"}
        assert constraints(with_contact=False) == full - {"H_PoC"}


def test_kinematic_program_replaces_h_f_by_sticking_contact():
    prog = build(kinematic=True, scene_file=DATA / "box_push_near.yaml")
    names = {b.evaluator().get_description() for b in prog.prog.GetAllConstraints()}
    assert {"H_coll", "H_PoC", "goal", "sticking", "pushing"} <= names
    costs = {b.evaluator().get_description() for b in prog.prog.GetAllCosts()}
    assert "H_F" not in costs and "lever" in costs
    sol = prog.solve()  # milliseconds per iteration: solve it for real
    assert sol.violation < 1e-3, sol.violations
    n = prog.settings.row("step_limits").step
    push = prog.push_steps
    assert np.abs(sol.q_pusher[push] - sol.q_pusher[push - 1]).max() <= n + 1e-6
    # the contact point keeps its place on the box between consecutive push steps
    c, s_ = np.cos(sol.q_obj[push, 2]), np.sin(sol.q_obj[push, 2])
    d = sol.contact - sol.q_obj[push, :2]
    local = np.stack((c * d[:, 0] + s_ * d[:, 1], -s_ * d[:, 0] + c * d[:, 1]), -1)
    assert np.abs(np.diff(local, axis=0)).max() < 1e-4
    # and reach steps keep their distance: the pusher never brushes the box on the way
    gaps = prog.obj.sdf(torch.from_numpy(sol.q_pusher[1:])[:, None], torch.from_numpy(
        sol.q_obj[1:]))[:, 0].numpy() - prog.pusher.shape.radius
    reach = np.setdiff1d(np.arange(1, prog.N + 1), push)
    assert gaps[reach - 1].min() > 0.003


def test_the_initial_guess_moves_at_most_guess_speed():
    prog = build()
    d = np.abs(np.diff(prog.guess["q_pusher"], axis=0))
    assert d.max() <= prog.settings.guess_speed + 1e-12


@pytest.mark.parametrize("weight,rigid", [(0.01, False), (0.0, False), (None, False),
                                          (0.01, True), (0.0, True)],
                         ids=["H_F-cost", "H_F-constraint", "kinematic", "H_q-cost",
                              "H_q-constraint"])
def test_constraint_gradients_match_finite_differences(weight, rigid):
    prog = (build(kinematic=True) if weight is None
            else build(H_F__weight=weight, rigid=rigid))
    guess = prog.guess
    values = {}
    v_ = prog.variables
    for v, x in ((v_.q_obj, guess["q_obj"]), (v_.q_actor, guess["q_pusher"]),
                 (v_.contact, guess["p"])):
        for var, val in zip(v.ravel(), x.ravel(), strict=True):
            values[var.get_id()] = val
    rng = np.random.default_rng(0)
    for b in list(prog.prog.GetAllConstraints()) + list(prog.prog.GetAllCosts()):
        name = b.evaluator().get_description()
        if name not in {"H_F", "H_coll", "H_PoC", "goal", "sticking", "pushing", "lever"}:
            continue
        x = np.array([values[v.get_id()] for v in b.variables()])
        x = x + rng.normal(0, 1e-3, x.shape)  # off the symmetric guess
        ad = b.evaluator().Eval(InitializeAutoDiff(x))
        J = ExtractGradient(ad)
        f0 = ExtractValue(ad).ravel()
        assert np.allclose(f0, b.evaluator().Eval(x), rtol=1e-6, atol=1e-9), name
        cols = rng.choice(len(x), min(6, len(x)), replace=False)
        for c in cols:
            e = np.zeros_like(x)
            e[c] = 1e-6
            fd = (b.evaluator().Eval(x + e) - b.evaluator().Eval(x - e)) / 2e-6
            scale = max(np.abs(fd).max(), np.abs(J[:, c]).max(), 1e-8)
            assert np.abs(fd - J[:, c]).max() / scale < 2e-2, (name, c)


def test_solve_skeleton_stops_where_the_kinematics_cannot_push():
    """box_push's goal is 0.36 m away; at 1 cm per push step one push covers 0.1 m, so the
    kinematic stage fails (after 30 major iterations: no number of them can reach the goal)
    and the learned program is never started."""
    from robotplan.pushing.program.solution import FEASIBLE
    from robotplan.pushing.program.solve import solve_skeleton

    torch.manual_seed(0)
    task = load_task(TASKS / "box_push.yaml")
    model = PushDynamics(DynamicsSpec(**TINY))
    sol = solve_skeleton(task, parse_skeleton("push@2", "pusher", "box"), model,
                         replace(load_skeleton_space(), init_frame="table"),
                         ProgramSettings(warm_iterations=30, warm_restarts=0).with_values(
                             {"step_limits.step": 0.01, "turn_limits.turn": 0.02}))
    assert sol.violation > FEASIBLE and "kinematic stage infeasible" in sol.status
    assert "H_F" not in sol.timings and sol.dynamics_mm2.size == 0


def test_learned_program_never_ends_worse_than_its_warm_start():
    from robotplan.pushing.program.solution import rank

    kin = build(kinematic=True, scene_file=DATA / "box_push_near.yaml")
    warm = kin.solve()
    torch.manual_seed(0)
    learned = PushProgram(kin.task, kin.skeleton, PushDynamics(DynamicsSpec(**TINY)),
                          kin.space, ProgramSettings(iterations=3), guess=kin.as_guess(warm))
    assert learned.keep_start and not kin.keep_start
    sol = learned.solve()
    start = learned.prog.GetInitialGuess(learned.prog.decision_variables())  # set by solve
    assert np.isfinite(start).all()
    assert rank(sol.violations, sol.cost) <= rank(*learned.evaluate(start))
    assert sol.q_obj.shape == (learned.N + 1, 3) and sol.contact.shape == (10, 2)


def test_a_start_the_learned_rows_accept_is_kept_without_a_learned_solve():
    """``start_solution`` measures the guess by the program's own rows; with
    ``accept_good_start`` a re-plan whose guess meets every row within ``good_rms_mm``
    returns it without a solver, one that meets them once the kinematic program repaired
    it returns the repair, and one beyond ``good_rms_mm`` goes on to the learned solve."""
    from robotplan.pushing.program.solution import FEASIBLE
    from robotplan.pushing.program.solve import solve_skeleton

    kin = build(kinematic=True, scene_file=DATA / "box_push_near.yaml")
    warm = kin.solve()
    assert warm.violation <= FEASIBLE
    torch.manual_seed(0)
    model = PushDynamics(DynamicsSpec(**TINY))
    learned = PushProgram(kin.task, kin.skeleton, model, kin.space, ProgramSettings(),
                          guess=kin.as_guess(warm))
    start = learned.start_solution()
    x = learned.prog.GetInitialGuess(learned.prog.decision_variables())
    violations, cost = learned.evaluate(x)
    assert start.violations == violations and start.cost == cost
    assert np.array_equal(start.q_obj, warm.q_obj) and start.dynamics_mm2.size == learned.N
    assert start.violation == max(violations.values())

    def replan(good_rms_mm: float, guess: dict | None = None):
        settings = ProgramSettings(iterations=3, accept_good_start=True,
                                   good_rms_mm=good_rms_mm)
        torch.manual_seed(0)
        return solve_skeleton(kin.task, kin.skeleton, model, kin.space, settings,
                              guess=guess or kin.as_guess(warm))

    kept = replan(good_rms_mm=1e6)
    assert kept.status.startswith("learned stage not run") and kept.success
    assert np.array_equal(kept.q_obj, warm.q_obj) and not kept.timings  # no solver ran
    off = kin.as_guess(warm)
    off["p"] = off["p"] + np.array([0.004, 0.0])  # contact points off the surfaces
    repaired = replan(good_rms_mm=1e6, guess=off)
    assert repaired.status.startswith("learned stage not run") and repaired.success
    assert "warm_start" in repaired.timings and "H_F" not in repaired.timings  # the repair's
    solved = replan(good_rms_mm=start.dynamics_rms_mm / 2)
    assert not solved.status.startswith("learned stage not run")
    assert solved.timings.get("H_F", 0.0) > 0.0


def test_a_start_far_from_the_constraints_is_kept_without_a_learned_solve():
    """With ``learned_start_violation`` a re-plan whose start misses the constraints by
    more than it is returned as it is (not solved); without it the learned stage runs."""
    from robotplan.pushing.program.solve import solve_skeleton

    kin = build(kinematic=True, scene_file=DATA / "box_push_near.yaml")
    warm = kin.solve()
    guess = kin.as_guess(warm)
    guess["p"] = guess["p"] + np.array([0.05, 0.0])  # contact points 5 cm off the object
    model = PushDynamics(DynamicsSpec(**TINY))

    def replan(bound: float | None):
        settings = ProgramSettings(iterations=3, warm_from_guess=False,
                                   learned_start_violation=bound)
        torch.manual_seed(0)
        return solve_skeleton(kin.task, kin.skeleton, model, kin.space, settings,
                              guess=guess)

    kept = replan(0.02)
    assert kept.violation > 0.02 and not kept.success
    assert kept.status.startswith("learned stage not run: its start misses")
    assert "H_F" not in kept.timings
    assert np.array_equal(kept.contact, guess["p"])
    ran = replan(None)
    assert ran.timings.get("H_F", 0.0) > 0.0
    assert not ran.status.startswith("learned stage not run")
    assert ran.violation <= kept.violation  # the learned solve never ends worse than its start


def test_arm_touch_program_ends_in_contact_and_hands_its_touch_point_on():
    """The touch goal's last state is a contact (H_coll allows touching there, not the
    reach clearance that contradicted H_touch), the kinematic stage of left-push,
    right-touch solves, and its contact point goes into the next stage's guess.

    SNOPT's path depends on the arithmetic: where the libraries choose kernels per CPU the
    touch from init 0 solves on some CPUs and init 1 on others (the skeleton search tries
    both; docs/experiments.md#cpu-arithmetic), so the first of the two that solves is
    checked."""
    from robotplan.pushing.program.skeleton import space_for

    task = load_task(TASKS / "two_arm_touch.yaml")
    scene, space = task.scene, space_for(task)
    for init in (0, 1):
        skeleton = parse_skeleton(f"left:push@2,right:touch@{init}", "left", "box")
        prog = PushProgram(task, skeleton, None, space)
        sol = prog.solve()
        if sol.violation < 1e-2:
            break
    assert sol.violation < 1e-2, sol.violations
    tip = prog.kin["right"].tip(sol.q_joints["right"][-1])
    gap = float(scene.bodies["box"].sdf(torch.tensor(tip[None, :2]),
                                        torch.tensor(sol.q_obj[-1]))[0])
    assert abs(gap - 0.03) < 0.005  # the tip's rim on the box (tip radius 3 cm)
    guess = prog.as_guess(sol)
    assert np.allclose(guess["p_touch"], sol.touch_point)


def _at_guess(prog: PushProgram) -> np.ndarray:
    x = np.zeros(prog.prog.num_vars())
    for V, value in prog._guess_pairs():
        x[prog.prog.FindDecisionVariableIndices(V.ravel())] = value.ravel()
    return x


def test_a_free_move_through_the_object_is_seen_by_the_dense_check():
    """The plan's free moves are checked again at 1 cm: a reach step from one side of the
    box to the other crosses it deeper than ``swept_check_depth`` by the box's half height
    plus the pusher's radius less that depth (in the row's units, ×100); a move grazing the
    box 5 mm deep, and the guess's own reach, not at all; no check without
    ``swept_check_spacing``."""
    prog = build(kinematic=True)
    q_obj, q_pusher = prog.guess["q_obj"].copy(), prog.guess["q_pusher"].copy()
    assert swept_shortfall(prog, q_obj, q_pusher) == 0.0
    x, y, _yaw = prog.obj.pose
    q_pusher[4], q_pusher[5] = (x - 0.3, y), (x + 0.3, y)
    deep = 0.06 + prog.pusher.shape.radius - prog.settings.row("swept").check_depth
    assert swept_shortfall(prog, q_obj, q_pusher) == pytest.approx(100 * deep, rel=0.05)
    grazing = q_pusher.copy()  # along the box's long face, in its frame B
    x_obj, y_obj, yaw = q_obj[5]
    R_WB = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    graze_B = prog.obj.shape.size[1] / 2 + prog.pusher.shape.radius - 0.005
    for t, along in ((4, -0.3), (5, 0.3)):
        grazing[t] = (x_obj, y_obj) + R_WB @ (along, graze_B)
    assert swept_shortfall(prog, q_obj, grazing) == 0.0
    x_guess = _at_guess(prog)
    actor = prog.prog.FindDecisionVariableIndices(prog.variables.q_actor.ravel())
    x_guess[actor] = q_pusher.ravel()
    worst, _ = prog.evaluate(x_guess)
    assert worst["swept"] >= swept_shortfall(prog, q_obj, q_pusher)
    unchecked = build(kinematic=True, swept__check_spacing=None)
    assert swept_shortfall(unchecked, q_obj, q_pusher) == 0.0


def _rotation(yaw: float) -> np.ndarray:
    return np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])


def test_a_push_step_hopping_through_the_object_is_seen_by_the_dense_check():
    """Push steps are checked as the object sees them (the pusher's start carried by the
    object's step): the guess's pushes, which keep their contact, are clear; a step that
    hops to the opposite face through the centre crosses the box by its half width plus the
    pusher's radius (scaled ×100 beyond ``push_check_depth``); a contact that keeps its
    place while the box turns a quarter under it is clear, though its straight move in the
    table frame cuts through the box."""
    prog = build(kinematic=True)
    q_obj, q_pusher = prog.guess["q_obj"].copy(), prog.guess["q_pusher"].copy()
    assert swept_shortfall(prog, q_obj, q_pusher) == 0.0
    t = int(prog.push_steps[len(prog.push_steps) // 2])
    centre, yaw = q_obj[t, :2], q_obj[t, 2]
    hop = q_pusher.copy()
    hop[t] = centre - (q_pusher[t] - centre)
    s = prog.settings
    deep = min(prog.obj.shape.size) / 2 + prog.pusher.shape.radius - s.row("swept").push_check_depth
    assert swept_shortfall(prog, q_obj, hop) >= 100 * deep * 0.95

    turned_obj, carried = q_obj.copy(), q_pusher.copy()
    turned_obj[t:, 2] += np.pi / 2
    contact_B = _rotation(yaw).T @ (q_pusher[t - 1] - q_obj[t - 1, :2])
    carried[t:] = centre + (_rotation(yaw + np.pi / 2) @ contact_B)
    assert swept_shortfall(prog, turned_obj, carried) == 0.0
    in_table_frame = crossing_depth(
        prog.obj, prog.pusher, torch.from_numpy(turned_obj[t:t + 1]),
        torch.from_numpy(carried[t - 1:t]), torch.from_numpy(carried[t:t + 1]), 0.01)
    assert in_table_frame > s.row("swept").push_check_depth


def test_a_pusher_that_starts_pressed_into_the_object_may_leave_it():
    """Observed 2 cm inside the box (a re-plan in a world that let it press in): the move
    out of the box from the start is held to that depth, not to ``swept.tolerance``, by the
    row and by the dense check; a later move as deep still fails the check."""
    task = load_task(TASKS / "box_push.yaml")
    box = task.scene.bodies["box"]
    x, y, yaw = box.pose
    R_WB = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    radius = task.scene.bodies["pusher"].shape.radius
    inside = np.array([x, y]) + R_WB @ (-(box.shape.size[0] / 2 + radius - 0.02), 0.0)
    task = task.at(task.scene.with_state({"pusher": tuple(inside)}))
    space = replace(load_skeleton_space(), init_frame="table")
    prog = PushProgram(task, parse_skeleton("push@2", "pusher", "box"), None, space)
    swept = prog.settings.row("swept")
    (binding,) = [b for b in prog.prog.GetAllConstraints()
                  if b.evaluator().get_description() == "swept"]
    lower = binding.evaluator().lower_bound().reshape(-1, swept.samples)
    assert lower[0] == pytest.approx(-100 * 0.02) and lower[1:] == pytest.approx(
        -100 * swept.tolerance)
    q_obj, q_pusher = prog.guess["q_obj"].copy(), prog.guess["q_pusher"].copy()
    q_pusher[1:9] = np.array([x, y]) + R_WB @ (-0.3, 0.0)  # straight out, then round
    assert swept_shortfall(prog, q_obj, q_pusher) == 0.0
    q_pusher[5] = inside  # pressed in as deep again, later
    assert swept_shortfall(prog, q_obj, q_pusher) > 0.0


def test_the_kinematic_stage_in_chunks_ends_once_its_rows_are_met():
    """``warm_chunk``: the kinematic stage's major iterations in chunks (the last one the
    rest), the learned stage's in one; solved in chunks the kinematic stage ends with its
    rows met (to FEASIBLE: this one never gets within ``warm_restart_above``, in chunks or
    in one solve)."""
    prog = build(kinematic=True, warm_chunk=40)
    assert prog._chunks() == [40] * 7 + [20]
    assert build(kinematic=True)._chunks() == [300]
    assert build(warm_chunk=40)._chunks() == [30]
    from robotplan.pushing.program.solution import FEASIBLE

    assert prog.solve().violation <= FEASIBLE
