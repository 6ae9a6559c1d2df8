import numpy as np
import pytest

from robotplan.pushing.program.skeleton import (
    Phase,
    actor_candidates,
    load_skeleton_space,
    parse_skeleton,
)
from tests.conftest import ROOT, TASKS


def test_paper_candidates_are_4_plus_16():
    space = load_skeleton_space()
    cands = space.candidates("pusher", "box")
    assert len(cands) == 20
    assert sum(c.pushes == 1 for c in cands) == 4
    assert all(c.phases[0].mode == "reach" for c in cands)
    assert len({c for c in cands}) == 20


def test_parse_skeleton():
    sk = parse_skeleton("push@0, push@3", "pusher", "box")
    assert [p.mode for p in sk.phases] == ["reach", "push", "reach", "push"]
    assert [p.init for p in sk.phases] == [0, 0, 3, 3]
    assert sk.as_rows()[1] == {"phase": 1, "mode": "push", "actor": "pusher", "object": "box",
                               "init": 0}
    with pytest.raises(ValueError, match="push@"):
        parse_skeleton("pull@1", "pusher", "box")


def test_arm_candidates_choose_the_actor_of_every_push():
    space = load_skeleton_space()
    cands = actor_candidates(space, ["left", "right"], "box")
    assert len(cands) == 2 * 4 + 4 * 16  # one push: 2 arms × 4 inits; two: 4 × 16
    for sk in cands:
        for reach, push in zip(sk.phases[::2], sk.phases[1::2], strict=True):
            assert (reach.mode, push.mode) == ("reach", "push")
            assert reach.actor == push.actor and reach.init == push.init
    touch = actor_candidates(space, ["left", "right"], "box", touch_actor="right")
    assert len(touch) == 4 + 2 * 16 + 4 * 64  # no push, one, two; each × 4 touch inits
    assert all(sk.phases[-1] == Phase("reach", "right", "box", sk.phases[-1].init)
               for sk in touch)


def test_parse_skeleton_with_actors_and_touch():
    sk = parse_skeleton("left:push@1, right:touch@2", "left", "box")
    assert [(p.mode, p.actor, p.init) for p in sk.phases] == [
        ("reach", "left", 1), ("push", "left", 1), ("reach", "right", 2)]


@pytest.mark.parametrize(("task", "expected", "frame"), [
    ("two_arm_left_only", {("left", "left")}, "object"),
    ("two_arm_handover", {("left", "right")}, "object"),
])
def test_reach_pruning_keeps_the_arms_that_can_reach(task, expected, frame):
    """Before any program: the left-only scene keeps left pushes only, from faces of the
    box whose straight pushes reach the goal; the handover scene keeps left-then-right
    only (the box starts beyond the right arm's reach, the goal beyond the left's)."""
    from robotplan.pushing.program.reach import reach_check
    from robotplan.pushing.search.request import SearchRequest
    from robotplan.pushing.search.scene_search import candidate_tiers
    from robotplan.scene.task import load_task

    task = load_task(TASKS / f"{task}.yaml")
    assert (task.obj, task.actors) == ("box", ("left", "right"))
    request = SearchRequest(task, ROOT / "learned" / "push_flow", quiet=True)
    kept, space = next(candidate_tiers(request))
    assert kept, "pruning removed every skeleton"
    assert space.init_frame == frame
    assert {tuple(p.actor for p in sk.phases if p.mode == "push") for sk in kept} <= expected
    every = actor_candidates(space, ["left", "right"], "box")
    assert len(kept) < len(every) / 4
    why = next(reach_check(task, sk, space) for sk in every if sk not in kept)
    assert "reach" in why or "goal" in why


def test_touch_pruning_ends_with_the_touching_arm():
    from robotplan.pushing.search.request import SearchRequest
    from robotplan.pushing.search.scene_search import candidate_tiers
    from robotplan.scene.task import load_task

    task = load_task(TASKS / "two_arm_touch.yaml")
    assert (task.obj, task.actors, task.touch_actor) == ("box", ("left", "right"), "right")
    kept, space = next(candidate_tiers(SearchRequest(task, ROOT / "learned" / "push_flow",
                                                     quiet=True)))
    every = actor_candidates(space, ["left", "right"], "box", touch_actor="right")
    assert kept and len(kept) < len(every) / 4
    assert all(sk.phases[-1].actor == "right" and sk.phases[-1].mode == "reach" for sk in kept)


def test_face_push_lengths_split_the_travel():
    from robotplan.pushing.program.guess import face_push_lengths

    dirs = np.array([[1.0, 0.0], [0.0, 1.0]])
    a, gap = face_push_lengths(dirs, np.array([0.3, 0.2]))
    assert np.allclose(a, [0.3, 0.2]) and gap < 1e-12
    a, gap = face_push_lengths(dirs, np.array([0.3, -0.2]))  # no pulling: −y is unreachable
    assert np.allclose(a, [0.3, 0.0]) and abs(gap - 0.2) < 1e-12
    a, _ = face_push_lengths(np.array([[1.0, 0.0], [1.0, 0.0]]), np.array([0.8, 0.0]))
    assert np.allclose(a, [0.4, 0.4])  # two pushes from one face share the travel
