"""End to end, slow: plan box_push with one skeleton, execute it, write the result page.
Run with `make test-slow`."""

import json
import subprocess
import sys

import pytest

from tests.conftest import ROOT, TASKS


@pytest.mark.slow
def test_solve_box_push_one_skeleton(tmp_path):
    out = tmp_path / "out"
    res = subprocess.run([sys.executable, "-m", "robotplan.cli", "solve",
                          str(TASKS / "box_push.yaml"), "--out", str(out), "--skeleton", "push@2",
                          "--workers", "1"], cwd=ROOT, capture_output=True, text=True,
                         timeout=1800)
    assert res.returncode in (0, 1), res.stderr  # 1: no_solution, still a whole result
    doc = json.loads((out / "result.json").read_text())
    assert doc["status"] in ("solved", "no_solution")
    assert doc["execution"]["simulator"] == "pybullet"
    assert 0.0 <= doc["execution"]["coverage"] <= 1.0
    assert len(doc["trajectory"]["pusher"]) == 21
    assert (out / "playback.html").stat().st_size > 100_000
