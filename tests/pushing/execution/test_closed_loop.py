"""Closed-loop execution: re-planning from the observed scene in real pybullet physics
with the real planner, where open loop fails; its pieces one by one."""

import math
import re
import time
from dataclasses import replace

import numpy as np
import pytest

import robotplan
from robotplan import load_scene
from robotplan.execution.physics import PHYSICS, SIMULATORS
from robotplan.execution.scene_world import Observation
from robotplan.pushing.execution.closed_loop import (
    LoopSettings,
    _goal_met,
    departure,
    execute_closed_loop,
    load_loop_overlays,
    loop_settings_for,
    steer_pusher,
)
from robotplan.pushing.execution.loop_settings import parse_loop_overrides
from robotplan.pushing.execution.perturb import Perturbation
from robotplan.pushing.search.planner import meets_constraints
from robotplan.scene.schema import PoseGoal
from robotplan.scene.task import PushTask, load_task, make_task
from tests.conftest import TASKS, assert_each_refused


def test_departure_names_the_object_and_how_far_it_is_off():
    planned = {"box": np.array([0.0, 0.0, 0.0])}
    assert departure(planned, {"box": np.array([0.005, 0.0, 0.05])}, 0.01, 0.1) is None
    far = departure(planned, {"box": np.array([0.012, 0.0, 0.0])}, 0.01, 0.1)
    assert far.startswith("box 12.0 mm")
    turned = departure(planned, {"box": np.array([0.0, 0.0, 2 * math.pi - 0.2])}, 0.01, 0.1)
    assert turned is not None and "11.5°" in turned  # yaw is compared modulo 2π


def test_steering_moves_the_pusher_sideways_to_the_object_and_against_its_turn():
    """A push step along +x: the target follows the object 1 cm to the left, and moves a
    further gain × yaw error to the left for an object turned counter-clockwise too far."""
    start, target = np.array([0.0, 0.0]), np.array([0.03, 0.0])
    planned = np.array([0.1, 0.0, 0.0])
    left_1cm = np.array([0.1, 0.01, 0.0])
    assert np.allclose(steer_pusher(target, start, planned, left_1cm, 0.05, 0.03),
                       [0.03, 0.01])
    turned = np.array([0.1, 0.0, 0.2])
    assert np.allclose(steer_pusher(target, start, planned, turned, 0.05, 0.03), [0.03, 0.01])
    far = np.array([0.1, -0.2, -1.0])
    assert np.allclose(steer_pusher(target, start, planned, far, 0.05, 0.03), [0.03, -0.03])
    assert np.allclose(steer_pusher(start, start, planned, far, 0.05, 0.03), start)


def test_chains_re_plan_from_their_own_phase_end_departures(tmp_path):
    """A scene in which an object pushes another takes the ``chains`` overlay of
    skeletons/loop.yaml; a single object's keeps the defaults; a bad overlay names its file
    and field."""
    single, chain = load_task(TASKS / "box_push.yaml"), load_task(TASKS / "three_objects.yaml")
    overlay = load_loop_overlays()["chains"]
    assert loop_settings_for(single) == LoopSettings()
    chained = loop_settings_for(chain)
    assert chained != LoopSettings()
    assert all(getattr(chained, k) == v for k, v in overlay.items())
    posed = loop_settings_for(make_task(replace(single.scene,
                                                goal=PoseGoal("box", (0.3, 0.1, 0.5)))))
    assert all(getattr(posed, k) == v for k, v in load_loop_overlays()["pose"].items())
    assert posed.fresh_after_miss and not LoopSettings().fresh_after_miss
    arms = loop_settings_for(load_task(TASKS / "two_arm_handover.yaml"))
    assert chained.max_replans == arms.max_replans < posed.max_replans == LoopSettings().max_replans
    assert_each_refused(load_loop_overlays.__wrapped__, tmp_path / "loop.yaml", (
        ("chains: {no_such: 1}", "loop.yaml: chains.no_such: not a closed-loop"),
        ("pets: {}", "pets: not a scene class"),
        ("chains: {phase_drift: yes}", "chains.phase_drift: must be a float")))


