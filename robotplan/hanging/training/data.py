"""Mug-hanging data from pybullet (paper §7.1, app. H): per scene a mug and a hook drawn from
``robots/hang/shapes.yaml``, mug poses drawn uniformly in X_h (position uniform in the cube,
orientation uniform on SO(3)) and dropped until one hangs, then ``per_scene`` labelled
configurations kept: where that drop left the mug (its settled pose), ``jitter`` poses drawn
about the settled pose and clear of the hook, the drawn pose that hung, ``near_arm`` poses
with the handle about the arm and clear of it, then failures in the order they were drawn.
Each is labelled by its own drop.

The label y is a hang *in place* (:meth:`robotplan.hanging.execution.world.DropResult.in_place`):
most uniformly drawn poses that hang were released above the hook and caught the arm on the
way down, and a model that learns those proposes drops, not placements
(docs/experiments.md#hang-labels). The plain drop outcome is kept as ``caught``.

Storage is compact (shape parameters and poses; the SDF grids are rendered when training):
shards of ``shard_size`` scenes and ``meta.json`` (see :mod:`robotplan.training.shards`).
Scene ``i`` is drawn from ``numpy.random.default_rng([seed, i])``: the data is the same for a
seed whatever the number of workers.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from robotplan.base.threads import one_thread
from robotplan.base.units import check_ray
from robotplan.geometry.transforms import perturbed_poses, quaternion_to_matrix, uniform_poses
from robotplan.hanging.execution.world import HANG_PHYSICS, HangWorld
from robotplan.hanging.scene.ranges import HangRanges, load_hang_ranges
from robotplan.sdf.mug_hook import MUG_FIELDS, Hook, Mug
from robotplan.training.shards import make_shards, prepare_folder

__all__ = ["IN_HOOK", "OPTIMISED", "HangDataSpec", "HangScene", "decode_hook", "decode_mug",
           "derived_shard", "generate_hang", "load_hang_shards", "simulate_hang_scene"]

FORMAT = 2
MAX_PARTS = 3
DRAW_BATCH = 256  # poses drawn from the scene's generator at a time
# where a kept pose came from (the ``role`` of each pose in a shard); OPTIMISED: an end pose
# of the planner's program (:mod:`robotplan.hanging.training.mining`); IN_HOOK: a pose that
# starts in collision (:mod:`robotplan.hanging.training.in_hook`)
SETTLED, JITTER, DRAWN, NEAR_ARM, OPTIMISED, IN_HOOK = 0, 1, 2, 3, 4, 5


@dataclass(frozen=True)
class HangDataSpec:
    per_scene: int = 20  # labelled configurations kept per scene
    max_draws: int = 20_000  # drops per scene at most while looking for a success
    # poses about the settled pose (which rests on the arm): offsets and turns, lifted, and
    # only those clear of the hook kept (docs/experiments.md#hang-labels)
    jitter: int = 8
    jitter_shift: float = 0.01  # m, standard deviation per axis of their offsets
    jitter_turn_deg: float = 5.0  # standard deviation per axis of their rotation vectors
    jitter_lift: float = 0.01  # m, at most, upwards
    jitter_tries: int = 64
    # poses with a point of the handle's centre line near a point of the arm's, any rotation,
    # clear of the hook: the near misses an optimiser meets (docs/experiments.md#hang-labels)
    near_arm: int = 5
    near_arm_spread: float = 0.02  # m, standard deviation per axis about the touching pose
    near_arm_tries: int = 64


@dataclass
class HangScene:
    """One scene: its shapes, ``per_scene`` poses X_HM ``(n, 7)`` with their labels."""

    mug: Mug
    hook: Hook
    poses: np.ndarray  # (n, 7) x, y, z, qw, qx, qy, qz of the mug in the hook frame
    hangs: np.ndarray  # (n,) bool: the label y, hangs in place
    caught: np.ndarray  # (n,) bool: hangs after the drop, wherever it came to rest
    collision: np.ndarray  # (n,) bool: in collision with the hook where it starts
    role: np.ndarray  # (n,) SETTLED, JITTER, NEAR_ARM or DRAWN
    draws: int  # uniform poses dropped until one hung
    found: bool  # one hung within max_draws


def simulate_hang_scene(index: int, seed: int, spec: HangDataSpec = HangDataSpec(),
                        ranges: HangRanges | None = None) -> HangScene:
    """Draw scene ``index`` of ``seed`` and label its poses by dropping them (deterministic)."""
    ranges = ranges or load_hang_ranges()
    rng = np.random.default_rng([seed, index])
    hook, mug = ranges.hook.sample(rng), ranges.mug.sample(rng)
    centre = ranges.grid.centre(hook)
    near: list[tuple] = []  # (X, in place, caught, collision, role) about the first hang
    drawn: list[tuple] = []  # uniform draws, the one that hung last
    draws = 0
    with HangWorld(hook, mug) as world:

        def label(X: np.ndarray, role: int) -> tuple:
            r = world.drop(X)
            return X, r.in_place(world.physics), r.hangs, r.collision_at_start, role

        def clear_of_hook(poses, role: int, n: int) -> list[tuple]:
            """The first ``n`` of ``poses`` that do not start inside the hook, labelled."""
            rows: list[tuple] = []
            for X in poses:
                row = label(X, role)
                if not row[3]:
                    rows.append(row)
                if len(rows) >= n:  # before the next pose is drawn
                    break
            return rows

        while not (drawn and drawn[-1][2]) and draws < spec.max_draws:
            for X in uniform_poses(rng, centre, ranges.grid.size, DRAW_BATCH):
                draws += 1
                drawn.append(label(X, DRAWN))
                if drawn[-1][2] or draws >= spec.max_draws:
                    break
        found = bool(drawn and drawn[-1][2])
        if found:
            # where the hanging pose comes to rest, from a drop of its own: pybullet carries
            # contact state from one drop to the next, so this is what the data was made with
            settled = np.array(world.drop(drawn[-1][0]).X_WM_end)
            near.append(label(settled, SETTLED))
            about = perturbed_poses(rng, settled, spec.jitter_shift,
                                    np.radians(spec.jitter_turn_deg), spec.jitter_tries)
            up = np.eye(7)[2]
            lifted = (X + rng.uniform(0.0, spec.jitter_lift) * up for X in about)
            near += clear_of_hook(lifted, JITTER, spec.jitter)
            near.append(drawn.pop())
        arm = clear_of_hook(handle_on_arm_poses(rng, hook.arm_points(), mug.handle_points(),
                                                spec.near_arm_spread, spec.near_arm_tries),
                            NEAR_ARM, spec.near_arm)
    keep = (near + arm + drawn)[: spec.per_scene]
    while len(keep) < spec.per_scene:  # a scene whose draws ran out early: repeat failures
        keep.append(keep[len(keep) % max(len(drawn), 1)])
    column = lambda k, dtype=None: np.array([row[k] for row in keep], dtype=dtype)  # noqa: E731
    return HangScene(mug, hook, column(0), column(1, bool), column(2, bool), column(3, bool),
                     column(4, np.int8), draws, found)


def _points_on(rng: np.random.Generator, line: np.ndarray, n: int) -> np.ndarray:
    """``n`` points ``(n, 3)`` uniform along the polyline ``line (K, 3)``."""
    seg = np.linalg.norm(np.diff(line, axis=0), axis=1)
    k = rng.choice(len(seg), size=n, p=seg / seg.sum())
    t = rng.uniform(0.0, 1.0, (n, 1))
    return line[k] + t * (line[k + 1] - line[k])


def handle_on_arm_poses(rng: np.random.Generator, arm: np.ndarray, handle: np.ndarray,
                        spread: float, n: int) -> np.ndarray:
    """``n`` mug poses X_HM ``(n, 7)``: a uniform rotation, and the position that puts a random
    point of the handle's centre line ``handle (K, 3)`` (mug frame) on a random point of the
    arm's ``arm (J, 3)`` (hook frame), offset by a Gaussian of ``spread`` per axis."""
    X = uniform_poses(rng, np.zeros(3), 0.0, n)
    R = quaternion_to_matrix(torch.from_numpy(X[:, 3:])).numpy()
    a, h = _points_on(rng, arm, n), _points_on(rng, handle, n)
    X[:, :3] = a - np.einsum("nij,nj->ni", R, h) + rng.normal(0.0, spread, (n, 3))
    return X


