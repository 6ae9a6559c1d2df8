"""robotplan.pushing.search.tiers and the one loop of search_scene over them: which tiers each task
is searched with, and when a tier ends the search (the programs themselves: test_planner,
test_pose_search and the slow end-to-end tests)."""

from dataclasses import replace

import numpy as np
import pytest

import robotplan.pushing.search.scene_search as search_module
from robotplan.pushing.program.skeleton import parse_skeleton
from robotplan.pushing.program.solution import Solution
from robotplan.pushing.search.planner import SearchResult
from robotplan.pushing.search.request import SearchRequest
from robotplan.pushing.search.tiers import load_tiers
from robotplan.scene import load_scene
from robotplan.scene.reader import SchemaError
from robotplan.scene.schema import PoseGoal
from robotplan.scene.task import make_task
from tests.conftest import TASKS

MODEL = TASKS.parent / "learned" / "push_flow"


def _tiers_for(request: SearchRequest) -> list[str]:
    return [t.name for t in load_tiers() if t.when.holds(request)]


def _request(name: str, **changes) -> SearchRequest:
    return SearchRequest(make_task(load_scene(TASKS / f"{name}.yaml")), MODEL, quiet=True,
                         progress=False, **changes)


def test_every_tier_has_a_search_and_a_plain_tier_is_for_every_task():
    tiers = load_tiers()
    assert {t.candidates for t in tiers} <= set(search_module.TIER_SEARCHES)
    plain = [t for t in tiers if t.candidates == "plain"]
    for name in ("two_arm_touch", "box_push", "obstacle_push", "three_objects"):
        assert sum(t.when.holds(_request(name)) for t in plain) == 1, name


def test_each_task_is_searched_with_the_tiers_its_kind_asks_for():
    box = _request("box_push")
    assert _tiers_for(box) == ["region_fits_first", "plain", "region_fits"]
    assert _tiers_for(box.but(replan=True)) == ["region_fits_replan", "plain"]
    tail = box.but(replan=True, skeleton="push@0", guesses={"tail": {}})
    assert _tiers_for(tail) == ["region_fits_tail", "plain"]
    assert _tiers_for(box.but(skeleton="push@0")) == ["plain"]
    assert _tiers_for(_request("obstacle_push")) == ["plain", "routes"]
    assert _tiers_for(_request("three_objects")) == ["plain"]
    assert _tiers_for(_request("two_arm_handover")) == ["plain"]
    scene = load_scene(TASKS / "box_push.yaml")
    posed = replace(scene, goal=PoseGoal("box", (0.1, 0.1, 0.5)))
    pose = SearchRequest(make_task(posed), MODEL)
    assert _tiers_for(pose) == ["pose_fits", "plain_pose"]
    assert _tiers_for(pose.but(guesses={"warm": {}})) == ["plain_pose_tail"]
    assert _tiers_for(pose.but(replan=True)) == ["pose_fits"]  # no plain pushes executing
    assert _tiers_for(pose.but(replan=True, guesses={"tail": {}})) == ["plain_pose_tail"]


def _fake_tiers(monkeypatch, results: dict[str, SearchResult]) -> list[tuple[str, float]]:
    """Each tier's search replaced by one that returns ``results[kind]`` and records the
    kind and the time budget it was given."""
    calls: list[tuple[str, float | None]] = []

    def fake(kind):
        def search(request, budgets, space):
            calls.append((kind, request.time_budget))
            result = results[kind]
            return result, {id(s): space for s in result.candidates}
        return search

    monkeypatch.setattr(search_module, "TIER_SEARCHES",
                        {kind: fake(kind) for kind in search_module.TIER_SEARCHES})
    return calls


def _plan(violation: float, rms_mm: float = 1.0) -> Solution:
    sk = parse_skeleton("push@0", "pusher", "box")
    return Solution(sk, True, "", violation, 1.0, 1.0, np.zeros((21, 3)), np.zeros((21, 2)),
                    dynamics_mm2=np.full(20, rms_mm**2))


def test_the_loop_ends_where_the_table_says(monkeypatch):
    """Solved fitted pushes end a fresh search; unsolved, the plain tier gets what is left
    of the time budget, and where it solves nothing the fits at the task's own budget come
    past the budget; in a re-plan, settled fitted pushes end it before the plain tier, and
    unsettled ones are not charged to the plain tier's budget."""
    solved, unsolved = _plan(1e-5), _plan(0.5)  # FEASIBLE: 1e-2
    results = {"plain": SearchResult(solved, [solved], 3.0),
               "region_fits": SearchResult(solved, [solved], 1.0)}
    calls = _fake_tiers(monkeypatch, results)
    result, _ = search_module.search_scene(_request("box_push", time_budget=2.0))
    assert calls == [("region_fits", 2.0)] and result.best is solved

    results["region_fits"] = SearchResult(None, [], 1.0)
    calls.clear()
    result, _ = search_module.search_scene(_request("box_push", time_budget=2.0))
    assert calls == [("region_fits", 2.0), ("plain", 1.0)] and result.best is solved

    results["plain"] = SearchResult(unsolved, [unsolved], 3.0)
    calls.clear()
    result, spaces = search_module.search_scene(_request("box_push", time_budget=2.0))
    # past the budget: still tried
    assert calls == [("region_fits", 2.0), ("plain", 1.0), ("region_fits", 0.0)]
    assert result.seconds == 5.0 and set(spaces) == {id(unsolved)}

    fitted = _plan(0.02)
    results["region_fits"] = SearchResult(fitted, [fitted], 1.5)
    calls.clear()
    again = _request("box_push", time_budget=2.0, replan=True, last_resort=0.05)
    result, _ = search_module.search_scene(again)
    assert [k for k, _ in calls] == ["region_fits"] and result.best is fitted  # settled
    calls.clear()
    result, _ = search_module.search_scene(again.but(last_resort=None))
    assert calls == [("region_fits", 2.0), ("plain", 2.0)]  # its 1.5 s are not charged
    assert result.seconds == 4.5


def test_a_bad_tier_table_is_refused_naming_the_field(tmp_path):
    path = tmp_path / "tiers.yaml"
    path.write_text("tiers:\n  - {name: x, candidates: everything}\n")
    with pytest.raises(SchemaError, match=r"tiers\[0\]\.candidates"):
        load_tiers.__wrapped__(path)
    path.write_text("tiers:\n  - {name: x, candidates: plain, when: {arms: true}}\n")
    with pytest.raises(SchemaError, match=r"tiers\[0\]\.when"):
        load_tiers.__wrapped__(path)


def test_a_tier_names_only_budgets_of_the_table(tmp_path):
    from robotplan.pushing.search.tiers import load_budgets

    path = tmp_path / "tiers.yaml"
    path.write_text("budgets: {fast: {iterations: 5}}\n"
                    "tiers:\n  - {name: x, candidates: plain, budgets: [fast, slow]}\n")
    with pytest.raises(ValueError, match=r"tiers\[0\]\.budgets: 'slow' is not a budget"):
        load_tiers.__wrapped__(path)
    path.write_text("budgets: {fast: {no_such: 5}}\ntiers: []\n")
    with pytest.raises(ValueError, match=r"budgets: fast\.no_such: not a program setting"):
        load_budgets.__wrapped__(path)
    path.write_text("budgets: {fast: {iterations: 5}}\ntiers: []\n")
    assert load_budgets.__wrapped__(path) == {"fast": {"iterations": 5}}
