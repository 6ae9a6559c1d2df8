"""robotplan.pushing.search.scene_search: the search logic around the programs (the programs
themselves: test_planner and the slow end-to-end tests)."""


import robotplan.pushing.search.scene_search as search_module
from robotplan.api import solve
from robotplan.pushing.search.planner import SearchResult
from robotplan.pushing.search.request import SearchRequest
from robotplan.scene import load_scene
from robotplan.scene.task import load_task, make_task
from tests.conftest import TASKS


def test_arm_search_tries_init_points_seen_from_the_goal_when_face_pushes_fail(
        monkeypatch, tmp_path):
    """Every program of the first search fails (no plan): the second search gets the goal
    frame's reach-pruned candidates, left arm only for this L in the left arm's reach."""
    calls = []

    def no_plan(request, skeletons, settings=None, space=None, ordered=False):
        calls.append((list(skeletons), space))
        return SearchResult(None, [], 1.0)

    monkeypatch.setattr(search_module, "search_push", no_plan)
    scene = load_scene(TASKS / "variants" / "left_only_lshape.yaml")
    doc = solve(scene, tmp_path, TASKS.parent / "learned" / "push_flow",
                                   progress=False, quiet=True)
    assert doc["status"] == "no_solution"
    assert [space.init_frame for _, space in calls] == ["object", "goal"]
    first, second = (skeletons for skeletons, _ in calls)
    assert len(first) == 1 and len(second) == 20
    assert {p.actor for sk in second for p in sk.phases} == {"left"}
    # both searches' time, and the reach checks that made their candidates
    assert doc["plan_seconds"] >= 2.0


def test_a_given_skeleton_gets_no_fallback(monkeypatch, tmp_path):
    calls = []

    def no_plan(*args, **kwargs):
        calls.append(args)
        return SearchResult(None, [], 1.0)

    monkeypatch.setattr(search_module, "search_push", no_plan)
    scene = load_scene(TASKS / "variants" / "left_only_lshape.yaml")
    solve(scene, tmp_path, TASKS.parent / "learned" / "push_flow",
                             skeleton="push@0", progress=False, quiet=True)
    assert len(calls) == 1


def test_no_further_tier_once_the_budget_is_spent_with_a_plan_in_hand():
    import numpy as np

    from robotplan.pushing.program.skeleton import parse_skeleton
    from robotplan.pushing.program.solution import Solution

    task = load_task(TASKS / "box_push.yaml")
    sk = parse_skeleton("push@0", task.actors[0], task.obj)
    sol = Solution(sk, False, "snopt info 31", 0.5, 1.0, 60.0, np.zeros((11, 3)),
                   np.zeros((11, 2)))
    with_plan = SearchResult(sol, [sol], 60.0)
    assert search_module.budget_spent(with_plan, 50.0)
    assert not search_module.budget_spent(with_plan, 70.0)  # time left
    assert not search_module.budget_spent(with_plan, None)  # no budget
    assert not search_module.budget_spent(SearchResult(None, [], 60.0), 50.0)  # nothing yet


def test_a_warm_start_along_a_route_keeps_its_steps_and_the_routes_settings(monkeypatch):
    """A re-plan warm started from a plan along a route (more steps per phase than the
    default, via points) is solved in that plan's space and with the routes' settings."""
    import numpy as np

    from robotplan.pushing.program.skeleton import Phase, Skeleton

    calls = []

    def record(request, skeletons, settings=None, space=None, ordered=False):
        calls.append((settings, space))
        return SearchResult(None, [], 1.0)

    monkeypatch.setattr(search_module, "search_push", record)
    task = load_task(TASKS / "obstacle_push.yaml")
    routed = Skeleton((Phase("reach", "pusher", "box", 2),
                       Phase("push", "pusher", "box", 2, via=(0.1, 0.25))))
    guess = {"q_obj": np.zeros((2 * 14 + 1, 3))}
    search_module.search_scene(SearchRequest(
        task, TASKS.parent / "learned" / "push_flow", skeleton=routed, quiet=True,
        progress=False, guesses={routed: guess}))
    settings, space = calls[0]
    assert space.steps_per_phase == 14
    assert settings.row("quasi_static").friction == 0.02 and settings.row("lever").weight == 100.0


