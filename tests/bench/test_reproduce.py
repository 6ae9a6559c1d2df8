"""``robotplan reproduce``: steps kept and reused by content, the report in Markdown and
HTML, the paper's numbers beside ours."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from robotplan.bench.paper import FLOW_REPRESENTATIONS, TAB2, TAB4, TAB5
from robotplan.bench.report import write_report
from robotplan.bench.reproduce import QUICK, reproduce
from robotplan.bench.reproduce_models import flow_representations, rigid_representations
from robotplan.bench.reproduce_report import _analytic_rows
from robotplan.bench.reproduce_tables import tab2_rows, tab4_rows, tab56_rows
from robotplan.bench.steps import Steps
from robotplan.cli.app import main
from robotplan.hanging.bench.report import tab3_blocks
from robotplan.hanging.bench.reproduce import HANG_REPRESENTATIONS, hang_representations


def test_report_tables_and_an_embedded_figure(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(2, 2))
    ax.plot(np.arange(3))
    fig.savefig(tmp_path / "plot.png")
    plt.close(fig)
    blocks = [("h1", "Title"), ("p", "see `robotplan reproduce`"),
              ("table", ["a", "b"], [[1, "x"], [2.5, "y"]]), ("image", "plot.png", "a plot")]
    md, page = write_report(blocks, tmp_path, "T")
    text = md.read_text()
    assert "# Title" in text and "| a | b |" in text and "| 2.5 | y |" in text
    assert "![a plot](plot.png)" in text
    html = page.read_text()
    assert "<code>robotplan reproduce</code>" in html and "<td>2.5</td>" in html
    assert "data:image/png;base64," in html


def test_fig6_sets_the_analytic_model_beside_the_learned_one_for_each_shape():
    def summary(median: float) -> dict:
        q = {"n": 2, "median": median, "q1": median / 2}
        return {"coverage": {"box": q, "lshape": q}, "open_loop_coverage": {"box": q,
                                                                          "lshape": q},
                "plan_seconds": {"box": {"median": 3.0}, "lshape": {"median": 9.0}}}

    rows = _analytic_rows({"fig3": {"result": summary(1.0)}, "fig6": {"result": summary(0.5)}})
    assert [r[:2] for r in rows] == [["boxes", "learned (Fig. 3's run)"], ["boxes", "analytic"],
                                     ["L-shapes", "learned (Fig. 3's run)"],
                                     ["L-shapes", "analytic"]]
    assert rows[1][3:5] == ["0.500 (0.250)", "0.500 (0.250)"] and rows[2][5] == "9.0"


def test_tab2_sets_each_object_frame_model_below_its_table_frame_one():
    def scored(contact: float, free: float) -> dict:
        return {"result": {"rmse_mm": {"contact": contact, "free": free},
                           "rmse_std_mm": {"contact": 1.0, "free": 2.0},
                           "baseline_rmse_mm": {"contact": 10.0, "free": 0.0},
                           "baseline_std_mm": {"contact": 4.0, "free": 0.0}}}

    results = {"rmse_flow_test": scored(3.9, 1.3), "rmse_direct_test": scored(7.0, 8.9),
               "rmse_flow_object_test": scored(2.1, 0.9), "rigid_test": {"result": {}}}
    rows = tab2_rows(results, "test", TAB2)
    assert [r[0] for r in rows] == ["F_flow", "F_flow, object frame", "F", "no motion"]
    assert rows[1][1:] == ["2.10 ± 1.00", "0.90 ± 2.00", "3.40 ± 1.60", "1.40 ± 1.80"]
    del results["rmse_flow_object_test"]
    assert [r[0] for r in tab2_rows(results, "test", TAB2)] == ["F_flow", "F", "no motion"]


def test_reproduce_refuses_a_folder_of_other_files(tmp_path, capsys):
    (tmp_path / "mine.txt").write_text("a user's file")
    assert main(["reproduce", "--out", str(tmp_path), "--quick"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--out" in err
    assert [p.name for p in tmp_path.iterdir()] == ["mine.txt"]


def test_each_representation_is_trained_alike_and_set_beside_the_paper(
        tiny_push_data, tiny_ood_push_data, tmp_path):
    """F_q on SDFs, ψ, ψ_s and point clouds, two encoders (tiny data, 2 steps each): every
    model folder says what it reads, each set has a row per representation, and the
    paper's own rows for ψ_s (b = 100), PointNet and PointNet++ are no longer marked "paper
    only" once ours sit beside them."""
    sizes = replace(QUICK, per_scene=2, representation_scenes=12, representation_steps=2)
    steps = Steps(tmp_path, progress=False)
    sets = {"test": tiny_push_data, "ood": tiny_ood_push_data}
    reps, models = rigid_representations(steps, sizes, tiny_push_data, sets)
    assert set(reps) == {"reps_test", "reps_ood"}
    assert list(models) == list(reps["reps_test"])
    assert all((folder / "weights.pt").is_file() for folder in models.values())
    assert list(reps["reps_test"]) == ["sdf", "occupancy", "smooth100", "smooth1000",
                                       "pointnet", "pointnet2"]
    specs = [json.loads(p.read_text())
             for p in sorted(tmp_path.glob("steps/train_rigid_*/model/spec.json"))]
    assert sorted((s["representation"], s["occupancy_sharpness"], s["cloud_encoder"])
                  for s in specs) == [
        ("occupancy", 100.0, "pointnet"), ("pointcloud", 100.0, "pointnet"),
        ("pointcloud", 100.0, "pointnet2"), ("sdf", 100.0, "pointnet"),
        ("smooth_occupancy", 100.0, "pointnet"), ("smooth_occupancy", 1000.0, "pointnet")]
    shipped = reps["reps_test"]["sdf"][0]  # any evaluation has the fields a row reads
    rows = tab56_rows({"rigid_test": shipped, **reps}, "test", TAB5, sizes)
    labels = [row[0] for row in rows]
    assert "F_q on occupancy ψ_s (b = 100), 2 steps" in labels
    assert "occupancy ψ_s (b = 100) (paper only)" not in labels
    assert not any(label.endswith("(paper only)") and "PointNet" in label for label in labels)
    smooth = rows[labels.index("F_q on occupancy ψ_s (b = 100), 2 steps")]
    assert smooth[-3:] == ["2.7", "2.7", "0.76"] and "±" in smooth[1]


