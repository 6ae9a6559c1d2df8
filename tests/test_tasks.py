"""Every task script runs through the facade: its fast variant (one given skeleton), and
its full skeleton search (slow). The L-shape's fast variant runs by default; one learned
program of the arm, chain and obstacle scenes costs 30–90 s on two cores, so their fast
variants run with the slow tests."""

import subprocess
import sys

import pytest

from tests.conftest import ROOT

SCRIPTS = sorted(p.stem for p in (ROOT / "tasks").glob("*.py") if p.stem != "task_cli")
# one script runs by default: box_push's and box_goal_sweep's fast variants solve box_push
# with push@0 as tests/test_api.py and `make demo` do, so they run with the slow tests
DEFAULT_FAST = {"lshape_push"}


def _run(script: str, out, *flags: str) -> str:
    res = subprocess.run([sys.executable, str(ROOT / "tasks" / f"{script}.py"), "--out",
                          str(out), *flags], capture_output=True, text=True, timeout=1800)
    assert res.returncode == 0, res.stderr[-3000:]
    assert "Traceback" not in res.stderr
    return res.stdout


def test_every_scenario_has_a_script():
    scenes = {p.stem for p in (ROOT / "tasks").glob("*.yaml")}
    assert scenes <= set(SCRIPTS), scenes - set(SCRIPTS)


@pytest.mark.parametrize("script", [
    pytest.param(s, marks=() if s in DEFAULT_FAST else pytest.mark.slow) for s in SCRIPTS])
def test_fast_variant_plans_executes_and_writes_a_playback(script, tmp_path):
    out = _run(script, tmp_path, "--fast")
    assert "in pybullet" in out or "no plan" in out
    if "no plan" not in out:
        assert list(tmp_path.rglob("playback.html"))


@pytest.mark.slow
@pytest.mark.parametrize("script", SCRIPTS)
def test_full_variant_solves(script, tmp_path):
    out = _run(script, tmp_path)
    assert "solved," in out and "not solved" not in out, out
    assert list(tmp_path.rglob("playback.html"))
