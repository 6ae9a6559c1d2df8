"""robotplan diagnose: a plan's push steps against one-step pybullet and the learned model."""

import json

import numpy as np

from robotplan import load_scene
from robotplan.pushing.training.diagnose import check_steps, summarize, table
from robotplan.scene.task import load_task
from tests.cli.test_app import run
from tests.conftest import DATA, ROOT

FLOW = ROOT / "learned" / "push_flow"


def _straight_push_plan(scene, speed: float, turn: float) -> dict:
    """A hand-made plan: the pusher starts 1 mm into the box's west face (through its centre,
    along its long axis) and pushes east at ``speed`` m/step; the box moves with it and, the
    plan claims, turns by ``turn`` rad a step about its centre."""
    box = scene.bodies["box"]
    x0, y0, yaw = box.pose
    u = np.array([np.cos(yaw), np.sin(yaw)])
    start = np.array([x0, y0]) - u * (box.shape.size[0] / 2 + 0.03 - 0.001)
    pusher = [start + u * speed * k for k in range(6)]
    objects = [[x0 + u[0] * speed * k, y0 + u[1] * speed * k, yaw + turn * k]
               for k in range(6)]
    return {"trajectory": {"pusher": [p.tolist() for p in pusher], "objects": {"box": objects}}}


def test_physics_and_model_agree_on_a_centred_push_and_catch_a_wrong_turn():
    task = load_task(DATA / "box_push_near.yaml")
    checks = check_steps(task, _straight_push_plan(task.scene, 0.02, np.radians(5)), FLOW)
    assert len(checks) == 5  # every step in contact
    s = summarize(checks)
    phys = np.array([c.physics for c in checks])
    # the box moves forward and does not follow the plan's turn (from the planned, turned
    # states the push is off-centre the other way)
    u = np.array([np.cos(0.4), np.sin(0.4)])
    assert (phys[1:, :2] @ u).min() > 0.005
    assert np.degrees(phys[:, 2]).max() < 1.0
    # the plan's 5° a step is caught; the model, like physics, turns the box far less
    assert s["plan_vs_physics"]["turn_deg"] > 3.0
    assert s["model_vs_physics"]["turn_deg"] < 2.0
    assert s["model_vs_physics"]["translation_mm"] < 10.0
    assert len(table(checks).splitlines()) == len(checks) + 1


def test_cli_diagnose(tmp_path):
    scene_file = DATA / "box_push_near.yaml"
    res = run("diagnose", str(tmp_path), str(scene_file))
    assert res.returncode == 2 and res.stderr.count("\n") == 1 and "result.json" in res.stderr
    plan = _straight_push_plan(load_scene(scene_file), 0.02, 0.0)
    (tmp_path / "result.json").write_text(json.dumps(plan))
    res = run("diagnose", str(tmp_path), str(scene_file), "--json")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["summary"]["push_steps"] == len(out["steps"]) >= 3


def test_cli_diagnose_refuses_arm_and_chained_plans_in_one_line(tmp_path):
    """Plans it cannot check (arms; one object pushing another) get one line, exit 2."""
    from tests.conftest import TASKS

    for task, objects in (("two_arm_left_only", {"box": [[0.0, 0.0, 0.0]]}),
                          ("three_objects", {"red": [[0.0, 0.0, 0.0]],
                                             "blue": [[0.0, 0.0, 0.0]]})):
        (tmp_path / "result.json").write_text(json.dumps(
            {"trajectory": {"pusher": [[0.0, 0.0]], "objects": objects}}))
        res = run("diagnose", str(tmp_path), str(TASKS / f"{task}.yaml"))
        assert res.returncode == 2 and res.stderr.count("\n") == 1, res.stderr
        assert "not diagnosed yet" in res.stderr and "Traceback" not in res.stderr