def test_a_warm_started_search_plans_with_the_quick_budget(monkeypatch):
    """A search from an earlier plan (a re-plan) gets the ``quick`` budget of
    skeletons/tiers.yaml over its scene's settings; the same search without a guess does
    not."""
    import numpy as np

    from robotplan.pushing.program.skeleton import parse_skeleton
    from robotplan.pushing.search.tiers import load_budgets

    calls = []

    def record(request, skeletons, settings=None, space=None, ordered=False):
        calls.append(settings)
        return SearchResult(None, [], 1.0)

    monkeypatch.setattr(search_module, "search_push", record)
    task = load_task(TASKS / "box_push.yaml")
    sk = parse_skeleton("push@0", task.actors[0], task.obj)
    model = TASKS.parent / "learned" / "push_rigid"
    guess = {"q_obj": np.zeros((2 * 10 + 1, 3))}
    request = SearchRequest(task, model, skeleton=sk, quiet=True, progress=False)
    search_module.search_scene(request.but(guesses={sk: guess}))
    search_module.search_scene(request)
    warm, fresh = calls
    overlay = load_budgets()["quick"]
    assert overlay, "skeletons/tiers.yaml has a quick budget"
    for key, value in overlay.items():
        assert getattr(warm, key) == value, key
    assert any(getattr(fresh, key) != value for key, value in overlay.items())
    assert warm.good_rms_mm == fresh.good_rms_mm  # the scene's own overlays stay


def _box_pose_goal(monkeypatch, record):
    """The tasks of ``tasks/box_push.yaml`` and of the same box asked 15 cm on and turned
    0.8 rad (a pose goal), with ``record`` in place of every ``search_push``."""
    from dataclasses import replace

    import robotplan.pushing.search.pose_search as pose_search
    from robotplan.scene.schema import PoseGoal

    monkeypatch.setattr(search_module, "search_push", record)
    monkeypatch.setattr(pose_search, "search_push", record)
    region = load_scene(TASKS / "box_push.yaml")
    x, y, yaw = region.objects[0].pose
    return make_task(region), make_task(replace(region, goal=PoseGoal(
        region.objects[0].name, (x + 0.15, y, yaw + 0.8))))


def test_a_pose_goal_searches_its_fitted_pushes_first(monkeypatch):
    """A pose goal's tier is the pushes fitted in closed form, each with its own guess in a
    space of object-frame face normals; the plain tier follows only when no program of it
    was solved (nothing fitted)."""
    import numpy as np

    import robotplan.pushing.search.pose_search as pose_search
    from robotplan.pushing.program.solution import Solution

    calls = []

    def record(request, skeletons, settings=None, space=None, ordered=False):
        guesses = request.guesses
        calls.append((list(skeletons), space, guesses, settings))
        tried = [Solution(sk, False, "snopt info 31", 0.5, 1.0, 1.0, np.zeros((1, 3)),
                          np.zeros((1, 2))) for sk in skeletons[:1] if guesses]
        return SearchResult(tried[0] if tried else None, tried, 1.0)

    _, task = _box_pose_goal(monkeypatch, record)
    yaw = task.scene.objects[0].pose[2]
    model = TASKS.parent / "learned" / "push_rigid"
    request = SearchRequest(task, model, quiet=True, progress=False)
    search_module.search_scene(request)
    # their starts, at the quick budget, then at its own: unsolved fitted plans, no plain tier
    (starts, _, _, checked), (quick, _, _, _), (fitted, space, guesses, settings) = calls
    assert starts == quick == fitted and not checked.parallel and settings.parallel
    assert fitted and set(guesses) == set(fitted)
    assert space.init_frame == "object" and space.steps_per_phase >= 10
    for sk in fitted:
        states = len(sk.phases) * space.steps_per_phase + 1
        assert guesses[sk]["q_obj"].shape == (states, 3)
        assert abs(guesses[sk]["q_obj"][-1, 2] - (yaw + 0.8)) < 0.02  # the guess turns
    # the pose overlay
    assert settings.row("quasi_static").turn_gain != 1.0 and settings.row("H_pose").tol == 0.02
    monkeypatch.setattr(pose_search, "pose_candidates", lambda *a, **k: (space, [], {}))
    search_module.search_scene(request)
    plain, plain_space, none, _ = calls[-1]
    assert len(plain) > len(fitted) and none is None and plain_space.init_frame == "goal"


