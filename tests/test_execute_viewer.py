"""Open-loop execution in real pybullet physics, and the MeshCat playback page."""

import numpy as np

from robotplan import load_scene
from robotplan.execute import execute_push
from robotplan.viewer import write_playback
from tests.conftest import TASKS


def hand_made_push() -> np.ndarray:
    """Go below-left of the box, then push it east into the goal (box_push.yaml)."""
    approach = np.linspace([-0.28, 0.10], [-0.20, 0.0], 10)
    push = np.linspace([-0.20, 0.0], [0.35, 0.05], 30)
    return np.vstack([approach, push[1:]])


def test_execution_pushes_the_box_into_the_goal():
    scene = load_scene(TASKS / "box_push.yaml")
    q = hand_made_push()
    ex = execute_push(scene, "box", "pusher", q)
    assert ex.object_poses.shape == (len(q), 3)
    assert np.abs(ex.pusher_positions - q).max() < 0.01  # the pusher tracks its path
    assert ex.final_pose[0] > 0.25 and ex.coverage > 0.9
    still = execute_push(scene, "box", "pusher", np.tile(q[:1], (5, 1)))
    assert still.coverage == 0.0 and np.allclose(still.final_pose, scene.bodies["box"].pose,
                                                 atol=1e-3)


def test_playback_is_one_self_contained_page(tmp_path):
    scene = load_scene(TASKS / "box_push.yaml")
    q = hand_made_push()
    ex = execute_push(scene, "box", "pusher", q)
    page = tmp_path / "playback.html"
    write_playback(scene, page, {"pusher": q}, {"box": ex.object_poses,
                                                "pusher": ex.pusher_positions})
    html = page.read_text()
    assert html.startswith("<!DOCTYPE html>") or "<html" in html[:200]
    assert "src=\"http" not in html and len(html) > 100_000
    assert "Animation" in html  # the timeline is embedded (as packed MeshCat commands)


def test_arm_execution_tracks_the_plan_and_pushes_with_its_tip(tmp_path):
    """The left iiwa follows an IK'd push path under position control: its tip stays on
    Drake's forward kinematics of the planned angles, the box moves, the idle right arm
    holds still; the playback draws both arms."""
    from robotplan.arm_program import _kinematics
    from robotplan.arms import track_tip_path
    from robotplan.execute import execute_arms

    scene = load_scene(TASKS / "two_arm_left_only.yaml")
    left, right = (next(r for r in scene.robots if r.name == n) for n in ("left", "right"))
    kin = _kinematics(left)
    above = np.array([[-0.45, -0.37, 0.12]])
    down = np.array([[-0.45, -0.37, 0.03]])
    push = np.stack([np.full(12, -0.45), np.linspace(-0.37, -0.10, 12), np.full(12, 0.03)], 1)
    Q = track_tip_path(kin, np.vstack([above, down, push[1:]]), kin.q0, 0.07, 0.12)
    Q = np.vstack([kin.q0, Q])
    q_right = np.tile(_kinematics(right).q0, (len(Q), 1))
    substeps = [60, 60] + [20] * (len(Q) - 3)
    ex = execute_arms(scene, "box", {"left": Q, "right": q_right}, substeps)
    planned = np.array([kin.tip(q) for q in Q])
    assert np.abs(ex.tips["left"][:3] - planned[:3]).max() < 2e-3  # before contact
    assert np.abs(ex.joints["right"] - q_right).max() < 1e-3
    moved = ex.final_pose[:2] - np.asarray(scene.bodies["box"].pose[:2])
    assert moved[1] > 0.1, f"the box moved {moved} m"
    assert ex.coverage is not None and ex.touch_distance is None
    page = tmp_path / "playback.html"
    plain = tmp_path / "plain.html"
    write_playback(scene, plain, {"box": ex.object_poses}, {"box": ex.object_poses})
    write_playback(scene, page, {"box": ex.object_poses}, {"box": ex.object_poses},
                   joints=({"left": Q, "right": q_right}, ex.joints))
    assert page.stat().st_size > plain.stat().st_size + 100_000  # the arm meshes
