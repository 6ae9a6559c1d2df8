"""``robotplan bench push``: plan and execute random push scenes, as the paper's Fig. 3.

Scenes are drawn as in the paper (:mod:`robotplan.pushing.bench.push_scenes`). Each scene is
solved by the skeleton search once and its plan executed in each simulator (pybullet by
default; MuJoCo beside it) both ways, closed loop (re-planning from the observed scene) and
open loop (the paper's protocol), in the nominal world or, with ``perturb``, in a perturbed
one drawn per scene.

``DIR`` receives ``scenes/NNN.yaml`` (re-solvable with ``robotplan solve``), ``rows.jsonl``
(one line per finished scene, so an interrupted run continues where it stopped),
``results.csv``, ``coverage.png`` (box plot per shape type) and ``summary.json``.
"""

from __future__ import annotations

import csv
import io
import json
import time
from pathlib import Path

import numpy as np
import yaml

from robotplan.base.files import write_atomically
from robotplan.base.units import UnitsReport, check_ray, run_units
from robotplan.pushing.bench.push_scenes import copy_meshes, draw_scene, family_of, scene_name
from robotplan.pushing.bench.push_summary import (
    box_plot,
    candidate_timings,
    compare_simulators,
    of_simulator,
    summarize,
)
from robotplan.scene import parse_scene

__all__ = ["bench_scene", "finished_rows", "run_bench_push"]


def finished_rows(rows_path: Path) -> dict[str, dict]:
    """The rows of a ``rows.jsonl`` (one JSON object per finished scene) by scene name;
    empty where the file is not there yet (a benchmark continues where it stopped)."""
    if not rows_path.exists():
        return {}
    rows = (json.loads(line) for line in rows_path.read_text().splitlines() if line.strip())
    return {row["scene"]: row for row in rows}


SIM_FIELDS = ("outcome", "coverage", "open_loop_coverage", "execute_seconds",
              "open_loop_seconds", "replans")
"""A row's fields that each simulator has its own of (``row["sims"][name]``)."""


def _executed(result: dict) -> dict:
    """One simulator's :data:`SIM_FIELDS` of a scene's ``result.json``."""
    ex = result.get("execution") or {}
    open_loop = result.get("open_loop") or {}
    return {"outcome": result["status"], "coverage": float(ex.get("coverage") or 0.0),
            "open_loop_coverage": float(open_loop.get("coverage") or 0.0),
            "execute_seconds": float(ex.get("seconds") or 0.0),
            "open_loop_seconds": float(open_loop.get("seconds") or 0.0),
            "replans": ex.get("replans") or []}


def bench_scene(job: tuple) -> dict:
    """Plan one benchmark scene and execute the plan in each simulator (a unit of
    :func:`run_bench_push`): its row, the first simulator's outcome at the top and every
    one's under ``sims``. ``job = (i, kind, seed, out, model_dir, workers, exhaustive,
    time_budget, perturb, loop, program, rehearse, sims, kinds)``; the scene file and the
    solution (one folder per simulator when there are several) are written under ``out``."""
    from robotplan.api import planner_for
    from robotplan.pushing.execution.perturb import Perturbation
    from robotplan.scene.task import make_task

    (i, kind, seed, out, model_dir, workers, exhaustive, time_budget, perturb, loop, program,
     rehearse, sims, kinds) = job
    doc = draw_scene(i, seed, kind, out / "scenes")
    name = doc["name"]
    scene_path = out / "scenes" / f"{name}.yaml"
    scene_path.write_text(yaml.safe_dump(doc, sort_keys=False, default_flow_style=None))
    scene = parse_scene(doc, scene_path)
    t0 = time.time()
    world = (Perturbation(int(np.random.default_rng([perturb, i, len(kind)]).integers(2**31)))
             if perturb is not None else None)
    task = make_task(scene)
    planner = planner_for(task)
    planned = planner.plan(task, model_dir, workers=workers, progress=False,
                           exhaustive=exhaustive, quiet=True, time_budget=time_budget,
                           program=program, rehearse_plan=rehearse, candidate_kinds=kinds)
    executed = {}
    for sim in sims:
        folder = out / "solutions" / name / (sim if len(sims) > 1 else "")
        result = planner.report(planned, folder, quiet=True, perturb=world,
                                compare_open_loop=True, loop=loop, sim=sim)
        executed[sim] = _executed(result)
    return {"scene": name, "shape": kind, "family": family_of(i, kind),
            "footprint": scene.objects[0].shape.describe(),
            "model": Path(result["model"]).name,
            "status": result["plan_status"], **executed[sims[0]], "sims": executed,
            "plan_seconds": result["plan_seconds"], "total_seconds": round(time.time() - t0, 1),
            "rehearsal_seconds": (result.get("rehearsal") or {}).get("seconds", 0.0),
            "programs": result["programs_solved"],
            "skeleton": " ".join(f"{p['mode']}@{p['init']}" for p in result["skeleton"]),
            "violation": result["violation"],
            "dynamics_rms_mm": result.get("dynamics_rms_mm"),
            "timings": candidate_timings(result.get("candidates") or [])}


