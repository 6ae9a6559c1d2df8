"""``robotplan robot reach``: the measured reach is the one robot.yaml states; a folder that
is not a robot's is refused in one line with exit status 2."""

from __future__ import annotations

import json

from robotplan.scene.robots import ROBOTS_DIR, load_robot_model
from tests.cli.test_app import call


def test_reach_measures_what_robot_yaml_says(capsys):
    res = call(capsys, "robot", "reach", str(ROBOTS_DIR / "panda"), "--json")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    lo, hi = out["reach"]
    stated = load_robot_model("panda").reach
    assert abs(lo - stated[0]) <= 0.01 and abs(hi - stated[1]) <= 0.01, (out, stated)


def test_reach_refuses_what_is_not_a_robot_folder(capsys, tmp_path):
    for given in (str(tmp_path), "no_such_model"):
        res = call(capsys, "robot", "reach", given)
        assert res.returncode == 2
        assert len(res.stderr.strip().splitlines()) == 1 and given in res.stderr
    res = call(capsys, "robot", "reach", "panda", "--tip-height", "0.2")
    assert res.returncode == 2 and "--tip-height" in res.stderr
