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
