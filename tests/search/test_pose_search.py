"""The pose goal's tier: fitted pushes as skeletons with their guess, solved by SNOPT."""

import math

import numpy as np

from robotplan.program.push_program import PushProgram
from robotplan.program.skeleton import load_skeleton_space
from robotplan.program.solution import FEASIBLE
from robotplan.scene.loader import parse_scene
from robotplan.search.pose_search import pose_candidates
from robotplan.search.scene_search import settings_for
from tests.search.test_pose_pushes import BOX, scene_doc


def test_kinematic_program_solves_a_turn_from_the_fitted_guess():
    """A box moved 12 cm and turned 60°: the fitted guess meets sticking, H_PoC and the pose
    row exactly, and SNOPT's kinematic stage ends feasible from it."""
    scene = parse_scene(scene_doc(BOX, [0.12, 0.05, 0.3 + math.radians(60)]))
    settings = settings_for(scene)
    space, skeletons, guesses = pose_candidates(scene, "object", "pusher",
                                                load_skeleton_space(), settings)
    assert skeletons
    sk = skeletons[0]
    prog = PushProgram(scene, sk, None, space, settings, guess=guesses[sk])
    x = np.zeros(prog.prog.num_vars())
    for V, value in prog._guess_pairs():
        x[prog.prog.FindDecisionVariableIndices(V.ravel())] = value.ravel()
    worst, _ = prog.evaluate(x)
    assert worst["sticking"] < 1e-6 and worst["H_PoC"] < 1e-6 and worst["H_pose"] < 0.01
    sol = prog.solve()
    assert sol.violation <= FEASIBLE
    turn = sol.q_obj[-1, 2] - sol.q_obj[0, 2]
    assert abs(turn - math.radians(60)) < 0.02


def test_a_given_skeleton_fixes_the_faces_of_the_fit():
    """``--skeleton push@1,push@2`` for a pose goal: the fit of exactly those face classes
    (object frame), with its guess, even when another sequence would fit better."""
    from robotplan.program.skeleton import parse_skeleton

    scene = parse_scene(scene_doc(BOX, [0.12, 0.05, 0.3 + math.radians(60)]))
    settings = settings_for(scene)
    given = parse_skeleton("push@1,push@2", "pusher", "object")
    space, skeletons, guesses = pose_candidates(scene, "object", "pusher",
                                                load_skeleton_space(), settings, given=given)
    assert skeletons == [given] and space.init_frame == "object"
    g = guesses[given]
    assert g["q_obj"].shape == (4 * space.steps_per_phase + 1, 3)
    assert not np.allclose(g["q_obj"][-1], g["q_obj"][0])  # it pushes
