"""End to end, slow: the skeleton search on box_push through the CLI, the pybullet
execution and the result page. Run with `make test-slow`."""

import json
import subprocess
import sys

import pytest

from tests.conftest import ROOT, TASKS


@pytest.mark.slow
def test_solve_box_push(tmp_path):
    out = tmp_path / "out"
    res = subprocess.run([sys.executable, "-m", "robotplan.cli", "solve",
                          str(TASKS / "box_push.yaml"), "--out", str(out)], cwd=ROOT,
                         capture_output=True, text=True, timeout=1800)
    assert res.returncode == 0, res.stderr
    assert "<- best" in res.stdout  # the table of candidates
    doc = json.loads((out / "result.json").read_text())
    assert doc["status"] == "solved"
    assert doc["execution"]["simulator"] == "pybullet"
    assert doc["execution"]["coverage"] >= 0.95
    assert len(doc["trajectory"]["pusher"]) == 21
    assert (out / "playback.html").stat().st_size > 100_000


@pytest.mark.slow
@pytest.mark.parametrize(("task", "actors"), [
    ("two_arm_left_only", {"left"}),
    ("two_arm_handover", {"left", "right"}),
])
def test_solve_two_arm_scenes(tmp_path, task, actors):
    """The arm scenes through the CLI: the right arms push, pybullet executes the joint
    trajectories of both arms, coverage ≥ 0.95 (#6), joint trajectories in result.json."""
    out = tmp_path / "out"
    res = subprocess.run([sys.executable, "-m", "robotplan.cli", "solve",
                          str(TASKS / f"{task}.yaml"), "--out", str(out)], cwd=ROOT,
                         capture_output=True, text=True, timeout=1800)
    assert res.returncode == 0, res.stderr
    doc = json.loads((out / "result.json").read_text())
    assert {row["actor"] for row in doc["skeleton"] if row["mode"] == "push"} == actors
    assert doc["execution"]["coverage"] >= 0.95
    steps = len(doc["trajectory"]["t"])
    for name in ("left", "right"):
        assert len(doc["trajectory"]["joints"][name]) == steps
        assert len(doc["executed"]["joints"][name][0]) == 7
    assert (out / "playback.html").stat().st_size > 1_000_000  # both arms' meshes


@pytest.mark.slow
def test_solve_two_arm_touch(tmp_path):
    """Left pushes the box into the right arm's reach, the right tip ends on it (#6: within
    1 cm in pybullet)."""
    out = tmp_path / "out"
    res = subprocess.run([sys.executable, "-m", "robotplan.cli", "solve",
                          str(TASKS / "two_arm_touch.yaml"), "--out", str(out)], cwd=ROOT,
                         capture_output=True, text=True, timeout=1800)
    assert res.returncode == 0, res.stderr
    doc = json.loads((out / "result.json").read_text())
    assert doc["skeleton"][-1]["actor"] == "right" and doc["skeleton"][-1]["mode"] == "reach"
    assert doc["execution"]["touch_distance"] <= 0.01
