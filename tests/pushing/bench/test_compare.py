"""``robotplan bench push --dynamics A,B``: the same scenes with each model, side by side."""

import json

import pytest

from robotplan.pushing.bench.compare import compare_rows
from robotplan.pushing.cli.bench_push_commands import dynamics_list_problem
from tests.cli.test_app import run


def _row(scene: str, shape: str, closed: float, open_loop: float, status: str) -> dict:
    return {"scene": scene, "shape": shape, "status": status, "coverage": closed,
            "open_loop_coverage": open_loop, "plan_seconds": 10.0, "replans": []}


def test_comparison_counts_each_models_scenes_apart():
    rows = {"flow": [_row("a", "box", 1.0, 0.5, "solved"), _row("b", "box", 0.2, 0.2,
                                                                     "no_solution")],
            "rigid": [_row("a", "box", 1.0, 1.0, "solved"), _row("b", "box", 0.95, 0.8,
                                                                      "solved")]}
    out = compare_rows(rows)
    assert out["flow"]["box"]["below_0_9"] == {"closed_loop": 1, "open_loop": 2}
    assert out["flow"]["box"]["unsolved"] == 1 and out["rigid"]["box"]["unsolved"] == 0
    assert out["rigid"]["box"]["closed_loop"]["min"] == 0.95
    assert out["rigid"]["box"]["open_loop"]["median"] == pytest.approx(0.9)


def test_a_list_of_dynamics_names_shipped_kinds_only(tmp_path):
    assert dynamics_list_problem(["flow", "rigid", "direct"], None) is None
    assert dynamics_list_problem(["auto"], "learned/push_flow") is None
    for kinds, model, why in ((["flow", "quadratic"], None, "'quadratic'"),
                              (["flow", "auto"], None, "shipped kinds"),
                              (["rigid", "flow"], "learned/push_flow", "shipped kinds")):
        assert why in dynamics_list_problem(kinds, model)
    res = run("bench", "push", "--scenes", "1", "--dynamics", "flow,quadratic",
              "--out", str(tmp_path / "b"))
    assert res.returncode == 2 and res.stderr.count("\n") == 1, res.stderr
    assert "--dynamics" in res.stderr and "'quadratic'" in res.stderr


@pytest.mark.slow
def test_two_models_on_the_same_box_scene(tmp_path):
    out = tmp_path / "cmp"
    res = run("bench", "push", "--scenes", "1", "--shapes", "box", "--dynamics", "flow,rigid",
              "--time-budget", "30", "--out", str(out), "--json")
    assert res.returncode == 0, res.stderr[-2000:]
    doc = json.loads((out / "compare.json").read_text())
    assert set(doc["models"]) == {"flow", "rigid"}
    assert all(doc["models"][k]["box"]["closed_loop"]["n"] == 1 for k in doc["models"])
    for kind, folder in (("flow", "push_flow"), ("rigid", "push_rigid")):
        row = json.loads((out / kind / "rows.jsonl").read_text().splitlines()[0])
        assert row["model"] == folder and row["scene"] == "bench_box_000"
    assert (out / "compare.png").stat().st_size > 10_000