def test_a_users_loop_settings_are_typed_and_win_over_the_scene_class():
    """``--loop NAME=VALUE`` items become LoopSettings fields of their own types and replace
    the scene class's overlay; a wrong name, type or form is refused naming the item."""
    items = ["last_resort_beyond_drift=on", "last_resort_violation=0.03", "max_replans=4",
             "phase_drift = 0.03"]
    overrides = parse_loop_overrides(items)
    assert overrides == {"last_resort_beyond_drift": True, "last_resort_violation": 0.03,
                         "max_replans": 4, "phase_drift": 0.03}
    assert type(overrides["max_replans"]) is int and type(overrides["phase_drift"]) is float
    chain = load_task(TASKS / "three_objects.yaml")
    settings = loop_settings_for(chain, overrides=overrides)
    assert settings.phase_drift == 0.03 != loop_settings_for(chain).phase_drift
    assert settings.phase_drift_yaw == loop_settings_for(chain).phase_drift_yaw  # the class's
    assert settings.last_resort_beyond_drift and settings.max_replans == 4
    assert parse_loop_overrides([]) == {}
    for item, says in (("no_such=1", "no_such: not a closed-loop setting"),
                       ("max_replans=2.5", "max_replans: '2.5' is not a int"),
                       ("redo_last_push=maybe", "redo_last_push: 'maybe' is not a bool"),
                       ("drift=nan", "drift: 'nan' is not a float"),
                       ("drift=-0.1", "drift: must not be negative"),
                       ("drift", "expected NAME=VALUE"), ("drift=", "expected NAME=VALUE")):
        with pytest.raises(ValueError, match=re.escape(says)):
            parse_loop_overrides([item])


def test_a_perturbed_world_is_seeded_and_within_its_spread():
    a, b = Perturbation(3), Perturbation(3)
    assert a.physics() == b.physics() and a.physics() != Perturbation(4).physics()
    ph = a.physics()
    for name in ("object_mass", "object_friction", "pusher_friction"):
        ratio = getattr(ph, name) / getattr(PHYSICS, name)
        assert 0.8 <= ratio <= 1.2 and ratio != 1.0
    seen = Observation({"box": np.zeros(3)})
    draws = np.array([a.observer()(seen).poses["box"] for _ in range(1)]
                     + [pose for f in [a.observer()] for pose in
                        (f(seen).poses["box"] for _ in range(400))])
    assert np.allclose(draws[0], draws[1])  # the same seed, the same first draw
    assert draws[:, 0].std() == pytest.approx(0.001, rel=0.2)
    assert np.degrees(draws[:, 2].std()) == pytest.approx(0.5, rel=0.2)


@pytest.fixture(scope="module")
def box_plan():
    scene = load_scene(TASKS / "box_push.yaml")
    return robotplan.plan(scene, skeleton="push@0", workers=1, progress=False, quiet=True)


def _box_moved(planned):
    """The plan's task in its scene with the box 6 cm back and turned 0.3 rad (17°) from
    where the plan expects it."""
    x, y, yaw = planned.scene.bodies["box"].pose
    return planned.task.at(planned.scene.with_state({"box": (x, y - 0.06, yaw + 0.3)}))


def _observed_box(observed) -> None:
    """A re-planner gets the plan's task in the observed scene."""
    assert isinstance(observed, PushTask)
    assert (observed.obj, observed.actors) == ("box", ("pusher",))


def _implausible_when_fresh(observed, tail, fresh, last_resort=None, deadline=None):
    """A re-planner that plans nothing from a tail alone; asked for a fresh search it returns
    a real plan from the observed scene that meets every constraint, flagged not solved (as
    one the learned dynamics call implausible)."""
    _observed_box(observed)
    if not fresh:
        return robotplan.PushPlan(observed, None, False)
    real = robotplan.plan(observed, workers=1, progress=False, quiet=True)
    assert real.best is not None and meets_constraints(real.best)
    return robotplan.PushPlan(observed, real.best, False)


