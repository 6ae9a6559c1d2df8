"""Pose goals: quasi-static pushes along face normals, fitted in closed form."""

import math

import numpy as np
import pytest
import torch

from robotplan.functionals.sticking import QuasiStaticPush
from robotplan.pushing.search.pose_pushes import (
    FIT_SHARE,
    FIT_TOLERANCE,
    PosePushes,
    TurningBody,
    faces_of,
    fit_pose_pushes,
    push_arc,
    rotation,
)
from robotplan.pushing.search.pose_search import pose_guess
from robotplan.scene.loader import parse_scene
from robotplan.scene.task import make_task


def scene_doc(shape: dict, goal_pose: list[float], radius: float = 0.03) -> dict:
    return {"version": 1, "name": "pose_test",
            "workspace": {"center": [0.0, 0.0], "size": [1.4, 1.4], "resolution": 0.01},
            "objects": [{"name": "object", "shape": shape, "pose": [0.0, 0.0, 0.3]}],
            "pushers": [{"name": "pusher", "radius": radius, "position": [0.25, 0.2]}],
            "goal": {"type": "pose", "object": "object", "pose": goal_pose}}


BOX = {"type": "box", "size": [0.16, 0.12]}
TEE = {"type": "polygon", "vertices": [[-0.1, 0.06], [-0.1, 0.02], [-0.025, 0.02],
                                       [-0.025, -0.1], [0.025, -0.1], [0.025, 0.02],
                                       [0.1, 0.02], [0.1, 0.06]]}


def test_push_arc_integrates_the_turning_law():
    """The closed-form arc against many small steps of c² Δθ = r × Δc along the normal; the
    program's QuasiStaticPush rows vanish along it (turn row, inside the cone)."""
    r_B, n_B, c = np.array([-0.08, 0.04]), np.array([1.0, 0.0]), 0.07
    c0, yaw0 = np.array([0.1, -0.2]), 0.4
    s = np.linspace(0.0, 0.15, 301)
    cs, ys = push_arc(c0, yaw0, r_B, n_B, c, s)
    x, yaw = c0.copy(), yaw0
    rate = (r_B[0] * n_B[1] - r_B[1] * n_B[0]) / c**2  # r × n is the same in any frame
    for ds in np.diff(s):  # midpoint rule
        mid = yaw + 0.5 * rate * ds
        c_m, s_m = math.cos(mid), math.sin(mid)
        x = x + ds * np.array([c_m * n_B[0] - s_m * n_B[1], s_m * n_B[0] + c_m * n_B[1]])
        yaw += rate * ds
    assert np.linalg.norm(x - cs[-1]) < 1e-5 and abs(yaw - ys[-1]) < 1e-9
    assert abs(ys[-1] - yaw0) > 0.5  # a lever of 4 cm turns it by more than half a radian
    H = QuasiStaticPush(np.zeros(2), c, mu=0.08)
    X = torch.as_tensor(np.column_stack((cs, ys)))
    Rs = [np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]]) for a in ys]
    p = torch.as_tensor(np.array([cc + R @ r_B for cc, R in zip(cs, Rs, strict=True)]))
    pusher = p - 0.03 * torch.as_tensor(np.array([R @ n_B for R in Rs]))
    rows = H(X[:-1], X[1:], pusher[1:], p[1:]).numpy()
    assert np.abs(rows[:, 0]).max() < 1e-5  # m: the turning law holds step by step
    assert (rows[:, 1:] > -1e-6).all()  # inside the friction cone


def test_faces_of_a_box_and_a_tee():
    box = parse_scene(scene_doc(BOX, [0.2, 0.1, 1.0]))
    faces = faces_of(box, "object", "pusher")
    assert sorted(f.init for f in faces) == [0, 1, 2, 3]
    for f in faces:  # the inward normal points from the face to the centre
        assert float(f.n @ (np.zeros(2) - f.point(0.5))) > 0
    tee = parse_scene(scene_doc(TEE, [0.2, 0.1, 1.0], radius=0.05))
    small = parse_scene(scene_doc(TEE, [0.2, 0.1, 1.0], radius=0.02))
    # the bar's underside beside the stem (7.5 cm) is too narrow for a 5 cm pusher only
    assert len(faces_of(tee, "object", "pusher")) < len(faces_of(small, "object", "pusher"))


