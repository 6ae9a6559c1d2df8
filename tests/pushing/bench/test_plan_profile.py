"""``bench plan``: a program's failure is read from its solution, the summary counts where
the time and the failures go, and a real box scene is planned and profiled."""

import json

import numpy as np
import pytest

from robotplan.cli.app import main
from robotplan.pushing.bench.plan_profile import failure, run_bench_plan, summarize_profile
from robotplan.pushing.program.skeleton import parse_skeleton
from robotplan.pushing.program.solution import FEASIBLE, Solution
from tests.conftest import ROOT


def _solution(status: str, violations: dict[str, float]) -> Solution:
    sk = parse_skeleton("push@0", "pusher", "box")
    worst = max(violations.values(), default=0.0)
    return Solution(sk, worst <= FEASIBLE, status, worst, 1.0, 2.5, np.zeros((21, 3)),
                    np.zeros((21, 2)), dynamics_mm2=np.full(20, 4.0),
                    timings={"H_coll": 0.5, "solver": 1.0}, violations=violations)


def test_a_failed_program_names_its_snopt_exit_its_stage_and_its_violated_rows_worst_first():
    s = _solution("kinematic stage infeasible (snopt info 13)",
                  {"H_coll": 0.3, "H_PoC": 2 * FEASIBLE, "goal": FEASIBLE / 2})
    entry = failure(s)
    assert entry["snopt_info"] == [13]
    assert entry["stage"] == "kinematic"
    assert not entry["solved"]
    assert list(entry["violated"]) == ["H_coll", "H_PoC"]  # goal is within FEASIBLE
    assert entry["dynamics_rms_mm"] == pytest.approx(2.0)

    ok = failure(_solution("snopt info 1", {"H_coll": 1e-5}))
    assert ok["stage"] == "learned" and ok["violated"] == {} and ok["snopt_info"] == [1]


def _row(name: str, shape: str, seconds: float, programs: list[dict]) -> dict:
    solved = any(p["solved"] for p in programs)
    return {"scene": name, "shape": shape, "solved": solved, "plan_seconds": seconds,
            "programs": programs,
            "timings": {"programs": float(len(programs)),
                        "total": sum(p["seconds"] for p in programs),
                        "solver": sum(p["seconds"] for p in programs) / 2}}


def _program(solved: bool, seconds: float, info: int = 1, stage: str = "learned",
             violated: dict | None = None) -> dict:
    return {"solved": solved, "seconds": seconds, "snopt_info": [info], "stage": stage,
            "violated": violated or {}}


def test_the_summary_counts_unsolved_searches_and_the_failed_programs_by_cause():
    rows = [
        _row("b0", "box", 2.0, [_program(True, 2.0)]),
        _row("b1", "box", 40.0, [_program(False, 30.0, 13, "kinematic", {"H_PoC": 0.5}),
                                 _program(True, 10.0)]),
        _row("l0", "lshape", 90.0, [_program(False, 50.0, 32, violated={"H_coll": 0.2}),
                                    _program(False, 40.0, 32, violated={"H_coll": 0.4,
                                                                        "H_PoC": 0.1})]),
    ]
    s = summarize_profile(rows)
    box, lshape = s["by_shape"]["box"], s["by_shape"]["lshape"]
    assert box["unsolved_searches"] == 0 and lshape["unsolved_searches"] == 1
    assert box["failed_programs"] == 1 and box["failed_seconds"] == pytest.approx(30.0)
    assert lshape["program_seconds"] == pytest.approx(90.0)
    assert box["plan_seconds"]["max"] == pytest.approx(40.0)
    assert s["failed"]["programs"] == 3
    assert s["failed"]["snopt_info"] == {"32": 2, "13": 1}
    assert s["failed"]["stage"] == {"learned": 2, "kinematic": 1}
    assert s["failed"]["violated_rows"]["H_coll"] == {"programs": 2, "median": pytest.approx(0.3)}
    assert s["failed"]["violated_rows"]["H_PoC"]["programs"] == 2
    assert s["time_profile"]["share"]["solver"] == pytest.approx(0.5)


def test_bench_plan_refuses_bad_shapes_and_a_finished_profile(tmp_path, capsys):
    assert main(["bench", "plan", "--out", str(tmp_path), "--shapes", "box,cube"]) == 2
    assert "--shapes" in capsys.readouterr().err
    (tmp_path / "summary.json").write_text("{}")
    assert main(["bench", "plan", "--out", str(tmp_path)]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert (tmp_path / "summary.json").read_text() == "{}"


@pytest.mark.skipif(not (ROOT / "learned" / "push_flow" / "weights.pt").exists(),
                    reason="push_flow not shipped")
def test_a_box_scene_is_planned_and_profiled_and_a_rerun_continues(tmp_path):
    summary = run_bench_plan(1, 0, tmp_path, None, ("box",), {"workers": 1})
    row = json.loads((tmp_path / "rows.jsonl").read_text().splitlines()[0])
    assert row["scene"] == "bench_box_000" and row["programs"]
    assert summary["by_shape"]["box"]["plan_seconds"]["n"] == 1
    timed = summary["time_profile"]
    assert timed["programs"] == len(row["programs"])
    total = sum(p["seconds"] for p in row["programs"])  # rounded to 0.1 s in the profile
    assert timed["candidate_seconds"] == pytest.approx(total, abs=0.051) and total > 0
    for program in row["programs"]:  # SNOPT ran, or the program's start was its plan
        assert "solver" in program["timings"] or program["stage"] == "start kept"
    assert row["solved"] == any(p["solved"] for p in row["programs"])
    # a second run finds the row and plans nothing again
    again = run_bench_plan(1, 0, tmp_path, None, ("box",), {"workers": 1})
    assert len((tmp_path / "rows.jsonl").read_text().splitlines()) == 1
    assert again["by_shape"] == summary["by_shape"]
