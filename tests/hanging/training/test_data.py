"""Hanging data from real pybullet drops: tiny (two scenes), deterministic per seed, every
kept label reproduced by dropping the pose again in a fresh world, resumable folders."""

import json

import numpy as np
import torch

from robotplan.cli.app import main
from robotplan.geometry.transforms import perturbed_poses, spatial_to_world, uniform_poses
from robotplan.hanging.execution.world import HangWorld
from robotplan.hanging.training.data import (
    DRAWN,
    JITTER,
    NEAR_ARM,
    SETTLED,
    HangDataSpec,
    decode_hook,
    decode_mug,
    handle_on_arm_poses,
    load_hang_shards,
    simulate_hang_scene,
)
from robotplan.sdf.mug_hook import polyline_distance


def test_every_scene_has_a_hang_and_poses_about_where_it_came_to_rest(tiny_hang_data):
    d = load_hang_shards(tiny_hang_data)
    assert d["poses"].shape == (3, 20, 7) and d["hangs"].shape == (3, 20)
    assert d["found"].all() and np.all(d["draws"] >= 1)
    spec, role = HangDataSpec(), d["role"]
    assert np.all(role[:, 0] == SETTLED)
    for s in range(3):
        near = d["poses"][s, role[s] == JITTER, :3]
        assert 1 <= len(near) <= spec.jitter and np.all(role[s, 1:1 + len(near)] == JITTER)
        assert 1 <= (role[s] == NEAR_ARM).sum() <= spec.near_arm
        assert not d["collision"][s, role[s] == NEAR_ARM].any(), "kept clear of the hook"
        assert np.all(np.linalg.norm(near - d["poses"][s, 0, :3], axis=-1)
                      < 6 * spec.jitter_shift + spec.jitter_lift)
        assert d["caught"][s, np.argmax(role[s] == DRAWN)], "the drawn pose that hung"
    assert np.all(d["hangs"] <= d["caught"]), "in place is a kind of hang"
    assert d["hangs"].sum() >= 3 and (d["caught"] & ~d["hangs"]).any()
    assert np.allclose(np.linalg.norm(d["poses"][..., 3:], axis=-1), 1.0)


def test_labels_are_reproduced_by_a_fresh_drop(tiny_hang_data):
    d = load_hang_shards(tiny_hang_data)
    for s in range(3):
        mug, hook = decode_mug(d["mug"][s]), decode_hook(d["hook"][s], *d["hook_radii"][s])
        with HangWorld(hook, mug) as world:
            results = [world.drop(X) for X in d["poses"][s][::-1]][::-1]
        assert [r.in_place() for r in results] == d["hangs"][s].tolist()
        assert [r.hangs for r in results] == d["caught"][s].tolist()
        assert [r.collision_at_start for r in results] == d["collision"][s].tolist()


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


def test_perturbed_poses_spread_as_asked(rng):
    X0 = np.array([0.1, 0.0, 0.3, np.cos(0.4), 0.0, np.sin(0.4), 0.0])
    X = perturbed_poses(rng, X0, 0.01, np.radians(8.0), 20_000)
    assert np.all(np.abs(X[:, :3].std(0) - 0.01) < 5e-4)
    turn = 2 * np.arccos(np.clip(np.abs(X[:, 3:] @ X0[3:]), 0.0, 1.0))
    # the angle of a rotation vector with N(0, σ²) per axis follows a Maxwell law, mean 2σ√(2/π)
    assert abs(turn.mean() - 2 * np.radians(8.0) * np.sqrt(2 / np.pi)) < np.radians(0.2)
    assert np.allclose(np.linalg.norm(X[:, 3:], axis=1), 1.0) and np.all(X[:, 3] >= 0)


def test_handle_on_arm_poses_put_the_handle_on_the_arm(rng):
    mug = decode_mug(np.array([0.04, 0.1, 0.6, 0.03, 0.03, 0.006, 0.005]))
    arm = np.array([[0.0, 0.0, 0.3], [0.12, 0.0, 0.32], [0.15, 0.0, 0.36]])
    X = handle_on_arm_poses(rng, arm, mug.handle_points(), 0.0, 200)
    line = mug.handle_points()
    t = np.linspace(0.0, 1.0, 50)[:, None, None]
    dense = torch.from_numpy((line[:-1] + t * (line[1:] - line[:-1])).reshape(-1, 3))
    # with no spread, some point of the handle's centre line lies on the arm's
    on = spatial_to_world(dense[None].expand(200, -1, -1), torch.from_numpy(X)).numpy()
    gap = np.array([polyline_distance(torch.from_numpy(p), arm).min().item() for p in on])
    assert np.all(gap < 1e-3)


def test_random_poses_are_uniform_rotations(rng):
    X = uniform_poses(rng, np.zeros(3), 0.4, 20_000)
    assert np.abs(X[:, :3]).max() <= 0.2
    # uniform on SO(3): the rotated z axis is uniform on the sphere, its z mean 0, var 1/3
    w, x, y, _ = X[:, 3:].T
    zz = 1 - 2 * (x * x + y * y)
    assert abs(zz.mean()) < 0.02 and abs(zz.var() - 1 / 3) < 0.02
    assert np.all(w >= 0)
