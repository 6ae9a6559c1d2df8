"""Open-loop execution in real physics (pybullet, and MuJoCo where the outcome is the
world's), and the MeshCat playback page."""

import json
from dataclasses import replace

import numpy as np
import pytest

from robotplan.execution.physics import PHYSICS, SIMULATORS
from robotplan.pushing.execution.execute import REACH_SPEED, execute_push, reach_substeps
from robotplan.scene import parse_scene
from robotplan.scene.bodies import Body
from robotplan.scene.task import load_task, make_task
from robotplan.sdf import Box, Circle, LShape, Polygon
from robotplan.viz.viewer import Layer, write_playback
from tests.conftest import DATA, TASKS, playback_commands


def hand_made_push() -> np.ndarray:
    """Go below-left of the box, then push it east into the goal (box_push.yaml)."""
    approach = np.linspace([-0.28, 0.10], [-0.20, 0.0], 10)
    push = np.linspace([-0.20, 0.0], [0.35, 0.05], 30)
    return np.vstack([approach, push[1:]])


@pytest.fixture(params=list(SIMULATORS))
def physics(request):
    """The push data's physics in each simulator."""
    return replace(PHYSICS, simulator=request.param)


def test_execution_pushes_the_box_into_the_goal(physics):
    task = load_task(TASKS / "box_push.yaml")
    q = hand_made_push()
    ex = execute_push(task, q, physics)
    assert ex.simulator == physics.simulator
    assert ex.object_poses.shape == (len(q), 3)
    assert np.abs(ex.pusher_positions - q).max() < 0.01  # the pusher tracks its path
    assert ex.final_pose[0] > 0.25 and ex.coverage > 0.9
    still = execute_push(task, np.tile(q[:1], (5, 1)), physics)
    assert still.coverage == 0.0 and np.allclose(still.final_pose,
                                                 task.scene.bodies["box"].pose, atol=1e-3)


def test_playback_is_one_self_contained_page(tmp_path):
    task = load_task(TASKS / "box_push.yaml")
    scene = task.scene
    q = hand_made_push()
    ex = execute_push(task, q)
    page = tmp_path / "playback.html"
    write_playback(scene, page, [Layer("plan", ex.times, {"pusher": q}),
                                 Layer("executed", ex.times, {"box": ex.object_poses,
                                                              "pusher": ex.pusher_positions},
                                       ghost=False)])
    html = page.read_text()
    assert html.startswith("<!DOCTYPE html>") or "<html" in html[:200]
    assert "src=\"http" not in html and len(html) > 100_000
    assert "Animation" in html  # the timeline is embedded (as packed MeshCat commands)


def test_arm_execution_tracks_the_plan_and_pushes_with_its_tip(tmp_path):
    """The left iiwa follows an IK'd push path under position control: its tip stays on
    Drake's forward kinematics of the planned angles, the box moves, the idle right arm
    holds still; the playback draws both arms."""
    from robotplan.functionals.kinematics import arm_kinematics, track_tip_path
    from robotplan.pushing.execution.execute import execute_arms

    task = load_task(TASKS / "two_arm_left_only.yaml")
    scene = task.scene
    left, right = (next(r for r in scene.robots if r.name == n) for n in ("left", "right"))
    kin = arm_kinematics(left)
    above = np.array([[-0.45, -0.37, 0.12]])
    down = np.array([[-0.45, -0.37, 0.03]])
    push = np.stack([np.full(12, -0.45), np.linspace(-0.37, -0.10, 12), np.full(12, 0.03)], 1)
    Q = track_tip_path(kin, np.vstack([above, down, push[1:]]), kin.q0, 0.07, 0.12)
    Q = np.vstack([kin.q0, Q])
    q_right = np.tile(arm_kinematics(right).q0, (len(Q), 1))
    substeps = [60, 60] + [20] * (len(Q) - 3)
    ex = execute_arms(task, {"left": Q, "right": q_right}, substeps)
    planned = np.array([kin.tip(q) for q in Q])
    assert np.abs(ex.tips["left"][:3] - planned[:3]).max() < 2e-3  # before contact
    assert np.abs(ex.joints["right"] - q_right).max() < 1e-3
    moved = ex.final_pose[:2] - np.asarray(scene.bodies["box"].pose[:2])
    assert moved[1] > 0.1, f"the box moved {moved} m"
    assert ex.coverage is not None and ex.touch_distance is None
    page = tmp_path / "playback.html"
    plain = tmp_path / "plain.html"
    plain_layers = [Layer("plan", ex.times, {"box": ex.object_poses}),
                    Layer("executed", ex.times, {"box": ex.object_poses}, ghost=False)]
    write_playback(scene, plain, plain_layers)
    write_playback(scene, page, [
        Layer("plan", ex.times, {"box": ex.object_poses}, {"left": Q, "right": q_right}),
        Layer("executed", ex.times, {"box": ex.object_poses}, ex.joints, ghost=False)])
    assert page.stat().st_size > plain.stat().st_size + 100_000  # the arm meshes
    commands = b"".join(playback_commands(page.read_text()))
    assert b"/plan/left/rod0" in commands and b"/executed/left/tool" in commands
    # each link mesh once: the planned arm is drawn with rods, not a second set of meshes
    assert b"/executed/left/lbr_iiwa_link_3/" in commands
    assert b"/plan/left/lbr_iiwa_link_3/" not in commands


