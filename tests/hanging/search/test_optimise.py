"""The hanging program in Drake and the search around it, on a real (untrained, seeded)
H_hang: outcomes any sound solver path must give. The search's bookkeeping (budgets, accept,
resume, checks) is tested from uniform starts, four SNOPT iterations a solve; the threaded
program, which needs more, has its own test."""

import math

import numpy as np
import pytest
import torch

from robotplan.geometry.transforms import uniform_poses
from robotplan.hanging.models.hang_model import HangSpec, HangSuccess
from robotplan.hanging.program.problem import HangProblem, HangSettings, solve_hang_once
from robotplan.hanging.search.optimise import optimise_hang, sample_hang
from robotplan.hanging.search.starts import start_pose
from robotplan.sdf.mug_hook import Hook, Mug
from tests.conftest import TINY_HANG_SPEC

HOOK = Hook(post_height=0.3, lengths=(0.12, 0.04), angles=(math.radians(10), math.radians(60)))
MUG = Mug(radius=0.04, height=0.1, handle_height=0.6, handle_reach=0.03, handle_span=0.03)


@pytest.fixture(scope="module")
def problem():
    torch.manual_seed(0)
    return HangProblem(HangSuccess(HangSpec(**TINY_HANG_SPEC)).eval(), MUG, HOOK)


@pytest.mark.parametrize("approach", [0, 10])
def test_the_program_moves_a_mug_out_of_the_hook(problem, approach):
    """H_hang ≤ κ always holds (κ above anything the network says): what is left is the
    collision row, and the mug must leave the arm it starts through, with or without the
    approach stage before the whole program."""
    arm_z = HOOK.post_height + 0.08 * math.tan(HOOK.angles[0])
    X0 = np.array([0.08, -(MUG.radius - MUG.wall / 2), arm_z - 0.06, 1.0, 0.0, 0.0, 0.0])
    start_h, start_c = problem.evaluate(X0[None])
    assert start_c[0] > 0.1, "the start is deep in collision"
    settings = HangSettings(kappa=1e6, major_iterations=20, approach_iterations=approach)
    sol = solve_hang_once(problem, X0, settings)
    assert sol.feasible and sol.h_coll_cm3 <= settings.collision_cm3 + settings.feasibility_tol
    assert abs(np.linalg.norm(sol.pose[3:]) - 1) < 1e-9
    assert np.all(sol.pose[:3] >= problem.lo - 1e-6) and np.all(sol.pose[:3] <= problem.hi + 1e-6)
    assert abs(sol.h_hang) <= abs(start_h[0]) + 1e-6, "the cost (H_hang²) did not rise"
    assert sol.evaluations > 0


def test_a_threaded_solve_keeps_the_arm_through_the_handle(problem):
    """From a threaded start the program with the row H_thread ≥ 0 ends threaded and clear
    of the hook (within its bound for threaded poses): κ above anything the network says,
    so the rows left are the collision and threading rows, both met at the start's pool."""
    settings = HangSettings(kappa=1e6, major_iterations=30, approach_iterations=10)
    X0, part = start_pose(problem, np.random.default_rng(2), settings)
    assert part is not None
    sol = solve_hang_once(problem, X0, settings, part)
    tol = settings.feasibility_tol
    assert sol.feasible and sol.thread_mm is not None and sol.thread_mm >= -tol
    assert sol.h_coll_cm3 <= settings.thread_collision_cm3 + tol
    margin = problem.h_thread.values(sol.pose)[0] * 1e3
    assert margin == pytest.approx(sol.thread_mm)
    assert problem.violation(sol, settings) <= tol
    plain = solve_hang_once(problem, X0, HangSettings(major_iterations=1, approach_iterations=0))
    assert plain.thread_mm is None, "without a part, no row"


def test_feasible_means_within_the_solvers_tolerance_of_each_bound(problem):
    s = HangSettings()
    tol = s.feasibility_tol
    h = np.array([s.kappa + tol / 2, s.kappa + 2 * tol, 0.0, 0.0])
    c = np.array([0.0, 0.0, s.collision_cm3 + tol / 2, s.collision_cm3 + 2 * tol])
    assert problem.feasible(h, c, s).tolist() == [True, False, True, False]
    threaded = np.array([0.0, 0.0, s.thread_collision_cm3 + tol / 2, 0.0])
    thread_mm = np.array([-tol / 2, -2 * tol, 1.0, 1.0])
    assert problem.feasible(np.zeros(4), threaded, s, thread_mm=thread_mm).tolist() == [
        True, False, True, True]
    assert not problem.feasible(np.zeros(1), threaded[2:3], s)[0], "unthreaded: the tight bound"


