"""The drop test of mug hanging in real pybullet: a hand-placed hanging pose hangs, poses
below the hook or through its arm do not, and the bodies pybullet simulates are the shapes
whose SDFs the planner sees."""

import math

import numpy as np
import pytest
import torch

from robotplan.hanging.execution.world import HangWorld
from robotplan.sdf.mug_hook import Hook, Mug

HOOK = Hook(post_height=0.3, lengths=(0.12, 0.04), angles=(math.radians(10), math.radians(60)))
MUG = Mug(radius=0.04, height=0.1, handle_height=0.6, handle_reach=0.03, handle_span=0.03)
ALONG_ARM = 0.08  # m from the post, where the hand-placed handle goes


def quarter_turn() -> tuple[float, ...]:
    """The mug turned 90° about z: its handle loop across the hook's arm (which runs along x)."""
    return (math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4))


def threaded_pose(dz: float = 0.0) -> tuple[float, ...]:
    """Upright, the arm through the middle of the handle's loop, ``dz`` higher."""
    arm_z = HOOK.post_height + ALONG_ARM * math.tan(HOOK.angles[0])
    loop_centre = MUG.radius + MUG.handle_reach / 2
    z = arm_z - MUG.handle_height * MUG.height + dz
    return (ALONG_ARM, -loop_centre, z, *quarter_turn())


@pytest.fixture(scope="module")
def world():
    with HangWorld(HOOK, MUG) as w:
        yield w


def test_a_mug_threaded_on_the_arm_hangs_in_place(world):
    result = world.drop(threaded_pose())
    assert result.hangs and result.on_hook and not result.on_ground
    assert result.in_place(), f"it comes down only onto its handle: {result.fall_m:.3f} m"
    assert type(result.in_place()) is bool, "result.json writes it"
    end = np.array(result.X_WM_end)
    assert end[2] > 0.1, "it stays up on the arm"


def test_a_mug_below_the_arm_falls_to_the_ground(world):
    result = world.drop(threaded_pose(dz=-0.2))
    assert not result.hangs and result.on_ground and not result.collision_at_start


def test_a_mug_beside_the_arm_falls(world):
    x, y, z, *q = threaded_pose()
    result = world.drop((x, y - 0.12, z, *q))
    assert not result.hangs and result.on_ground


def test_a_mug_through_the_arm_is_a_collision(world):
    x, _, z, *_ = threaded_pose()
    # upright, the cup's wall (handle away from the post) across the arm at its height
    result = world.drop((x, -(MUG.radius - MUG.wall / 2), z, 1.0, 0.0, 0.0, 0.0))
    assert result.collision_at_start and not result.hangs


def test_the_simulated_bodies_are_the_sdf_shapes(world, rng):
    """Distances pybullet measures from a small probe sphere against the SDFs: the ring of
    wall boxes circumscribes the cup (≤ r (1/cos(π/16) − 1) = 0.8 mm out), and Bullet
    rounds convex edges by its collision margin (a few tenths of a millimetre)."""
    assert_bodies_are_the_shapes(world, MUG, HOOK, rng, 1.5e-3)


def test_mesh_bodies_are_their_sdfs_and_a_threaded_mesh_mug_hangs(mesh_parts, rng):
    """A mesh hook is its mesh in pybullet, a mesh mug its skin's pieces, in the frames of
    their SDF lattices (within the lattice's 3 mm step and the skin's sagitta); the mug
    upright with the arm through the middle of its handle's opening hangs."""
    mug, hook = mesh_parts
    with HangWorld(hook, mug) as w:
        assert_bodies_are_the_shapes(w, mug, hook, rng, 2.5e-3)
        result = w.drop(threaded_mesh_pose(mug, hook))
        assert result.hangs, result


def threaded_mesh_pose(mug, hook, along: float = 0.07) -> tuple[float, ...]:
    """The mesh mug upright, turned a quarter, the hook's arm through the middle of its
    handle's opening ``along`` m out from the post: ``X_WM (7,)``."""
    x0, z0, _, _ = mug.opening()
    arm = hook.arm_points()
    arm_z = np.interp(along, arm[:, 0], arm[:, 2])
    return (along, -x0, arm_z - z0, *quarter_turn())


def assert_bodies_are_the_shapes(world, mug, hook, rng, tolerance: float) -> None:
    pb, c = world.pb, world.client
    probe_r = 0.002
    probe = pb.createMultiBody(0, pb.createCollisionShape(pb.GEOM_SPHERE, radius=probe_r,
                                                          physicsClientId=c),
                               physicsClientId=c)
    pose = np.array([0.0, 0.5, 0.2, 1.0, 0.0, 0.0, 0.0])
    world.collides(pose)  # places the mug there
    checked = 0
    for body, shape, at in ((world.mug, mug, pose[:3]), (world.hook, hook, np.zeros(3))):
        local = rng.uniform(-0.1, 0.2, (400, 3))
        phi = shape.sdf(torch.from_numpy(local)).numpy()
        near_shell = (phi > 0.004) & (phi < 0.03)
        for p, d in zip(local[near_shell], phi[near_shell], strict=True):
            pb.resetBasePositionAndOrientation(probe, (p + at).tolist(), [0, 0, 0, 1],
                                               physicsClientId=c)
            pb.performCollisionDetection(physicsClientId=c)
            near = pb.getClosestPoints(body, probe, 0.05, physicsClientId=c)
            measured = min(q[8] for q in near) + probe_r
            assert abs(measured - d) < tolerance, (p, d, measured)
            checked += 1
    assert checked > 40
    pb.removeBody(probe, physicsClientId=c)