@pytest.mark.parametrize("sim", list(SIMULATORS))
def test_closed_loop_recovers_a_box_that_is_not_where_it_was_planned(box_plan, sim):
    """The box is 6 cm and 17° from where the plan expects it: the plan pushes past it open
    loop; closed loop sees that after the first step and re-plans from there, in each
    simulator."""
    assert box_plan.solved
    moved = _box_moved(box_plan).scene
    open_loop = robotplan.execute(box_plan, moved, mode="open_loop", sim=sim)
    assert open_loop.coverage < 0.5 and open_loop.simulator == sim
    closed = robotplan.execute(box_plan, moved, sim=sim)
    assert closed.mode == "closed_loop" and closed.coverage >= 0.95
    first = closed.replans[0]
    assert first.step == 1 and "box" in first.reason
    assert any(r.solved for r in closed.replans)  # a re-planned tail took it there
    assert len(closed.plans) == 1 + sum(r.solved for r in closed.replans)
    assert closed.times.shape == (len(closed.object_poses),)
    assert np.all(np.diff(closed.times) > 0)


@pytest.mark.parametrize("sim", list(SIMULATORS))
def test_closed_loop_reaches_the_goal_in_a_perturbed_world(box_plan, sim):
    """Mass and frictions off by up to 20 %, observations noisy: the plan is re-planned
    from what is observed and the box still ends in the goal, in each simulator."""
    world = Perturbation(1)
    closed = robotplan.execute(box_plan, perturb=world, sim=sim)
    assert closed.coverage >= 0.95
    assert all(isinstance(v, int | float) for v in world.describe().values())


@pytest.mark.parametrize("fresh_after_miss", [True, False])
def test_a_departure_whose_tail_does_not_plan_asks_for_a_fresh_search(box_plan,
                                                                      fresh_after_miss):
    """The re-planner is asked with the plan's tail first; when that does not plan, a fresh
    search is asked at once only if ``fresh_after_miss``, and at the plan's end always."""
    calls, nothing_plans = _recording_nothing_plans()
    moved = _box_moved(box_plan)
    settings = LoopSettings(fresh_after_miss=fresh_after_miss, max_replans=3)
    ex = execute_closed_loop(moved, box_plan.best, nothing_plans, settings)
    assert calls[0] == (True, fresh_after_miss)
    assert len(ex.replans) == len(calls) <= 3
    assert not any(r.solved for r in ex.replans) and len(ex.plans) == 1


@pytest.mark.parametrize("stop_when_lost", [True, False])
def test_an_object_lost_with_no_re_plans_left_ends_the_run_only_when_asked(box_plan,
                                                                          stop_when_lost):
    """The box 6 cm off (beyond ``drift``) and the one re-plan plans nothing: with
    ``stop_when_lost`` the run ends there and says why; without it the stale plan runs to
    its end."""
    moved = _box_moved(box_plan)
    settings = LoopSettings(stop_when_lost=stop_when_lost, max_replans=1)
    ex = execute_closed_loop(moved, box_plan.best, _nothing_plans, settings)
    assert len(ex.replans) == 1 and not ex.replans[0].adopted
    planned_steps = len(box_plan.best.q_obj) - 1
    if stop_when_lost:
        assert "box" in ex.stopped and "no re-plans left" in ex.stopped
        assert len(ex.object_poses) - 1 == ex.replans[0].step < planned_steps
    else:
        assert ex.stopped is None and len(ex.object_poses) - 1 == planned_steps


def _nothing_plans(observed, tail, fresh, last_resort=None, deadline=None):
    _observed_box(observed)
    return robotplan.PushPlan(observed, None, False)


def _recording_nothing_plans():
    """A re-planner that plans nothing, and the list of how it was asked: whether with a
    tail, and whether a fresh search may follow."""
    calls: list[tuple[bool, bool]] = []

    def nothing_plans(observed, tail, fresh, last_resort=None, deadline=None):
        calls.append((tail is not None, fresh))
        return _nothing_plans(observed, tail, fresh)

    return calls, nothing_plans


