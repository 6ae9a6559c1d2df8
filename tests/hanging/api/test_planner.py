"""The facade on a hang scene: plan → execute → playback through ``robotplan.plan`` /
``execute`` / ``write_playback`` (a tiny H_hang trained by our code), poses in the world frame,
and ``robotplan solve`` refusing a missing model."""

import json
import math
from dataclasses import replace

import numpy as np
import pytest

import robotplan
from robotplan.cli.app import main
from robotplan.hanging.api.planner import HangPlan, HangPlanner
from robotplan.hanging.api.poses import compose, table_pose
from robotplan.hanging.program.problem import HangSettings
from robotplan.hanging.training.train import HangTrainConfig, train_hang
from robotplan.scene.task import HangTask, load_task, make_task
from tests.conftest import TASKS, TINY_HANG_SPEC


@pytest.fixture(scope="module")
def tiny_model(tiny_hang_data, tmp_path_factory):
    out = tmp_path_factory.mktemp("hang_model")
    train_hang(HangTrainConfig(data=str(tiny_hang_data), out=str(out), steps=3,
                               spec=TINY_HANG_SPEC), progress=False)
    return out


def test_plan_execute_and_playback_through_the_facade(tiny_model, tmp_path, monkeypatch):
    import robotplan.hanging.api.planner as hang_api

    scene = robotplan.load_scene(TASKS / "mug_hang.yaml")
    monkeypatch.setattr(hang_api, "HANG_DEFAULTS", HangSettings(restarts=1, major_iterations=5,
                                                                  approach_iterations=3))
    planned = robotplan.plan(scene, tiny_model)
    assert isinstance(planned, HangPlan) and planned.solution.evaluations > 0
    assert isinstance(planned.task, HangTask) and planned.scene is planned.task.scene is scene
    executed = robotplan.execute(planned)
    assert executed.drop and executed.drop[0][0] == 0.0
    assert np.allclose(executed.drop[0][1], planned.X_WM, atol=1e-6), "the drop starts there"
    robotplan.write_playback(planned, executed, tmp_path / "playback.html")
    assert (tmp_path / "playback.html").stat().st_size > 10_000


def test_the_closed_loop_searches_on_while_the_mug_falls(tiny_model):
    """Open loop drops the plan's pose once (the paper's protocol); closed loop, when the mug
    falls from it, goes on with the same search and drops each further pose, reporting the
    poses it passed over as re-plans, until one hangs or the restarts are spent."""
    from robotplan.hanging.api.planner import execute_hang, plan_hang

    task = load_task(TASKS / "mug_hang.yaml")
    settings = HangSettings(kappa=1e6, restarts=3, major_iterations=5,
                            approach_iterations=3)  # H_coll decides
    planned = plan_hang(task, tiny_model, settings=settings, check=None)
    assert planned.solved, "a pose clear of the hook within three solves"
    first = planned.solution.restarts
    opened = execute_hang(planned, "open_loop")
    assert opened.mode == "open_loop" and opened.replans == []
    assert np.array_equal(opened.solution.pose, planned.solution.pose)
    closed = execute_hang(planned, "closed_loop")
    assert planned.solution.restarts == first, "the plan is left as it was"
    assert closed.mode == "closed_loop" and closed.solution.feasible
    if opened.hung:
        assert closed.replans == [] and closed.hung
    else:
        assert closed.hung or closed.solution.restarts == settings.restarts
        assert 1 <= len(closed.replans) <= settings.restarts - 1 + int(closed.hung)
        assert all(r["reason"].startswith("the mug") and r["violation"] < 1e-3
                   for r in closed.replans)
        assert [r["step"] for r in closed.replans] == sorted({r["step"] for r in closed.replans})
        again = execute_hang(planned, "closed_loop")
        assert np.array_equal(again.solution.pose, closed.solution.pose), "executions repeat"
    with pytest.raises(ValueError, match="mode"):
        execute_hang(planned, "sideways")