def test_obstacles_are_fixed_bodies_and_contact_is_reported(physics):
    """Pushing the box straight east drives it into the wall: the wall holds, the contact
    is reported; a short push that stops 8 cm before it is not."""
    task = load_task(TASKS / "obstacle_push.yaml")
    into = np.vstack([np.linspace([-0.40, 0.0], [-0.34, 0.0], 5),
                      np.linspace([-0.34, 0.0], [0.0, 0.0], 16)[1:]])
    ex = execute_push(task, into, physics)
    assert ex.obstacle_contact
    assert ex.final_pose[0] + 0.06 < 0.02 + 0.005  # the box's face stays at the wall's
    short = execute_push(task, into[:8], physics)
    assert not short.obstacle_contact and short.final_pose[0] > -0.25 + 0.01


def test_every_object_is_simulated_and_forbidden_touches_are_reported(physics):
    """three_objects: a straight push of red into blue moves both (blue's coverage is
    reported); driving the pusher into blue, which it may not touch, is reported."""
    task = load_task(TASKS / "three_objects.yaml")
    scene = task.scene
    assert (task.obj, task.chained) == ("red", "blue")
    through_red = np.vstack([np.linspace([-0.40, -0.10], [-0.26, 0.02], 8),
                             np.linspace([-0.26, 0.02], [0.10, 0.02], 13)[1:]])
    ex = execute_push(task, through_red, physics)
    assert set(ex.others) == {"blue"} and ex.others["blue"].shape == (len(through_red), 3)
    assert ex.others["blue"][-1, 0] > scene.bodies["blue"].pose[0] + 0.1  # red pushed blue
    assert ex.forbidden_contacts == [] and 0.0 <= ex.coverage < 0.95
    at_blue = np.vstack([np.linspace([-0.40, -0.10], [0.05, -0.10], 10),
                         np.linspace([0.05, -0.10], [0.05, -0.02], 5)[1:]])
    ex = execute_push(task, at_blue, physics)
    assert ex.forbidden_contacts == ["blue"]


def test_guess_routes_the_object_around_the_obstacle():
    from robotplan.pushing.program.guess import object_route
    from robotplan.pushing.program.push_program import PushProgram
    from robotplan.pushing.program.skeleton import parse_skeleton, space_for

    task = load_task(TASKS / "obstacle_push.yaml")
    scene = task.scene
    prog = PushProgram(task, parse_skeleton("push@0,push@0", "pusher", "box"), None,
                       space_for(task))
    route = object_route(prog, np.array([-0.25, 0.0]), np.array([0.38, 0.0]))
    assert len(route) == 3 and abs(route[1, 1]) > 0.15 + 0.08
    wall = np.array(scene.bodies["wall"].pose[:2])
    ends = prog.guess["q_obj"][[20, 40], :2]
    assert np.linalg.norm(ends[0] - route[1]) < np.linalg.norm(ends[0] - wall)


