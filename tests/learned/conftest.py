from pathlib import Path

import pytest

from robotplan.training.push_data import generate


@pytest.fixture(scope="session")
def tiny_push_data(tmp_path_factory) -> Path:
    """12 real pybullet scenes (seed 5), in shards of 4: a few seconds."""
    out = tmp_path_factory.mktemp("push") / "data"
    generate(out, scenes=12, seed=5, workers=1, shard_size=4, progress=False)
    return out


TINY_SPEC = {"channels": (2, 2, 2), "sdf_features": 8, "point_features": 8, "hidden": (16, 16)}