def test_fitted_pushes_come_first_their_starts_then_the_quick_budget(monkeypatch):
    """A pose goal's fitted pushes (fresh, or executing: ``replan=True``) and a region
    goal's get their starts checked first (``start_only``), then the ``quick`` budget;
    where that solves nothing, a pose goal's fits their own settings and then, unless
    executing, the plain tier; a region goal's fresh search the plain tier and then its fits
    at its own settings, executing its fits at their own settings before the plain tier."""
    from robotplan.pushing.search.tiers import load_budgets

    calls = []

    def record(request, skeletons, settings=None, space=None, ordered=False):
        calls.append((request.task.goal, settings, request.guesses is not None))
        return SearchResult(None, [], 1.0)

    region, pose = _box_pose_goal(monkeypatch, record)
    model = TASKS.parent / "learned" / "push_rigid"
    budgets = load_budgets()

    def budget(settings) -> str:
        return next((name for name in ("start_only", "quick")
                     if all(getattr(settings, k) == v for k, v in budgets[name].items())),
                    "own")

    fits = [("fits", "start_only"), ("fits", "quick")]
    expected = {("pose", False): [*fits, ("fits", "own"), ("plain", "own")],
                ("pose", True): [*fits, ("fits", "own")],
                ("region", False): [*fits, ("plain", "own"), ("fits", "own")],
                ("region", True): [*fits, ("fits", "own"), ("plain", "own")]}
    for task in (pose, region):
        for replan in (False, True):
            calls.clear()
            search_module.search_scene(SearchRequest(task, model, quiet=True, progress=False,
                                                     replan=replan))
            assert all(kind == task.goal for kind, _, _ in calls)
            seen = [("fits" if guessed else "plain", budget(s)) for _, s, guessed in calls]
            assert seen == expected[task.goal, replan], (task.goal, replan)


def test_a_region_goal_the_plain_tier_misses_gets_pushes_fitted_into_the_region(monkeypatch):
    """A free pusher's region goal: first the pushes fitted to a pose inside the region
    (each with its guess ending there, the pose goals' turning gain, the region's own goal
    tolerance), then the plain tier, and where neither solves the fits again past the time
    budget; the plain tier is skipped where the fits solve. While executing (``replan``)
    the fitted pushes come first, and end the search where they solve or give a plan
    within the caller's last-resort bound."""
    import numpy as np
    import torch

    import robotplan.pushing.search.pose_search as pose_search
    from robotplan.pushing.program.rows_goal import region_goal
    from robotplan.pushing.program.settings import settings_for as overlay
    from robotplan.pushing.program.solution import Solution

    calls, budgets, solve_plain, solve_fits, unsolved_fits = [], [], [False], [False], [0.5]

    def record(request, skeletons, settings=None, space=None, ordered=False):
        guesses = request.guesses
        calls.append((list(skeletons), space, guesses, settings))
        budgets.append((request.time_budget, ordered))
        solved = solve_fits[0] if guesses else solve_plain[0]
        unsolved = unsolved_fits[0] if guesses else 0.5
        tried = [Solution(sk, solved, "snopt info 31", 0.0 if solved else unsolved, 1.0, 1.0,
                          np.zeros((1, 3)), np.zeros((1, 2))) for sk in skeletons[:1]]
        return SearchResult(tried[0] if tried else None, tried, 1.0)

    monkeypatch.setattr(search_module, "search_push", record)
    monkeypatch.setattr(pose_search, "search_push", record)
    task = load_task(TASKS / "box_push.yaml")
    scene = task.scene
    model = TASKS.parent / "learned" / "push_rigid"
    request = SearchRequest(task, model, quiet=True, progress=False)
    result, spaces = search_module.search_scene(request.but(time_budget=0.5))
    starts, (quick, _, first, _), (plain, _, none, _), (fitted, space, guesses, settings) = calls
    assert starts[0] == quick == fitted and set(first) == set(fitted)  # the fits first, again
    # four programs at most: no time budget
    assert budgets[0] == budgets[1] == budgets[3] == (None, True)
    assert plain and none is None and fitted and set(guesses) == set(fitted)
    assert space.init_frame == "object"
    gain = overlay("pose").row("quasi_static").turn_gain
    assert settings.row("quasi_static").turn_gain == gain != 1.0
    # the region's tolerance
    assert settings.row("goal").tol == search_module.task_settings(task).row("goal").tol
    body = scene.bodies[scene.objects[0].name]
    H = region_goal(body, scene.goal_region, settings)
    for sk in fitted:
        end = torch.from_numpy(guesses[sk]["q_obj"][-1:].copy())
        assert float(H(end)[0, 0]) / body.area <= settings.row("goal").tol  # ends in the region
    assert all(id(s) in spaces for s in result.candidates)

    calls.clear()
    solve_plain[0] = True
    search_module.search_scene(request)
    assert len(calls) == 3 and calls[2][2] is None  # the plain tier solved: no more fits

    calls.clear()
    solve_fits[0] = True
    result, _ = search_module.search_scene(request)
    assert len(calls) == 1 and calls[0][2] is not None and result.solved  # no plain tier

    calls.clear()  # executing, the fitted pushes come first: solved, no plain tier
    solve_fits[0] = True
    result, _ = search_module.search_scene(request.but(replan=True))
    assert len(calls) == 1 and calls[0][2] is not None and result.solved

    # unsolved fitted pushes within the caller's last-resort bound end the search too
    solve_fits[0], solve_plain[0], unsolved_fits[0] = False, False, 0.02
    for last_resort, searches in ((0.03, 1), (0.01, 4), (None, 4)):
        calls.clear()
        result, _ = search_module.search_scene(request.but(replan=True,
                                                           last_resort=last_resort))
        assert len(calls) == searches and not result.solved
        assert result.best.violation == 0.02  # the plain tier's plans violate more
        # the fitted pushes' starts and both budgets before the plain tier
        assert [g is not None for _, _, g, _ in calls] == [True, True, True, False][:searches]
    budgets.clear()  # the fitted pushes took 2 s: the plain tier still gets the whole budget
    search_module.search_scene(request.but(replan=True, time_budget=1.5))
    assert [b for b, _ in budgets] == [None, None, None, 1.5]


