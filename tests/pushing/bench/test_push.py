"""Benchmark scenes for ``robotplan bench push``: valid, deterministic, drawn as in the paper."""

import dataclasses
import json
import math

import numpy as np
import pytest

from robotplan.functionals.coverage import coverage
from robotplan.pushing.bench.push_scenes import GOAL_DISTANCE, draw_scene
from robotplan.pushing.bench.push_summary import candidate_timings, summarize, time_profile
from robotplan.pushing.program.skeleton import load_skeleton_space
from robotplan.pushing.search.planner import order_candidates
from robotplan.scene import parse_scene
from robotplan.scene.task import make_task
from tests.cli.test_app import call, run


@pytest.mark.parametrize("kind", ["box", "lshape"])
def test_scenes_are_valid_deterministic_and_in_the_data_ranges(kind):
    docs = [draw_scene(i, 5, kind) for i in range(30)]
    assert docs[3] == draw_scene(3, 5, kind)
    assert docs[3] != draw_scene(3, 6, kind)
    directions = set()
    for i, doc in enumerate(docs):
        scene = parse_scene(doc, f"bench/{i}.yaml")  # the scene schema's own checks
        obj, region = scene.objects[0], scene.goal_region
        assert obj.shape.type == kind
        side = min(obj.shape.size) if kind == "lshape" else None
        assert 0.08 - 1e-9 <= min(obj.shape.size) and max(obj.shape.size) <= 0.30 + 1e-9
        if side is not None:
            assert obj.shape.thickness <= 0.6 * side + 1e-4
        assert np.linalg.norm(obj.pose[:2]) < 0.15  # roughly in the middle
        assert 0.02 <= scene.pushers[0].radius <= 0.05
        offset = np.array(region.pose[:2]) - np.array(obj.pose[:2])
        assert abs(np.linalg.norm(offset) - GOAL_DISTANCE) < 0.1
        directions.add(round(math.degrees(math.atan2(offset[1], offset[0])) / 45) % 8)
        # the goal region holds the object in any orientation
        body = scene.bodies[obj.name]
        for yaw in np.linspace(0, math.pi, 7):
            at_goal = (region.pose[0], region.pose[1], float(yaw))
            assert coverage(body, at_goal, region) > 0.999
        # the object starts outside the goal: there is something to do
        assert coverage(body, body.pose, region) < 0.5
    assert len(directions) >= 6  # the 8 goal positions are all used


def test_summary_quartiles():
    rows = [{"shape": "box", "coverage": c, "plan_seconds": 10.0 * k}
            for k, c in enumerate([1.0, 0.9, 0.5, 1.0, 0.0])]
    s = summarize(rows)
    assert s["coverage"]["box"]["median"] == pytest.approx(0.9)
    assert s["coverage"]["box"]["q1"] == pytest.approx(0.5)
    assert s["coverage"]["box"]["min"] == 0.0
    assert s["plan_seconds"]["all"]["median"] == pytest.approx(20.0)


def test_a_closed_loop_is_timed_without_the_rehearsal_an_open_loop_with_it():
    rows = [{"shape": "box", "coverage": 1.0, "plan_seconds": 12.0, "rehearsal_seconds": 5.0,
             "execute_seconds": 3.0, "open_loop_seconds": 1.0}]
    s = summarize(rows)
    assert s["closed_loop_seconds"]["box"]["median"] == pytest.approx(10.0)
    assert s["open_loop_seconds"]["box"]["median"] == pytest.approx(13.0)
    assert s["rehearsal_seconds"]["box"]["median"] == pytest.approx(5.0)


def test_summary_counts_the_re_plans_the_loop_went_on_with():
    replans = [{"solved": True, "adopted": True, "seconds": 1.0},
               {"solved": False, "adopted": True, "seconds": 2.0},
               {"solved": False, "adopted": False, "seconds": 3.0}]
    rows = [{"shape": "box", "coverage": 1.0, "plan_seconds": 1.0, "replans": replans},
            {"shape": "box", "coverage": 1.0, "plan_seconds": 1.0, "replans": []}]
    s = summarize(rows)
    assert s["replans_adopted"]["box"] == {"adopted": 2, "of": 3}
    assert s["replans"]["box"]["median"] == pytest.approx(1.5)


def test_time_profile_sums_the_candidates_timers_over_scenes():
    a = candidate_timings([
        {"seconds": 3.0, "timings": {"H_F": 2.0, "solver": 1.0}},
        {"seconds": 1.5, "timings": {"H_F": 0.5, "H_coll": 1.0}}])
    assert a == {"programs": 2.0, "total": 4.5, "H_F": 2.5, "solver": 1.0, "H_coll": 1.0}
    b = candidate_timings([{"seconds": 0.5, "timings": {"solver": 0.5}}])
    rows = [{"timings": a}, {"timings": b}, {"coverage": 1.0}]  # the last one: no timings
    prof = time_profile(rows)
    assert prof["scenes"] == 2 and prof["untimed_scenes"] == 1 and prof["programs"] == 3
    assert prof["candidate_seconds"] == pytest.approx(5.0)
    assert list(prof["seconds"]) == ["H_F", "solver", "H_coll"]  # largest first
    assert prof["seconds"]["solver"] == pytest.approx(1.5)
    assert prof["share"]["H_F"] == pytest.approx(0.5)
    assert time_profile([])["candidate_seconds"] == 0.0


