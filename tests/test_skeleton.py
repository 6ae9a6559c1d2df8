import pytest

from robotplan.skeleton import load_skeleton_space, parse_skeleton


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
