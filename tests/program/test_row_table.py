"""The program's rows as data: the table in skeletons/rows.yaml and the settings overlays in
skeletons/settings.yaml, and the one builder that reads them."""

import pytest

from robotplan.program import settings as settings_module
from robotplan.program.push_program import PushProgram
from robotplan.program.push_rows import ROW_BUILDERS
from robotplan.program.row_table import load_rows, rows_for_stage
from robotplan.program.settings import DEFAULT_SETTINGS, ProgramSettings, settings_for
from robotplan.program.skeleton import load_skeleton_space, parse_skeleton
from robotplan.scene.task import load_task
from tests.conftest import TASKS, assert_each_refused


def test_every_row_of_the_table_has_a_builder_and_a_known_setting():
    rows = load_rows()
    added_after = ("arms", "chain", "chain_kinematic", "chain_learned")
    assert rows and all(r.row in ROW_BUILDERS for r in rows if r.stage not in added_after)
    for r in rows:
        assert r.enabled is None or isinstance(DEFAULT_SETTINGS.value(r.enabled), bool)
        assert set(r.bodies) <= {"object", "actor", "contact", "obstacles", "region", "joints",
                                 "chained"}
    kinematic, learned = rows_for_stage(False), rows_for_stage(True)
    assert "H_F" in [r.row for r in learned] and "H_F" not in [r.row for r in kinematic]
    assert "sticking" in [r.row for r in kinematic] and "sticking" not in [r.row for r in learned]


def test_every_row_a_program_adds_is_a_row_of_the_table():
    """The arm and chain programs name their rows after the table's: no row (and no scale)
    of theirs lives in code alone."""
    import re

    names = {r.row for r in load_rows()}
    program = TASKS.parent / "robotplan" / "program"
    used = set()
    for path in ("arm_program.py", "chain_program.py", "push_rows.py"):
        used |= set(re.findall(r'self\.spec\("(\w+)"\)', (program / path).read_text()))
    assert used and used <= names, used - names
    assert {"H_coll_chain", "H_PoC_chain", "tip_height", "tip_coupling"} <= used


def test_every_constant_of_the_table_is_read_by_the_program():
    """A row's constant that no code reads is documentation, not a setting: each ROW.NAME
    of the table is read in the package as ``row("ROW").NAME``, or through a name bound to
    ``row("ROW")`` in the same module, or it is the switch of its row."""
    import re

    sources = [p.read_text() for p in (TASKS.parent / "robotplan").rglob("*.py")]

    def read(row: str, name: str) -> bool:
        for text in sources:
            views = re.findall(rf'(\w+) = [^\n]*row\("{row}"\)\n', text)
            if re.search(rf'row\("{row}"\)\.{name}\b', text) or any(
                    re.search(rf"\b{v}\.{name}\b", text) for v in views):
                return True
        return False

    unread = [f"{spec.row}.{name}" for spec in load_rows() for name in spec.params
              if spec.enabled != f"{spec.row}.{name}" and not read(spec.row, name)]
    assert not unread, unread


def test_row_constants_are_settings_overlays_and_users_change():
    from robotplan.program.row_table import row_parameters

    assert DEFAULT_SETTINGS.row("goal").tol == row_parameters()["goal.tol"] == 0.003
    assert settings_for("pose").row("H_pose").tol == 0.02
    moved = DEFAULT_SETTINGS.with_values({"goal.tol": 0.01, "iterations": 5})
    assert moved.row("goal").tol == 0.01 and moved.iterations == 5
    assert moved.row("goal").a == DEFAULT_SETTINGS.row("goal").a
    with pytest.raises(ValueError, match="not a row constant"):
        DEFAULT_SETTINGS.with_values({"goal.no_such": 1.0})
    with pytest.raises(AttributeError, match="no parameter"):
        _ = DEFAULT_SETTINGS.row("goal").no_such


@pytest.mark.parametrize("learned", [False, True], ids=["kinematic", "learned"])
def test_the_program_adds_the_rows_in_table_order(learned, monkeypatch):
    """The builder follows the table: the rows it adds come in the table's order, and a row
    left out of the table is left out of the program."""
    task = load_task(TASKS / "obstacle_push.yaml")
    sk = parse_skeleton("push@0", "pusher", "box")
    added: list[str] = []
    original = PushProgram.add_row

    def spy(self, spec):
        added.append(spec.row)
        original(self, spec)

    monkeypatch.setattr(PushProgram, "add_row", spy)
    model = None
    if learned:
        from robotplan.base.resources import learned_dir
        from robotplan.models.dynamics import load_model
        model = load_model(learned_dir())
    prog = PushProgram(task, sk, model, load_skeleton_space(), ProgramSettings())
    expected = [r.row for r in rows_for_stage(learned, task.goal)]
    assert "goal" in expected and "H_pose" not in expected  # a region goal's rows
    assert added == expected
    names = [b.evaluator().get_description() for b in prog.prog.GetAllConstraints()]
    assert "H_coll" in names and "H_coll_wall" in names and "H_PoC" in names
    assert names.index("H_coll") < names.index("H_PoC") < names.index("H_g")

    without = tuple(r for r in load_rows() if r.row != "swept")
    monkeypatch.setattr("robotplan.program.push_program.rows_for_stage",
                        lambda learned, goal: [r for r in rows_for_stage(learned, goal)
                                               if r in without])
    prog = PushProgram(task, sk, model, load_skeleton_space(), ProgramSettings())
    assert "swept" not in {b.evaluator().get_description()
                           for b in prog.prog.GetAllConstraints()}


def test_settings_overlays_per_scene_class(tmp_path, monkeypatch):
    arms = settings_for("arms")
    assert arms.sparse_jacobians and not arms.row("friction_cone").turn
    assert arms.row("H_coll").a == DEFAULT_SETTINGS.row("H_coll").a
    routes = settings_for("routes", base=arms, solver="ipopt")
    assert routes.row("lever").weight == 100.0
    assert routes.sparse_jacobians and routes.solver == "ipopt"
    assert_each_refused(settings_module.load_overlays.__wrapped__, tmp_path / "settings.yaml", (
        ("arms: {no_such: 1}", "not a program setting"),
        ("pets: {}", "not a scene class"),
        ("arms: {sparse_jacobians: 3}", "must be a bool")))


def test_a_users_program_settings_win_over_every_later_overlay():
    from robotplan.program.settings import parse_program_overrides, with_overrides

    given = parse_program_overrides(["accept_good_start=off", "lever.weight=0.5",
                                     "step_limits.step=0.02", "solver=ipopt"])
    assert given == {"accept_good_start": False, "lever.weight": 0.5, "step_limits.step": 0.02,
                     "solver": "ipopt"}
    from robotplan.search.tiers import budget_settings

    mine = with_overrides(settings_for("arms"), given)
    # the re-plans' budget turns accept_good_start on and the routes' overlay sets lever.weight
    later = settings_for("routes", base=budget_settings("replan", mine))
    assert not later.accept_good_start and later.row("lever").weight == 0.5
    assert later.row("step_limits").step == 0.02
    assert later.solver == "ipopt" and later.sparse_jacobians
    assert budget_settings("replan", DEFAULT_SETTINGS).accept_good_start  # the budget's value
    for items, words in ((["no_such=1"], "not a program setting"),
                         (["with_contact=maybe"], "not a bool"),
                         (["H_coll.a=-1"], "must not be negative"),
                         (["H_coll.a"], "expected NAME=VALUE")):
        with pytest.raises(ValueError, match=words):
            parse_program_overrides(items)