def test_candidates_behind_the_object_come_first():
    doc = draw_scene(0, 1, "box")
    doc["objects"][0]["pose"] = [0.0, 0.0, 0.0]
    doc["goal"]["region"]["pose"] = [0.35, 0.0, 0.0]  # goal to the east: push from the west
    task = make_task(parse_scene(doc, "bench.yaml"))
    skeletons = load_skeleton_space().candidates("pusher", "object")
    ordered = order_candidates(task, skeletons)
    assert sorted(map(id, ordered)) == sorted(map(id, skeletons))
    # init 0, measured from the direction away from the goal (the default frame), is west of
    # the object: behind it
    first = ordered[0]
    assert first.pushes == 1 and first.phases[1].init == 0
    assert [p.init for p in ordered[1].phases if p.mode == "push"] == [0, 0]
    space = load_skeleton_space()
    assert space.init_frame == "goal"
    assert math.cos(space.init_angle(0, (0.0, 0.0), (0.35, 0.0))) == pytest.approx(-1.0)
    # in the table frame (the paper's), init 1 is north whatever the goal
    by_table = dataclasses.replace(space, init_frame="table")
    assert by_table.init_angle(1, (0.0, 0.0), (0.35, 0.0)) == pytest.approx(math.pi / 2)


def test_bench_push_refuses_bad_options(tmp_path, capsys):
    res = run("bench", "push", "--scenes", "1", "--shapes", "box,triangle",
              "--out", str(tmp_path / "b"))
    assert res.returncode == 2 and res.stderr.count("\n") == 1 and "--shapes" in res.stderr
    res = call(capsys, "bench", "push", "--scenes", "0", "--out", str(tmp_path / "b"))
    assert res.returncode == 2 and "--scenes" in res.stderr


@pytest.mark.slow
def test_a_scene_runs_as_a_ray_task_and_the_summary_says_where(tmp_path):
    pytest.importorskip("ray")
    out = tmp_path / "b"
    res = run("bench", "push", "--scenes", "1", "--shapes", "box", "--workers", "1",
              "--time-budget", "30", "--ray", "local", "--out", str(out))
    assert res.returncode == 0, res.stderr[-2000:]
    row = json.loads((out / "rows.jsonl").read_text().splitlines()[0])
    assert row["scene"] == "bench_box_000" and row["coverage"] >= 0.9
    assert (out / "solutions" / "bench_box_000" / "result.json").is_file()
    units = json.loads((out / "summary.json").read_text())["units"]
    assert units["executor"] == "ray" and units["units"] == 1


def test_unseen_shape_scenes_cover_eight_families_three_concave():
    """``--shapes ood``: valid scenes, every family twice in 16, concave T, cross and U, in
    the data's size range, with a goal region that holds them in any orientation."""
    from robotplan.geometry.polygons import is_convex
    from robotplan.pushing.bench.push_scenes import OOD_FAMILIES, family_of

    docs = [draw_scene(i, 5, "ood") for i in range(16)]
    assert docs[3] == draw_scene(3, 5, "ood") and docs[3] != draw_scene(3, 6, "ood")
    seen = {}
    for i, doc in enumerate(docs):
        scene = parse_scene(doc, f"bench/{i}.yaml")
        shape = scene.objects[0].shape
        fam = family_of(i, "ood")
        seen[fam] = seen.get(fam, 0) + 1
        outline = shape.outline()
        extent = np.ptp(outline, axis=0)
        assert 0.08 <= extent.min() and extent.max() <= 0.30, (fam, extent)
        assert is_convex(outline) == (fam not in ("T", "cross", "U")), fam
        region, body = scene.goal_region, scene.bodies["object"]
        for yaw in np.linspace(0, math.pi, 5):
            assert coverage(body, (region.pose[0], region.pose[1], float(yaw)), region) > 0.999
    assert seen == {f: 2 for f in OOD_FAMILIES}


def test_pose_scenes_turn_a_box_or_a_t_shape_30_to_90_degrees():
    """``--shapes pose``: boxes and T-shapes alternate; the goal is the object's own
    footprint at a pose 0.15–0.3 m away, turned by 30–90°."""
    from robotplan.pushing.bench.push_scenes import family_of

    for i in range(8):
        doc = draw_scene(i, 2, "pose")
        scene = parse_scene(doc, f"bench/{i}.yaml")
        goal, start = scene.goal, scene.objects[0].pose
        assert goal.type == "pose" and family_of(i, "pose") == ("box", "T")[i % 2]
        turn = abs((goal.pose[2] - start[2] + math.pi) % (2 * math.pi) - math.pi)
        assert math.radians(30) - 1e-3 <= turn <= math.radians(90) + 1e-3
        assert 0.15 - 1e-3 <= math.dist(goal.pose[:2], start[:2]) <= 0.3 + 1e-3
        region = scene.goal_region  # the object's own footprint at the goal pose
        assert region.shape == scene.objects[0].shape
        assert coverage(scene.bodies["object"], goal.pose, region) > 0.999
