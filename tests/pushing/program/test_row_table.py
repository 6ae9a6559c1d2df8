"""The program's rows as data: the table in skeletons/rows.yaml and the settings overlays in
skeletons/settings.yaml, and the one builder that reads them."""

import pytest

from robotplan.pushing.program import settings as settings_module
from robotplan.pushing.program.builder import ROWS
from robotplan.pushing.program.push_program import PushProgram
from robotplan.pushing.program.row_table import load_rows, rows_for_stage
from robotplan.pushing.program.settings import DEFAULT_SETTINGS, ProgramSettings, settings_for
from robotplan.pushing.program.skeleton import load_skeleton_space, parse_skeleton
from robotplan.scene.task import load_task
from tests.conftest import TASKS, assert_each_refused


def test_every_row_of_the_table_has_a_functional_and_a_known_setting():
    rows = load_rows()
    assert rows and all(r.row in ROWS for r in rows)
    assert set(ROWS) == {r.row for r in rows}  # no functional outside the table
    for r in rows:
        assert r.enabled is None or isinstance(DEFAULT_SETTINGS.value(r.enabled), bool)
    kinematic = rows_for_stage(("both", "kinematic"))
    learned = rows_for_stage(("both", "learned"))
    assert "H_F" in [r.row for r in learned] and "H_F" not in [r.row for r in kinematic]
    assert "sticking" in [r.row for r in kinematic] and "sticking" not in [r.row for r in learned]


def test_the_table_is_checked_when_read(tmp_path):
    """Every field is data the builder reads, so each is checked: known bodies, steps and
    stages, no bounds on a cost, [lower, upper] on an inequality, equal ends on an
    equality."""
    from robotplan.pushing.program.row_table import load_rows as read_table

    row = "{row: r, bodies: [object], steps: all, type: %s, scale: 1, stage: both%s}"
    cases = (
        (row % ("ineq", ", bounds: [0, 1]"), None),
        (row % ("eq", ""), None),
        (row % ("cost", ", bounds: [0, 1]"), "a cost has no bounds"),
        (row % ("ineq", ""), "needs \\[lower, upper\\]"),
        (row % ("eq", ", bounds: [0, 1]"), "ends are equal"),
        (row % ("ineq", ", bounds: [0]"), "must be \\[lower, upper\\]"),
        (row % ("ineq", ", bounds: [0, 2x]"), "not a name"),
        (row.replace("[object]", "[elbow]") % ("cost", ""), "none of"),
        (row.replace("all", "sometimes") % ("cost", ""), "none of"))
    for i, (text, words) in enumerate(cases):
        path = tmp_path / f"rows{i}.yaml"
        path.write_text(f"rows:\n  - {text}\n")
        if words is None:
            assert read_table(path)[0].row == "r"
        else:
            assert_each_refused(read_table, path, ((path.read_text(), words),))


def test_every_constant_of_the_table_is_read_by_the_program():
    """A row's constant that nothing reads is documentation, not a setting: each ROW.NAME
    of the table is named by a row's bounds (bare in its own row), read by its row's
    functional as ``ctx.constants.NAME``, read in the package as ``row("ROW").NAME`` (or
    through a name bound to ``row("ROW")`` in the same module), or it is its row's switch."""
    import inspect
    import re

    sources = [p.read_text() for p in (TASKS.parent / "robotplan").rglob("*.py")]
    rows = load_rows()

    def in_bounds(row: str, name: str) -> bool:
        return any(end in (f"{row}.{name}", f"-{row}.{name}")
                   or (spec.row == row and end in (name, f"-{name}"))
                   for spec in rows for pair in spec.bounds.values() for end in pair)

    def by_functional(row: str, name: str) -> bool:
        fn = ROWS[row]
        module = inspect.getmodule(getattr(fn, "func", fn))
        return re.search(rf"constants\.{name}\b", inspect.getsource(module)) is not None

    def read(row: str, name: str) -> bool:
        if in_bounds(row, name) or by_functional(row, name):
            return True
        for text in sources:
            views = re.findall(rf'(\w+) = [^\n]*row\("{row}"\)\n', text)
            if re.search(rf'row\("{row}"\)\.{name}\b', text) or any(
                    re.search(rf"\b{v}\.{name}\b", text) for v in views):
                return True
        return False

    unread = [f"{spec.row}.{name}" for spec in rows for name in spec.params
              if spec.enabled != f"{spec.row}.{name}" and not read(spec.row, name)]
    assert not unread, unread


