"""The command line as a user runs it: real subprocesses, exit codes, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import yaml

from robotplan.cli.app import main
from tests.conftest import ROOT, TASKS
from tests.scene.test_loader import BAD_CASES


def run(*args: str, cwd=ROOT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "robotplan.cli", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=120)


def call(capsys, *args: str) -> subprocess.CompletedProcess:
    """The command through :func:`main` in this process, as :func:`run` reports it: each
    test below runs its first case as a real process and the others here, seconds apiece
    cheaper (``python -m robotplan.cli`` is ``sys.exit(main())``)."""
    capsys.readouterr()
    code = main(list(args))
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(["robotplan", *args], code, out, err)


def test_check_prints_one_ok_line_per_good_file():
    files = sorted(str(p) for p in TASKS.glob("*.yaml"))
    res = run("check", *files)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert len(lines) == len(files)
    assert all(line.startswith(f"ok {f}: ") for line, f in zip(lines, files, strict=False))
    assert res.stderr == ""


def test_check_refuses_every_bad_case_with_one_line_and_exit_2(tmp_path):
    files = []
    for case, data, _field in BAD_CASES:
        f = tmp_path / f"{case}.yaml"
        f.write_text(yaml.safe_dump(data))
        files.append(f)
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    tag = tmp_path / "tag.yaml"
    tag.write_text("!!python/object/apply:os.system ['echo pwned']\n")
    files += [empty, tag]
    good = TASKS / "box_push.yaml"
    res = run("check", str(good), *map(str, files))
    assert res.returncode == 2
    assert res.stdout.splitlines() == [f"ok {good}: " + res.stdout.split(": ", 1)[1].strip()]
    errors = res.stderr.splitlines()
    assert len(errors) == len(files), res.stderr
    fields = [c[2] for c in BAD_CASES] + ["", ""]
    for line, f, field in zip(errors, files, fields, strict=True):
        assert line.startswith(f"error: {f}: {field}")
    assert "Traceback" not in res.stderr and "pwned" not in res.stdout


def test_render_writes_png_and_refuses_to_overwrite(tmp_path, capsys):
    scene = str(TASKS / "lshape_push.yaml")
    res = call(capsys, "render", scene, "--out", str(tmp_path))
    png = tmp_path / "lshape_push_sdf.png"
    assert res.returncode == 0, res.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    before = png.stat().st_mtime_ns
    again = run("render", scene, "--out", str(tmp_path))
    assert again.returncode == 2 and "--overwrite" in again.stderr
    assert png.stat().st_mtime_ns == before
    assert list(tmp_path.iterdir()) == [png]  # no temporary files left behind


def test_bench_sdf_json():
    res = run("bench", "sdf", "--json", "--steps", "4", "--repeats", "2")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["steps"] == 4 and out["grid"] == [140, 140]
    assert out["values"] == 4 * 140 * 140 * out["bodies"]
    assert out["median_ms"] > 0


def test_bad_scene_for_bench_is_exit_2(tmp_path):
    f = tmp_path / "x.yaml"
    f.write_text("version: 3\n")
    res = run("bench", "sdf", "--scene", str(f))
    assert res.returncode == 2
    assert res.stderr.strip() == f"error: {f}: version: unsupported version 3; this robotplan " \
                                 "reads version 1"


def test_bench_functional_json_runs_small():
    res = run("bench", "functional", "--json", "--no-naive", "--configurations", "1",
              "--repeats", "1")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    for key in ("hf_phase_ms", "integral_rel_error", "coll_phase_ms", "goal_ms",
                "hf_40_steps_peak_rss_mb"):
        assert out[key] > 0, key
    assert out["integral_rel_error"] < 0.2
    assert isinstance(out["native_kernels"], bool)  # whether robotplan/base/kernels.c ran


def test_bench_functional_times_h_q_for_an_f_q_folder():
    res = run("bench", "functional", "--json", "--model", str(ROOT / "learned" / "push_rigid"),
              "--repeats", "1")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["steps"] == 10 and out["hq_phase_ms"] > out["hq_value_only_ms"] > 0
    assert "hf_phase_ms" not in out and out["coll_phase_ms"] > 0


def test_bench_functional_refuses_a_non_model(tmp_path):
    res = run("bench", "functional", "--model", str(tmp_path))
    assert res.returncode == 2 and "--model" in res.stderr and "Traceback" not in res.stderr


def test_bench_contact_push_refuses_a_non_model_and_plans_with_a_point_cloud_model(
        tmp_path, capsys):
    import torch

    from robotplan.pushing.models.dynamics import DynamicsSpec
    from robotplan.pushing.models.rigid import RigidMotion, save_rigid

    res = call(capsys, "bench", "contact-push", "--model", str(tmp_path))
    assert res.returncode == 2 and "--model" in res.stderr
    # H_q differentiates a point-cloud F_q by autograd: the command plans with it (an
    # untrained one on a coarse grid: seconds)
    torch.manual_seed(0)
    cloud = DynamicsSpec(kind="rigid", encoder="joint", representation="pointcloud",
                         grid=(48, 48), cloud_points=32, cloud_widths=(8, 16),
                         sdf_features=8, point_features=8, hidden=(16, 16))
    save_rigid(RigidMotion(cloud), tmp_path / "cloud")
    res = call(capsys, "bench", "contact-push", "--json", "--model", str(tmp_path / "cloud"))
    assert res.returncode == 0 and res.stderr == "", res.stderr
    out = json.loads(res.stdout)
    assert out["model"] == str(tmp_path / "cloud") and out["planned_pusher_travel_m"] > 0
    assert len(out["q_obj"]) == len(out["q_pusher"]) > 1


def test_solve_refuses_unsupported_scenes_and_used_folders(tmp_path, capsys):
    # two objects the pusher may both touch: no chain, not planned yet
    text = (TASKS / "three_objects.yaml").read_text().replace("touches: [red]", "")
    assert "touches" not in text.split("goal:")[0].split("pushers:")[1]
    scene = tmp_path / "two_free.yaml"
    scene.write_text(text)
    res = run("solve", str(scene), "--out", str(tmp_path / "a"))
    assert res.returncode == 2 and "objects" in res.stderr and "Traceback" not in res.stderr
    for task, skeleton in (("box_push", "push@0>blue"), ("three_objects", "push@0")):
        res = call(capsys, "solve", str(TASKS / f"{task}.yaml"), "--out",
                   str(tmp_path / task), "--skeleton", skeleton)
        assert res.returncode == 2 and "--skeleton" in res.stderr, res.stderr
        assert res.stderr.count("\n") == 1 and "Traceback" not in res.stderr
    used = tmp_path / "b"
    used.mkdir()
    (used / "mine.txt").write_text("keep me")
    res = call(capsys, "solve", str(TASKS / "box_push.yaml"), "--out", str(used))
    assert res.returncode == 2 and "--overwrite" in res.stderr
    assert (used / "mine.txt").read_text() == "keep me"


def test_view_needs_a_playback(tmp_path):
    res = run("view", str(tmp_path))
    assert res.returncode == 2 and "playback" in res.stderr


def test_check_reads_exponents_and_check_and_solve_refuse_oversized_scenes(tmp_path, capsys):
    base = yaml.safe_load((TASKS / "box_push.yaml").read_text())

    def scene(name: str, change, text=None) -> str:
        data = json.loads(json.dumps(base))
        change(data)
        f = tmp_path / name
        f.write_text(text(data) if text else yaml.safe_dump(data))
        return str(f)

    def tiny_x(d: dict) -> None:
        d["objects"][0]["pose"][0] = 3e-06  # YAML 1.1 alone would read "3e-06" as a string

    exponents = [scene("exp.json", tiny_x, json.dumps), scene("exp.yaml", tiny_x)]
    km = scene("km.yaml", lambda d: d["workspace"].update(size=[1e6, 1e6]))
    region = scene("region.yaml", lambda d: d["goal"]["region"]["shape"].update(size=[.1, .1]))
    # a 5 MB file of 30,000 triangles: refused by its size, before any parsing
    big = scene("big.yaml", lambda d: d.update(obstacles=[
        {"name": f"o{i}", "pose": [0.5, 0.5, 0], "shape": {"type": "polygon", "vertices": [
            [0.001 * i, 0], [0.001 * i + 0.01, 0], [0.001 * i, 0.01]]}} for i in range(30_000)]),
        json.dumps)
    type_map = scene("type.yaml", lambda d: d["objects"][0]["shape"].update(type={}))
    assert Path(big).stat().st_size > 4_000_000
    res = run("check", *exponents, km, region, big, type_map)
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert [line.split(":")[0] for line in res.stdout.splitlines()] == [f"ok {f}"
                                                                        for f in exponents]
    fields = [(km, "workspace.size: "), (region, "goal.region: "), (big, ""),
              (type_map, "objects[0].shape.type: ")]
    errors = res.stderr.splitlines()
    assert len(errors) == len(fields), res.stderr
    for line, (f, field) in zip(errors, fields, strict=True):
        assert line.startswith(f"error: {f}: {field}"), line
    assert "MB is too large for a scene file" in errors[2]
    for f in (km, region):
        out = tmp_path / f"out_{Path(f).stem}"
        res = call(capsys, "solve", f, "--out", str(out))
        assert res.returncode == 2 and "Traceback" not in res.stderr
        assert res.stderr.count("\n") == 1 and not out.exists()


def test_dynamics_picks_a_shipped_model_and_a_model_folder_overrides_it(tmp_path):
    from argparse import Namespace

    from robotplan.cli.common import model_folder

    assert Path(model_folder(Namespace(dynamics="rigid", model=None))).name == "push_rigid"
    assert model_folder(Namespace(dynamics="auto", model=None)) is None  # the scene's own
    assert model_folder(Namespace(dynamics="rigid", model=str(tmp_path))) == str(tmp_path)
    res = run("solve", str(TASKS / "box_push.yaml"), "--out", str(tmp_path / "a"),
              "--dynamics", "quadratic")
    assert res.returncode == 2 and "--dynamics" in res.stderr and "Traceback" not in res.stderr


def test_render_draws_a_hang_scene_in_3d(tmp_path):
    assert run("render", str(TASKS / "mug_hang.yaml"), "--out", str(tmp_path)).returncode == 0
    assert (tmp_path / "mug_hang_scene.png").read_bytes()[:4] == b"\x89PNG"


def test_footprint_commands_refuse_a_hang_scene(tmp_path, capsys):
    scene = str(TASKS / "mug_hang.yaml")
    assert call(capsys, "check", scene).returncode == 0
    solved = tmp_path.parent / f"{tmp_path.name}_solved"
    solved.mkdir()
    (solved / "result.json").write_text("{}")
    for argv in (["bench", "sdf", "--scene", scene], ["diagnose", str(solved), scene]):
        res = run(*argv) if argv[0] == "bench" else call(capsys, *argv)
        assert res.returncode == 2, argv
        err = res.stderr.strip()
        assert "\n" not in err and "goal:" in err and "3D" in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())


def test_a_bad_loop_or_program_setting_is_refused_before_any_work(tmp_path, capsys):
    """``--loop`` and ``--program`` of solve and bench push, ``--candidates`` of bench push:
    one line naming the option and the item, exit 2, nothing written."""
    for option, item in (("--loop", "no_such=1"), ("--loop", "max_replans=x"),
                         ("--program", "with_contact=maybe"), ("--program", "no_such=1"),
                         ("--candidates", "plain,fitted")):
        for argv in (["solve", str(TASKS / "box_push.yaml"), "--out", str(tmp_path / "s")],
                     ["bench", "push", "--out", str(tmp_path / "b")]):
            if option == "--candidates" and argv[0] == "solve":
                continue  # a benchmark's option
            first = option == "--loop" and item == "no_such=1" and argv[0] == "solve"
            res = run(*argv, option, item) if first else call(capsys, *argv, option, item)
            err = res.stderr.strip()
            assert res.returncode == 2, argv
            assert "\n" not in err and err.startswith(f"error: {option}: ")
            assert "Traceback" not in err
    assert not list(tmp_path.iterdir())


def test_solve_open_loop_without_rehearsal_runs_the_plan_as_searched(tmp_path, capsys):
    """``--no-rehearse``: no rehearsal in ``result.json`` and the open loop drives the pusher
    along the plan (the rehearsed open loop is checked through the API in test_api)."""
    out = tmp_path / "plain"
    res = call(capsys, "solve", str(TASKS / "box_push.yaml"), "--out", str(out),
               "--skeleton", "push@0", "--workers", "1", "--open-loop", "--no-rehearse")
    assert res.returncode in (0, 1), res.stderr
    doc = json.loads((out / "result.json").read_text())
    assert doc["execution"]["mode"] == "open_loop" and doc["rehearsal"] is None
    assert len(doc["executed"]["pusher"]) == len(doc["trajectory"]["pusher"])


def test_an_unknown_simulator_is_one_line_and_exit_2(tmp_path, capsys):
    """``--sim`` names simulators: a wrong one is refused before anything runs, for the
    commands that execute (one simulator) and those that compare (a list)."""
    res = run("solve", str(TASKS / "box_push.yaml"), "--out", str(tmp_path / "s"),
              "--sim", "bullet3")
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert res.stderr.strip() == ("error: --sim: unknown simulator 'bullet3'; expected one "
                                  "of pybullet, mujoco")
    for args in (("solve", str(TASKS / "box_push.yaml"), "--sim", "pybullet,mujoco"),
                 ("bench", "push", "--sim", "pybullet,physx"),
                 ("data", "push", "--scenes", "2", "--seed", "0", "--sim", "pybullet,mujoco")):
        res = call(capsys, *args, "--out", str(tmp_path / "o"))
        assert res.returncode == 2 and res.stderr.startswith("error: --sim: "), res.stderr
        assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