def _encode_hook(hook: Hook) -> np.ndarray:
    """``(2 + 2 · MAX_PARTS,)``: post height, parts, lengths, angles (zero-padded)."""
    n = len(hook.lengths)
    pad = [0.0] * (MAX_PARTS - n)
    return np.array([hook.post_height, n, *hook.lengths, *pad, *hook.angles, *pad])


def decode_hook(code: np.ndarray, post_radius: float, rod_radius: float) -> Hook:
    n = int(code[1])
    return Hook(float(code[0]), tuple(map(float, code[2:2 + n])),
                tuple(map(float, code[2 + MAX_PARTS:2 + MAX_PARTS + n])),
                post_radius=post_radius, rod_radius=rod_radius)


def decode_mug(code: np.ndarray) -> Mug:
    return Mug(**{name: float(v) for name, v in zip(MUG_FIELDS, code, strict=True)})


def derived_shard(data: dict[str, np.ndarray], first: int, last: int, seed: int, role: int,
                  label: Callable[..., dict[str, np.ndarray]]
                  ) -> tuple[dict[str, np.ndarray], int]:
    """A shard of a folder made from the scenes ``first ≤ i < last`` of the hang data ``data``
    (:func:`load_hang_shards`' arrays): ``label(i, hook, mug, world, rng)`` gets scene ``i``'s
    shapes, a pybullet world of them and ``default_rng([seed, scene_index])``, and returns
    its ``k`` labelled poses, per pose ``poses (k, 7)``, ``hangs``, ``caught``, ``collision``
    and any more. The shard keeps each scene's shapes and gives every pose ``role``; returns
    the arrays and the number of poses."""
    rows = []
    for i in range(first, last):
        hook, mug = decode_hook(data["hook"][i], *data["hook_radii"][i]), decode_mug(data["mug"][i])
        with HangWorld(hook, mug) as world:
            rows.append(label(i, hook, mug, world,
                              np.random.default_rng([seed, int(data["scene_index"][i])])))
    stacked = {key: np.array([r[key] for r in rows]) for key in rows[0]}
    head = {key: data[key][first:last] for key in ("scene_index", "mug", "hook", "hook_radii")}
    n = last - first
    return dict(**head, role=np.full(stacked["hangs"].shape, role, dtype=np.int8),
                draws=np.zeros(n, dtype=int), found=stacked["hangs"].any(axis=1),
                **stacked), int(stacked["hangs"].size)