def test_row_constants_are_settings_overlays_and_users_change():
    from robotplan.pushing.program.row_table import row_parameters

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
    """The builder follows the table: the rows it adds come in the table's order, each
    at its steps, and a row left out of the table is left out of the program."""
    from robotplan.pushing.program import builder

    task = load_task(TASKS / "obstacle_push.yaml")
    sk = parse_skeleton("push@0", "pusher", "box")
    added: list[tuple[str, list[int]]] = []
    original = dict(builder.ROWS)

    def spy(name):
        def row(ctx):
            added.append((name, ctx.steps.tolist()))
            original[name](ctx)
        return row

    monkeypatch.setattr(builder, "ROWS", {name: spy(name) for name in original})
    model = None
    if learned:
        from robotplan.base.resources import learned_dir
        from robotplan.pushing.models.dynamics import load_model
        model = load_model(learned_dir())
    prog = PushProgram(task, sk, model, load_skeleton_space(), ProgramSettings())
    stage = ("both", "learned" if learned else "kinematic")
    expected = [r.row for r in rows_for_stage(stage, task.goal)]
    assert "goal" in expected and "H_pose" not in expected  # a region goal's rows
    assert [name for name, _ in added] == expected
    steps = dict(added)
    N, push = prog.N, prog.push_steps.tolist()
    assert steps["start"] == [0] and steps["goal"] == [N] and steps["H_PoC"] == push
    assert steps["H_coll"] == list(range(1, N + 1))
    assert steps["swept"] == [t for t in range(1, N + 1) if t not in push]
    names = [b.evaluator().get_description() for b in prog.prog.GetAllConstraints()]
    assert "H_coll" in names and "H_coll_wall" in names and "H_PoC" in names
    assert names.index("H_coll") < names.index("H_PoC") < names.index("goal")

    without = tuple(r for r in load_rows() if r.row != "swept")
    monkeypatch.setattr(builder, "rows_for_stage",
                        lambda stages, goal: [r for r in rows_for_stage(stages, goal)
                                              if r in without])
    prog = PushProgram(task, sk, model, load_skeleton_space(), ProgramSettings())
    assert "swept" not in {b.evaluator().get_description()
                           for b in prog.prog.GetAllConstraints()}


def test_a_rows_bounds_and_scale_come_from_the_table(monkeypatch):
    """The table's bounds and scale are what the program holds a row to: the goal row's
    upper bound is its ``tol`` times its scale, and a table that scales the row by 10
    scales its bound by 10."""
    from dataclasses import replace

    from robotplan.pushing.program import builder

    task = load_task(TASKS / "box_push.yaml")
    sk = parse_skeleton("push@0", "pusher", "box")

    def goal_bound() -> float:
        prog = PushProgram(task, sk, None, load_skeleton_space(), ProgramSettings())
        (goal,) = [b.evaluator() for b in prog.prog.GetAllConstraints()
                   if b.evaluator().get_description() == "goal"]
        return float(goal.upper_bound()[0])

    assert goal_bound() == pytest.approx(DEFAULT_SETTINGS.row("goal").tol)
    ten = [replace(r, scale=10.0 * r.scale) if r.row == "goal" else r for r in load_rows()]
    monkeypatch.setattr(builder, "rows_for_stage",
                        lambda stages, goal: [r for r in ten if r.stage in stages
                                              and (r.goals is None or goal in r.goals)])
    assert goal_bound() == pytest.approx(10 * DEFAULT_SETTINGS.row("goal").tol)


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
    from robotplan.pushing.program.settings import parse_program_overrides, with_overrides

    given = parse_program_overrides(["accept_good_start=off", "lever.weight=0.5",
                                     "step_limits.step=0.02", "solver=ipopt"])
    assert given == {"accept_good_start": False, "lever.weight": 0.5, "step_limits.step": 0.02,
                     "solver": "ipopt"}
    from robotplan.pushing.search.tiers import budget_settings

    mine = with_overrides(settings_for("arms"), given)
    # the quick budget turns accept_good_start on and the routes' overlay sets lever.weight
    later = settings_for("routes", base=budget_settings("quick", mine))
    assert not later.accept_good_start and later.row("lever").weight == 0.5
    assert later.row("step_limits").step == 0.02
    assert later.solver == "ipopt" and later.sparse_jacobians
    assert budget_settings("quick", DEFAULT_SETTINGS).accept_good_start  # the budget's value
    for items, words in ((["no_such=1"], "not a program setting"),
                         (["with_contact=maybe"], "not a bool"),
                         (["H_coll.a=-1"], "must not be negative"),
                         (["H_coll.a"], "expected NAME=VALUE")):
        with pytest.raises(ValueError, match=words):
            parse_program_overrides(items)
