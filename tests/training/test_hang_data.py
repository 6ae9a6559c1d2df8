"""Hanging data from real pybullet drops: tiny (two scenes), deterministic per seed, every
kept label reproduced by dropping the pose again in a fresh world, resumable folders."""

import json

import numpy as np

from robotplan.cli.main import main
from robotplan.execution.hang_world import HangWorld
from robotplan.geometry.transforms import uniform_poses
from robotplan.training.hang_data import (
    HangDataSpec,
    decode_hook,
    decode_mug,
    load_hang_shards,
    simulate_hang_scene,
)


def test_every_scene_has_a_success_and_its_settled_pose(tiny_hang_data):
    d = load_hang_shards(tiny_hang_data)
    assert d["poses"].shape == (3, 20, 7) and d["hangs"].shape == (3, 20)
    assert d["found"].all()
    assert np.all(d["hangs"].sum(1) >= 1) and np.all(d["hangs"].sum(1) <= 10)
    assert np.all(d["draws"] >= 1)
    assert np.allclose(np.linalg.norm(d["poses"][..., 3:], axis=-1), 1.0)


def test_labels_are_reproduced_by_a_fresh_drop(tiny_hang_data):
    d = load_hang_shards(tiny_hang_data)
    for s in range(3):
        mug, hook = decode_mug(d["mug"][s]), decode_hook(d["hook"][s], *d["hook_radii"][s])
        with HangWorld(hook, mug) as world:
            labels = [world.drop(X).hangs for X in d["poses"][s][::-1]][::-1]
        assert labels == d["hangs"][s].tolist()


def test_a_scene_is_the_same_for_its_seed(tiny_hang_data):
    d = load_hang_shards(tiny_hang_data)
    again = simulate_hang_scene(1, 0, HangDataSpec())
    assert np.array_equal(again.poses, d["poses"][1])
    assert again.draws == d["draws"][1]


def test_a_folder_resumes_and_refuses_other_settings(tiny_hang_data, capsys):
    meta = json.loads((tiny_hang_data / "meta.json").read_text())
    assert meta["scenes"] == 3 and meta["ranges"]["grid"]["cells"] == 40
    assert main(["data", "hang", "--scenes", "3", "--seed", "0", "--out",
                 str(tiny_hang_data), "--workers", "1", "--shard-size", "2"]) == 0
    assert json.loads(capsys.readouterr().out.strip().splitlines()[-1])["made_shards"] == 0
    assert main(["data", "hang", "--scenes", "3", "--seed", "1", "--out",
                 str(tiny_hang_data)]) == 2
    assert "seed" in capsys.readouterr().err


def test_random_poses_are_uniform_rotations(rng):
    X = uniform_poses(rng, np.zeros(3), 0.4, 20_000)
    assert np.abs(X[:, :3]).max() <= 0.2
    # uniform on SO(3): the rotated z axis is uniform on the sphere, its z mean 0, var 1/3
    w, x, y, _ = X[:, 3:].T
    zz = 1 - 2 * (x * x + y * y)
    assert abs(zz.mean()) < 0.02 and abs(zz.var() - 1 / 3) < 0.02
    assert np.all(w >= 0)