@pytest.mark.slow
def test_tab4_trains_a_flow_on_each_representation_and_scores_it_in_what_it_reads(
        tiny_push_data, tmp_path):
    sizes = replace(QUICK, per_scene=2, flow_steps=2)
    steps = Steps(tmp_path, progress=False)
    results = flow_representations(steps, sizes, tiny_push_data, tiny_push_data)
    assert list(results) == list(FLOW_REPRESENTATIONS)
    assert [r[0]["result"]["representation"] for r in results.values()] == [
        "sdf", "occupancy", "smooth_occupancy", "smooth_occupancy"]
    rows = tab4_rows({"tab4": results}, sizes, TAB4)
    assert [row[0] for row in rows[:2]] == ["F_flow on SDF, 2 steps", "no motion, SDF"]
    assert rows[1][-2:] == ["10.80 ± 3.40", "0.00 ± 0.00"]
    psi = rows[rows.index(next(r for r in rows if r[0] == "no motion, occupancy ψ = sign(φ)"))]
    # the same samples: ψ's no-motion error (× 1000) is far above φ's in mm, as the paper's
    assert float(psi[1].split(" ± ")[0]) > float(rows[1][1].split(" ± ")[0])


@pytest.mark.slow
def test_a_tiny_reproduction_end_to_end_and_again_from_its_steps(tmp_path):
    tiny = replace(QUICK, name="quick", test_scenes=3, ood_scenes=3, per_scene=3, pose_fit=2,
                   push_scenes=1, ood_push_scenes=1, ablation_scenes=1, hang_scenes=1,
                   hang_methods=("opt_only",), time_budget=5.0, representation_scenes=6,
                   representation_steps=2, contact_push=("occupancy",), flow_steps=2,
                   hang_representations=("sdf", "pointnet"), hang_train_scenes=2,
                   hang_test_scenes=1,
                   hang_train_steps=2, hang_representation_scenes=1,
                   hang_representation_methods=("sampling_k1",), hang_evaluations=64)
    ledger = tmp_path / "ledger"
    md = reproduce(tmp_path, tiny, workers=1, progress=False, ledger=ledger)
    text = md.read_text()
    for item in ("Tab. 2", "Tab. 4", "Tab. 5", "Tab. 6", "Fig. 3", "Fig. 5", "Fig. 6",
                 "Fig. 8", "Fig. 11", "Tab. 3", "| every row |", "without H_PoC",
                 "| analytic |", "--candidates plain"):
        assert item in text, item
    assert "Not run yet" not in text, "every item of the paper has its code"
    assert "| F_flow | " in text and "| 3.40 ± 1.60 | 1.40 ± 1.80 |" in text
    assert "| F_q, T(Δq)[φ1_{t−1}] | " in text  # F_q scored in Tab. 2's terms beside F_flow
    assert "| F_flow, object frame | " in text and "| F, object frame | " in text
    run = json.loads((tmp_path / "run.json").read_text())
    assert "| F_q on occupancy ψ_s (b = 100), 2 steps |" in text
    # data, training and evaluation of six representations: 1 + 6 + 12 steps; Figs. 5, 6: 1;
    # Tab. 4's four F_flow: 4 + 4; Tab. 3's two H_hang: 2 data, 2 trainings, 2 benches;
    # Tab. 2's object-frame F_flow and F on both sets: 4
    assert len(run["steps"]) == 55 and run["sizes"]["test_scenes"] == 3
    reproduce(tmp_path, tiny, workers=1, progress=False, ledger=ledger)
    again = json.loads((tmp_path / "run.json").read_text())
    assert [s["folder"] for s in again["steps"]] == [s["folder"] for s in run["steps"]]
    assert (tmp_path / "quick.html").stat().st_size > 1000
    # a fresh clone: a new output folder and the committed ledger; nothing runs again
    elsewhere = tmp_path / "elsewhere"
    md = reproduce(elsewhere, tiny, workers=1, progress=False, ledger=ledger)
    fresh = json.loads((elsewhere / "run.json").read_text())
    assert {s["state"] for s in fresh["steps"]} == {"done"}
    assert not (elsewhere / "steps").exists()
    assert md.read_text() == text and (elsewhere / "quick_fig3_coverage.png").is_file()


