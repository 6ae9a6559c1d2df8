"""Poses inside the hook for H_hang: drawn near where a scene's mug hangs, kept only where
pybullet says the mug starts in collision, labelled failures without a drop."""

import json

import numpy as np

from robotplan.cli.app import main
from robotplan.hanging.execution.world import HangWorld
from robotplan.hanging.training.data import IN_HOOK, decode_hook, decode_mug, load_hang_shards
from robotplan.hanging.training.train import HangSamples
from tests.conftest import TINY_HANG_SPEC


def _make(data, out, *extra) -> int:
    return main(["data", "hang-in-hook", "--data", str(data), "--out", str(out),
                 "--per-scene", "4", "--shard-size", "2", *extra])


def _scene(d, s):
    return decode_hook(d["hook"][s], *d["hook_radii"][s]), decode_mug(d["mug"][s])


def test_every_pose_falls_because_it_starts_in_the_hook(tiny_hang_data, tmp_path):
    out = tmp_path / "in_hook"
    assert _make(tiny_hang_data, out, "--workers", "1") == 0
    d, source = load_hang_shards(out), load_hang_shards(tiny_hang_data)
    assert d["poses"].shape == (3, 4, 7) and (d["role"] == IN_HOOK).all()
    assert not d["hangs"].any() and not d["caught"].any() and d["collision"].all()
    assert np.array_equal(d["mug"], source["mug"])
    for s in range(3):
        hook, mug = _scene(d, s)
        with HangWorld(hook, mug) as world:
            for X in d["poses"][s]:
                drop = world.drop(X)  # the full test the label stands in for
                assert drop.collision_at_start and not drop.in_place(world.physics)
            above = d["poses"][s, 0] + np.array([0, 0, 1.0, 0, 0, 0, 0])
            assert not world.collides(above)


def test_collides_agrees_with_the_drop_on_the_labelled_data(tiny_hang_data):
    d = load_hang_shards(tiny_hang_data)
    for s in range(3):
        hook, mug = _scene(d, s)
        with HangWorld(hook, mug) as world:
            assert [world.collides(X) for X in d["poses"][s]] == d["collision"][s].tolist()


def test_the_folder_is_the_same_for_any_workers_and_a_rerun_is_a_no_op(tiny_hang_data,
                                                                       tmp_path, capsys):
    one, two = tmp_path / "one", tmp_path / "two"
    assert _make(tiny_hang_data, one, "--workers", "1") == 0
    assert _make(tiny_hang_data, two, "--workers", "2") == 0
    for k in range(2):
        name = f"shard_{k:05d}.npz"
        assert (one / name).read_bytes() == (two / name).read_bytes()
    capsys.readouterr()
    assert _make(tiny_hang_data, one, "--workers", "1") == 0
    assert json.loads(capsys.readouterr().out)["made_shards"] == 0
    assert _make(tiny_hang_data, one, "--seed", "1") == 2
    assert "seed" in capsys.readouterr().err


def test_training_reads_the_folder_beside_the_data(tiny_hang_data, tmp_path):
    from robotplan.hanging.models.hang_model import HangSpec

    out = tmp_path / "in_hook"
    assert _make(tiny_hang_data, out, "--workers", "1", "--scenes", "2") == 0
    spec = HangSpec(**TINY_HANG_SPEC)
    base = HangSamples(tiny_hang_data, spec)
    both = HangSamples([tiny_hang_data, out], spec)
    assert len(both) == len(base) + 8 and not both.hangs[len(base):].any()


def test_bad_input_exits_2(tmp_path, tiny_hang_data, capsys):
    assert _make(tmp_path / "none", tmp_path / "o") == 2
    assert main(["data", "hang-in-hook", "--data", str(tiny_hang_data), "--out",
                 str(tmp_path / "o"), "--per-scene", "0"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert "--data: no such folder" in err[0] and "--per-scene" in err[1]