@pytest.mark.parametrize("shape", [BOX, TEE])
def test_fit_reaches_a_pose_made_by_two_pushes(shape):
    scene = parse_scene(scene_doc(shape, [0.0, 0.0, 0.0]))
    faces = faces_of(scene, "object", "pusher")
    made = PosePushes((faces[0], faces[1]), (0.3, 0.7), (0.12, 0.08), 0.0)
    guess = pose_guess(scene, "object", "pusher", made, 20)
    goal = [float(v) for v in guess["q_obj"][-1]]
    scene = parse_scene(scene_doc(shape, goal))
    fits = fit_pose_pushes(make_task(scene), tuple(goal), max_pushes=2)
    assert fits and fits[0].error <= FIT_TOLERANCE
    body = TurningBody(scene, "object", 1.0)
    for fit in fits:  # fewest pushes first, each within tolerance when the first is
        end = pose_guess(scene, "object", "pusher", fit, 20)["q_obj"][-1]
        miss = np.hypot(*(end[:2] - goal[:2])) + body.radius * abs(end[2] - goal[2])
        assert fit.error > FIT_TOLERANCE or miss < 2 * FIT_TOLERANCE


@pytest.mark.parametrize("shape", [BOX, TEE])
def test_a_turn_in_place_near_the_target_is_fitted_with_two_pushes(shape):
    """The object 1.7° from its target about its centroid (a few millimetres at its turning
    radius, under FIT_TOLERANCE): one push turns it only along an arc, so none counts as
    reaching the target; the fits must leave at most FIT_SHARE of the start's error, which
    two pushes do."""
    start = parse_scene(scene_doc(shape, [0.0, 0.0, 0.3]))
    body = TurningBody(start, "object", 1.0)
    yaw0, yaw = 0.3, 0.3 + 0.03
    c_W = rotation(yaw0) @ body.c_B  # the centroid stays where it is
    goal = (*(c_W - rotation(yaw) @ body.c_B), yaw)
    scene = parse_scene(scene_doc(shape, [float(v) for v in goal]))
    start_error = body.radius * 0.03
    assert start_error < FIT_TOLERANCE
    one = fit_pose_pushes(make_task(scene), goal, max_pushes=1)
    assert one and not any(f.within for f in one)
    assert all(f.tolerance == pytest.approx(FIT_SHARE * start_error) for f in one)
    two = fit_pose_pushes(make_task(scene), goal, max_pushes=2)
    assert two[0].within and len(two[0].faces) == 2
    assert two[0].error <= FIT_SHARE * start_error
    assert min(two[0].lengths) > 0.0005  # both push: neither is a placeholder


def test_the_guess_keeps_the_pusher_on_the_table_beside_its_edge():
    """A box 8 cm from the table's edge pushed away from it: the guess's standoff behind
    the face towards the edge and its circle round the box would lie beyond the edge;
    every state of the pusher stays on the table."""
    doc = scene_doc(BOX, [0.0, 0.0, 0.0])
    doc["objects"][0]["pose"] = [0.62, 0.0, 0.0]
    doc["pushers"][0]["position"] = [0.45, 0.0]
    scene = parse_scene(doc)
    # the face towards the edge, pushed back from the edge's side
    face = min(faces_of(scene, "object", "pusher"), key=lambda f: f.n[0])
    pushes = PosePushes((face,), (0.5,), (0.05,), 0.0)
    q = pose_guess(scene, "object", "pusher", pushes, 12)["q_pusher"]
    x0, x1, y0, y1 = scene.workspace.bounds
    assert (q[:, 0] >= x0).all() and (q[:, 0] <= x1).all()
    assert (q[:, 1] >= y0).all() and (q[:, 1] <= y1).all()
