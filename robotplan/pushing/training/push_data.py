"""Push data from pybullet (paper §7.2, appendix I): random pushes of boxes and L-shapes, or
(``shapes="ood"``) of footprints never seen in training (paper Tab. 6).

Each scene draws an object (a box, or an L-shape in its bounding box; with ``ood`` scene
``i`` a footprint of family ``i mod 8``), a pusher radius and a start on a circle around
the object, then drives the pusher along random straight segments whose headings are biased
towards the object's centre, until the object starts to leave the table or ``max_states``
states are kept. Every ``keep_every``-th simulation step the state is kept; two consecutive
kept states form one sample (t−1, t).

Storage is compact (footprint parameters + poses, no grids): shards ``shard_NNNNN.npz`` of
``shard_size`` scenes, each written atomically, plus ``meta.json`` with the settings. Scene
``i`` is drawn from ``numpy.random.default_rng([seed, i])``, so the data is the same for a
seed whatever the number of workers, and a re-run on a partial folder only makes the
missing shards.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from robotplan.base.units import check_ray
from robotplan.execution.physics import PHYSICS, Physics, PushSimulator, push_world
from robotplan.pushing.training.footprints import (
    BOX,
    LSHAPE,
    MAX_VERTICES,
    OOD_FAMILIES,
    decode_footprint,
    draw_ood_shape,
    encode_footprint,
)
from robotplan.sdf import Box, LShape, Shape2D
from robotplan.sdf.footprint import footprint_centroid
from robotplan.training.shards import make_shards, prepare_folder

__all__ = ["PushDataSpec", "SceneRecord", "data_simulator", "generate", "load_shards",
           "scene_families", "scene_footprint", "simulate_scene"]

FORMAT = 1
PER_SCENE = ("scene_index", "shape_type", "size", "thickness", "vertices", "pusher_radius")


@dataclass(frozen=True)
class PushDataSpec:
    """The ranges scenes are drawn from (metres, seconds, m/s)."""

    box_side: tuple[float, float] = (0.08, 0.30)
    lshape_side: tuple[float, float] = (0.12, 0.30)
    lshape_thickness: tuple[float, float] = (0.05, 0.10)  # and at most 0.6 × shorter side
    lshape_share: float = 0.5
    height: float = 0.06
    pusher_radius: tuple[float, float] = (0.02, 0.05)
    start_gap: tuple[float, float] = (0.01, 0.15)  # pusher surface to object bound circle
    object_region: float = 0.55  # object start position uniform in ± this
    speed: tuple[float, float] = (0.10, 0.35)
    segment_seconds: tuple[float, float] = (0.2, 0.8)
    heading_noise: float = 0.5  # rad, std of the heading around the object direction
    max_states: int = 100
    table_margin: float = 0.0  # the scene ends when the footprint crosses the edge
    shapes: str = "train"  # "train": boxes and L-shapes; "ood": the unseen footprint families


@dataclass
class SceneRecord:
    """One simulated scene: its footprint and ``K`` kept states."""

    shape: Shape2D
    pusher_radius: float
    object_pose: np.ndarray  # (K, 3) x, y, yaw of the shape frame
    pusher_xy: np.ndarray  # (K, 2)
    contact: np.ndarray  # (K,) bool: pusher touched the object during the step into k


def draw_shape(rng: np.random.Generator, spec: PushDataSpec, kind: str | None = None
               ) -> Shape2D:
    """A box or an L-shape from the data ranges (``kind`` None: L with ``lshape_share``)."""
    if kind is None:
        kind = "lshape" if rng.random() < spec.lshape_share else "box"
    if kind == "lshape":
        w, h = rng.uniform(*spec.lshape_side, size=2)
        t_max = min(spec.lshape_thickness[1], 0.6 * min(w, h))
        t = rng.uniform(spec.lshape_thickness[0], t_max)
        return LShape((float(w), float(h)), float(t))
    w, h = rng.uniform(*spec.box_side, size=2)
    return Box((float(w), float(h)))


def _on_table(outline: np.ndarray, margin: float) -> bool:
    return bool(np.abs(outline).max() <= PHYSICS.table_size / 2 - margin)


def _world_outline(shape: Shape2D, pose: np.ndarray) -> np.ndarray:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return shape.outline() @ np.array([[c, s], [-s, c]]) + pose[:2]


def simulate_scene(index: int, seed: int, spec: PushDataSpec = PushDataSpec(),
                   world: PushSimulator | None = None) -> SceneRecord:
    """Draw scene ``index`` of ``seed`` and simulate it (deterministic)."""
    rng = np.random.default_rng([seed, index])
    if spec.shapes == "ood":
        shape = draw_ood_shape(rng, OOD_FAMILIES[index % len(OOD_FAMILIES)])
    else:
        shape = draw_shape(rng, spec)
    radius = float(rng.uniform(*spec.pusher_radius))
    while True:
        pose = np.array([*rng.uniform(-spec.object_region, spec.object_region, 2),
                         rng.uniform(-math.pi, math.pi)])
        if _on_table(_world_outline(shape, pose), 0.02):
            break
    centre = pose[:2] + _rotate(footprint_centroid(shape), pose[2])
    for _ in range(100):
        ang = rng.uniform(0, 2 * math.pi)
        dist = shape.bound_radius + radius + rng.uniform(*spec.start_gap)
        start = centre + dist * np.array([math.cos(ang), math.sin(ang)])
        if np.abs(start).max() < PHYSICS.table_size / 2 - radius:
            break
    own = world is None
    world = world or push_world()
    try:
        world.reset(shape, spec.height, tuple(pose), radius, tuple(start))
        return _rollout(world, shape, radius, rng, spec)
    finally:
        if own:
            world.close()


def _rotate(v: np.ndarray, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _rollout(world: PushSimulator, shape: Shape2D, radius: float, rng: np.random.Generator,
             spec: PushDataSpec) -> SceneRecord:
    dt, keep = world.physics.timestep, world.physics.keep_every
    centroid = footprint_centroid(shape)
    pose, _ = world.object_pose()
    target = world.pusher_position()
    poses, pushers, contacts = [pose], [target.copy()], [False]
    steps_left, heading, speed = 0, 0.0, 0.0
    touched = False
    step = 0
    while len(poses) < spec.max_states:
        if steps_left == 0:  # a new straight segment, heading biased to the object centre
            obj_pose, _ = world.object_pose()
            to_obj = obj_pose[:2] + _rotate(centroid, obj_pose[2]) - target
            heading = math.atan2(to_obj[1], to_obj[0]) + rng.normal(0.0, spec.heading_noise)
            speed = rng.uniform(*spec.speed)
            steps_left = max(1, round(rng.uniform(*spec.segment_seconds) / dt))
        target = target + speed * dt * np.array([math.cos(heading), math.sin(heading)])
        steps_left -= 1
        touched |= world.step(tuple(target))
        step += 1
        if step % keep:
            continue
        pose, tilt = world.object_pose()
        pusher = world.pusher_position()
        if (not _on_table(_world_outline(shape, pose), spec.table_margin) or tilt > 0.05
                or np.abs(pusher).max() > PHYSICS.table_size / 2):
            break
        poses.append(pose)
        pushers.append(pusher)
        contacts.append(touched)
        touched = False
    return SceneRecord(shape, radius, np.array(poses), np.array(pushers),
                       np.array(contacts, dtype=bool))


def _make_shard(args: tuple[int, int, int, PushDataSpec, Physics]
                ) -> tuple[dict[str, np.ndarray], int]:
    """Scenes ``first ≤ i < last`` of ``seed``, simulated in a world of ``physics`` in this
    worker: the shard's arrays and its number of samples."""
    first, last, seed, spec, physics = args
    from robotplan.base.threads import one_thread

    one_thread()
    world = push_world(physics)
    try:
        records = [simulate_scene(i, seed, spec, world) for i in range(first, last)]
    finally:
        world.close()
    offsets = np.cumsum([0] + [len(r.object_pose) for r in records])
    codes = [encode_footprint(r.shape) for r in records]
    arrays = dict(
        scene_index=np.arange(first, last),
        shape_type=np.array([c[0] for c in codes], dtype=np.int8),
        size=np.array([c[1] for c in codes], dtype=np.float32),
        thickness=np.array([c[2] for c in codes], dtype=np.float32),
        vertices=np.array([c[3] for c in codes], dtype=np.float32),
        pusher_radius=np.array([r.pusher_radius for r in records], dtype=np.float32),
        offsets=offsets.astype(np.int64),
        object_pose=np.concatenate([r.object_pose for r in records]).astype(np.float32),
        pusher_xy=np.concatenate([r.pusher_xy for r in records]).astype(np.float32),
        contact=np.concatenate([r.contact for r in records]),
    )
    return arrays, int(offsets[-1] - len(records))


