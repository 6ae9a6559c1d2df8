"""The steps of Tab. 3's representation rows in ``robotplan reproduce``: H_hang trained alike
on each object representation of the paper's app. A.5 (the SDF, the occupancy measures ψ and
ψ_s, PointNet and PointNet++ clouds), each planned with on the same scenes."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from robotplan.bench.paper import spec_flags
from robotplan.bench.steps import Steps

__all__ = ["COLLISION_ROWS", "HANG_REPRESENTATIONS", "hang_representations"]

# H_hang on each representation: key → (the paper's row, HangSpec fields, the collision
# rows the paper plans with (HangSettings.collision), its main first)
HANG_REPRESENTATIONS = {
    "sdf": ("SDF φ", {}, ("sdf",)),
    "occupancy": ("occupancy ψ = sign(φ)", {"representation": "occupancy"}, ("model",)),
    "smooth1000": ("occupancy ψ_s (b = 1000)", {"representation": "smooth_occupancy",
                                                "occupancy_sharpness": 1000.0}, ("model",)),
    "pointnet": ("PointNet", {"representation": "pointcloud"}, ("sdf", "none")),
    "pointnet2": ("PointNet++", {"representation": "pointcloud", "cloud_encoder": "pointnet2"},
                  ("sdf", "none")),
}

# the suffix of a bench step's name and of its report row, per collision row beyond the main
COLLISION_ROWS = {"none": ", no collision row"}


def hang_representations(steps: Steps, sizes, workers: int, ray: str | None) -> dict:
    """Hanging data (training scenes of seed 0, held-out scenes of seed 1), H_hang trained
    alike on each of ``sizes.hang_representations`` (keys of :data:`HANG_REPRESENTATIONS`:
    the paper's network and loss, the same data, seed and steps) and scored on the held-out
    scenes, and ``bench hang`` with each on the same scenes (seed 2) with the paper's main
    collision row for it, and with ``sizes.hang_every_collision_row`` also with its others:
    key → ``{"train": the training step's result (its last row scores the held-out scenes),
    "bench": the main bench step's result, "bench_<collision>": the others'}``."""
    from robotplan.hanging.bench.bench import PAPER_HANG, run_bench_hang
    from robotplan.hanging.training.data import generate_hang
    from robotplan.hanging.training.train import HangTrainConfig, train_hang

    def data(name: str, scenes: int, seed: int) -> tuple[dict, Path]:
        res = steps.run(name, {"scenes": scenes, "seed": seed}, lambda f: generate_hang(
            f / "data", scenes, seed, workers=workers, progress=False, ray=ray),
            f"robotplan data hang --scenes {scenes} --seed {seed}",
            runs=("robotplan.hanging.training.data",))
        return res, steps.out / res["folder"] / "data"

    train_step, train_dir = data("data_hang", sizes.hang_train_scenes, 0)
    test_step, test_dir = data("data_hang_test", sizes.hang_test_scenes, 1)
    n = sizes.hang_train_steps
    settings = replace(PAPER_HANG, evaluations=sizes.hang_evaluations)
    methods = ",".join(sizes.hang_representation_methods)
    bench_scenes = sizes.hang_representation_scenes
    out: dict[str, dict] = {}
    for key in sizes.hang_representations:
        _label, fields, collisions = HANG_REPRESENTATIONS[key]
        cfg = {"steps": n, "warmup": min(200, n // 10), "val_every": n, "spec": fields}
        trained = steps.run(
            f"train_hang_{key}", {**cfg, "data": "data_hang", "test": "data_hang_test"},
            lambda f, c=cfg: train_hang(HangTrainConfig(
                data=str(train_dir), test=str(test_dir), out=str(f / "model"),
                device=steps.device, **c),
                progress=False),
            f"robotplan train hang --data DATA --test TEST --steps {n}{spec_flags(fields)}",
            runs=("robotplan.hanging.training.train",), needs=(train_step, test_step))
        model = steps.out / trained["folder"] / "model"
        out[key] = {"train": trained}
        for i, collision in enumerate(collisions if sizes.hang_every_collision_row
                                      else collisions[:1]):
            name = "bench" if i == 0 else f"bench_{collision}"
            chosen = replace(settings, collision=collision)
            out[key][name] = steps.run(
                f"{name}_hang_{key}", {"scenes": bench_scenes, "seed": 2, "methods": methods,
                                       "evaluations": sizes.hang_evaluations,
                                       "model": f"train_hang_{key}", "collision": collision},
                lambda f, m=model, c=chosen: run_bench_hang(
                    bench_scenes, 2, f / "bench", m, workers=workers, progress=False,
                    methods=sizes.hang_representation_methods, settings=c, ray=ray),
                f"robotplan bench hang --scenes {bench_scenes} --seed 2 --model MODEL "
                f"--methods {methods} --evaluations {sizes.hang_evaluations} "
                f"--collision {collision} --check none --no-threading",
                runs=("robotplan.hanging.bench.bench",), needs=(trained,))
    return out