def test_past_its_deadline_a_search_starts_no_tier_and_no_program(monkeypatch):
    import time

    from robotplan.pushing.program.skeleton import parse_skeleton
    from robotplan.pushing.search import planner

    solved = []
    monkeypatch.setattr(planner, "_solve", lambda sk: solved.append(sk))
    task = load_task(TASKS / "box_push.yaml")
    request = SearchRequest(task, TASKS.parent / "learned" / "push_rigid", workers=1,
                            progress=False, quiet=True)
    late = request.but(deadline=time.monotonic() - 1.0)
    result, _ = search_module.search_scene(late)
    assert result.best is None and not result.candidates and not solved
    sk = parse_skeleton("push@0", task.actors[0], task.obj)
    assert not planner.search_push(late, [sk]).candidates and not solved
    assert not request.past_deadline() and late.past_deadline()


def test_a_search_limited_to_plain_candidates_never_fits_pushes(monkeypatch):
    """The paper's search (``candidate_kinds=("plain",)``): the optimiser from the skeleton
    space's initializations, no pushes fitted in closed form, even where nothing solves;
    an unknown kind is refused naming the known ones."""
    import pytest

    import robotplan.pushing.search.pose_search as pose_search

    calls = []

    def record(request, skeletons, settings=None, space=None, ordered=False):
        calls.append(request.guesses)
        return SearchResult(None, [], 1.0)

    monkeypatch.setattr(search_module, "search_push", record)
    monkeypatch.setattr(pose_search, "search_push", record)
    task = load_task(TASKS / "box_push.yaml")
    request = SearchRequest(task, TASKS.parent / "learned" / "push_rigid", quiet=True,
                            progress=False)
    search_module.search_scene(request.but(candidate_kinds=("plain",)))
    assert calls == [None]  # one plain tier, no fitted guesses
    calls.clear()
    search_module.search_scene(request)
    assert len(calls) > 1 and any(g is not None for g in calls)  # the default fits first
    with pytest.raises(ValueError, match="region_fits"):
        search_module.search_scene(request.but(candidate_kinds=("nope",)))