def _legacy_settings(key: str, before: object) -> object:
    if key == "spec" and isinstance(before, dict):  # folders made before ``shapes``
        before.setdefault("shapes", "train")
    if key == "physics" and isinstance(before, dict):  # folders made in pybullet alone
        before.setdefault("link_friction", PHYSICS.link_friction)
        before.setdefault("simulator", "pybullet")
    return before


def generate(out: Path, scenes: int, seed: int, workers: int = 2, shard_size: int = 50,
             spec: PushDataSpec = PushDataSpec(), progress: bool = True,
             ray: str | None = None, physics: Physics = PHYSICS) -> dict:
    """Make (or finish) the data set in ``out``, in ``workers`` local processes or on Ray
    (``ray``: :func:`robotplan.base.units.run_units`), simulated in ``physics``'s world
    (``physics.simulator``). Returns a summary."""
    meta = {"format": FORMAT, "seed": seed, "shard_size": shard_size,
            "physics": physics.as_dict(), "spec": asdict(spec)}
    check_ray(ray)
    prepare_folder(out, meta, scenes, _legacy_settings)
    shards, made, samples = make_shards(out, scenes, shard_size, _make_shard,
                                        (seed, spec, physics), workers, progress, "push data", ray)
    return {"scenes": scenes, "shards": shards, "made_shards": made, "new_samples": samples}


