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
