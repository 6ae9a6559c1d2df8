"""H_hang trained by our own code on tiny real data: the loss (eq. 21) falls, runs resume,
folders load safely, the functional's pose Jacobian matches central differences in float64."""

import json

import numpy as np
import pytest
import torch

from robotplan.cli.app import main
from robotplan.hanging.functionals.h_hang import HangSuccessFunctional
from robotplan.hanging.models.hang_model import HangSpec, HangSuccess, hang_loss, load_hang_model
from robotplan.hanging.training.data import decode_hook, decode_mug, load_hang_shards
from robotplan.hanging.training.train import HangTrainConfig, train_hang
from tests.conftest import TINY_HANG_SPEC


def test_loss_is_eq_21():
    h = torch.tensor([0.0, 0.5, 0.0, 3.0])
    y = torch.tensor([True, True, False, False])
    expected = (0.0 + 0.25 + 1.0 + np.exp(-3.0)) / 4
    assert abs(float(hang_loss(h, y)) - expected) < 1e-7


def test_the_papers_network_shapes():
    model = HangSuccess(HangSpec())
    assert model(torch.zeros(3, 2, 40, 40, 40)).shape == (3,)
    convs = [m for m in model.encoder if isinstance(m, torch.nn.Conv3d)]
    assert [c.out_channels for c in convs] == [3, 5, 5]
    assert [c.kernel_size[0] for c in convs] == [3, 5, 5]
    assert [c.stride[0] for c in convs] == [1, 2, 2]


@pytest.fixture(scope="module")
def trained(tiny_hang_data, tmp_path_factory):
    out = tmp_path_factory.mktemp("hang_model")
    cfg = HangTrainConfig(data=str(tiny_hang_data), out=str(out), test=str(tiny_hang_data),
                          steps=40, batch=16, lr=3e-3, warmup=5, val_every=40,
                          spec=TINY_HANG_SPEC)
    train_hang(cfg, progress=False)
    return out


def test_training_lowers_the_loss_and_writes_the_folder(trained):
    history = json.loads((trained / "training.json").read_text())["history"]
    first, last = history[0]["validation"], history[-1]["validation"]
    assert history[0]["step"] == 0 and history[-1]["step"] == 40
    assert last["loss"] < 0.8 * first["loss"]
    model = load_hang_model(trained)
    assert model.spec.features == TINY_HANG_SPEC["features"]


def test_a_run_resumes_where_it_stopped(trained, tiny_hang_data):
    assert main(["train", "hang", "--data", str(tiny_hang_data), "--out", str(trained),
                 "--resume", "--steps", "45", "--threads", "1"]) == 0
    history = json.loads((trained / "training.json").read_text())["history"]
    assert history[-1]["step"] == 45
    assert [h["step"] for h in history].count(40) == 1