def load_shards(folder: Path, scenes: int | None = None) -> dict[str, np.ndarray]:
    """All shards of ``folder`` concatenated (first ``scenes`` scenes if given).

    Returns arrays per scene (``shape_type, size, thickness, vertices, pusher_radius,
    scene_index``, ``offsets (S+1,)``; see :mod:`robotplan.pushing.training.footprints`) and per
    state (``object_pose, pusher_xy, contact``).
    """
    paths = sorted(Path(folder).glob("shard_*.npz"))
    if not paths:
        raise FileNotFoundError(f"{folder}: no push data shards (shard_*.npz) here")
    parts = [dict(np.load(p)) for p in paths]
    for p in parts:  # shards of boxes and L-shapes only may hold no vertices
        p.setdefault("vertices", np.full((len(p["scene_index"]), MAX_VERTICES, 2), np.nan,
                                         dtype=np.float32))
    out: dict[str, np.ndarray] = {}
    for key in PER_SCENE:
        out[key] = np.concatenate([p[key] for p in parts])
    for key in ("object_pose", "pusher_xy", "contact"):
        out[key] = np.concatenate([p[key] for p in parts])
    lengths = np.concatenate([np.diff(p["offsets"]) for p in parts])
    out["offsets"] = np.concatenate([[0], np.cumsum(lengths)])
    if scenes is not None and scenes < len(out["scene_index"]):
        end = out["offsets"][scenes]
        for key in PER_SCENE:
            out[key] = out[key][:scenes]
        for key in ("object_pose", "pusher_xy", "contact"):
            out[key] = out[key][:end]
        out["offsets"] = out["offsets"][: scenes + 1]
    return out


def scene_footprint(data: dict[str, np.ndarray], scene: int) -> Shape2D:
    """The footprint of ``scene`` (a row of :func:`load_shards`' per-scene arrays)."""
    return decode_footprint(int(data["shape_type"][scene]), data["size"][scene],
                            float(data["thickness"][scene]), data["vertices"][scene])


def data_simulator(folder: Path) -> str:
    """The simulator that made the push data in ``folder`` (``meta.json``; pybullet for
    folders made before there was a choice)."""
    meta = json.loads((Path(folder) / "meta.json").read_text())
    return meta.get("physics", {}).get("simulator", "pybullet")


def scene_families(folder: Path, data: dict[str, np.ndarray]) -> np.ndarray:
    """The footprint family of each scene of :func:`load_shards`' ``data`` from ``folder``,
    ``(S,)`` strings: "box" or "lshape" for training data; for unseen footprints
    (``shapes: ood`` in ``meta.json``) scene ``i``'s family ``OOD_FAMILIES[i mod 8]``."""
    meta = json.loads((Path(folder) / "meta.json").read_text())
    if meta.get("spec", {}).get("shapes") == "ood":
        return np.array(OOD_FAMILIES)[data["scene_index"] % len(OOD_FAMILIES)]
    names = {BOX: "box", LSHAPE: "lshape"}
    return np.array([names.get(int(code), "other") for code in data["shape_type"]])
