"""Hard examples for H_hang: the poses the planner finds with a model, labelled by their drop.

A success model trained on drawn poses is right on poses like those it saw and can be wrong
where an optimiser goes looking for its minimum: SNOPT descends H_hang to ≈ 0 at poses whose
drop falls (docs/experiments.md#hang-mining). For every scene of a data folder, this runs the
planner's own program (:func:`robotplan.hanging.program.problem.solve_hang_once`) ``starts``
times from where the planner starts (:func:`robotplan.hanging.search.starts.start_pose`),
drops each end pose in pybullet and stores it labelled, in the format of
:mod:`robotplan.hanging.training.data` with the role ``OPTIMISED``, beside the model's value
there. Training on the data folder plus such folders (``robotplan train hang --mined``)
teaches the network where it was wrong; mining again with the new model finds its next
mistakes.

Scene ``i`` draws its starts from ``numpy.random.default_rng([seed, i])``: a folder is the
same whatever the number of workers, and an interrupted run continues.
"""

from __future__ import annotations

import hashlib
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from robotplan.base.threads import one_thread
from robotplan.base.units import check_ray
from robotplan.hanging.execution.world import HANG_PHYSICS, HangWorld
from robotplan.hanging.models.hang_model import load_hang_model
from robotplan.hanging.program.problem import (
    HANG_DEFAULTS,
    HangProblem,
    HangSettings,
    solve_hang_once,
)
from robotplan.hanging.search.starts import start_pose
from robotplan.hanging.training.data import OPTIMISED, derived_shard, load_hang_shards
from robotplan.training.shards import make_shards, prepare_folder

__all__ = ["MiningSpec", "mine_hang", "mine_scene"]

FORMAT = 1


@dataclass(frozen=True)
class MiningSpec:
    starts: int = 2  # SNOPT solves per scene, each from where the planner would start
    major_iterations: int = HANG_DEFAULTS.major_iterations
    start_pool: int = HANG_DEFAULTS.start_pool  # see HangSettings
    approach_iterations: int = HANG_DEFAULTS.approach_iterations


def mine_scene(problem: HangProblem, rng: np.random.Generator, spec: MiningSpec,
               world: HangWorld) -> dict[str, np.ndarray]:
    """``spec.starts`` end poses of the program on one scene, each dropped: ``poses (n, 7)``,
    ``hangs`` (in place), ``caught``, ``collision``, ``h_model`` (H_hang there)."""
    # the program without H_thread from uniform starts: where the learned H_hang alone leads
    settings = HangSettings(major_iterations=spec.major_iterations,
                            start_pool=spec.start_pool,
                            approach_iterations=spec.approach_iterations, threading=False)
    rows = []
    for _ in range(spec.starts):
        X0, part = start_pose(problem, rng, settings)
        sol = solve_hang_once(problem, X0, settings, part)
        r = world.drop(sol.pose)
        rows.append((sol.pose, r.in_place(world.physics), r.hangs, r.collision_at_start,
                     sol.h_hang))
    return {"poses": np.array([r[0] for r in rows]),
            "hangs": np.array([r[1] for r in rows], dtype=bool),
            "caught": np.array([r[2] for r in rows], dtype=bool),
            "collision": np.array([r[3] for r in rows], dtype=bool),
            "h_model": np.array([r[4] for r in rows])}


def _mine_shard(args: tuple) -> tuple[dict[str, np.ndarray], int]:
    """Scenes ``first ≤ i < last`` of ``data``, mined with a model and a pybullet client of
    this worker: the shard's arrays and its number of poses."""
    first, last, data, model_dir, seed, spec = args
    one_thread()
    model = load_hang_model(model_dir)
    return derived_shard(data, first, last, seed, OPTIMISED,
                         lambda i, hook, mug, world, rng: mine_scene(
                             HangProblem(model, mug, hook), rng, spec, world))


def _weights_digest(model_dir: Path) -> str:
    return hashlib.sha256((model_dir / "weights.pt").read_bytes()).hexdigest()[:16]


def mine_hang(data: Path, model_dir: Path, out: Path, seed: int, scenes: int | None = None,
              spec: MiningSpec = MiningSpec(), workers: int = 2, shard_size: int = 10,
              progress: bool = True, first: int = 0, ray: str | None = None) -> dict:
    """Mine (or finish mining) ``scenes`` scenes of ``data`` from its scene ``first`` on (all
    the rest by default) with the model in ``model_dir`` into ``out``. Returns a summary:
    scenes, poses, the fraction the model calls a success (H_hang ≤ κ1) and of those the
    fraction that hang in place. The shards run in ``workers`` local processes or on Ray
    (``ray``: :func:`robotplan.base.units.run_units`)."""
    d = load_hang_shards(data)
    if not 0 <= first < len(d["mug"]):
        raise ValueError(f"{data}: --first {first}: the folder has {len(d['mug'])} scenes")
    n = len(d["mug"]) - first if scenes is None else min(scenes, len(d["mug"]) - first)
    meta = {"format": FORMAT, "kind": "mined", "data": str(data), "first": first,
            "seed": seed, "model": str(model_dir),
            "weights_sha256": _weights_digest(model_dir), "spec": asdict(spec),
            "physics": HANG_PHYSICS.as_dict(), "shard_size": shard_size}
    check_ray(ray)
    prepare_folder(out, meta, n)
    head = {key: v[first:first + n] for key, v in d.items()}
    _, made, _ = make_shards(out, n, shard_size, _mine_shard,
                             (head, model_dir, seed, spec), workers, progress, "mine hang",
                             ray)
    mined = load_hang_shards(out)
    believed = mined["h_model"] <= HANG_DEFAULTS.kappa
    return {"scenes": n, "poses": int(mined["hangs"].size), "made_shards": made,
            "model_success": round(float(believed.mean()), 4),
            "in_place_of_model_success": round(float(mined["hangs"][believed].mean()), 4)
            if believed.any() else None,
            "in_place": round(float(mined["hangs"].mean()), 4)}
