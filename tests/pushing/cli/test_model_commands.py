"""``robotplan train push``: the widths and input representation of the model it builds,
and their refusals."""

from __future__ import annotations

import json
import sys

from robotplan.cli.app import main


def _train(data, out, *extra: str) -> int:
    return main(["train", "push", "--data", str(data), "--out", str(out), "--model", "rigid",
                 "--encoder", "joint", "--steps", "2", "--batch", "4", "--val-every", "100",
                 "--device", "cpu", "--threads", "1", *extra])


def test_train_push_builds_the_widths_it_is_given(tiny_push_data, tmp_path, capsys):
    assert _train(tiny_push_data, tmp_path / "fq", "--channels", "2,3,4", "--sdf-features",
                  "6", "--hidden", "16,8,5", "--kernels", "3,3,5", "--strides", "2,2,2") == 0
    spec = json.loads((tmp_path / "fq" / "spec.json").read_text())
    assert spec["channels"] == [2, 3, 4] and spec["sdf_features"] == 6
    assert spec["kernels"] == [3, 3, 5] and spec["strides"] == [2, 2, 2]
    assert spec["hidden"] == [16, 8, 5] and spec["encoder"] == "joint"
    capsys.readouterr()


def test_train_push_refuses_widths_that_build_no_model(tiny_push_data, tmp_path, capsys):
    """A wrong number of convolution widths: one line naming the option, exit 2, nothing
    written."""
    assert _train(tiny_push_data, tmp_path / "fq", "--channels", "4,8") == 2
    err = capsys.readouterr().err.strip()
    assert err == "error: --channels: 3 convolutions, got 2 values"
    assert not (tmp_path / "fq").exists()


def test_train_push_refuses_strides_that_shrink_the_grid_away(tiny_push_data, tmp_path,
                                                               capsys):
    assert _train(tiny_push_data, tmp_path / "fq", "--strides", "9,9,9") == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --kernels/--strides:") and "\n" not in err
    assert not (tmp_path / "fq").exists()


def test_train_push_builds_an_occupancy_baseline(tiny_push_data, tmp_path, capsys):
    """F_q on ψ_s = tanh(b φ) (paper eq. 11): the spec says so, and the trained folder loads
    and predicts."""
    import torch

    from robotplan.pushing.models.rigid import load_rigid

    assert _train(tiny_push_data, tmp_path / "fq", "--representation", "smooth_occupancy",
                  "--sharpness", "1000") == 0
    spec = json.loads((tmp_path / "fq" / "spec.json").read_text())
    assert spec["representation"] == "smooth_occupancy"
    assert spec["occupancy_sharpness"] == 1000.0
    model = load_rigid(tmp_path / "fq")
    assert model.encoder.representation == "smooth_occupancy" and model.encoder.scale == 1.0
    assert torch.isfinite(model(torch.rand(1, 3, 140, 140) - 0.5)).all()
    capsys.readouterr()


