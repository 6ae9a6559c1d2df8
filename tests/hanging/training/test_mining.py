"""Mining hard examples for H_hang: the planner's end poses, dropped in pybullet and labelled,
stored in the hang data format and trained on beside the drawn data."""

import json

import numpy as np
import pytest
import torch

from robotplan.cli.app import main
from robotplan.hanging.execution.world import HangWorld
from robotplan.hanging.models.hang_model import (
    HangSpec,
    HangSuccess,
    load_hang_model,
    save_hang_model,
)
from robotplan.hanging.program.problem import HangProblem
from robotplan.hanging.training.data import OPTIMISED, decode_hook, decode_mug, load_hang_shards
from robotplan.hanging.training.train import HangSamples, HangTrainConfig, train_hang
from tests.conftest import TINY_HANG_SPEC


@pytest.fixture(scope="module")
def tiny_model(tmp_path_factory):
    torch.manual_seed(3)
    out = tmp_path_factory.mktemp("hang_tiny_model")
    save_hang_model(HangSuccess(HangSpec(**TINY_HANG_SPEC)), out)
    return out


@pytest.fixture(scope="module")
def mined(tiny_hang_data, tiny_model, tmp_path_factory):
    out = tmp_path_factory.mktemp("mined") / "m"
    assert main(["data", "hang-mine", "--data", str(tiny_hang_data), "--model",
                 str(tiny_model), "--out", str(out), "--scenes", "2", "--starts", "1",
                 "--workers", "1"]) == 0
    return out


def test_mined_poses_are_labelled_by_their_own_drop(mined, tiny_model):
    d = load_hang_shards(mined)
    assert d["poses"].shape == (2, 1, 7) and (d["role"] == OPTIMISED).all()
    assert np.allclose(np.linalg.norm(d["poses"][..., 3:], axis=-1), 1.0, atol=1e-9)
    model = load_hang_model(tiny_model)
    for s in range(2):
        mug, hook = decode_mug(d["mug"][s]), decode_hook(d["hook"][s], *d["hook_radii"][s])
        X = d["poses"][s, 0]
        with HangWorld(hook, mug) as world:
            drop = world.drop(X)
        assert drop.in_place(world.physics) == d["hangs"][s, 0]
        assert drop.hangs == d["caught"][s, 0]
        assert drop.collision_at_start == d["collision"][s, 0]
        h = HangProblem(model, mug, hook).hang_values(X[None])[0]
        assert abs(h - d["h_model"][s, 0]) < 1e-6 * max(1.0, abs(h))


def test_mining_again_is_a_no_op_and_other_settings_are_refused(mined, tiny_hang_data,
                                                                tiny_model, capsys):
    args = ["data", "hang-mine", "--data", str(tiny_hang_data), "--model", str(tiny_model),
            "--out", str(mined), "--scenes", "2", "--workers", "1"]
    assert main([*args, "--starts", "1"]) == 0
    assert json.loads(capsys.readouterr().out)["made_shards"] == 0
    assert main([*args, "--starts", "3"]) == 2
    assert "spec" in capsys.readouterr().err


def test_mining_starts_at_a_chosen_scene(tiny_hang_data, tiny_model, tmp_path):
    out = tmp_path / "m"
    assert main(["data", "hang-mine", "--data", str(tiny_hang_data), "--model",
                 str(tiny_model), "--out", str(out), "--first", "2", "--starts", "1",
                 "--workers", "1"]) == 0
    d, source = load_hang_shards(out), load_hang_shards(tiny_hang_data)
    assert d["scene_index"].tolist() == source["scene_index"][2:].tolist()
    assert np.array_equal(d["mug"], source["mug"][2:])


def test_bad_mining_input_exits_2(tmp_path, tiny_hang_data, tiny_model, capsys):
    assert main(["data", "hang-mine", "--data", str(tmp_path / "none"), "--out",
                 str(tmp_path / "o")]) == 2
    assert main(["data", "hang-mine", "--data", str(tiny_hang_data), "--model",
                 str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    assert main(["data", "hang-mine", "--data", str(tiny_hang_data), "--model",
                 str(tiny_model), "--out", str(tmp_path / "o"), "--first", "3"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert "--data: no such folder" in err[0] and "--model" in err[1]
    assert "--first 3" in err[2] and "3 scenes" in err[2]


def test_training_reads_mined_folders_beside_the_data(mined, tiny_hang_data, tiny_model,
                                                      tmp_path):
    spec = HangSpec(**TINY_HANG_SPEC)
    both = HangSamples([tiny_hang_data, mined], spec)
    base = HangSamples(tiny_hang_data, spec)
    assert len(both) == len(base) + 2 and (both.source[len(base):] == 1).all()
    assert both.scene[len(base):].min() == base.scene.max() + 1
    d = load_hang_shards(mined)
    assert torch.equal(both.hangs[len(base):], torch.from_numpy(d["hangs"].reshape(-1)))
    cfg = HangTrainConfig(data=str(tiny_hang_data), out=str(tmp_path / "m"),
                          test=str(tiny_hang_data), mined=[str(mined)], mined_repeat=3,
                          init=str(tiny_model), steps=2, batch=8, val_every=2)
    row = train_hang(cfg, progress=False)
    history = json.loads((tmp_path / "m" / "training.json").read_text())
    assert history["samples"]["train"] == len(base) + 2 * 3
    start = load_hang_model(tiny_model)
    # step 0 validates the initial weights: the model it started from
    first = history["history"][0]["validation"]["loss"]
    assert row["step"] == 2 and first == pytest.approx(_loss(start, base), rel=1e-4)


def _loss(model, samples):
    from robotplan.hanging.training.train import hang_metrics

    return hang_metrics(model, samples, np.arange(len(samples)))["loss"]