@pytest.mark.slow
def test_h_hang_on_each_representation_is_trained_alike_and_planned_with(tmp_path):
    """Tab. 3's baselines (tiny: 2 scenes of data, 1 held out, 2 steps, one scene planned
    with 64 evaluations): each model folder says what it reads, each is scored on the
    held-out scene and a bench ran with it, and the report sets a row per representation
    beside the paper's best row of it."""
    sizes = replace(QUICK, hang_representations=tuple(HANG_REPRESENTATIONS),
                    hang_train_scenes=2, hang_test_scenes=1, hang_train_steps=2,
                    hang_representation_scenes=1, hang_representation_methods=("sampling_k1",),
                    hang_evaluations=64, hang_every_collision_row=True)
    steps = Steps(tmp_path, progress=False)
    results = hang_representations(steps, sizes, workers=1, ray=None)
    assert list(results) == list(HANG_REPRESENTATIONS)
    specs = {key: json.loads(next(tmp_path.glob(f"steps/train_hang_{key}-*/model/spec.json"))
                             .read_text()) for key in results}
    assert [(s["representation"], s["cloud_encoder"]) for s in specs.values()] == [
        ("sdf", "pointnet"), ("occupancy", "pointnet"), ("smooth_occupancy", "pointnet"),
        ("pointcloud", "pointnet"), ("pointcloud", "pointnet2")]
    for key, step in results.items():
        # H_coll on ψ for the ψ models; the point clouds also without a collision row
        collision = "model" if key in ("occupancy", "smooth1000") else "sdf"
        assert ("bench_none" in step) == key.startswith("pointnet")
        for name in ("bench", "bench_none"):
            if name not in step:
                continue
            bench = step[name]
            run = json.loads((tmp_path / bench["folder"] / "bench" / "run.json").read_text())
            assert run["evaluations"] == 64 and f"/train_hang_{key}-" in run["model"]
            assert run["collision"] == (collision if name == "bench" else "none")
            assert run["threading"] is False and run["check"] is None, "the paper's protocol"
            assert bench["result"]["sampling_k1"]["found"] in (0.0, 1.0)
        held_out = step["train"]["result"]["validation"]
        assert held_out["samples"] == 20 and "k1" in held_out
    shipped = {"result": {"opt_sampling": {"found": 1.0, "sim_success": 1.0,
                                           "collision_free": 1.0, "total": 1.0},
                          "median_seconds": 9.0}}
    blocks = tab3_blocks({"tab3": shipped, "tab3_representations": results}, sizes)
    tables = [b for b in blocks if b[0] == "table"]
    assert tables[0][2][0][0] == "opt_sampling" and tables[0][2][0][-1].endswith("87.3")
    rows = tables[1][2]
    labels = [label for label, *_ in HANG_REPRESENTATIONS.values()]
    assert [r[0] for r in rows] == [*labels[:4], "PointNet, no collision row", labels[4],
                                    "PointNet++, no collision row"]
    assert rows[1][-1].endswith("total 34.0") and all(r[1] == "sampling_k1" for r in rows)
    assert rows[4][-1] == "" and "no collision" in blocks[-3][1]
    held = tables[2][2]
    assert [r[0] for r in held] == labels
    assert all(len(r[2].split(" / ")) == 3 for r in held)


