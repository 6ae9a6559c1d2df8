"""Routes around obstacles as straight face pushes (robotplan.pushing.search.route)."""

from __future__ import annotations

import numpy as np
import torch

from robotplan import load_scene
from robotplan.pushing.program.push_program import PushProgram
from robotplan.pushing.program.skeleton import space_for
from robotplan.pushing.search.route import (
    GOAL_INSIDE,
    _clear,
    centred_pushes,
    face_routes,
    routed_candidates,
)
from robotplan.scene.task import make_task
from tests.conftest import TASKS

GOAL = np.array([0.38, 0.0])


def test_routes_pass_the_wall_on_either_side_with_clearance():
    scene = load_scene(TASKS / "obstacle_push.yaml")
    routes = face_routes(scene, "box", GOAL)
    assert len(routes) == 2  # the straight and the L-shaped routes cross the wall
    sides = sorted(float(r.waypoints[1, 1]) for r in routes)
    # wall top 0.15 + the box's half side 0.06 + clearance 0.04
    assert np.allclose(sides, [-0.25, 0.25], atol=1e-6)
    for r in routes:
        assert np.allclose(r.waypoints[0], [-0.25, 0.0]) and np.allclose(r.waypoints[-1], GOAL)
        assert abs(r.length - (0.25 + 0.63 + 0.25)) < 1e-9
        assert _clear(scene, "box", r.waypoints, 0.0, 0.035)
    north = next(r for r in routes if r.waypoints[1, 1] > 0)
    assert north.directions == (1, 0, 3)  # +y, +x, −y in the box's frame


def test_a_route_ends_where_the_object_lies_inside_the_goal_region():
    scene = load_scene(TASKS / "variants" / "obstacle_push_rect_box.yaml")
    region = scene.goal_region
    centre = np.array(region.pose[:2])
    aimed = face_routes(scene, "box", centre)
    ended = face_routes(scene, "box", centre, region=region)
    assert all(np.allclose(r.waypoints[-1], centre) for r in aimed)
    south = next(r for r in ended if r.directions[0] == 3)  # south of the wall, then east
    # 2 cm short of the centre the turned box lies inside the region already: no third push
    assert south.directions == (3, 0) and np.linalg.norm(south.waypoints[-1] - centre) < 0.03
    outline = scene.bodies["box"].outline_world(np.append(south.waypoints[-1], 0.4))
    assert float(region.sdf(torch.as_tensor(outline)).max()) <= -GOAL_INSIDE + 1e-9
    # the north route ends above the region: it keeps its leg down into it
    assert any(r.directions == (1, 0, 3) for r in ended)


def test_clear_rejects_a_path_through_the_wall_and_off_the_table():
    scene = load_scene(TASKS / "obstacle_push.yaml")
    assert not _clear(scene, "box", np.array([[-0.25, 0.0], GOAL]), 0.0, 0.0)
    # passing 3 cm above the wall: clear by 0.03 but not by 0.04
    above = np.array([[-0.25, 0.24], [0.38, 0.24]])
    assert _clear(scene, "box", above, 0.0, 0.025) and not _clear(scene, "box", above, 0.0, 0.04)
    assert not _clear(scene, "box", np.array([[0.0, 0.6], [0.0, 0.69]]), 0.0, 0.0)


def test_routes_without_obstacles_are_the_two_l_shapes(box_scene):
    start = np.array(box_scene.bodies["box"].pose[:2])
    goal = start + np.array([0.2, -0.1])
    routes = face_routes(box_scene, "box", goal)
    assert len(routes) == 2 and all(len(r.directions) == 2 for r in routes)
    assert {r.directions for r in routes} == {(0, 3), (3, 0)}


def test_routed_skeletons_push_from_behind_and_the_guess_follows_the_route():
    task = make_task(load_scene(TASKS / "obstacle_push.yaml"))
    space, skeletons = routed_candidates(task, space_for(task), 0.027)
    # the longest push, 0.63 m at 2.7 cm a step, plus two steps into contact
    assert space.steps_per_phase == 26 and space.init_frame == "object"
    north = next(sk for sk in skeletons if sk.phases[1].via[1] > 0)
    assert [ph.init for ph in north.phases if ph.mode == "push"] == [3, 2, 1]
    assert north.as_rows()[1]["via"] == [-0.25, 0.25]
    assert "push(pusher->box@3 to (-0.25, 0.25))" in north.describe()
    prog = PushProgram(task, north, None, space)
    T = space.steps_per_phase
    ends = prog.guess["q_obj"][[2 * T, 4 * T, 6 * T], :2]
    assert np.abs(ends - [(-0.25, 0.25), (0.38, 0.25), (0.38, 0.0)]).max() < 1e-9
    pusher = prog.guess["q_pusher"]
    push = slice(T + 3, 2 * T + 1)  # behind the south face, below the box, while pushing north
    assert (pusher[push, 1] < prog.guess["q_obj"][push, 1] - 0.06).all()


def test_long_segments_are_split_into_several_pushes():
    task = make_task(load_scene(TASKS / "obstacle_push.yaml"))
    space, skeletons = routed_candidates(task, space_for(task), 0.01, max_pushes=5)
    # 28 steps of 1 cm: the 0.63 m push is split in three (0.21 m, 23 steps)
    assert space.steps_per_phase == 27
    assert all(sk.pushes == 5 for sk in skeletons)


def test_pybullet_turns_a_box_pushed_off_its_centre_line():
    """Why routes push straight through the centroid: in pybullet a centred face push moves
    the box straight, one 2 mm off the centre line turns it by > 0.1 rad within 0.3 m."""
    from robotplan.execution.pybullet_world import PushWorld
    from robotplan.sdf import Box

    def yaw_after_push(offset: float) -> float:
        with PushWorld() as world:
            world.reset(Box((0.12, 0.12)), 0.06, (0.0, 0.0, 0.0), 0.03, (-0.095, offset))
            for k in range(15 * 20):  # 15 kept steps of 2 cm, 20 simulation steps each
                world.step((-0.095 + 0.02 * (k + 1) / 20, offset))
            return float(world.object_pose()[0][2])

    assert abs(yaw_after_push(0.0)) < 0.005
    assert yaw_after_push(0.002) < -0.1 and yaw_after_push(-0.002) > 0.1


def test_centred_pushes_find_the_faces_a_sphere_meets_on_the_centroid_line():
    from robotplan.sdf import Box, LShape

    assert centred_pushes(Box((0.14, 0.10)), 0.025) == {0, 1, 2, 3}
    # from above (towards −y), the sphere on the L's centroid line meets the upright bar's
    # corner: no centred face push that way, so no route uses it
    lshape = LShape((0.16, 0.14), 0.06)
    assert centred_pushes(lshape, 0.03) == {0, 1, 2}
    scene = load_scene(TASKS / "obstacle_push.yaml")
    assert face_routes(scene, "box", GOAL, pushable={0, 1, 2}) == []
