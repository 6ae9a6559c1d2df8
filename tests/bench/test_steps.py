"""The steps of ``robotplan reproduce``: kept and reused by what they read (their parameters,
the modules they run, the files they read, the steps they need), from their folder or from
a ledger kept with the code."""

import json
import subprocess
import sys

from robotplan.bench.step_keys import files_digest, module_closure, modules_digest
from robotplan.bench.steps import Steps

DATA = ("robotplan.pushing.training.push_data",)


def _counting():
    calls = []

    def step(folder):
        calls.append(folder)
        (folder / "made.txt").write_text(str(len(calls)))
        return {"value": len(calls)}

    return step, calls


def test_a_step_is_reused_until_its_parameters_or_reads_change(tmp_path):
    step, calls = _counting()
    steps = Steps(tmp_path / "out", progress=False)
    first = steps.run("s", {"n": 1}, step, "cmd", runs=DATA)
    again = steps.run("s", {"n": 1}, step, "cmd", runs=DATA)
    assert first["result"] == again["result"] == {"value": 1} and len(calls) == 1
    assert steps.run("s", {"n": 2}, step, "cmd", runs=DATA)["result"] == {"value": 2}
    model = tmp_path / "model.txt"
    model.write_text("a")
    assert steps.run("s", {"n": 1}, step, "cmd", runs=DATA, reads=(model,))["result"] == {
        "value": 3}
    model.write_text("changed")  # the file it reads changed: it runs again
    assert steps.run("s", {"n": 1}, step, "cmd", runs=DATA, reads=(model,))["result"] == {
        "value": 4}
    assert len({c.name for c in calls}) == 4  # each in a folder of its own
    assert [s["state"] for s in steps.log] == ["ran", "done", "ran", "ran", "ran"]


def test_a_step_keys_on_the_modules_it_runs_not_the_whole_package():
    closure = module_closure(DATA)
    assert "robotplan.pushing.training.push_data" in closure
    # the simulators it opens by name from a registry are read
    assert {"robotplan.execution.pybullet_world", "robotplan.execution.mujoco_world"} <= set(
        closure)
    assert not any(m.startswith(("robotplan.hanging", "robotplan.cli", "robotplan.api"))
                   for m in closure)
    assert modules_digest(DATA) == modules_digest(DATA)
    assert modules_digest(DATA) != modules_digest(("robotplan.hanging.bench.bench",))


def test_the_ledger_stands_in_for_a_step_until_one_that_needs_it_must_run(tmp_path):
    """A second machine (a fresh output folder, the same ledger) reuses both steps without
    running them; a consumer with new parameters needs the data step's outputs, so that one
    runs there first; status lists done, stale and missing without running anything."""
    ledger = tmp_path / "ledger"
    make, made = _counting()
    use, used = _counting()

    def chain(steps, n: int):
        data = steps.run("data", {"scenes": 2}, make, "data", runs=DATA)

        def consume(folder):
            assert (steps.out / data["folder"] / "made.txt").is_file()
            return use(folder)

        return data, steps.run("eval", {"n": n}, consume, "eval", runs=DATA, needs=(data,))

    first = Steps(tmp_path / "a", progress=False, ledger=ledger)
    chain(first, 1)
    assert json.loads((ledger / "eval.json").read_text())["key"] == first.log[1]["key"]
    fresh = Steps(tmp_path / "b", progress=False, ledger=ledger)
    chain(fresh, 1)
    assert len(made) == len(used) == 1 and [s["state"] for s in fresh.log] == ["done"] * 2
    assert not (tmp_path / "b" / "steps").exists()  # nothing ran there
    status = Steps(tmp_path / "c", progress=False, ledger=ledger, dry=True)
    chain(status, 2)
    assert [s["state"] for s in status.log] == ["done", "stale"]
    chain(fresh, 2)  # the consumer runs, so the data it needs is made here first
    assert len(made) == 2 and len(used) == 2
    assert fresh.log[-1]["state"] == "ran"
    other = Steps(tmp_path / "d", progress=False, ledger=tmp_path / "empty", dry=True)
    chain(other, 1)
    assert [s["state"] for s in other.log] == ["missing", "missing"]


