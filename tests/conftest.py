"""Shared fixtures: every RNG seeded, one torch thread, paths to the example scenes."""

from __future__ import annotations

# isort: off
import robotplan  # noqa: F401  first: it pins the CPU arithmetic before numpy loads OpenBLAS
# isort: on
import random
from pathlib import Path

import numpy as np
import pytest
import torch

ROOT = Path(__file__).resolve().parents[1]
TASKS = ROOT / "tasks"
DATA = Path(__file__).resolve().parent / "data"


@pytest.fixture(autouse=True)
def _seed_everything() -> None:
    random.seed(0)
    np.random.seed(0)
    torch.manual_seed(0)
    torch.set_num_threads(1)


@pytest.fixture(autouse=True, scope="session")
def _private_cache(tmp_path_factory) -> None:
    """Derived files (a mesh's convex pieces) go to a folder of the test run, not the
    user's cache."""
    import os

    os.environ["ROBOTPLAN_CACHE"] = str(tmp_path_factory.mktemp("cache"))


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(1234)


@pytest.fixture
def box_scene():
    from robotplan import load_scene

    return load_scene(TASKS / "box_push.yaml")


@pytest.fixture(scope="session")
def tiny_push_data(tmp_path_factory) -> Path:
    """12 real pybullet scenes (seed 5), in shards of 4: a few seconds."""
    from robotplan.pushing.training.push_data import generate

    out = tmp_path_factory.mktemp("push") / "data"
    generate(out, scenes=12, seed=5, workers=1, shard_size=4, progress=False)
    return out


@pytest.fixture(scope="session")
def tiny_ood_push_data(tmp_path_factory) -> Path:
    """8 real pybullet scenes of the unseen footprints (seed 5), one of each family."""
    from robotplan.pushing.training.push_data import PushDataSpec, generate

    out = tmp_path_factory.mktemp("push_ood") / "data"
    generate(out, scenes=8, seed=5, workers=1, shard_size=4, progress=False,
             spec=PushDataSpec(shapes="ood"))
    return out


@pytest.fixture(scope="session")
def tiny_hang_data(tmp_path_factory) -> Path:
    """3 real hanging scenes (seed 0) made by ``robotplan data hang``: a few seconds."""
    from robotplan.cli.app import main

    out = tmp_path_factory.mktemp("hang") / "data"
    assert main(["data", "hang", "--scenes", "3", "--seed", "0", "--out", str(out),
                 "--workers", "1", "--shard-size", "2"]) == 0
    return out


def assert_each_refused(load, path: Path, cases) -> None:
    """Each ``(text, why)`` of ``cases`` written to ``path`` makes ``load(path)`` raise a
    ValueError whose message matches ``why``."""
    for text, why in cases:
        path.write_text(text)
        with pytest.raises(ValueError, match=why):
            load(path)


TINY_HANG_SPEC = {"channels": (2, 2, 2), "features": 8, "hidden": (16, 16)}
TINY_SPEC = {"channels": (2, 2, 2), "sdf_features": 8, "point_features": 8, "hidden": (16, 16)}


def playback_commands(html: str) -> list[bytes]:
    """The MeshCat commands a written playback page replays, as packed bytes (their paths
    and mesh data appear verbatim in them)."""
    import base64
    import re

    return [base64.b64decode(m) for m in
            re.findall(r'fetch\("data:application/octet-binary;base64,([^"]+)"\)', html)]
