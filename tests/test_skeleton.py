import pytest

from robotplan.skeleton import (
    Phase,
    actor_candidates,
    load_skeleton_space,
    parse_skeleton,
    space_for,
)
from tests.conftest import TASKS


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


@pytest.mark.parametrize(("task", "expected"), [
    ("two_arm_left_only", {("left",), ("left", "left")}),
    ("two_arm_handover", {("left", "right")}),
])
def test_reach_pruning_keeps_the_arms_that_can_reach(task, expected):
    """Before any program: the left-only scene keeps left pushes only, the handover scene
    left-then-right only (the box starts beyond the right arm's reach, the goal beyond the
    left's)."""
    from robotplan import load_scene
    from robotplan.arm_program import reach_check

    scene = load_scene(TASKS / f"{task}.yaml")
    space = space_for(scene)
    every = actor_candidates(space, ["left", "right"], "box")
    kept = [sk for sk in every if reach_check(scene, sk, space) is None]
    assert kept, "pruning removed every skeleton"
    assert {tuple(p.actor for p in sk.phases if p.mode == "push") for sk in kept} <= expected
    assert len(kept) < len(every) / 4
    why = next(reach_check(scene, sk, space) for sk in every if sk not in kept)
    assert "reach" in why


def test_touch_pruning_ends_with_the_touching_arm():
    from robotplan import load_scene
    from robotplan.arm_program import reach_check

    scene = load_scene(TASKS / "two_arm_touch.yaml")
    space = space_for(scene)
    every = actor_candidates(space, ["left", "right"], "box", touch_actor="right")
    kept = [sk for sk in every if reach_check(scene, sk, space) is None]
    assert kept and len(kept) < len(every) / 4
    assert all(sk.phases[-1].actor == "right" and sk.phases[-1].mode == "reach" for sk in kept)
