"""``bench hang``: Tab. 3's fractions as the paper counts them, a real one-scene run, and bad
arguments refused with exit 2."""

import json

from robotplan.base.resources import learned_dir
from robotplan.cli.app import main
from robotplan.hanging.bench.bench import METHODS, summarize_hang


def run(found: bool, hangs: bool, free: bool, in_place: bool = False) -> dict:
    return {"found": found, "sim_success": hangs, "collision_free": free,
            "in_place": in_place, "seconds": 1.0}


def test_fractions_are_of_the_found_and_of_the_successes():
    rows = [{"scene": 0, "opt_sampling": run(True, True, True)},
            {"scene": 1, "opt_sampling": run(True, True, False, in_place=True)},
            {"scene": 2, "opt_sampling": run(True, False, True)},
            {"scene": 3, "opt_sampling": run(False, False, False)}]
    s = summarize_hang(rows)["opt_sampling"]
    assert s == {"found": 0.75, "sim_success": round(2 / 3, 4), "collision_free": 0.5,
                 "total": 0.25, "in_place": round(1 / 3, 4)}


def test_the_closed_loop_row_carries_its_seconds_and_drops():
    rows = [{"scene": i, "closed_loop": {**run(True, i < 2, True), "seconds": 10.0 * (i + 1),
                                         "drops": i + 1}} for i in range(3)]
    s = summarize_hang(rows)
    assert s["closed_loop"]["total"] == round(2 / 3, 4)
    assert s["closed_loop"]["median_seconds"] == 20.0 and s["closed_loop"]["median_drops"] == 2
    assert "opt_sampling" not in s and s["median_seconds"] is None


def test_one_real_scene_and_bad_arguments(tmp_path, tiny_hang_data, capsys):
    model = tmp_path / "model"
    assert main(["train", "hang", "--data", str(tiny_hang_data), "--out", str(model),
                 "--steps", "2", "--threads", "1"]) == 0
    capsys.readouterr()
    bench = ["bench", "hang", "--scenes", "1", "--model", str(model), "--out",
             str(tmp_path / "b"), "--methods", "sampling_k2,sampling_k3", "--workers", "1"]
    assert main([*bench, "--evaluations", "128", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["scenes"] == 1 and summary["evaluations"] == 128
    assert set(summary["sampling_k3"]) == {"found", "sim_success", "collision_free", "total",
                                           "in_place"}
    assert summary["units"]["executor"] == "processes" and summary["units"]["units"] == 1
    row = json.loads((tmp_path / "b" / "rows.jsonl").read_text())
    assert 1 <= row["sampling_k2"]["evaluations"] <= row["sampling_k3"]["evaluations"] <= 128
    assert main([*bench, "--evaluations", "64"]) == 2, "a folder of another budget"
    assert main([*bench, "--evaluations", "128", "--collision", "none"]) == 2, "and of a row"
    assert main([*bench, "--evaluations", "128", "--check", "none"]) == 2, "and of a check"
    assert main([*bench, "--evaluations", "128", "--no-threading"]) == 2, "and of the starts"
    run_json = json.loads((tmp_path / "b" / "run.json").read_text())
    assert run_json["collision"] == "sdf" and run_json["threading"] is True
    assert run_json["check"] == str(learned_dir("hang_check")), "the shipped check by default"
    assert main(["bench", "hang", "--model", str(model), "--out", str(tmp_path / "c"),
                 "--methods", "guess"]) == 2
    assert main(["bench", "hang", "--model", str(tmp_path), "--out", str(tmp_path / "c")]) == 2
    assert main(["bench", "hang", "--model", str(model), "--check", str(tmp_path),
                 "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert "--methods" in err and "--model" in err and "other settings" in err
    assert f"{tmp_path}: --check: not a model folder" in err
    assert set(METHODS) == {"opt_sampling", "opt_only", "sampling_k1", "sampling_k2",
                            "sampling_k3"}


def test_mesh_scenes_go_through_every_mug_and_hook_pair():
    from robotplan.hanging.bench.bench import MESH_HOOKS, MESH_MUGS, mesh_pair

    pairs = [mesh_pair(i) for i in range(12)]
    assert len(set(pairs)) == len(MESH_MUGS) * len(MESH_HOOKS) == 6
    assert pairs[:6] == pairs[6:]
    assert all(m.is_file() and h.is_file() for m, h in pairs)


def test_each_simulator_is_summarized_and_a_bad_one_refused(tmp_path, capsys):
    """Rows of two simulators: the row's own outcomes are the first's, each one's under
    ``by_simulator``; ``--sim`` names only known simulators (exit 2, one line)."""
    both = {"pybullet": {"sim_success": True, "collision_free": True, "in_place": True},
            "mujoco": {"sim_success": False, "collision_free": True, "in_place": False}}
    rows = [{"scene": 0, "opt_sampling": {**run(True, True, True, True), "by_simulator": both}},
            {"scene": 1, "opt_sampling": {**run(False, False, False), "by_simulator": {
                s: run(False, False, False) for s in both}}}]
    assert summarize_hang(rows)["opt_sampling"]["total"] == 0.5
    assert summarize_hang(rows, "pybullet") == summarize_hang(rows)
    mujoco = summarize_hang(rows, "mujoco")["opt_sampling"]
    assert mujoco["found"] == 0.5 and mujoco["sim_success"] == 0.0 and mujoco["total"] == 0.0
    assert main(["bench", "hang", "--out", str(tmp_path / "b"), "--sim",
                 "pybullet,nosuch"]) == 2
    assert capsys.readouterr().err.strip() == (
        "error: --sim: unknown simulator 'nosuch'; expected one of pybullet, mujoco")
    assert not (tmp_path / "b").exists()