def test_without_a_collision_row_a_pose_in_the_hook_is_kept(problem):
    """``collision="none"`` (the paper's point-cloud rows "no collision"): H_hang alone
    decides whether a pose is found, wherever the mug ends."""
    s = HangSettings(collision="none")
    h = np.array([0.0, s.kappa + 1.0])
    c = np.array([5.0, 0.0])
    assert problem.feasible(h, c, s).tolist() == [True, False]
    arm_z = HOOK.post_height + 0.08 * math.tan(HOOK.angles[0])
    X0 = np.array([0.08, -(MUG.radius - MUG.wall / 2), arm_z - 0.06, 1.0, 0.0, 0.0, 0.0])
    start_h, _ = problem.evaluate(X0[None])
    sol = solve_hang_once(problem, X0, HangSettings(kappa=1e6, major_iterations=20,
                                                    collision="none"))
    assert sol.feasible and abs(sol.h_hang) <= abs(start_h[0]) + 1e-6
    assert sol.feasible == bool(problem.feasible(np.array([sol.h_hang]), np.array([1e3]),
                                                 HangSettings(kappa=1e6,
                                                              collision="none"))[0])


def test_a_pooled_start_is_the_pools_best_pose_within_the_collision_bound(problem):
    settings = HangSettings(start_pool=32, threading=False)
    pool = uniform_poses(np.random.default_rng(5), (problem.lo + problem.hi) / 2,
                         float(problem.hi[0] - problem.lo[0]), 32)
    h, c = problem.evaluate(pool)
    clear = c <= settings.collision_cm3
    assert clear.any() and not clear.all(), "the pool holds both kinds"
    problem.evaluations = 0
    X0, part = start_pose(problem, np.random.default_rng(5), settings)
    assert part is None
    i = int(np.nonzero((pool == X0).all(axis=1))[0][0])
    assert clear[i] and h[i] == h[clear].min()
    assert problem.evaluations == 32
    single, _ = start_pose(problem, np.random.default_rng(5), HangSettings(threading=False))
    one = uniform_poses(np.random.default_rng(5), (problem.lo + problem.hi) / 2,
                        float(problem.hi[0] - problem.lo[0]), 1)[0]
    assert np.array_equal(single, one) and problem.evaluations == 32


def test_sampling_stops_at_a_feasible_pose_or_spends_its_budget(problem):
    rng = np.random.default_rng(0)
    found, none = sample_hang(problem, rng, (1e6, -1e6), settings=HangSettings(evaluations=64))
    assert found.feasible and found.evaluations <= 64
    assert not none.feasible and none.evaluations == 64


def test_sampling_thresholds_share_one_stream_of_poses(problem):
    settings = HangSettings(evaluations=128)
    h = problem.hang_values(np.random.default_rng(3).random((1, 7)))  # any value of this net
    kappas = (float(h[0]) + 10.0, -1e6)
    together = sample_hang(problem, np.random.default_rng(2), kappas, settings)
    alone = sample_hang(problem, np.random.default_rng(2), kappas[:1], settings)[0]
    assert together[0].evaluations == alone.evaluations
    assert np.array_equal(together[0].pose, alone.pose)


def test_restarts_stop_at_the_budget(problem):
    rng = np.random.default_rng(1)
    sol = optimise_hang(problem, rng, HangSettings(kappa=1e-12, evaluations=30,
                                                   major_iterations=5, approach_iterations=3,
                                                   threading=False),
                        restarts=20)
    assert not sol.feasible and sol.restarts < 20 and sol.evaluations >= 30


def test_a_refused_pose_does_not_end_the_search_and_a_resumed_one_goes_on(problem):
    """``accept`` (the closed loop's drop) sees every feasible pose; the first it takes ends
    the search; ``resume`` goes on from a refused result with the same generator, as if the
    search had never stopped."""
    settings = HangSettings(kappa=1e6, major_iterations=4, approach_iterations=2,
                            threading=False)
    seen: list[np.ndarray] = []

    def second(sol) -> bool:
        seen.append(sol.pose.copy())
        return len(seen) == 2

    taken = optimise_hang(problem, np.random.default_rng(6), settings, restarts=4,
                          accept=second)
    assert taken.feasible and taken.restarts == 2 and len(seen) == 2
    assert np.array_equal(taken.pose, seen[1])
    rng = np.random.default_rng(6)
    first = optimise_hang(problem, rng, settings, restarts=4)
    assert first.restarts == 1 and np.array_equal(first.pose, seen[0])
    resumed = optimise_hang(problem, rng, settings, restarts=4, accept=lambda sol: True,
                            resume=first)
    assert np.array_equal(resumed.pose, taken.pose)
    assert (resumed.restarts, resumed.evaluations) == (taken.restarts, taken.evaluations)
    assert first.restarts == 1, "the refused result itself is left as it was"
    none = optimise_hang(problem, np.random.default_rng(6), settings, restarts=3,
                         accept=lambda sol: False)
    assert none.feasible and none.restarts == 3