def test_uses_tells_a_steps_outputs_from_files_read_by_content(tmp_path):
    step, _ = _counting()
    steps = Steps(tmp_path / "out", progress=False)
    data = steps.run("data", {}, step, "data", runs=DATA)
    outside = tmp_path / "learned"
    outside.mkdir()
    uses = steps.uses(tmp_path / "out" / data["folder"] / "made.txt", outside)
    assert [n["key"] for n in uses["needs"]] == [data["key"]]
    assert uses["reads"] == (outside,)
    assert files_digest([outside]) == files_digest([outside])


def test_a_run_in_parts_leaves_the_steps_it_may_not_start_and_those_that_need_them(
        tmp_path):
    from robotplan.bench.reproduce import step_filter

    ledger = tmp_path / "ledger"
    step, calls = _counting()
    allow = step_filter(("data_*", "eval_*"))
    steps = Steps(tmp_path / "out", progress=False, ledger=ledger, allow=allow)
    data = steps.run("data_a", {}, step, "cmd", runs=DATA)
    model = steps.run("train_a", {}, step, "cmd", runs=DATA, needs=(data,))
    scored = steps.run("eval_a", {}, step, "cmd", runs=DATA, needs=(model,))
    assert [s["state"] for s in steps.log] == ["ran", "skipped", "skipped"]
    assert scored["result"] == {} and len(calls) == 1 and not steps.complete
    assert sorted(p.name for p in ledger.iterdir()) == ["data_a.json"]
    # the next part, without limits, runs the rest and reuses the first part's step
    steps = Steps(tmp_path / "out", progress=False, ledger=ledger)
    data = steps.run("data_a", {}, step, "cmd", runs=DATA)
    model = steps.run("train_a", {}, step, "cmd", runs=DATA, needs=(data,))
    steps.run("eval_a", {}, step, "cmd", runs=DATA, needs=(model,))
    assert [s["state"] for s in steps.log] == ["done", "ran", "ran"] and steps.complete
    assert step_filter() is None
    assert step_filter(hours=0.0)("anything") is False  # no time left: nothing starts
    assert step_filter(hours=1.0)("anything") is True


def test_a_step_another_run_is_making_is_left_to_it(tmp_path):
    """Two runs on one output folder: the step whose lock a live process holds is neither
    started over nor run twice; its lock taken over once that process has ended."""
    step, calls = _counting()
    out = tmp_path / "out"
    ran = Steps(out, progress=False).run("train_a", {}, step, "cmd", runs=DATA)
    folder = out / ran["folder"]
    (folder / "result.json").unlink()  # as while it is being made
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        folder.with_suffix(".lock").write_text(str(other.pid))
        steps = Steps(out, progress=False)
        left = steps.run("train_a", {}, step, "cmd", runs=DATA)
        after = steps.run("eval_a", {}, step, "cmd", runs=DATA, needs=(left,))
        assert [s["state"] for s in steps.log] == ["skipped", "skipped"]
        assert after["result"] == {} and len(calls) == 1
        assert (folder / "made.txt").read_text() == "1"  # its outputs untouched
        status = Steps(out, progress=False, dry=True)
        status.run("train_a", {}, step, "cmd", runs=DATA)
        assert status.log[0]["state"] == "running"
    finally:
        other.kill()
        other.wait()
    steps = Steps(out, progress=False)
    assert steps.run("train_a", {}, step, "cmd", runs=DATA)["state"] == "ran"
    assert len(calls) == 2 and not folder.with_suffix(".lock").exists()


def test_a_ledger_entry_keeps_lists_on_one_line_and_reads_back_the_same():
    from robotplan.bench.steps import ledger_json

    entry = {"key": "k", "result": {"by_scene": {"scene": [0, 1, 2], "x_mm": [1.5, 2.0, 0.25]},
                                    "rows": [{"shape": "box"}], "nested": [[1, 2], [3]],
                                    "text": ["two  spaces", "a [bracket", "]"], "empty": []}}
    text = ledger_json(entry)
    assert json.loads(text) == entry
    assert '"scene": [0, 1, 2]' in text and '"x_mm": [1.5, 2.0, 0.25]' in text
