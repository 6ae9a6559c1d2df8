"""Push data: real pybullet rollouts, deterministic per seed, resumable, physically sane."""

import json

import numpy as np
import pytest
import torch

from robotplan.pushing.training.push_data import generate, load_shards, simulate_scene
from robotplan.pushing.training.samples import PushSamples, object_sdf
from robotplan.sdf import Box, LShape, Workspace


def test_scene_is_deterministic_for_seed_and_index():
    a, b = simulate_scene(3, seed=11), simulate_scene(3, seed=11)
    assert np.array_equal(a.object_pose, b.object_pose)
    assert np.array_equal(a.contact, b.contact)
    c = simulate_scene(4, seed=11)
    assert a.shape != c.shape or not np.array_equal(a.object_pose[0], c.object_pose[0])


def test_scene_ranges_and_pushes_move_the_object():
    moved = 0
    for i in range(8):
        r = simulate_scene(i, seed=2)
        assert 0.02 <= r.pusher_radius <= 0.05
        if isinstance(r.shape, Box):
            assert all(0.08 <= s <= 0.30 for s in r.shape.size)
        else:
            assert isinstance(r.shape, LShape)
            assert all(0.12 <= s <= 0.30 for s in r.shape.size)
            assert 0.05 <= r.shape.thickness <= min(0.10, 0.6 * min(r.shape.size)) + 1e-9
        step = np.linalg.norm(np.diff(r.object_pose[:, :2], axis=0), axis=1)
        # the object only moves in steps with contact (quasi-static pushing)
        if (~r.contact[1:]).any():
            assert step[~r.contact[1:]].max() < 2e-3
        moved += step.sum() > 0.05
    assert moved >= 4, "most scenes push the object a few centimetres"


def test_generate_is_resumable_and_deterministic(tiny_push_data, tmp_path):
    meta = json.loads((tiny_push_data / "meta.json").read_text())
    assert meta["seed"] == 5 and meta["physics"]["keep_every"] == 20
    shards = sorted(tiny_push_data.glob("shard_*.npz"))
    assert len(shards) == 3
    # a partial copy finishes without redoing finished shards, and equals the original
    copy = tmp_path / "copy"
    copy.mkdir()
    for p in [tiny_push_data / "meta.json", *shards[:2]]:
        (copy / p.name).write_bytes(p.read_bytes())
    summary = generate(copy, scenes=12, seed=5, workers=1, shard_size=4, progress=False)
    assert summary["made_shards"] == 1
    a, b = load_shards(copy), load_shards(tiny_push_data)
    for key in a:
        assert np.array_equal(a[key], b[key], equal_nan=True), key
    # the shard made again has the same bytes; where and how long it ran is kept apart
    assert (copy / shards[2].name).read_bytes() == shards[2].read_bytes()
    run = json.loads((copy / "run.json").read_text())
    assert run["executor"] == "processes" and run["units"] == 1 and run["shards"] == 1


def test_ray_tasks_write_the_bytes_local_processes_write(tmp_path):
    """A local Ray cluster of 2 workers against 2 local processes: the same files, byte for
    byte, but for run.json."""
    pytest.importorskip("ray")
    local, on_ray = tmp_path / "local", tmp_path / "ray"
    generate(local, scenes=4, seed=7, workers=2, shard_size=1, progress=False)
    generate(on_ray, scenes=4, seed=7, workers=2, shard_size=1, progress=False, ray="local")
    names = sorted(p.name for p in local.iterdir())
    assert names == sorted(p.name for p in on_ray.iterdir())
    assert len(names) == 6  # four shards, meta.json, run.json
    for name in names:
        if name != "run.json":
            assert (local / name).read_bytes() == (on_ray / name).read_bytes(), name
    run = json.loads((on_ray / "run.json").read_text())
    assert run["executor"] == "ray" and run["workers"] == 2 and run["units"] == 4
    assert sum(run["hosts"].values()) == 4


def test_other_settings_in_the_same_folder_are_refused(tiny_push_data):
    with pytest.raises(ValueError, match="seed"):
        generate(tiny_push_data, scenes=12, seed=6, workers=1, shard_size=4, progress=False)


def test_contact_flags_agree_with_geometry(tiny_push_data):
    s = PushSamples(tiny_push_data)
    b = s.batch(np.arange(len(s)), dtype=torch.float64)
    # distance between pusher surface and object at t
    gap = object_sdf(b.params, b.object_now, b.pusher_now[:, None, :])[:, 0] - b.radius
    contact = b.contact.numpy()
    assert contact.mean() > 0.3
    assert np.median(gap.numpy()[contact]) < 0.01
    assert np.median(gap.numpy()[~contact]) > 0.01