def test_train_push_refuses_point_clouds_for_f_flow(tiny_push_data, tmp_path, capsys):
    assert main(["train", "push", "--data", str(tiny_push_data), "--out", str(tmp_path / "m"),
                 "--model", "flow", "--representation", "pointcloud"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "error: --representation pointcloud: only with --model rigid (F_q)"
    assert not (tmp_path / "m").exists()


def test_train_push_refuses_an_encoder_option_it_cannot_use(tiny_push_data, tmp_path, capsys):
    for extra, why in ((("--sharpness", "100"), "only with --representation smooth_occupancy"),
                       (("--representation", "smooth_occupancy", "--sharpness", "-5"),
                        "-5.0 is not a positive number"),
                       (("--cloud-encoder", "pointnet2"), "only with --representation "
                                                          "pointcloud")):
        assert _train(tiny_push_data, tmp_path / "fq", *extra) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"error: {extra[-2]}:") and why in err and "\n" not in err
        assert not (tmp_path / "fq").exists()


def test_data_push_on_ray_without_the_package_is_one_line_and_writes_nothing(
        tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    argv = ["data", "push", "--scenes", "2", "--seed", "1", "--out", str(tmp_path / "d"),
            "--ray", "local"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("error: --ray needs the ray package")
    assert not (tmp_path / "d").exists()


def test_train_push_builds_an_object_frame_f_q(tiny_push_data, tmp_path, capsys):
    """``--frame object``: the spec carries the frame and the window X_h of 64 × 64 cm."""
    from robotplan.pushing.models.rigid import load_rigid

    assert _train(tiny_push_data, tmp_path / "fq", "--frame", "object") == 0
    spec = json.loads((tmp_path / "fq" / "spec.json").read_text())
    assert spec["frame"] == "object" and spec["grid"] == [64, 64]
    assert spec["workspace_center"] == [0.0, 0.0] and spec["workspace_size"] == [0.64, 0.64]
    assert load_rigid(tmp_path / "fq").spec.frame == "object"
    capsys.readouterr()


def test_train_push_refuses_what_an_object_frame_cannot_use(tiny_push_data, tmp_path, capsys):
    for extra, why in ((("--augment", "turns"), "without --augment turns"),
                       (("--rigid-loss", "sdf"), "--rigid-loss delta")):
        assert _train(tiny_push_data, tmp_path / "fq", "--frame", "object", *extra) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: --frame object:") and why in err and "\n" not in err
        assert not (tmp_path / "fq").exists()
    assert main(["train", "push", "--data", str(tiny_push_data), "--out", str(tmp_path / "m"),
                 "--model", "flow", "--frame", "object", "--augment", "headings"]) == 2
    assert (capsys.readouterr().err.strip()
            == "error: --augment headings: only with --model rigid (F_q)")
    assert not (tmp_path / "m").exists()
    for extra, why in ((("--placement-reach", "0.1"), "only with --augment placements"),
                       (("--augment", "placements", "--placement-reach", "nan"), "0 to 0.2 m")):
        assert _train(tiny_push_data, tmp_path / "fq", "--frame", "object", *extra) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: --placement-reach") and why in err and "\n" not in err
        assert not (tmp_path / "fq").exists()
    for window in ("headings", "placements"):
        assert _train(tiny_push_data, tmp_path / "fq", "--augment", window) == 2
        assert (capsys.readouterr().err.strip()
                == f"error: --augment {window}: only with --frame object")
        assert not (tmp_path / "fq").exists()


def test_eval_push_averages_over_the_views_it_is_given(tiny_push_data, tmp_path, capsys):
    """``--views 4`` scores the model averaged over the quarter turns (F_q in Tab. 5 and
    Tab. 2 terms); ``--views`` with ``--record`` would store what the network alone does not
    do, and is refused in one line, exit 2, nothing recorded."""
    assert _train(tiny_push_data, tmp_path / "fq") == 0
    capsys.readouterr()
    eval_push = ["eval", "push", "--model", str(tmp_path / "fq"), "--data",
                 str(tiny_push_data), "--per-scene", "2", "--threads", "1", "--device", "cpu",
                 "--json"]
    results = {}
    for views in ("1", "4"):
        assert main([*eval_push, "--views", views]) == 0
        results[views] = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert results["4"]["views"] == 4 and results["1"]["views"] == 1
    assert results["4"]["samples"] == results["1"]["samples"]
    assert results["4"]["delta_q_error"] != results["1"]["delta_q_error"]
    assert results["4"]["rmse_mm"]["contact"] > 0
    before = sorted(p.name for p in (tmp_path / "fq").iterdir())
    assert main([*eval_push, "--views", "8", "--record"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--views" in err[0] and str(tmp_path / "fq") in err[0]
    assert sorted(p.name for p in (tmp_path / "fq").iterdir()) == before


def test_an_object_frame_f_flow_trains_scores_and_fits(tiny_push_data, tmp_path, capsys):
    """``--model flow --frame object`` trains; ``eval push`` scores it on the table's X_h
    and fits poses to it through its H_F; turning its grid (``--views``) is refused in one
    line naming the model, exit 2."""
    out = tmp_path / "flow"
    assert main(["train", "push", "--data", str(tiny_push_data), "--out", str(out),
                 "--model", "flow", "--frame", "object", "--steps", "2", "--batch", "4",
                 "--points", "16", "--val-every", "100", "--threads", "1"]) == 0
    spec = json.loads((out / "spec.json").read_text())
    assert spec["kind"] == "flow" and spec["frame"] == "object" and spec["grid"] == [64, 64]
    capsys.readouterr()
    eval_push = ["eval", "push", "--model", str(out), "--data", str(tiny_push_data),
                 "--per-scene", "1", "--threads", "1", "--json"]
    assert main(eval_push) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["frame"] == "object" and result["baseline_rmse_mm"]["contact"] > 1.0
    assert main([*eval_push, "--pose-fit", "3"]) == 0
    fitted = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert fitted["pose_fit"]["samples"] == 3 and set(fitted["delta_q_error"]) == {
        "x_mm", "y_mm", "alpha_deg"}
    assert main([*eval_push, "--views", "4"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {out}") and "--views" in err and "\n" not in err
