"""The facade: plan() without a simulator, of a task or of a scene (classified first), from
a scene at observed poses and from an earlier plan; execute() and write_playback() on its
result."""

import numpy as np
import pytest

import robotplan
from robotplan import load_scene
from tests.conftest import TASKS


@pytest.fixture(scope="module")
def box_plan():
    task = robotplan.load_task(TASKS / "box_push.yaml")
    return task.scene, robotplan.plan(task, skeleton="push@0", workers=1, progress=False,
                                      quiet=True)


def test_plan_needs_no_simulator_and_execute_runs_it(box_plan, tmp_path):
    scene, planned = box_plan
    assert isinstance(planned, robotplan.PushPlan)
    assert planned.task == robotplan.make_task(scene) and planned.scene is scene
    assert planned.obj == "box"
    assert planned.best is not None and planned.solved
    summary = planned.summary()
    assert summary["plan_status"] == "solved" and summary["skeleton"][0]["mode"] == "reach"
    executed = robotplan.execute(planned, mode="open_loop")
    assert executed.mode == "open_loop" and not executed.replans
    assert executed.times.shape == (len(planned.best.q_pusher),)
    assert 0.0 <= executed.coverage <= 1.0
    robotplan.write_playback(planned, executed, tmp_path / "playback.html")
    assert (tmp_path / "playback.html").stat().st_size > 10_000


def test_a_scene_at_observed_poses_and_a_warm_start(box_plan):
    scene, planned = box_plan
    x, y, yaw = scene.objects[0].pose
    observed = scene.with_state({"box": (x + 0.01, y - 0.01, yaw + 0.02)})
    assert observed.bodies["box"].pose == pytest.approx((x + 0.01, y - 0.01, yaw + 0.02))
    assert scene.bodies["box"].pose == pytest.approx((x, y, yaw))  # the original stays
    with pytest.raises(KeyError, match="no body"):
        scene.with_state({"nothing": (0, 0, 0)})
    again = robotplan.plan(observed, warm_start=planned, workers=1, max_pushes=1,
                           progress=False, quiet=True)  # a scene: classified first
    assert again.task == planned.task.at(observed) and again.scene is observed
    first = again.candidates[0]
    assert first.skeleton == planned.best.skeleton  # the old skeleton, tried first
    # the kinematic stage repairs the earlier plan re-anchored at the observed start
    assert first.status and "kinematic stage infeasible" not in first.status
    assert np.allclose(first.q_obj[0], observed.bodies["box"].pose)
    assert again.best is not None


def test_solve_records_the_mode_every_replan_and_both_executions(tmp_path):
    import json

    scene = load_scene(TASKS / "box_push.yaml")
    doc = robotplan.solve(scene, tmp_path, skeleton="push@0", workers=1, progress=False,
                          quiet=True, compare_open_loop=True, loop={"max_replans": 8})
    saved = json.loads((tmp_path / "result.json").read_text())
    assert saved["execution"]["mode"] == "closed_loop" == doc["execution"]["mode"]
    assert saved["execution"]["loop_settings"] == {"max_replans": 8}  # the user's, recorded
    assert isinstance(saved["execution"]["replans"], list)
    for r in saved["execution"]["replans"]:
        assert {"time", "step", "reason", "solved", "adopted", "violation", "seconds",
                "skeleton", "timings"} <= set(r)
        assert r["adopted"] or not r["solved"]  # a solved re-plan is always taken
        # a solver ran: its stages' seconds are there (none where a start was taken as it is)
        if r["timings"] is not None:
            assert sum(r["timings"].values()) > 0
    executed = saved["executed"]
    assert len(executed["t"]) == len(executed["objects"]["box"]) == len(executed["pusher"])
    assert len(saved["trajectory"]["t"]) == len(saved["trajectory"]["objects"]["box"])
    adopted = sum(r["solved"] for r in saved["execution"]["replans"])
    assert len(saved["replanned"]) == adopted
    assert 0.0 <= saved["open_loop"]["coverage"] <= 1.0
    # the open loop ran the plan rehearsed in F_q (box_push plans with it by default)
    rehearsal = saved["rehearsal"]
    assert len(rehearsal["t"]) == len(rehearsal["pusher"]) == len(rehearsal["object"])
    assert rehearsal["seconds"] <= saved["plan_seconds"]
    assert (tmp_path / "playback.html").exists()
