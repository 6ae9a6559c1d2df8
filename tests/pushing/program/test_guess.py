"""The initial guess: where the pusher meets the object, and H_PoC's contact points."""

import math

import numpy as np
import pytest
import torch

from robotplan.pushing.program.guess import contact_offset, contact_point_guess
from robotplan.pushing.program.push_program import PushProgram
from robotplan.pushing.program.settings import ProgramSettings
from robotplan.pushing.program.skeleton import load_skeleton_space, parse_skeleton
from robotplan.scene.task import load_task
from tests.conftest import DATA, TASKS


def kinematic_program(scene_file, obj, text="push@0"):
    task = load_task(scene_file)
    return PushProgram(task, parse_skeleton(text, "pusher", obj), None, load_skeleton_space(),
                       ProgramSettings())


def phi_obj(prog, points, X):
    return prog.obj.sdf(torch.as_tensor(points, dtype=torch.float64)[None],
                        torch.as_tensor(X, dtype=torch.float64)[None])[0].numpy()


@pytest.mark.parametrize("scene_file, obj", [(DATA / "lshape_push.yaml", "object"),
                                             (TASKS / "box_push.yaml", "box")],
                         ids=["lshape-origin-in-notch", "box"])
def test_contact_offset_is_the_outermost_touch_on_the_ray(scene_file, obj):
    prog = kinematic_program(scene_file, obj)
    X = np.array(prog.obj.pose, dtype=float)
    target = prog.pusher.shape.radius - 0.001
    reach = prog.obj.shape.bound_radius + prog.pusher.shape.radius
    touched = 0
    for ang in np.linspace(0.0, 2 * math.pi, 24, endpoint=False):
        u = np.array([math.cos(ang), math.sin(ang)])
        d = float(contact_offset(prog, X, u) @ u)
        beyond = X[:2] + np.linspace(d + 1e-4, reach, 50)[:, None] * u
        assert (phi_obj(prog, beyond, X) >= target - 1e-6).all()  # free from there outwards
        offset = contact_offset(prog, X, u)
        at = phi_obj(prog, (X[:2] + offset)[None], X)[0]
        assert abs(at - target) < 1e-6  # the pusher touches the L (1 mm deep)
        if abs(float(offset @ u) - np.linalg.norm(offset)) < 1e-9:
            touched += 1  # on the ray itself
    assert touched >= 12  # the others look into the notch's opening


def test_guess_contact_points_stay_off_the_pusher_centre():
    prog = kinematic_program(DATA / "lshape_push.yaml", "object")
    g = prog.guess
    steps = np.asarray(prog.push_steps)
    p, q2, q1 = g["p"], g["q_pusher"][steps], g["q_obj"][steps]
    r = prog.pusher.shape.radius
    # φ_pusher's gradient vanishes at its centre: a contact point started there never moves
    assert (np.linalg.norm(p - q2, axis=1) >= 0.5 * r - 1e-9).all()
    # the pusher is guessed outside the L, touching it after the approach steps
    gap = np.array([phi_obj(prog, q2[i:i + 1], q1[i])[0] for i in range(len(steps))]) - r
    assert (gap > -2e-3).all() and abs(gap[-1]) < 2e-3


def test_contact_point_guess_is_on_the_pusher_facing_the_object():
    prog = kinematic_program(DATA / "lshape_push.yaml", "object")
    X = np.tile(np.array(prog.obj.pose, dtype=float), (3, 1))
    q2 = X[:, :2] + contact_offset(prog, X[0], np.array([0.3, -1.0])) + [[0, 0], [0.01, 0],
                                                                         [0, 0.02]]
    p = contact_point_guess(prog, X, q2)
    r = prog.pusher.shape.radius
    assert np.allclose(np.linalg.norm(p - q2, axis=1), r, atol=1e-9)
    # facing the object: p is nearer to it than the centre by the radius
    assert np.allclose(phi_obj(prog, p[:1], X[0]), phi_obj(prog, q2[:1], X[0]) - r, atol=1e-6)