@pytest.mark.slow
@pytest.mark.parametrize("sim", list(SIMULATORS))
def test_closed_loop_recovers_an_arm_push_when_the_box_is_not_where_it_was_planned(sim):
    """The left iiwa's two pushes are planned for the box where the scene puts it; the box
    stands 6 cm further back. Open loop the arm pushes air; closed loop sees that after the
    first step, re-plans the arm's joints from there (the re-plan that solves may come later,
    as the measured joints move it) and the box ends in the goal."""
    scene = load_scene(TASKS / "two_arm_left_only.yaml")
    planned = robotplan.plan(scene, skeleton="left:push@2,left:push@3", workers=2,
                             progress=False, quiet=True)
    assert planned.solved
    x, y, yaw = scene.bodies["box"].pose
    moved = scene.with_state({"box": (x, y - 0.06, yaw)})
    open_loop = robotplan.execute(planned, moved, mode="open_loop", sim=sim)
    assert open_loop.coverage < 0.5
    closed = robotplan.execute(planned, moved, sim=sim)
    assert closed.coverage >= 0.95
    assert closed.replans[0].step == 1  # it sees the box off the plan at once
    solved = [r for r in closed.replans if r.solved]
    assert solved and all("left" in r.skeleton for r in solved)
    assert set(closed.joints) == {"left", "right"}
    assert len(closed.joints["left"]) == len(closed.object_poses)


@pytest.mark.slow
def test_closed_loop_reaches_a_pose_goal_that_open_loop_misses():
    """Push-T's task on a box: moved 15 cm and turned −45°. The fitted pushes plan it;
    pybullet turns the box further than planned (open loop 0.89 on the benchmark), the
    closed loop re-plans from the observed pose and ends with at least 0.95 of the target
    footprint covered."""
    from robotplan.pushing.bench.push_scenes import draw_scene
    from robotplan.scene.loader import parse_scene

    scene = parse_scene(draw_scene(4, 0, "pose"))
    planned = robotplan.plan(scene, workers=2, progress=False, quiet=True)
    assert planned.solved
    open_loop = robotplan.execute(planned, mode="open_loop")
    closed = robotplan.execute(planned)
    assert closed.coverage >= max(0.95, open_loop.coverage)
    assert closed.replans and all(r.step > 0 for r in closed.replans)


def test_at_the_plan_end_a_pose_goal_is_met_from_pose_coverage_on():
    """The loop stops closing a pose goal once the object covers ``pose_coverage`` of its
    target footprint, at or above Push-T's success (0.95): a closing push from there can
    leave it lower as often as higher."""
    from robotplan.pushing.bench.push_scenes import draw_scene
    from robotplan.pushing.execution.execute import outcome
    from robotplan.scene.loader import parse_scene

    task = make_task(parse_scene(draw_scene(4, 0, "pose")))
    scene, obj = task.scene, task.obj
    assert task.goal == "pose" and obj == scene.goal.object
    settings = loop_settings_for(task)
    assert 0.95 <= settings.pose_coverage < 1.0
    target = np.array(scene.goal.pose)
    shifted = [target + np.array([dx, 0.0, 0.0]) for dx in np.linspace(0, 0.02, 201)]
    covered = [outcome(task, scene.bodies[obj], q, np.zeros(2), 0.0)[0] for q in shifted]
    above = next(q for q, c in zip(shifted[::-1], covered[::-1], strict=True)
                 if c >= settings.pose_coverage)
    below = next(q for q, c in zip(shifted, covered, strict=True) if c < settings.pose_coverage)
    assert _goal_met(task, Observation({obj: above}), settings)
    assert not _goal_met(task, Observation({obj: below}), settings)


