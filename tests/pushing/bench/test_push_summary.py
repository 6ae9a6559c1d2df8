"""The summary of ``bench push`` across simulators: each one's quartiles and how far they
part, per scene."""

from __future__ import annotations

import json

import pytest

from robotplan.pushing.bench.push_summary import compare_simulators, of_simulator
from tests.cli.test_app import call


def _row(scene: str, pybullet: tuple[float, float], mujoco: tuple[float, float]) -> dict:
    sims = {name: {"outcome": "solved", "coverage": c, "open_loop_coverage": o,
                   "execute_seconds": 1.0, "open_loop_seconds": 1.0, "replans": []}
            for name, (c, o) in (("pybullet", pybullet), ("mujoco", mujoco))}
    return {"scene": scene, "shape": "box", "plan_seconds": 1.0, **sims["pybullet"],
            "sims": sims}


def test_each_simulator_is_summarised_and_the_gaps_are_per_scene() -> None:
    rows = [_row("a", (1.0, 0.9), (1.0, 0.5)), _row("b", (0.8, 1.0), (1.0, 1.0))]
    assert [r["open_loop_coverage"] for r in of_simulator(rows, "mujoco")] == [0.5, 1.0]
    out = compare_simulators(rows, ["pybullet", "mujoco"])
    assert out["by_simulator"]["mujoco"]["coverage"]["box"]["min"] == 1.0
    assert out["by_simulator"]["pybullet"]["coverage"]["box"]["min"] == 0.8
    gaps = out["disagreement"]["mujoco-pybullet"]
    assert gaps["coverage"]["per_scene"] == {"a": 0.0, "b": pytest.approx(0.2)}
    assert gaps["open_loop_coverage"]["per_scene"] == {"a": pytest.approx(-0.4), "b": 0.0}
    assert gaps["open_loop_coverage"]["abs_mean"] == pytest.approx(0.2)
    assert "disagreement" not in compare_simulators(rows, ["mujoco"])


@pytest.mark.slow
def test_one_plan_runs_in_both_simulators(tmp_path, capsys) -> None:
    """``bench push --sim pybullet,mujoco`` on one box scene: one plan, executed in each
    simulator both ways, each world's result in its own folder naming it."""
    out = tmp_path / "b"
    res = call(capsys, "bench", "push", "--scenes", "1", "--shapes", "box", "--workers", "1",
               "--sim", "pybullet,mujoco", "--out", str(out))
    assert res.returncode == 0, res.stderr[-2000:]
    assert "mujoco-pybullet: coverage differs by" in res.stdout
    row = json.loads((out / "rows.jsonl").read_text().splitlines()[0])
    assert list(row["sims"]) == ["pybullet", "mujoco"]
    assert row["coverage"] == row["sims"]["pybullet"]["coverage"]
    for sim in ("pybullet", "mujoco"):
        result = json.loads((out / "solutions" / row["scene"] / sim / "result.json")
                            .read_text())
        assert result["execution"]["simulator"] == sim
        assert result["execution"]["coverage"] == row["sims"][sim]["coverage"]
        assert row["sims"][sim]["coverage"] >= 0.9
    summary = json.loads((out / "summary.json").read_text())
    assert summary["simulators"]["names"] == ["pybullet", "mujoco"]
    assert (out / "coverage_mujoco.png").stat().st_size > 10_000
    header = (out / "results.csv").read_text().splitlines()[0].split(",")
    assert {"coverage_pybullet", "coverage_mujoco", "open_loop_coverage_mujoco"} <= set(header)
    assert "sims" not in header