def _make_shard(args: tuple) -> tuple[dict[str, np.ndarray], int]:
    """Scenes ``first ≤ i < last`` of ``seed``, dropped in this worker's pybullet: the
    shard's arrays and its number of samples."""
    first, last, seed, spec = args
    one_thread()
    scenes = [simulate_hang_scene(i, seed, spec) for i in range(first, last)]
    arrays = dict(
        scene_index=np.arange(first, last),
        mug=np.array([[getattr(s.mug, f) for f in MUG_FIELDS] for s in scenes]),
        hook=np.array([_encode_hook(s.hook) for s in scenes]),
        hook_radii=np.array([(s.hook.post_radius, s.hook.rod_radius) for s in scenes]),
        poses=np.array([s.poses for s in scenes]),
        hangs=np.array([s.hangs for s in scenes]),
        caught=np.array([s.caught for s in scenes]),
        collision=np.array([s.collision for s in scenes]),
        role=np.array([s.role for s in scenes]),
        draws=np.array([s.draws for s in scenes]),
        found=np.array([s.found for s in scenes]),
    )
    return arrays, len(scenes) * spec.per_scene


def generate_hang(out: Path, scenes: int, seed: int, workers: int = 2, shard_size: int = 20,
                  spec: HangDataSpec = HangDataSpec(), progress: bool = True,
                  ray: str | None = None) -> dict:
    """Make (or finish) the hanging data set in ``out``, in ``workers`` local processes or
    on Ray (``ray``: :func:`robotplan.base.units.run_units`). Returns a summary."""
    ranges = load_hang_ranges()
    meta = {"format": FORMAT, "seed": seed, "shard_size": shard_size,
            "physics": HANG_PHYSICS.as_dict(), "spec": asdict(spec),
            "ranges": asdict(ranges)}
    check_ray(ray)
    prepare_folder(out, meta, scenes)
    shards, made, samples = make_shards(out, scenes, shard_size, _make_shard, (seed, spec),
                                        workers, progress, "hang data", ray)
    return {"scenes": scenes, "shards": shards, "made_shards": made, "new_samples": samples}


def load_hang_shards(folder: Path) -> dict[str, np.ndarray]:
    """All shards of ``folder`` concatenated: per scene ``mug (S, 7)``, ``hook (S, 8)``,
    ``hook_radii (S, 2)``, ``poses (S, n, 7)``, ``hangs``, ``caught``, ``collision``,
    ``role (S, n)``, ``draws``, ``found``, ``scene_index``."""
    paths = sorted(Path(folder).glob("shard_*.npz"))
    if not paths:
        raise FileNotFoundError(f"{folder}: no hanging data shards (shard_*.npz) here")
    parts = [dict(np.load(p)) for p in paths]
    return {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