def run_bench_push(scenes: int, seed: int, out: Path, model_dir: str | Path | None,
                   workers: int = 2,
                   shapes: tuple[str, ...] = ("box", "lshape"), exhaustive: bool = False,
                   time_budget: float | None = None, perturb: int | None = None,
                   loop: dict | None = None, ray: str | None = None,
                   program: dict | None = None, rehearse: bool = True,
                   sims: tuple[str, ...] = ("pybullet",),
                   candidate_kinds: tuple[str, ...] | None = None) -> dict:
    """Solve ``scenes`` scenes per shape type and execute each plan in every simulator of
    ``sims``; returns the summary (the first simulator's at the top, every one's and their
    disagreement per scene under ``simulators``, :func:`compare_simulators`).
    ``model_dir``: the learned dynamics' folder, None for each scene's default.
    ``perturb``: the seed of the perturbed worlds (one per scene), None for the nominal.
    ``loop``: closed-loop settings in place of each scene class's (``LoopSettings`` fields),
    ``program`` its program settings (``ProgramSettings`` fields, e.g. the ablations).
    ``rehearse``: rehearse F_q's plans before the open loop (``robotplan.api.plan``).
    ``candidate_kinds``: the kinds of candidates each search may try (``("plain",)``: the
    paper's optimiser alone, :class:`~robotplan.pushing.search.request.SearchRequest`).
    ``workers``: processes of each scene's skeleton search. The scenes run one after the
    other here, or as Ray tasks of ``workers`` CPUs each (``ray``:
    :func:`robotplan.base.units.run_units`; the solutions are written under ``out``, so a
    cluster of several machines needs it on a shared file system); where and how long they
    ran goes to the summary's ``units``."""
    check_ray(ray)
    (out / "scenes").mkdir(parents=True, exist_ok=True)
    if "mesh" in shapes:
        copy_meshes(out / "scenes")
    rows_path = out / "rows.jsonl"
    done = {name: row for name, row in finished_rows(rows_path).items()
            if list(row.get("sims", {"pybullet": None})) == list(sims)}
    todo = [(i, kind) for i in range(scenes) for kind in shapes]
    jobs = [(i, kind, seed, out, model_dir, workers, exhaustive, time_budget, perturb, loop,
             program, rehearse, tuple(sims), candidate_kinds)
            for i, kind in todo if scene_name(i, kind) not in done]
    report = UnitsReport()
    for row in run_units(bench_scene, jobs, 1, ray, report, cpus_per_unit=workers):
        done[row["scene"]] = row
        with rows_path.open("a") as f:
            f.write(json.dumps(row) + "\n")
        print(f"[{len(done)}/{len(todo)}] {row['scene']}: {row['footprint']}, plan "
              f"{row['plan_seconds']:.1f} s, {row['programs']} programs, {row['skeleton']}",
              flush=True)
        for sim, ex in row["sims"].items():
            print(f"    {sim}: coverage {ex['coverage']:.3f} closed loop "
                  f"({len(ex['replans'])} re-plans), {ex['open_loop_coverage']:.3f} open loop",
                  flush=True)
    rows = [done[scene_name(i, kind)] for i, kind in todo]
    summary = summarize(rows)
    summary["simulators"] = compare_simulators(rows, sims)
    summary.update({"seed": seed, "model": str(model_dir) if model_dir else "auto",
                    "exhaustive": exhaustive,
                    "time_budget_s": time_budget, "perturb": perturb,
                    "loop_settings": loop or {}, "program_settings": program or {},
                    "candidate_kinds": list(candidate_kinds or ()),
                    "rehearse": rehearse,
                    "units": report.as_dict()})
    buf = io.StringIO()
    flat = [{**{k: v for k, v in r.items()
                if k not in ("timings", "replans", "footprint", "sims")},
             "replans": len(r.get("replans", [])),
             **{f"{key}_{sim}": len(ex[key]) if key == "replans" else ex[key]
                for sim, ex in r.get("sims", {}).items() if len(sims) > 1
                for key in ("coverage", "open_loop_coverage", "replans")}} for r in rows]
    fields = list(dict.fromkeys(k for r in flat for k in r))
    writer = csv.DictWriter(buf, fieldnames=fields)
    writer.writeheader()
    writer.writerows(flat)
    write_atomically(out / "results.csv", lambda tmp: tmp.write_text(buf.getvalue()))
    for k, sim in enumerate(sims):
        box_plot(of_simulator(rows, sim), out / ("coverage.png" if k == 0 else
                                                  f"coverage_{sim}.png"), summary["model"], sim)
    write_atomically(out / "summary.json",
                     lambda tmp: tmp.write_text(json.dumps(summary, indent=1)))
    return summary
