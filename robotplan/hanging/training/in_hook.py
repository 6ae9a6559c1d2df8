"""Poses inside the hook for H_hang: failures by definition, labelled without a drop.

Uniformly drawn poses seldom start inside the hook (2.7 % of ``data hang``'s), and those that
do lie far from where a mug hangs. A network that saw few of them is free to be low there:
the sampled pose of least H_hang lies inside the hook in every scene of a bench, and most
poses the optimiser finds sit on the collision row's bound with H_hang below κ, falling when
dropped (docs/experiments.md#hang-in-hook). For every scene of a data folder this draws
poses near where the mug hangs (offsets and turns about the scene's hanging poses) and with
the handle about the arm (:func:`robotplan.hanging.training.data.handle_on_arm_poses`), and
keeps the first ``per_scene`` that start in collision in pybullet
(:meth:`robotplan.hanging.execution.world.HangWorld.collides`): every drop from there is a
failure, so no drop is simulated. Stored in the format of
:mod:`robotplan.hanging.training.data` with the role ``IN_HOOK``; trained on as an extra folder
(``robotplan train hang --mined DIR``).

Scene ``i`` draws from ``numpy.random.default_rng([seed, i])``: a folder is the same whatever
the number of workers, and an interrupted run continues.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from itertools import chain, zip_longest
from pathlib import Path

import numpy as np

from robotplan.base.threads import one_thread
from robotplan.base.units import check_ray
from robotplan.geometry.transforms import perturbed_poses
from robotplan.hanging.execution.world import HANG_PHYSICS, HangWorld
from robotplan.hanging.training.data import (
    IN_HOOK,
    derived_shard,
    handle_on_arm_poses,
    load_hang_shards,
)
from robotplan.sdf.mug_hook import Hook, Mug
from robotplan.training.shards import make_shards, prepare_folder

__all__ = ["InHookSpec", "in_hook_poses", "make_in_hook"]

FORMAT = 1


@dataclass(frozen=True)
class InHookSpec:
    per_scene: int = 10  # poses in collision kept per scene
    shift: float = 0.015  # m, standard deviation per axis of the offsets about hanging poses
    turn_deg: float = 10.0  # standard deviation per axis of their rotation vectors
    arm_spread: float = 0.01  # m, about the handle-on-arm poses
    tries: int = 256  # candidates per kind at most


def in_hook_poses(world: HangWorld, hook: Hook, mug: Mug, rng: np.random.Generator,
                  hanging: np.ndarray, spec: InHookSpec = InHookSpec()) -> np.ndarray:
    """Up to ``spec.per_scene`` poses X_HM ``(n, 7)`` of ``mug`` that start in collision with
    ``hook`` in ``world`` (theirs): candidates about the poses ``hanging (H, 7)`` (may be
    empty) and handle-on-arm candidates, taken in turn."""
    about = (perturbed_poses(rng, hanging[k], spec.shift, np.radians(spec.turn_deg), 1)[0]
             for k in rng.integers(0, len(hanging), spec.tries)) if len(hanging) else ()
    arm = handle_on_arm_poses(rng, hook.arm_points(), mug.handle_points(), spec.arm_spread,
                              spec.tries)
    kept: list[np.ndarray] = []
    for X in chain.from_iterable(zip_longest(about, arm)):
        if X is not None and world.collides(X):
            kept.append(X)
            if len(kept) >= spec.per_scene:
                break
    return np.array(kept).reshape(-1, 7)


def _in_hook_shard(args: tuple) -> tuple[dict[str, np.ndarray], int]:
    """Scenes ``first ≤ i < last`` of ``data``: the shard's arrays and its number of poses.
    A scene with fewer colliding candidates than asked for repeats them."""
    first, last, data, seed, spec = args
    one_thread()
    no = np.zeros(spec.per_scene, dtype=bool)

    def label(i: int, hook: Hook, mug: Mug, world: HangWorld, rng: np.random.Generator):
        found = in_hook_poses(world, hook, mug, rng, data["poses"][i][data["hangs"][i]], spec)
        if not len(found):
            raise RuntimeError(f"scene {int(data['scene_index'][i])}: no candidate pose "
                               "starts in collision with the hook")
        return {"poses": found[np.arange(spec.per_scene) % len(found)], "hangs": no,
                "caught": no, "collision": ~no}

    return derived_shard(data, first, last, seed, IN_HOOK, label)


def make_in_hook(data: Path, out: Path, seed: int, scenes: int | None = None,
                 spec: InHookSpec = InHookSpec(), workers: int = 2, shard_size: int = 50,
                 progress: bool = True, ray: str | None = None) -> dict:
    """Make (or finish) the in-hook folder ``out`` for the first ``scenes`` scenes of
    ``data`` (all by default), in ``workers`` local processes or on Ray (``ray``:
    :func:`robotplan.base.units.run_units`). Returns a summary."""
    d = load_hang_shards(data)
    n = len(d["mug"]) if scenes is None else min(scenes, len(d["mug"]))
    meta = {"format": FORMAT, "kind": "in_hook", "data": str(data), "seed": seed,
            "spec": asdict(spec), "physics": HANG_PHYSICS.as_dict(), "shard_size": shard_size}
    check_ray(ray)
    prepare_folder(out, meta, n)
    head = {key: v[:n] for key, v in d.items()}
    shards, made, samples = make_shards(out, n, shard_size, _in_hook_shard,
                                        (head, seed, spec), workers, progress, "in hook", ray)
    return {"scenes": n, "shards": shards, "made_shards": made, "new_samples": samples}
