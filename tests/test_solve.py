"""robotplan.solve's search logic around the programs (the programs themselves: test_planner
and the slow end-to-end tests)."""

import robotplan.solve as solve_module
from robotplan.planner import SearchResult
from robotplan.scene import load_scene
from tests.conftest import TASKS


def test_arm_search_tries_init_points_seen_from_the_goal_when_face_pushes_fail(
        monkeypatch, tmp_path):
    """Every program of the first search fails (no plan): the second search gets the goal
    frame's reach-pruned candidates, left arm only for this L in the left arm's reach."""
    calls = []

    def no_plan(scene, model_dir, skeletons, settings, workers, progress, exhaustive,
                time_budget, space):
        calls.append((list(skeletons), space))
        return SearchResult(None, [], 1.0)

    monkeypatch.setattr(solve_module, "search_push", no_plan)
    scene = load_scene(TASKS / "variants" / "left_only_lshape.yaml")
    doc = solve_module.solve_scene(scene, tmp_path, TASKS.parent / "learned" / "push_flow",
                                   progress=False, quiet=True)
    assert doc["status"] == "no_solution"
    assert [space.init_frame for _, space in calls] == ["object", "goal"]
    first, second = (skeletons for skeletons, _ in calls)
    assert len(first) == 1 and len(second) == 20
    assert {p.actor for sk in second for p in sk.phases} == {"left"}
    assert doc["plan_seconds"] == 2.0  # both searches' time


def test_a_given_skeleton_gets_no_fallback(monkeypatch, tmp_path):
    calls = []

    def no_plan(*args):
        calls.append(args)
        return SearchResult(None, [], 1.0)

    monkeypatch.setattr(solve_module, "search_push", no_plan)
    scene = load_scene(TASKS / "variants" / "left_only_lshape.yaml")
    solve_module.solve_scene(scene, tmp_path, TASKS.parent / "learned" / "push_flow",
                             skeleton="push@0", progress=False, quiet=True)
    assert len(calls) == 1
