"""Rehearsal: a plan run closed loop in F_q, with the real planner re-planning, then its
pusher's states open loop in real pybullet physics."""

from pathlib import Path

import numpy as np
import pytest

import robotplan
from robotplan import load_scene
from robotplan.base.resources import learned_dir
from robotplan.pushing.api.playback import playback_layers
from robotplan.pushing.api.push import PushPlanner
from robotplan.pushing.bench.push_scenes import draw_scene
from robotplan.pushing.execution.execute import plan_substeps, run_open_loop
from robotplan.pushing.execution.imagined_world import ImaginedWorld
from robotplan.pushing.execution.rehearsal import rehearsable, rehearsal_world, rehearse
from robotplan.pushing.models.loading import load_dynamics
from robotplan.scene.loader import parse_scene
from robotplan.scene.task import PushTask, load_task, make_task
from tests.conftest import TASKS
from tests.pushing.search.test_pose_pushes import BOX, scene_doc


@pytest.fixture(scope="module")
def fq():
    return load_dynamics(learned_dir("push_rigid"))


@pytest.fixture(scope="module")
def box_plan(fq):
    scene = load_scene(TASKS / "box_push.yaml")
    return robotplan.plan(scene, learned_dir("push_rigid"), skeleton="push@0", workers=1,
                          progress=False, quiet=True)


def _nothing_plans(observed, tail, fresh, last_resort=None, deadline=None):
    assert isinstance(observed, PushTask) and observed.obj == "box"
    return robotplan.PushPlan(observed, None, False)


def test_only_one_pusher_one_object_no_obstacles_and_a_region_goal_are_rehearsed():
    kinds = {name: rehearsable(load_task(TASKS / f"{name}.yaml"))
             for name in ("box_push", "lshape_push", "three_objects", "obstacle_push",
                          "two_arm_left_only")}
    assert kinds == {"box_push": True, "lshape_push": True, "three_objects": False,
                     "obstacle_push": False, "two_arm_left_only": False}
    posed = make_task(parse_scene(scene_doc(BOX, [0.1, 0.05, 0.8])))
    assert posed.goal == "pose" and posed.single and not rehearsable(posed)


def test_boxes_and_l_shapes_rehearse_in_the_object_frame_f_q_other_footprints_in_their_own():
    own = learned_dir("push_rigid")
    for name in ("box_push", "lshape_push"):
        world = rehearsal_world(load_task(TASKS / f"{name}.yaml"), own)
        assert world.name == "push_rigid_object"
    doc = draw_scene(0, 0, "ood")
    unseen = make_task(parse_scene(doc, "ood.yaml"))
    assert unseen.scene.bodies[unseen.obj].shape.type == "polygon"
    assert rehearsal_world(unseen, own) == own
    assert rehearsal_world(unseen, own, "elsewhere") == Path("elsewhere")


def test_without_re_plans_a_rehearsal_is_the_plan_run_in_f_q(box_plan, fq):
    task, sol = box_plan.task, box_plan.best
    r = rehearse(task, sol, _nothing_plans, fq)
    assert np.array_equal(r.pusher, sol.q_pusher[:, :2])
    assert r.substeps == plan_substeps(task, sol)
    with ImaginedWorld(task, fq) as world:
        poses = [world.observe().poses["box"]]
        for t, n in enumerate(r.substeps):
            world.run_step({"pusher": sol.q_pusher[t]}, {"pusher": sol.q_pusher[t + 1]}, n)
            poses.append(world.observe().poses["box"])
    assert np.array_equal(r.object_poses, np.array(poses))
    assert r.times()[-1] == pytest.approx(sum(r.substeps) / 240)
    entry = r.summary()
    assert entry["replans"] == len(r.replans) and len(entry["pusher"]) == len(entry["t"])


def test_past_its_budget_a_rehearsal_asks_for_no_re_plan(box_plan, fq):
    x, y, yaw = box_plan.scene.bodies["box"].pose
    moved = box_plan.task.at(box_plan.scene.with_state({"box": (x, y - 0.06, yaw + 0.3)}))
    asked = []

    def replan(*args):
        asked.append(args)
        return _nothing_plans(*args)

    r = rehearse(moved, box_plan.best, replan, fq, budget=0.0)
    assert not asked and r.replans and not any(rp.adopted for rp in r.replans)
    assert np.array_equal(r.pusher, box_plan.best.q_pusher[:, :2])
    assert rehearse(moved, box_plan.best, replan, fq).replans and asked


def test_a_rehearsal_re_plans_where_f_q_leaves_the_plan_and_its_open_loop_ends_in_the_goal(
        box_plan, fq):
    """The box sits 6 cm and 17° from where the plan expects it. Run as it is, the plan
    pushes past it; rehearsed in F_q (re-planning through the real planner), the pusher's
    states take it to the goal, in F_q and open loop in pybullet."""
    x, y, yaw = box_plan.scene.bodies["box"].pose
    moved = box_plan.task.at(box_plan.scene.with_state({"box": (x, y - 0.06, yaw + 0.3)}))
    plain = robotplan.execute(box_plan, moved.scene, mode="open_loop")
    assert plain.coverage < 0.5
    r = rehearse(moved, box_plan.best, PushPlanner().replanner(box_plan), fq)
    assert any(rp.adopted for rp in r.replans) and r.coverage >= 0.95
    ex = run_open_loop(moved, {"pusher": r.pusher}, r.substeps)
    assert ex.coverage >= 0.9


def test_plan_rehearses_only_when_asked_and_the_open_loop_runs_the_rehearsal(box_plan, tmp_path):
    assert box_plan.rehearsal is None and box_plan.summary()["rehearsal"] is None
    scene = box_plan.scene
    planned = robotplan.plan(scene, learned_dir("push_rigid"), skeleton="push@0", workers=1,
                             progress=False, quiet=True, rehearse_plan=True)
    r = planned.rehearsal
    assert r is not None and planned.seconds >= r.seconds
    assert planned.summary()["rehearsal"]["model_coverage"] == r.coverage
    assert Path(r.model).name == "push_rigid_object"  # a box: the object-frame F_q
    ex = robotplan.execute(planned, mode="open_loop")
    assert len(ex.pusher_positions) == len(r.pusher)
    assert np.abs(ex.pusher_positions[-1] - r.pusher[-1]).max() < 0.01
    layers = playback_layers(planned, ex)
    assert [layer.name for layer in layers] == ["rehearsal", "executed"]
    assert np.array_equal(layers[0].tracks["box"], r.object_poses)
    robotplan.write_playback(planned, ex, tmp_path / "playback.html")
    assert (tmp_path / "playback.html").stat().st_size > 10_000
    flow = robotplan.plan(scene, learned_dir("push_flow"), skeleton="push@0", workers=1,
                          progress=False, quiet=True, rehearse_plan=True)
    assert flow.rehearsal is None  # F_flow plans are not rehearsed
    with pytest.raises(ValueError, match="not an F_q"):
        robotplan.plan(scene, rehearse_plan=True, rehearsal_model=learned_dir("push_flow"))