@pytest.mark.parametrize("fresh_beyond_drift", [True, False])
def test_a_gross_departure_at_a_phase_end_asks_for_a_fresh_search(box_plan,
                                                                  fresh_beyond_drift):
    """The box 6 cm off (beyond ``drift``): the mid-phase re-plan asks for the tail alone;
    at the reach's end, still 6 cm off, a fresh search follows the tail at once only with
    ``fresh_beyond_drift``, and with it the bound of a last-resort plan."""
    calls = []

    def nothing_plans(observed, tail, fresh, last_resort, deadline=None):
        calls.append((len(calls), tail is not None, fresh, last_resort))
        return _nothing_plans(observed, tail, fresh)

    moved = _box_moved(box_plan)
    settings = LoopSettings(fresh_beyond_drift=fresh_beyond_drift, max_replans=2)
    execute_closed_loop(moved, box_plan.best, nothing_plans, settings)
    bound = settings.last_resort_violation if fresh_beyond_drift else None
    assert calls == [(0, True, False, None), (1, True, fresh_beyond_drift, bound)]


def test_at_the_plan_end_a_re_plan_that_meets_the_constraints_is_taken(box_plan):
    """The box 6 cm off and turned: re-plans on the way plan nothing; at the plan's end the
    re-planner returns a real plan from the observed scene that meets every constraint,
    flagged not solved (as one the learned dynamics call implausible). With
    ``adopt_feasible_at_end`` the loop goes on with it and ends nearer the goal than without,
    where it stops short."""
    moved = _box_moved(box_plan)
    runs = {}
    for adopt in (False, True):
        settings = LoopSettings(fresh_beyond_drift=False, adopt_feasible_at_end=adopt,
                                last_resort_beyond_drift=False, max_replans=5)
        ex = execute_closed_loop(moved, box_plan.best, _implausible_when_fresh,
                                 settings)
        end = [r for r in ex.replans if r.reason == "goal not met at the plan's end"]
        assert end and not any(r.solved for r in ex.replans)
        assert end[0].adopted == adopt and len(ex.plans) == 1 + sum(r.adopted
                                                                    for r in ex.replans)
        runs[adopt] = ex.coverage
    assert runs[False] < 0.9 and runs[True] > runs[False] + 0.1


@pytest.mark.parametrize("beyond_drift", [True, False])
def test_a_gross_phase_end_departure_takes_a_last_resort_plan_only_when_asked(box_plan,
                                                                             beyond_drift):
    """The box 6 cm off: at the reach's end the fresh search returns a real plan from the
    observed scene that meets the constraints, flagged not solved. The loop goes on with it
    there only with ``last_resort_beyond_drift``."""
    moved = _box_moved(box_plan)
    settings = LoopSettings(last_resort_beyond_drift=beyond_drift, max_replans=2)
    ex = execute_closed_loop(moved, box_plan.best, _implausible_when_fresh, settings)
    at_phase_end = [r for r in ex.replans if r.reason.endswith("at the end of a phase")]
    assert at_phase_end and not at_phase_end[0].solved
    assert at_phase_end[0].adopted == beyond_drift


@pytest.mark.parametrize("redo_last_push", [True, False])
def test_at_the_plan_end_the_last_push_is_redone_first_only_when_asked(box_plan,
                                                                       redo_last_push):
    """The box 6 cm off and nothing plans: at the plan's end the re-planner gets the plan's
    last push to redo (``redo_last_push``) or none, and may search afresh either way."""
    calls, nothing_plans = _recording_nothing_plans()
    moved = _box_moved(box_plan)
    settings = LoopSettings(redo_last_push=redo_last_push, max_replans=8)
    ex = execute_closed_loop(moved, box_plan.best, nothing_plans, settings)
    assert ex.replans[-1].reason == "goal not met at the plan's end"
    assert calls[-1] == (redo_last_push, True)


@pytest.mark.parametrize("deadline", [5.0, math.inf])
def test_every_re_plan_is_asked_with_the_deadline_of_the_loop_settings(box_plan, deadline):
    asked: list[tuple[float, float]] = []

    def nothing_plans(observed, tail, fresh, last_resort=None, until=None):
        asked.append((time.monotonic(), until))
        return _nothing_plans(observed, tail, fresh)

    settings = LoopSettings(replan_deadline=deadline, max_replans=2)
    ex = execute_closed_loop(_box_moved(box_plan), box_plan.best, nothing_plans, settings)
    assert ex.replans and len(asked) == len(ex.replans)
    for now, until in asked:
        assert until is None if math.isinf(deadline) else now <= until <= now + deadline
