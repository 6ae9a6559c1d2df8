"""The steps of ``robotplan reproduce``: kept and reused by their parameters and inputs."""

from robotplan.bench.steps import Steps, inputs_digest


def test_a_step_is_reused_until_its_parameters_or_inputs_change(tmp_path):
    calls = []

    def step(folder):
        calls.append(folder)
        (folder / "made.txt").write_text("x")
        return {"value": len(calls)}

    steps = Steps(tmp_path, "digest-a", progress=False)
    first = steps.run("s", {"n": 1}, step, "cmd")
    again = steps.run("s", {"n": 1}, step, "cmd")
    assert first["result"] == again["result"] == {"value": 1} and len(calls) == 1
    assert steps.run("s", {"n": 2}, step, "cmd")["result"] == {"value": 2}
    other_code = Steps(tmp_path, "digest-b", progress=False)
    assert other_code.run("s", {"n": 1}, step, "cmd")["result"] == {"value": 3}
    assert len({c.name for c in calls}) == 3  # each in a folder of its own
    assert [s["name"] for s in steps.log] == ["s", "s", "s"]


def test_the_inputs_digest_is_stable():
    assert inputs_digest() == inputs_digest() and len(inputs_digest()) == 64