@pytest.mark.slow  # robust_samples is off by default; its nine programs take ~10 s
def test_a_robust_search_goes_on_past_a_pose_whose_neighbourhood_it_rejects(problem):
    """With ``robust_samples`` a feasible pose ends the restarts only when H_hang's median
    about it is ≤ robust_kappa; when none is, every restart runs and the feasible pose of
    least median wins."""
    base = HangSettings(kappa=1e6, major_iterations=4, robust_samples=8, approach_iterations=0,
                        threading=False)
    strict = optimise_hang(problem, np.random.default_rng(4),
                           HangSettings(**{**base.__dict__, "robust_kappa": -1e6}), restarts=3)
    assert strict.feasible and strict.restarts == 3 and strict.robust_h is not None
    loose = optimise_hang(problem, np.random.default_rng(4),
                          HangSettings(**{**base.__dict__, "robust_kappa": 1e6}), restarts=3)
    assert loose.feasible and loose.restarts == 1
    # the same first solve: the strict search kept the least median of its three
    assert strict.robust_h <= loose.robust_h
    plain = optimise_hang(problem, np.random.default_rng(4),
                          HangSettings(kappa=1e6, major_iterations=4, approach_iterations=0,
                                       threading=False),
                          restarts=3)
    assert plain.robust_h is None and plain.evaluations + 8 == loose.evaluations


def test_the_collision_row_on_what_the_model_reads():
    """``collision="model"``: for a ψ model H_coll reads ψ (the paper's occupancy rows: the
    overlap stays, its gradient in the pose goes); for an SDF model it is the SDF row."""
    arm_z = HOOK.post_height + 0.08 * math.tan(HOOK.angles[0])
    X0 = np.array([[0.08, -(MUG.radius - MUG.wall / 2), arm_z - 0.06, 1.0, 0.0, 0.0, 0.0]])
    torch.manual_seed(0)
    psi = HangProblem(HangSuccess(HangSpec(**TINY_HANG_SPEC, representation="occupancy")),
                      MUG, HOOK, "model")
    sdf_model = HangSuccess(HangSpec(**TINY_HANG_SPEC))
    on_sdf = HangProblem(sdf_model, MUG, HOOK)
    assert psi.collision_cm3(X0)[0] > 0.1 and on_sdf.collision_cm3(X0)[0] > 0.1
    _, (jac,) = psi.h_coll.jacobians(torch.from_numpy(X0))
    assert not jac.any()
    _, (jac,) = on_sdf.h_coll.jacobians(torch.from_numpy(X0))
    assert jac.abs().max() > 0
    same = HangProblem(sdf_model, MUG, HOOK, "model")
    assert same.collision_cm3(X0)[0] == on_sdf.collision_cm3(X0)[0]


def test_a_check_network_refuses_a_found_pose_and_the_search_goes_on(problem):
    """With a check network a feasible pose ends the restarts only where that network's
    H_hang is ≤ check_kappa too; when none is, every restart runs and the feasible pose of
    least check value wins. Each check costs one evaluation."""
    torch.manual_seed(1)
    check = HangSuccess(HangSpec(**TINY_HANG_SPEC)).eval()
    checked = HangProblem(problem.model, MUG, HOOK, check=check)
    base = HangSettings(kappa=1e6, major_iterations=4, approach_iterations=0, threading=False)
    strict = optimise_hang(checked, np.random.default_rng(4),
                           HangSettings(**{**base.__dict__, "check_kappa": -1e6}), restarts=3)
    assert strict.feasible and strict.restarts == 3
    assert strict.check_h == pytest.approx(checked.check_value(strict.pose), abs=1e-9)
    loose = optimise_hang(checked, np.random.default_rng(4),
                          HangSettings(**{**base.__dict__, "check_kappa": 1e6}), restarts=3)
    assert loose.feasible and loose.restarts == 1
    assert strict.check_h <= loose.check_h, "the same first solve, and two more to pick from"
    plain = optimise_hang(problem, np.random.default_rng(4), base, restarts=3)
    assert plain.check_h is None and np.array_equal(plain.pose, loose.pose)
    assert plain.evaluations + 1 == loose.evaluations
