"""The skeleton search end to end on box_push with the shipped F_flow: the most promising
skeleton is solved first, the search stops when it is good, and the plan works in pybullet."""


import numpy as np
import pytest

from robotplan import load_scene
from robotplan.pushing.execution.execute import execute_push
from robotplan.pushing.program.settings import ProgramSettings
from robotplan.pushing.program.skeleton import parse_skeleton
from robotplan.pushing.search.planner import FEASIBLE, GOOD_RMS_MM, search_push
from robotplan.pushing.search.request import SearchRequest
from robotplan.scene.task import load_task
from tests.conftest import DATA, ROOT

MODEL = ROOT / "learned" / "push_flow"


def _plan(violation: float = 1e-4, rms_mm: float = 3.0, cost: float = 1.0,
          clearance: float = np.inf):
    """A solved one-push plan of 21 states with the given violation, residual, cost and
    obstacle clearance."""
    from robotplan.pushing.program.solution import Solution

    sk = parse_skeleton("push@0", "pusher", "box")
    return Solution(sk, True, "", violation, cost, 1.0, np.zeros((21, 3)), np.zeros((21, 2)),
                    dynamics_mm2=np.full(20, rms_mm**2), clearance=clearance)


@pytest.mark.skipif(not (MODEL / "weights.pt").exists(), reason="push_flow not shipped")
def test_search_solves_box_push_and_the_plan_works_in_pybullet():
    task = load_task(DATA / "box_push_near.yaml")  # one push at the data's speeds
    scene = task.scene
    # the goal is east of the box: the push from straight behind (init 0 in the goal frame,
    # from the west) is tried first
    skeletons = [parse_skeleton(s, "pusher", "box") for s in ("push@2", "push@0")]
    result = search_push(SearchRequest(task, MODEL, workers=1, progress=False), skeletons,
                         ProgramSettings(iterations=40))
    assert len(result.candidates) == 1, "stops at the first good-enough plan"
    best = result.best
    assert best.skeleton == skeletons[1]
    assert best.violation <= FEASIBLE and best.dynamics_rms_mm <= GOOD_RMS_MM
    assert np.allclose(best.q_obj[0], scene.bodies["box"].pose)
    assert {"warm_start", "H_F", "H_coll", "H_PoC", "goal", "solver"} <= set(best.timings)
    assert 0 < sum(best.timings.values()) <= 1.01 * best.seconds + 0.01
    ex = execute_push(task, best.q_pusher)
    assert ex.coverage >= 0.95


def test_ranking_prefers_plans_the_learned_dynamics_believe():
    """Feasible plans rank by their H_F residual (ties below the noise floor), then cost; a
    feasible plan the model calls impossible is not solved."""
    from robotplan.pushing.program.solution import Solution
    from robotplan.pushing.search.planner import PLAUSIBLE_RMS_MM, SearchResult, plan_rank

    sk = parse_skeleton("push@0", "pusher", "box")

    def plan(violation, rms_mm, cost):
        return Solution(sk, True, "", violation, cost, 1.0, np.zeros((21, 3)),
                        np.zeros((21, 2)), dynamics_mm2=np.full(20, rms_mm**2))

    believed, doubted, broken = plan(1e-4, 3.0, 9.0), plan(1e-4, 8.0, 1.0), plan(0.5, 1.0, 0.1)
    assert sorted([broken, doubted, believed], key=plan_rank) == [believed, doubted, broken]
    assert plan_rank(plan(1e-4, 2.0, 5.0)) < plan_rank(plan(1e-4, 4.0, 6.0))  # both at the floor
    assert SearchResult(doubted).solved
    assert not SearchResult(plan(1e-4, PLAUSIBLE_RMS_MM + 1, 1.0)).solved


def test_the_search_stops_on_a_good_plan_or_after_its_patience_with_a_solved_one():
    from robotplan.pushing.search.planner import (
        PATIENCE_S,
        PLAUSIBLE_RMS_MM,
        is_solved,
        stops_search,
    )

    good, solved, broken = _plan(1e-4, 3.0), _plan(1e-4, 8.0), _plan(0.5, 1.0)
    assert is_solved(solved) and not is_solved(broken)
    early, late = PATIENCE_S - 1.0, PATIENCE_S + 1.0
    assert stops_search(good, True, 1.0, None, False)
    assert not stops_search(solved, True, early, None, False)
    assert stops_search(solved, True, late, None, False)
    # a broken plan collected late stops the search only if a solved one came before
    assert stops_search(broken, True, late, None, False)
    assert not stops_search(broken, False, late, None, False)
    # exhaustive: only the time budget stops it, once a solved plan is in hand
    assert not stops_search(good, True, late, None, True)
    assert stops_search(broken, True, 101.0, 100.0, True)
    # past the budget without one it waits for the programs still running
    assert not stops_search(broken, False, 101.0, 100.0, True)
    # a looser good-enough residual (F_q's overlay) stops at the first solved plan
    assert stops_search(solved, False, early, None, False, PLAUSIBLE_RMS_MM)
    assert not stops_search(broken, False, early, None, False, PLAUSIBLE_RMS_MM)


def test_plans_around_obstacles_must_keep_the_margin():
    """A feasible plan that skims an obstacle is neither good enough nor solved, and ranks
    behind one that keeps OBSTACLE_MARGIN, whatever their costs."""
    from robotplan.pushing.search.planner import (
        OBSTACLE_MARGIN,
        SearchResult,
        good_enough,
        plan_rank,
    )

    def plan(clearance: float, cost: float):
        return _plan(cost=cost, clearance=clearance)

    skims, clear, free = plan(0.01, 1.0), plan(OBSTACLE_MARGIN + 0.01, 5.0), plan(np.inf, 7.0)
    assert not good_enough(skims) and not SearchResult(skims).solved
    assert good_enough(clear) and SearchResult(clear).solved and good_enough(free)
    assert min([skims, clear], key=plan_rank) is clear
    assert plan_rank(plan(0.015, 1.0)) < plan_rank(plan(0.005, 1.0))  # the shortfall itself ranks


def test_search_measures_the_clearance_of_its_plans():
    from robotplan.pushing.program.solution import Solution
    from robotplan.pushing.search.planner import plan_clearance

    scene = load_scene(ROOT / "tasks" / "obstacle_push.yaml")
    sk = parse_skeleton("push@0", "pusher", "box")
    q = np.column_stack((np.linspace(-0.25, 0.35, 21), np.full(21, 0.23), np.zeros(21)))
    sol = Solution(sk, True, "", 1e-4, 1.0, 1.0, q, np.zeros((21, 2)))
    assert plan_clearance(scene, sol) == pytest.approx(0.02, abs=1e-9)
