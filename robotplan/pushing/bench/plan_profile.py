"""``robotplan bench plan``: where the planning time and the failures go.

The random push scenes of ``bench push`` (:mod:`robotplan.pushing.bench.push_scenes`) are
planned, not executed: per scene, the search's wall-clock seconds, its programs in the order
they finished, and for each program its seconds, the seconds inside each row's functional
(value and Jacobian together: SNOPT asks for both in one call), inside SNOPT itself
(``solver``) and in the kinematic stage (``warm_start``), and, for a program that did not
solve, why: SNOPT's exit (its ``info``), the stage it ended in and the rows it left
violated, by how much (each in its row's scaled units; solved means all ≤ ``FEASIBLE``).

``DIR`` receives ``scenes/NAME.yaml``, ``rows.jsonl`` (one line per finished scene: an
interrupted run continues where it stopped) and ``summary.json``.
"""

from __future__ import annotations

import json
import re
import time
from collections import Counter
from pathlib import Path

import numpy as np
import yaml

from robotplan.base.files import write_atomically
from robotplan.pushing.bench.push import finished_rows
from robotplan.pushing.bench.push_scenes import copy_meshes, draw_scene, scene_name
from robotplan.pushing.bench.push_summary import candidate_timings, quartiles, time_profile
from robotplan.pushing.program.solution import FEASIBLE, Solution
from robotplan.pushing.search.planner import is_solved
from robotplan.scene import parse_scene
from robotplan.scene.task import make_task

__all__ = ["failure", "profile_scene", "run_bench_plan", "summarize_profile"]


def failure(s: Solution) -> dict:
    """One program's entry: its skeleton, seconds and timings; SNOPT's exit codes; the
    stage it ended in; the rows left above ``FEASIBLE``, worst first."""
    codes = [int(c) for c in re.findall(r"snopt info (\d+)", s.status)]
    stage = ("kinematic" if "kinematic stage infeasible" in s.status
             else "start kept" if "learned stage not run" in s.status else "learned")
    violated = {name: float(v) for name, v in
                sorted(s.violations.items(), key=lambda kv: -kv[1]) if v > FEASIBLE}
    return {"skeleton": s.skeleton.describe(), "solved": is_solved(s),
            "seconds": round(s.seconds, 3), "violation": float(s.violation),
            "dynamics_rms_mm": round(s.dynamics_rms_mm, 3), "snopt_info": codes,
            "stage": stage, "violated": violated, "timings": s.timings}


def profile_scene(i: int, kind: str, seed: int, out: Path, model_dir: str | Path | None,
                  search: dict) -> dict:
    """Plan benchmark scene ``i`` of shape type ``kind`` (no simulator): its row.
    ``search``: fields of the search request (``workers``, ``time_budget``, ``program``)."""
    from robotplan.pushing.api.push import PushPlanner

    doc = draw_scene(i, seed, kind, out / "scenes")
    path = out / "scenes" / f"{doc['name']}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False, default_flow_style=None))
    task = make_task(parse_scene(doc, path))
    t0 = time.perf_counter()
    planned = PushPlanner().plan(task, model_dir, progress=False, quiet=True, **search)
    seconds = time.perf_counter() - t0
    programs = [failure(s) for s in planned.candidates]
    return {"scene": doc["name"], "shape": kind, "solved": planned.solved,
            "plan_seconds": round(seconds, 2), "programs": programs,
            "best": planned.best.skeleton.describe() if planned.best else None,
            "violation": float(planned.best.violation) if planned.best else None,
            "timings": candidate_timings(programs)}


def summarize_profile(rows: list[dict]) -> dict:
    """Per shape: plan seconds, searches without a solved plan, programs per search and
    the seconds spent in programs that did not solve; over all: the time per timer
    (:func:`~robotplan.pushing.bench.push_summary.time_profile`) and the failed programs by SNOPT
    exit, by stage and by the rows they left violated (count, median violation)."""
    out: dict = {"scenes": len(rows), "by_shape": {}}
    for kind in sorted({r["shape"] for r in rows}):
        sel = [r for r in rows if r["shape"] == kind]
        failed = [p for r in sel for p in r["programs"] if not p["solved"]]
        out["by_shape"][kind] = {
            "plan_seconds": quartiles([r["plan_seconds"] for r in sel]),
            "unsolved_searches": sum(not r["solved"] for r in sel),
            "programs": quartiles([len(r["programs"]) for r in sel]),
            "failed_programs": len(failed),
            "failed_seconds": round(sum(p["seconds"] for p in failed), 1),
            "program_seconds": round(sum(p["seconds"] for r in sel for p in r["programs"]), 1)}
    failed = [p for r in rows for p in r["programs"] if not p["solved"]]
    rows_hit: dict[str, list[float]] = {}
    for p in failed:
        for name, v in p["violated"].items():
            rows_hit.setdefault(name, []).append(v)
    out["failed"] = {
        "programs": len(failed),
        "snopt_info": dict(Counter(str(p["snopt_info"][-1]) if p["snopt_info"] else "none"
                                   for p in failed).most_common()),
        "stage": dict(Counter(p["stage"] for p in failed).most_common()),
        "violated_rows": {name: {"programs": len(v), "median": float(np.median(v))}
                          for name, v in sorted(rows_hit.items(), key=lambda kv: -len(kv[1]))}}
    out["time_profile"] = time_profile(rows)
    return out


def run_bench_plan(scenes: int, seed: int, out: Path, model_dir: str | Path | None,
                   shapes: tuple[str, ...] = ("box", "lshape"), search: dict | None = None
                   ) -> dict:
    """Plan ``scenes`` scenes per shape type and profile them; returns the summary.
    ``search``: fields of the search request (``workers``, ``time_budget``, ``program``)."""
    search = dict(search or {})
    (out / "scenes").mkdir(parents=True, exist_ok=True)
    if "mesh" in shapes:
        copy_meshes(out / "scenes")
    rows_path = out / "rows.jsonl"
    done = finished_rows(rows_path)
    todo = [(i, kind) for i in range(scenes) for kind in shapes]
    for i, kind in todo:
        name = scene_name(i, kind)
        if name in done:
            continue
        row = profile_scene(i, kind, seed, out, model_dir, search)
        done[name] = row
        with rows_path.open("a") as f:
            f.write(json.dumps(row) + "\n")
        bad = [p for p in row["programs"] if not p["solved"]]
        why = Counter(next(iter(p["violated"]), p["stage"]) for p in bad).most_common(2)
        print(f"[{len(done)}/{len(todo)}] {name}: {'solved' if row['solved'] else 'NOT solved'}"
              f" in {row['plan_seconds']:.1f} s, {len(row['programs'])} programs"
              + (f", {len(bad)} failed ({', '.join(f'{k} ×{n}' for k, n in why)})"
                 if bad else ""), flush=True)
    rows = [done[scene_name(i, kind)] for i, kind in todo]
    summary = summarize_profile(rows)
    summary.update({"seed": seed, "model": str(model_dir) if model_dir else "auto",
                    "search": {k: v for k, v in search.items() if k != "program"},
                    "program": search.get("program") or {}})
    write_atomically(out / "summary.json",
                     lambda tmp: tmp.write_text(json.dumps(summary, indent=1)))
    return summary
