"""The pose goal's tier: fitted pushes as skeletons with their guess, solved by SNOPT."""

import math

import numpy as np
import pytest

from robotplan.pushing.program.push_program import PushProgram
from robotplan.pushing.program.skeleton import load_skeleton_space
from robotplan.pushing.program.solution import FEASIBLE
from robotplan.pushing.search.pose_search import pose_candidates
from robotplan.pushing.search.scene_search import task_settings
from robotplan.scene.loader import parse_scene
from robotplan.scene.task import make_task
from tests.pushing.search.test_pose_pushes import BOX, scene_doc


def test_kinematic_program_solves_a_turn_from_the_fitted_guess():
    """A box moved 12 cm and turned 60°: the fitted guess meets sticking, H_PoC, the
    quasi-static push and the pose row exactly, and SNOPT's kinematic stage ends feasible
    from it."""
    task = make_task(parse_scene(scene_doc(BOX, [0.12, 0.05, 0.3 + math.radians(60)])))
    assert (task.obj, task.actors, task.goal) == ("object", ("pusher",), "pose")
    settings = task_settings(task)
    space, skeletons, guesses = pose_candidates(task, load_skeleton_space(), settings)
    assert skeletons
    sk = skeletons[0]
    prog = PushProgram(task, sk, None, space, settings, guess=guesses[sk])
    x = np.zeros(prog.prog.num_vars())
    for V, value in prog._guess_pairs():
        x[prog.prog.FindDecisionVariableIndices(V.ravel())] = value.ravel()
    worst, _ = prog.evaluate(x)
    assert worst["sticking"] < 1e-6 and worst["H_PoC"] < 1e-6 and worst["H_pose"] < 0.01
    assert worst["quasi_static"] < 1e-6  # the discrete turning law and the friction cone
    sol = prog.solve()
    assert sol.violation <= FEASIBLE
    turn = sol.q_obj[-1, 2] - sol.q_obj[0, 2]
    assert abs(turn - math.radians(60)) < 0.02


def test_a_given_skeleton_fixes_the_faces_of_the_fit():
    """``--skeleton push@1,push@2`` for a pose goal: the fit of exactly those face classes
    (object frame), with its guess, even when another sequence would fit better."""
    from robotplan.pushing.program.skeleton import parse_skeleton

    task = make_task(parse_scene(scene_doc(BOX, [0.12, 0.05, 0.3 + math.radians(60)])))
    settings = task_settings(task)
    given = parse_skeleton("push@1,push@2", "pusher", "object")
    space, skeletons, guesses = pose_candidates(task, load_skeleton_space(), settings,
                                                given=given)
    assert skeletons == [given] and space.init_frame == "object"
    g = guesses[given]
    assert g["q_obj"].shape == (4 * space.steps_per_phase + 1, 3)
    assert not np.allclose(g["q_obj"][-1], g["q_obj"][0])  # it pushes


def test_without_a_close_fit_the_fits_within_fit_tolerance_are_candidates(monkeypatch):
    """Where no fit leaves FIT_SHARE of the start's error (here: a share of zero), the
    candidates are the fits within FIT_TOLERANCE, not none."""
    from robotplan.pushing.search import pose_pushes

    task = make_task(parse_scene(scene_doc(BOX, [0.12, 0.05, 0.3 + math.radians(60)])))
    scene = task.scene
    settings = task_settings(task)
    space = load_skeleton_space()
    _, close, _ = pose_candidates(task, space, settings)
    monkeypatch.setattr(pose_pushes, "FIT_SHARE", 0.0)
    fits = pose_pushes.fit_pose_pushes(task, tuple(scene.goal.pose),
                                       turn_gain=settings.row("quasi_static").turn_gain)
    assert fits and not any(f.within for f in fits)
    _, loose, guesses = pose_candidates(task, space, settings)
    assert loose and set(loose) == set(guesses)
    assert len(loose) == sum(f.error <= pose_pushes.FIT_TOLERANCE for f in fits)
    assert close  # with the shipped share, the close fits are candidates


def region_doc(size: list[float], yaw: float, region: list[float]) -> dict:
    """A box of ``size`` at ``yaw`` and a box region of ``region`` 35 cm east of it."""
    doc = scene_doc({"type": "box", "size": size}, [0.0, 0.0, 0.0])
    doc["objects"][0]["pose"] = [0.0, 0.0, yaw]
    doc["goal"] = {"type": "region", "object": "object",
                   "region": {"shape": {"type": "box", "size": region},
                              "pose": [0.35, 0.02, 0.0]}}
    return doc


