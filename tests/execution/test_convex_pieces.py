"""A mesh that is not a plate goes to the simulator as convex pieces of its skin, once per
machine (cached by content)."""

from __future__ import annotations

import numpy as np

from robotplan.execution.convex_pieces import convex_pieces_file
from robotplan.scene.meshes import MeshShape, mesh_footprint
from tests.conftest import TASKS


def test_a_mug_rests_at_its_pose_as_its_pieces(rng):
    from robotplan.execution.pybullet_world import PushWorld

    shape, height = mesh_footprint(MeshShape("meshes/bench/mug.obj"), TASKS / "scene.yaml")
    assert not shape.prism
    pieces = convex_pieces_file(shape.mesh_file, shape.scale)
    assert pieces.read_text().count("\no ") + pieces.read_text().startswith("o ") >= 3
    stamp = pieces.stat().st_mtime_ns
    assert convex_pieces_file(shape.mesh_file, shape.scale) == pieces
    assert pieces.stat().st_mtime_ns == stamp
    pose = (0.1, -0.05, 0.7)
    with PushWorld() as world:
        world.reset(shape, height, pose, None)
        for _ in range(120):  # half a second: it stands still, upright
            world.pb.stepSimulation(physicsClientId=world.client)
        (x, y, yaw), tilt = world.object_pose()
        assert np.abs(np.array([x, y, yaw]) - pose).max() < 2e-3 and tilt < 0.01
        pb, c = world.pb, world.client
        # the cup's centre in the world: B is the footprint's centroid, the cup's axis is the
        # mesh's origin
        cup = np.array(pose[:2]) + _turn(-np.array(shape.mesh_offset[:2]), pose[2])
        probe = pb.createCollisionShape(pb.GEOM_SPHERE, radius=0.004, physicsClientId=c)
        for angle in pose[2] + rng.uniform(0.6, 2 * np.pi - 0.6, 12):  # away from the handle
            p = cup + 0.07 * np.array([np.cos(angle), np.sin(angle)])
            ball = pb.createMultiBody(0, probe, basePosition=[*p, 0.006], physicsClientId=c)
            gap = min(f[8] for f in pb.getClosestPoints(world.object, ball, 0.5,
                                                        physicsClientId=c)) + 0.004
            assert abs(gap - (0.07 - 0.045)) < 4e-3, (angle, gap)
            pb.removeBody(ball, physicsClientId=c)


def _turn(v: np.ndarray, yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])