def test_a_missing_steps_time_is_scaled_from_another_sizes_ledger(tmp_path):
    from robotplan.bench.reproduce import scaled_seconds

    quick = tmp_path / "quick"
    quick.mkdir()
    (quick / "bench_push.json").write_text(json.dumps(
        {"key": "k", "seconds": 30.0, "params": {"scenes": 2, "seed": 0}}))
    assert scaled_seconds("bench_push", {"scenes": 20, "seed": 0}, [quick]) == 300.0
    assert scaled_seconds("bench_hang", {"scenes": 20}, [quick]) is None
    (quick / "train_rigid_sdf.json").write_text(json.dumps(
        {"key": "k", "seconds": 20.0, "params": {"steps": 250, "spec": {}}}))
    # another seed, another representation, a larger batch: the nearest measured step
    assert scaled_seconds("train_rigid_sdf_seed1", {"steps": 500}, [quick]) == 40.0
    assert scaled_seconds("train_rigid_pointnet2", {"steps": 500, "batch": 128},
                          [quick]) == 160.0
    assert scaled_seconds("train_flow_sdf", {"steps": 500}, [quick]) is None


def test_status_lists_every_step_without_running_any(tmp_path, capsys):
    from tests.cli.test_app import call

    res = call(capsys, "reproduce", "--out", str(tmp_path / "r"), "--quick", "--status",
               "--ledger", "none")
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert lines[-1].startswith("quick: 0 of ") and "never run" in lines[-1]
    assert all(line.split()[0] == "missing" for line in lines[:-1])
    assert {"data_test", "bench_push", "bench_hang"} <= {line.split()[1] for line in lines[:-1]}
    assert not (tmp_path / "r" / "steps").exists()


def test_a_row_of_two_seeds_pools_their_scenes_and_shows_an_interval():
    """Two seeds' evaluations of the same scenes: the row's mean is the seeds' mean, its
    interval holds it, and the turn gain is pooled per shape."""
    from robotplan.bench.reproduce_models import seeded, training_config

    def evaluation(err: float) -> dict:
        n = [4.0, 4.0, 4.0]
        sums = {"scene": [0, 1, 2], "contact": n, "shape": ["box", "lshape", "box"],
                **{k: [err * 4 * (1 + 0.1 * i) for i in range(3)]
                   for k in ("x_mm", "y_mm", "alpha_deg")},
                **{f"baseline_{k}": [40.0] * 3 for k in ("x_mm", "y_mm", "alpha_deg")},
                "turn_product": [2.0, 1.0, 2.0], "turn_square": [4.0, 4.0, 4.0]}
        mean = sum(sums["x_mm"]) / 12
        dq = {k: [mean, 1.0] for k in ("x_mm", "y_mm", "alpha_deg")}
        return {"result": {"delta_q_error": dq, "baseline_delta_q_error": dq,
                           "turn_gain": {"box": 0.5, "lshape": 0.25}, "by_scene": sums}}

    sizes = replace(QUICK, training_seeds=(0, 1))
    rows = tab56_rows({"rigid_test": evaluation(2.0),
                       "reps_test": {"sdf": [evaluation(2.0), evaluation(4.0)]}},
                      "test", TAB5, sizes)
    row = rows[1]
    assert row[0] == f"F_q on SDF, {sizes.representation_steps} steps, 2 seeds"
    mean = float(row[1].split(" ± ")[0])
    lo, hi = (float(v) for v in row[1].split("[")[1].rstrip("]").split(", "))
    assert mean == pytest.approx(3.3, abs=0.01) and lo <= mean <= hi
    assert row[4].startswith("boxes 0.50 [") and "L-shapes 0.25" in row[4]
    assert seeded("train_rigid_sdf", 0) == "train_rigid_sdf"
    assert seeded("train_rigid_sdf", 1) == "train_rigid_sdf_seed1"
    cfg = training_config(100, 1, {"encoder": "joint"}, (("batch", 128),))
    assert cfg["seed"] == 1 and cfg["batch"] == 128 and "seed" not in training_config(
        100, 0, {})


def test_tab3_shares_carry_intervals_over_the_scenes_they_are_of():
    from robotplan.hanging.bench.report import _cells

    summary = {"scenes": 150, "opt_sampling": {"found": 1.0, "sim_success": 0.5,
                                               "collision_free": 1.0, "total": 0.5}}
    found, sim, free, total = _cells(summary, "opt_sampling")
    assert found == "100.0 [100.0, 100.0]" and free == "100.0 [100.0, 100.0]"
    lo, hi = (float(v) for v in total.split("[")[1].rstrip("]").split(", "))
    assert total.startswith("50.0 [") and 40 < lo < 50 < hi < 60 and sim == total


def test_reproduce_refuses_no_time_budget_no_threads_and_an_absent_device(tmp_path, capsys):
    import torch

    bad = [("--hours", "0"), ("--threads", "0")]
    if not torch.cuda.is_available():
        bad.append(("--device", "cuda"))
    for flag, value in bad:
        assert main(["reproduce", "--out", str(tmp_path / "r"), "--quick", flag, value]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and flag in err