def _outside_share(scene, pose, settings) -> float:
    import torch

    from robotplan.pushing.program.rows_goal import region_goal

    body = scene.bodies["object"]
    H = region_goal(body, scene.goal_region, settings)
    return float(H(torch.tensor([pose], dtype=torch.float64))[0, 0]) / body.area


def test_a_region_target_meets_the_goal_row_with_the_least_turn():
    """A 22 x 16 cm box turned 29° into a 40 x 40 cm region: at its start yaw the program's
    goal row (H_g, inset) leaves too much outside, so the target turns it, by the least
    5° step that leaves at most half of goal_tol outside, with the centroid on the region's."""
    from robotplan.pushing.search.pose_search import REGION_SLACK, YAW_STEP_DEG, region_target

    task = make_task(parse_scene(region_doc([0.22, 0.16], 0.5, [0.4, 0.4])))
    scene = task.scene
    settings = task_settings(task)
    x, y, yaw = region_target(task, settings)
    assert np.allclose([x, y], [0.35, 0.02], atol=1e-9)  # a box's centroid is its origin
    bound = REGION_SLACK * settings.row("goal").tol
    assert _outside_share(scene, (x, y, yaw), settings) <= bound
    assert _outside_share(scene, (x, y, 0.5), settings) > bound
    turn = yaw - 0.5
    assert -0.5 < turn < 0.0  # towards the region's axes
    less = turn + math.radians(YAW_STEP_DEG)
    assert _outside_share(scene, (x, y, 0.5 + less), settings) > bound


def test_a_region_target_without_room_to_spare_takes_the_least_turn_to_the_best_fit():
    """A 26 x 18 cm box turned 29° in a 40 x 40 cm region leaves more than the slack outside
    at any yaw: the target is the least turn whose share is near the least (about 0°, not a
    quarter or half turn to the same fit)."""
    from robotplan.pushing.search.pose_search import region_target

    task = make_task(parse_scene(region_doc([0.26, 0.18], 0.5, [0.4, 0.4])))
    yaw = region_target(task, task_settings(task))[2]
    assert abs(yaw) < math.radians(5.0)


def test_a_region_target_keeps_a_fitting_yaw_and_refuses_a_region_too_small():
    from robotplan.pushing.search.pose_search import region_target

    small = make_task(parse_scene(region_doc([0.1, 0.06], 0.37, [0.4, 0.4])))
    settings = task_settings(small)
    assert region_target(small, settings)[2] == pytest.approx(0.37)  # fits as is
    # larger than the 7 cm wide region in every direction: more than half outside at any yaw
    narrow = make_task(parse_scene(region_doc([0.18, 0.18], 0.0, [0.5, 0.07])))
    assert region_target(narrow, settings) is None


def test_a_region_target_centres_an_l_shape_by_its_box_where_its_centroid_would_stick_out():
    """A 20 cm L-shape (6 cm legs) and a 40 cm square region: its centroid lies ~3 cm off its
    bounding box's centre, so with the centroid on the region's the goal row finds 0.3 % or
    more of it outside at every turn; with its box centred it fits unturned (0.08 %), and
    the target is that pose."""
    import torch

    from robotplan.pushing.program.rows_goal import region_goal
    from robotplan.pushing.search.pose_search import REGION_SLACK, region_target

    doc = {"version": 1, "name": "l_region",
           "workspace": {"center": [0.0, 0.0], "size": [1.4, 1.4], "resolution": 0.01},
           "objects": [{"name": "object", "pose": [-0.2, 0.0, 0.0],
                        "shape": {"type": "lshape", "size": [0.2, 0.2], "thickness": 0.06}}],
           "pushers": [{"name": "pusher", "radius": 0.02, "position": [-0.45, 0.0]}],
           "goal": {"type": "region", "object": "object",
                    "region": {"shape": {"type": "box", "size": [0.4, 0.4]},
                               "pose": [0.25, 0.0, 0.0]}}}
    task = make_task(parse_scene(doc))
    settings = task_settings(task)
    body = task.scene.bodies["object"]
    x, y, yaw = region_target(task, settings)
    H = region_goal(body, task.region, settings)
    outside = float(H(torch.tensor([[x, y, yaw]], dtype=torch.float64))[0, 0]) / body.area
    assert outside <= REGION_SLACK * settings.row("goal").tol
    assert abs(yaw) < 1e-9  # unturned