def test_no_motion_baseline_is_zero_without_contact(tiny_push_data):
    s = PushSamples(tiny_push_data)
    b = s.batch(np.arange(len(s)), dtype=torch.float64)
    g = Workspace().points(torch.float64)[::4, ::4].reshape(1, -1, 2)
    base = (b.phi1_now(g) - b.phi1_prev(g)).pow(2).mean(1).sqrt().numpy()
    assert base[~b.contact.numpy()].max() < 2e-3
    assert base[b.contact.numpy()].mean() > 2e-3


def test_unseen_footprints_are_pushed_stored_and_rendered_exactly(tiny_ood_push_data):
    """``shapes="ood"``: scene i is family i mod 8, simulated in pybullet, stored in the
    shards and rendered by its own SDF; contact flags agree with that geometry."""
    d = load_shards(tiny_ood_push_data)
    assert sorted(d["shape_type"].tolist()) == [2] * 7 + [3]  # 7 polygons and the disc
    s = PushSamples(tiny_ood_push_data)
    assert s.footprints is not None
    b = s.batch(np.arange(len(s)), dtype=torch.float64)
    for i in (0, len(s) // 2, len(s) - 1):
        shape = s.footprints[s.scene[i]]
        x, y, yaw = b.object_now[i].tolist()
        point = torch.tensor([[[x + 0.01, y - 0.02]]], dtype=torch.float64)
        c, sn = np.cos(yaw), np.sin(yaw)
        body = torch.tensor([[0.01 * c - 0.02 * sn, -0.01 * sn - 0.02 * c]],
                            dtype=torch.float64)
        assert float(b.slice(i, i + 1).phi1_now(point)[0, 0]) == pytest.approx(
            float(shape.sdf(body)[0]), abs=1e-9)
    gap = torch.stack([b.slice(i, i + 1).phi1_now(b.pusher_now[i][None, None])[0, 0]
                       for i in range(len(s))]) - b.radius
    contact = b.contact.numpy()
    assert contact.mean() > 0.2
    assert np.median(gap.numpy()[contact]) < 0.01
    assert np.median(gap.numpy()[~contact]) > 0.01


def test_scene_families_name_each_scene_footprint(tiny_push_data, tiny_ood_push_data):
    """Training data: box or lshape as stored; unseen footprints: family i mod 8, each one
    the footprint the scene holds (a disc for the circle, polygons of its vertex count)."""
    from robotplan.pushing.training.footprints import OOD_FAMILIES
    from robotplan.pushing.training.push_data import scene_families, scene_footprint
    from robotplan.sdf import Box, Circle, LShape, Polygon

    d = load_shards(tiny_push_data)
    names = scene_families(tiny_push_data, d)
    kinds = {Box: "box", LShape: "lshape"}
    assert names.tolist() == [kinds[type(scene_footprint(d, k))] for k in range(len(names))]
    assert set(names) == {"box", "lshape"}
    d = load_shards(tiny_ood_push_data)
    names = scene_families(tiny_ood_push_data, d)
    assert sorted(names.tolist()) == sorted(OOD_FAMILIES)
    corners = {"triangle": 3, "trapezoid": 4, "pentagon": 5, "hexagon": 6, "T": 8, "U": 8,
               "cross": 12}
    for k, name in enumerate(names):
        shape = scene_footprint(d, k)
        if name == "circle":
            assert isinstance(shape, Circle)
        else:
            assert isinstance(shape, Polygon) and len(shape.vertices) == corners[name]


def test_push_data_from_mujoco_reads_as_pybullets(tiny_push_data, tmp_path):
    """The same scenes simulated in MuJoCo: the folder names its simulator and holds the
    same arrays (the same draws, the same footprints) with pushes that move the objects; an
    older folder reads as pybullet's, and a folder of one simulator refuses the other's."""
    from dataclasses import replace

    from robotplan.execution.physics import PHYSICS
    from robotplan.pushing.training.push_data import data_simulator

    mujoco = tmp_path / "mujoco"
    generate(mujoco, scenes=12, seed=5, workers=1, shard_size=4, progress=False,
             physics=replace(PHYSICS, simulator="mujoco"))
    assert data_simulator(mujoco) == "mujoco" and data_simulator(tiny_push_data) == "pybullet"
    a, b = load_shards(mujoco), load_shards(tiny_push_data)
    assert set(a) == set(b)
    for key in ("shape_type", "size", "pusher_radius"):
        assert np.array_equal(a[key], b[key]), key
    moved = np.linalg.norm(np.diff(a["object_pose"][:, :2], axis=0), axis=1)
    assert a["contact"].any() and moved[moved < 0.1].max() > 0.005  # pushes move objects
    with pytest.raises(ValueError, match="physics"):
        generate(mujoco, scenes=12, seed=5, workers=1, shard_size=4, progress=False)