@pytest.mark.parametrize("shape", [
    Polygon(((-0.12, 0.1), (-0.12, 0.04), (-0.03, 0.04), (-0.03, -0.12), (0.03, -0.12),
             (0.03, 0.04), (0.12, 0.04), (0.12, 0.1))),  # a T: concave
    Polygon(((-0.1, -0.08), (0.1, -0.08), (0.0, 0.11))),  # a triangle
    Circle(0.07),
    Box((0.2, 0.1)),
    LShape((0.24, 0.16), 0.06),
])
def test_footprints_are_simulated_as_their_outlines(shape, rng):
    """pybullet's body of a polygon (convex pieces), a disc (cylinder), a box or an L-shape
    (boxes about the centroid, the data's bodies): the distance from
    probe spheres around and inside its concavities matches the SDF to 2 mm."""
    assert_simulated_as_outline(shape, 0.06, rng)


@pytest.mark.parametrize("file", ["l_bracket.stl", "bench/hex_nut.stl"])
def test_a_plate_mesh_is_simulated_as_its_footprints_prism(file, rng):
    """A plate's body (a mesh that is its footprint extruded) is that prism in exact convex
    pieces, a nut's cut through its bore; placed so that its footprint lies where the
    planner's does, the bore open to probes."""
    from robotplan.scene.meshes import MeshShape, mesh_footprint

    shape, height = mesh_footprint(MeshShape(f"meshes/{file}", 0.001), TASKS / "scene.yaml")
    assert shape.prism
    assert_simulated_as_outline(shape, height, rng)


def assert_simulated_as_outline(shape, height: float, rng) -> None:
    import torch

    from robotplan.execution.pybullet_world import PushWorld

    pose = (0.1, -0.05, 0.7)
    body = Body("o", "object", shape, pose, 0.0, height)
    with PushWorld() as world:
        world.reset(shape, height, pose, None)
        assert np.abs(world.object_pose()[0] - pose).max() < 2e-3
        pb, c = world.pb, world.client
        probe = pb.createCollisionShape(pb.GEOM_SPHERE, radius=0.005, physicsClientId=c)
        points = rng.uniform(-0.2, 0.2, (40, 2)) + np.array(pose[:2])
        phi = body.sdf(torch.tensor(points), torch.tensor(pose, dtype=torch.float64)).numpy()
        for p, d in zip(points, phi, strict=True):
            if d < 0.003:  # distances are only reported outside the body
                continue
            ball = pb.createMultiBody(0, probe, basePosition=[p[0], p[1], height / 2],
                                      physicsClientId=c)
            found = pb.getClosestPoints(world.object, ball, 0.5, physicsClientId=c)
            gap = min(f[8] for f in found) + 0.005
            assert abs(gap - d) < 2e-3, (p, gap, d)
            pb.removeBody(ball, physicsClientId=c)


def test_reach_substeps_slow_free_moves_to_the_data_speed():
    q = np.array([[0.0, 0.0], [0.30, 0.40], [0.31, 0.40], [0.32, 0.40]])  # 50, 1, 1 cm
    steps = reach_substeps(q, np.array([False, False, True]))
    assert steps == [20 * int(np.ceil(0.5 / REACH_SPEED)), 20, 20]
    assert reach_substeps(q, np.array([True, True, True])) == [20, 20, 20]


def test_fast_reach_no_longer_clips_the_object():
    """A real plan's reach phase (tests/data/lshape_fast_reach.json) jumps up to 60 cm a
    step: in 20 simulation steps a step the pusher lags, clips the L and flings it; at the
    data's speed the L stays within 1 cm of where the plan holds it until the push."""
    case = json.loads((DATA / "lshape_fast_reach.json").read_text())
    task = make_task(parse_scene(case["scene"], DATA / "lshape_fast_reach.json"))
    scene = task.scene
    q = np.array(case["pusher"])
    T = (len(q) - 1) // len(case["phases"])
    push = np.array([case["phases"][t // T] == "push" for t in range(len(q) - 1)])
    start = np.array(scene.bodies["object"].pose)
    fast = execute_push(task, q)
    slow = execute_push(task, q, substeps=reach_substeps(q, push))
    reach_end = int(np.argmax(push))  # the last state of the reach phase
    assert np.abs(fast.object_poses[reach_end, :2] - start[:2]).max() > 0.05
    assert np.abs(slow.object_poses[reach_end, :2] - start[:2]).max() < 0.01
    lag = lambda ex: np.abs(ex.pusher_positions - q)[:reach_end + 1].max()  # noqa: E731
    assert lag(fast) > 0.05 and lag(slow) < 0.01  # the slow pusher tracks its reach
    assert slow.coverage > 0.5 > fast.coverage