def test_eval_prints_the_thresholds(trained, tiny_hang_data, capsys):
    assert main(["eval", "hang", "--model", str(trained), "--data", str(tiny_hang_data),
                 "--json", "--threads", "1"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["samples"] == 60 and set(result) >= {"k1", "k2", "k3", "loss"}


def test_bad_folders_exit_2(tmp_path, tiny_hang_data, trained, capsys):
    assert main(["train", "hang", "--data", str(tmp_path / "none"), "--out",
                 str(tmp_path / "m")]) == 2
    assert main(["train", "hang", "--data", str(tiny_hang_data), "--out", str(trained)]) == 2
    assert main(["eval", "hang", "--model", str(tiny_hang_data), "--data",
                 str(tiny_hang_data)]) == 2
    err = capsys.readouterr().err
    assert "--data: no such folder" in err and "not empty" in err and "spec.json" in err


# the paper's baselines (app. A.5), tiny: ψ_s of b = 1000, PointNet and PointNet++ clouds
BASELINES = {"smooth_occupancy": {"representation": "smooth_occupancy"},
             "pointnet": {"representation": "pointcloud", "cloud_points": 64,
                          "cloud_widths": (8, 16)},
             "pointnet2": {"representation": "pointcloud", "cloud_encoder": "pointnet2",
                           "cloud_points": 64, "cloud_widths": (8, 16), "cloud_centroids": 8,
                           "cloud_neighbours": 4, "cloud_local_widths": (8,)}}


@pytest.mark.parametrize("representation", ["sdf", *BASELINES])
def test_pose_jacobian_against_central_differences(tiny_hang_data, representation):
    """Through 64,000 grid cells and the ReLUs the map is piecewise smooth: a step may cross a
    kink (large steps) or drown in rounding (small ones), so each column must match at one of
    three step sizes; a wrong Jacobian matches at none. For the baselines the gradient runs
    through ψ_s = tanh(b φ) or through the boundary clouds' interpolated vertices."""
    d = load_hang_shards(tiny_hang_data)
    mug, hook = decode_mug(d["mug"][0]), decode_hook(d["hook"][0], *d["hook_radii"][0])
    torch.manual_seed(0)
    model = HangSuccess(HangSpec(**TINY_HANG_SPEC,
                                 **BASELINES.get(representation, {}))).double()
    functional = HangSuccessFunctional(model, mug, hook)
    X = torch.from_numpy(d["poses"][0][:3])
    _, (jac,) = functional.jacobians(X)
    assert jac.shape == (3, 1, 7) and jac.abs().max() > 0
    for k in range(7):
        errors = []
        for eps in (1e-6, 1e-7, 1e-8):
            step = torch.zeros(7, dtype=torch.float64)
            step[k] = eps
            with torch.no_grad():
                fd = (functional(X + step) - functional(X - step))[:, 0] / (2 * eps)
            errors.append(float(((jac[:, 0, k] - fd).abs() / (fd.abs() + 1e-6)).max()))
        assert min(errors) < 2e-4, (k, errors)


def test_the_occupancy_baseline_passes_no_gradient(tiny_hang_data):
    """ψ = sign(φ): H_hang is flat in the mug's pose (the paper's argument for SDFs)."""
    d = load_hang_shards(tiny_hang_data)
    mug, hook = decode_mug(d["mug"][0]), decode_hook(d["hook"][0], *d["hook_radii"][0])
    torch.manual_seed(0)
    model = HangSuccess(HangSpec(**TINY_HANG_SPEC, representation="occupancy")).double()
    _, (jac,) = HangSuccessFunctional(model, mug, hook).jacobians(
        torch.from_numpy(d["poses"][0][:3]))
    assert jac.shape == (3, 1, 7) and not jac.any()


@pytest.mark.parametrize("representation", ["occupancy", *BASELINES])
def test_baselines_train_and_load(tiny_hang_data, tmp_path, representation):
    fields = BASELINES.get(representation, {"representation": "occupancy"})
    cfg = HangTrainConfig(data=str(tiny_hang_data), out=str(tmp_path / "m"), steps=6,
                          batch=8, lr=3e-3, warmup=2, val_every=6,
                          spec={**TINY_HANG_SPEC, **fields})
    row = train_hang(cfg, progress=False)
    assert np.isfinite(row["validation"]["loss"])
    model = load_hang_model(tmp_path / "m")
    assert model.spec.representation == fields["representation"]
    assert model.spec.cloud_encoder == fields.get("cloud_encoder", "pointnet")
    assert model(torch.zeros(2, 2, 40, 40, 40) + 0.01).shape == (2,)


def test_train_hang_takes_the_representation_options(tiny_hang_data, tmp_path, capsys):
    out = tmp_path / "psi"
    assert main(["train", "hang", "--data", str(tiny_hang_data), "--out", str(out),
                 "--representation", "smooth_occupancy", "--sharpness", "500", "--steps", "1",
                 "--batch", "4", "--val-every", "1", "--threads", "1"]) == 0
    spec = json.loads((out / "spec.json").read_text())
    assert spec["representation"] == "smooth_occupancy" and spec["occupancy_sharpness"] == 500
    for bad, why in ((["--sharpness", "500"], "--sharpness: only with"),
                     (["--representation", "occupancy", "--cloud-encoder", "pointnet2"],
                      "--cloud-encoder: only with"),
                     (["--representation", "occupancy", "--init", str(out)],
                      "the --init model's spec sets them")):
        capsys.readouterr()
        assert main(["train", "hang", "--data", str(tiny_hang_data), "--out",
                     str(tmp_path / "bad"), *bad]) == 2
        err = capsys.readouterr().err
        assert why in err and len(err.strip().splitlines()) == 1