def test_the_planner_hands_each_call_to_its_function(monkeypatch, tmp_path):
    """:class:`HangPlanner` is the four functions as methods: a task in, the options as given,
    the facade's push-only execution options dropped."""
    import robotplan.hanging.api.planner as hang_api

    calls = []

    def record(name):
        return lambda *args, **kwargs: calls.append((name, args, kwargs)) or name

    for name in ("plan_hang", "execute_hang", "write_hang_playback_page", "solve_hang"):
        monkeypatch.setattr(hang_api, name, record(name))
    task = load_task(TASKS / "mug_hang.yaml")
    planner = HangPlanner()
    assert planner.plan(task, "m", seed=3, restarts=2) == "plan_hang"
    assert planner.execute("p", "open_loop", perturb=None, loop=None, quiet=True) == "execute_hang"
    assert planner.playback("p", "e", str(tmp_path / "x.html")) is None
    assert planner.solve(task, str(tmp_path), "m", mode="open_loop", quiet=True,
                         restarts=1) == "solve_hang"
    assert calls == [
        ("plan_hang", (task, "m"), {"seed": 3, "restarts": 2}),
        ("execute_hang", ("p", "open_loop", "pybullet"), {}),
        ("write_hang_playback_page", ("p", "e", tmp_path / "x.html"), {}),
        ("solve_hang", (task, tmp_path, "m"), {"mode": "open_loop", "restarts": 1})]


def test_world_poses_follow_the_hook():
    X_WH = table_pose(0.2, -0.1, math.pi / 2)
    X_HM = np.array([0.1, 0.0, 0.25, 1.0, 0.0, 0.0, 0.0])
    X_WM = compose(X_WH, X_HM)
    assert np.allclose(X_WM[:3], [0.2, 0.0, 0.25], atol=1e-12)
    assert np.allclose(np.abs(X_WM[3:]), [math.sqrt(0.5), 0, 0, math.sqrt(0.5)], atol=1e-12)


def test_solve_writes_the_result_or_refuses_a_missing_model(tiny_model, tmp_path, capsys):
    scene_path = tmp_path / "moved.yaml"
    text = (TASKS / "mug_hang.yaml").read_text().replace("pose: [0.0, 0.0, 0.0]",
                                                         "pose: [0.1, 0.1, 0.5]")
    scene_path.write_text(text)
    assert main(["solve", str(scene_path), "--out", str(tmp_path / "none"),
                 "--model", str(tmp_path / "nothing")]) == 2
    assert "no trained H_hang" in capsys.readouterr().err
    scene = robotplan.load_scene(scene_path)
    assert scene.obstacles[0].pose == (0.1, 0.1, 0.5)
    assert replace(scene, name="x").goal.on == "hook"
    doc_path = tmp_path / "out" / "result.json"
    from robotplan.hanging.api.planner import solve_hang

    task = make_task(scene)
    doc = solve_hang(task, tmp_path / "out", tiny_model, restarts=1,
                     settings=HangSettings(major_iterations=5, approach_iterations=3),
                     check=tiny_model)
    assert json.loads(doc_path.read_text()) == doc
    assert doc["check"] is None and doc["check_h"] is None, "the closed loop drops instead"
    opened = solve_hang(task, tmp_path / "open", tiny_model, restarts=1, mode="open_loop",
                        settings=HangSettings(major_iterations=5, approach_iterations=3),
                        check=tiny_model)
    assert opened["check"] == str(tiny_model)
    assert (opened["check_h"] is None) == (opened["status"] == "no_solution")
    assert set(doc["execution"]) >= {"hung", "collision_at_start", "final_pose", "in_place",
                                     "mode", "replans"}
    assert doc["execution"]["mode"] == "closed_loop"
    assert doc["execution"]["simulator"] == "pybullet"
    assert len(doc["pose"]) == 7
    in_mujoco = solve_hang(task, tmp_path / "mujoco", tiny_model, restarts=1, mode="open_loop",
                           settings=HangSettings(major_iterations=5, approach_iterations=3),
                           check=None, sim="mujoco")
    assert in_mujoco["execution"]["simulator"] == "mujoco"
    assert in_mujoco["pose"] == opened["pose"], "the same plan, dropped in MuJoCo"
    assert (tmp_path / "out" / doc["picture"]).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_inverse_pose_undoes_the_hook_pose():
    from robotplan.hanging.api.poses import inverse_pose

    X_WH = table_pose(0.2, -0.1, 0.7, z=0.05)
    X_HM = np.array([0.1, -0.02, 0.25, 0.9, 0.1, -0.3, 0.2])
    X_HM[3:] /= np.linalg.norm(X_HM[3:])
    back = compose(inverse_pose(X_WH), compose(X_WH, X_HM))
    assert np.allclose(back[:3], X_HM[:3], atol=1e-12)
    assert abs(abs(back[3:] @ X_HM[3:]) - 1.0) < 1e-12
