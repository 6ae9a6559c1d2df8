"""``robotplan bench push``: plan and execute random push scenes, as the paper's Fig. 3.

Scenes are drawn as in the paper (:mod:`robotplan.pushing.bench.push_scenes`). Each scene is
solved by the skeleton search once and its plan executed in pybullet both ways, closed
loop (re-planning from the observed scene) and open loop (the paper's protocol), in the
nominal world or, with ``perturb``, in a perturbed one drawn per scene.

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
from robotplan.scene import parse_scene

__all__ = ["candidate_timings", "finished_rows", "quartiles", "run_bench_push", "summarize",
           "time_profile", "time_profile_line"]


def quartiles(values: list[float]) -> dict:
    """``n``, the quartiles ``q1``, ``median``, ``q3`` and the extremes ``min``, ``max``."""
    if not values:
        return {"n": 0}
    q = np.percentile(values, [25, 50, 75])
    return {"n": len(values), "q1": round(float(q[0]), 4), "median": round(float(q[1]), 4),
            "q3": round(float(q[2]), 4), "min": round(float(min(values)), 4),
            "max": round(float(max(values)), 4)}


def candidate_timings(candidates: list[dict]) -> dict[str, float]:
    """Seconds per timer summed over a search's ``candidates`` (``result.json``): each
    functional's callbacks, ``solver`` (SNOPT itself), ``warm_start``…, plus ``programs``
    (their count) and ``total`` (the candidates' own seconds; with parallel workers more
    than the wall-clock plan time)."""
    out: dict[str, float] = {"programs": float(len(candidates)), "total": 0.0}
    for cand in candidates:
        out["total"] += float(cand.get("seconds") or 0.0)
        for name, seconds in (cand.get("timings") or {}).items():
            out[name] = out.get(name, 0.0) + float(seconds)
    return {k: round(v, 3) for k, v in out.items()}


def finished_rows(rows_path: Path) -> dict[str, dict]:
    """The rows of a ``rows.jsonl`` (one JSON object per finished scene) by scene name;
    empty where the file is not there yet (a benchmark continues where it stopped)."""
    if not rows_path.exists():
        return {}
    rows = (json.loads(line) for line in rows_path.read_text().splitlines() if line.strip())
    return {row["scene"]: row for row in rows}


def time_profile(rows: list[dict]) -> dict:
    """Where the planning time goes over a benchmark: each timer's seconds summed over all
    scenes' candidates and its share of the candidates' total, largest first. Rows without
    ``timings`` (e.g. in a ``rows.jsonl`` written without them) are left out and counted."""
    timed = [r["timings"] for r in rows if r.get("timings")]
    total = sum(t["total"] for t in timed)
    names = {k for t in timed for k in t} - {"programs", "total"}
    sums = sorted(((sum(t.get(k, 0.0) for t in timed), k) for k in names), reverse=True)
    seconds = {k: round(v, 1) for v, k in sums}  # largest first
    return {"scenes": len(timed), "untimed_scenes": len(rows) - len(timed),
            "programs": int(sum(t["programs"] for t in timed)),
            "candidate_seconds": round(total, 1), "seconds": seconds,
            "share": {k: round(v / total, 3) if total else 0.0 for k, v in seconds.items()}}


def time_profile_line(profile: dict, top: int = 6) -> str | None:
    """One line of a :func:`time_profile`: its programs, their seconds and the ``top``
    timers' shares; None where no program was timed."""
    if not profile["candidate_seconds"]:
        return None
    shares = ", ".join(f"{k} {100 * v:.0f} %" for k, v in list(profile["share"].items())[:top])
    return (f"time: {profile['programs']} programs, {profile['candidate_seconds']:.0f} s in "
            f"their callbacks and solver: {shares}")


def summarize(rows: list[dict]) -> dict:
    """Quartiles per shape type: coverage closed loop (``coverage``) and open loop, plan
    time (the rehearsal's included), the rehearsal's seconds, wall time of plan + execution
    each way (a closed loop needs no rehearsal: its seconds are left out), re-plans per
    scene, how many of them the loop went on with, and their seconds."""
    out: dict = {"scenes": len(rows), "coverage": {}, "open_loop_coverage": {},
                 "plan_seconds": {}, "rehearsal_seconds": {}, "closed_loop_seconds": {},
                 "open_loop_seconds": {},
                 "replans": {}, "replans_adopted": {}, "replan_seconds": {}, "below_0_9": {}}
    for kind in sorted({r["shape"] for r in rows}):
        sel = [r for r in rows if r["shape"] == kind]
        out["coverage"][kind] = quartiles([r["coverage"] for r in sel])
        out["open_loop_coverage"][kind] = quartiles([r.get("open_loop_coverage", 0.0)
                                                      for r in sel])
        out["below_0_9"][kind] = {
            "closed_loop": sum(r["coverage"] < 0.9 for r in sel),
            "open_loop": sum(r.get("open_loop_coverage", 0.0) < 0.9 for r in sel)}
        out["plan_seconds"][kind] = quartiles([r["plan_seconds"] for r in sel])
        out["rehearsal_seconds"][kind] = quartiles([r.get("rehearsal_seconds", 0.0)
                                                     for r in sel])
        out["closed_loop_seconds"][kind] = quartiles(
            [r["plan_seconds"] - r.get("rehearsal_seconds", 0.0) + r.get("execute_seconds", 0.0)
             for r in sel])
        out["open_loop_seconds"][kind] = quartiles(
            [r["plan_seconds"] + r.get("open_loop_seconds", 0.0) for r in sel])
        out["replans"][kind] = quartiles([len(r.get("replans", [])) for r in sel])
        every = [x for r in sel for x in r.get("replans", [])]
        out["replans_adopted"][kind] = {
            "adopted": sum(bool(x.get("adopted", x.get("solved"))) for x in every),
            "of": len(every)}
        out["replan_seconds"][kind] = quartiles([x["seconds"] for x in every])
    out["plan_seconds"]["all"] = quartiles([r["plan_seconds"] for r in rows])
    mixed = [r for r in rows if r["shape"] in ("ood", "pose")]
    if mixed:
        out["coverage_by_family"] = {
            fam: quartiles([r["coverage"] for r in mixed if r.get("family") == fam])
            for fam in sorted({r.get("family") for r in mixed})}
    poses = [r for r in rows if r["shape"] == "pose"]
    if poses:  # Push-T's success: coverage of the target footprint ≥ 0.95
        out["pose_success"] = {
            "closed_loop": round(sum(r["coverage"] >= 0.95 for r in poses) / len(poses), 3),
            "open_loop": round(sum(r.get("open_loop_coverage", 0) >= 0.95 for r in poses)
                               / len(poses), 3)}
    out["time_profile"] = time_profile(rows)
    return out


MODEL_NAMES = {"push_flow": "F_flow", "push_rigid": "F_q", "push_direct": "F"}


def _box_plot(rows: list[dict], path: Path, model: str) -> None:
    """Coverage per shape type, open and closed loop side by side; ``model`` names the
    learned dynamics in the title (``auto``: the models the rows used)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kinds = sorted({r["shape"] for r in rows})
    fig, ax = plt.subplots(figsize=(5.5, 3.9), dpi=120)
    jitter = np.random.default_rng(0)  # the dots' spread only: the same picture every run
    for offset, key, color, dots, label in (
            (-0.18, "open_loop_coverage", "#bbbbbb", "#555555", "open loop"),
            (0.18, "coverage", "#8fc0e6", "#1d5f93", "closed loop")):
        data = [[r.get(key, 0.0) for r in rows if r["shape"] == k] for k in kinds]
        positions = np.arange(1, len(kinds) + 1) + offset
        box = ax.boxplot(data, positions=positions, widths=0.3, showfliers=False,
                         patch_artist=True)
        for patch in box["boxes"]:
            patch.set_facecolor(color)
        # every scene as a dot: a box of all-equal values is a line, the dots still show n
        for x, values in zip(positions, data, strict=True):
            ax.scatter(x + jitter.uniform(-0.09, 0.09, len(values)), values, s=9,
                       color=dots, alpha=0.8, linewidths=0, zorder=3)
        ax.plot([], [], color=color, linewidth=8, label=label)

    def label(kind: str) -> str:
        sel = [r for r in rows if r["shape"] == kind]
        below = [sum(r.get(key, 0.0) < 0.9 for r in sel)
                 for key in ("open_loop_coverage", "coverage")]
        return f"{kind} (n={len(sel)})\nbelow 0.9: {below[0]} open, {below[1]} closed"

    ax.set_xticks(range(1, len(kinds) + 1), [label(k) for k in kinds], fontsize=8)
    ax.set_ylabel("coverage of the object inside the goal")
    ax.set_ylim(-0.02, 1.02)
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.08), ncol=2, fontsize=8,
              frameon=False)
    if model == "auto":
        used = sorted({r["model"] for r in rows if r.get("model")})
        model = ", ".join(MODEL_NAMES.get(m, m) for m in used) or "auto"
    else:
        model = MODEL_NAMES.get(Path(model).name, Path(model).name)
    ax.set_title(f"execution in pybullet: open vs closed loop ({model})")
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()

    def write(tmp: Path) -> None:
        fig.savefig(tmp, format="png")

    write_atomically(path, write)
    plt.close(fig)


def bench_scene(job: tuple) -> dict:
    """Plan and execute one benchmark scene (a unit of :func:`run_bench_push`): its row.
    ``job = (i, kind, seed, out, model_dir, workers, exhaustive, time_budget, perturb,
    loop, program, rehearse)``; the scene file and the solution are written under ``out``."""
    from robotplan.api import solve
    from robotplan.pushing.execution.perturb import Perturbation

    (i, kind, seed, out, model_dir, workers, exhaustive, time_budget, perturb, loop, program,
     rehearse) = job
    doc = draw_scene(i, seed, kind, out / "scenes")
    name = doc["name"]
    scene_path = out / "scenes" / f"{name}.yaml"
    scene_path.write_text(yaml.safe_dump(doc, sort_keys=False, default_flow_style=None))
    scene = parse_scene(doc, scene_path)
    t0 = time.time()
    world = (Perturbation(int(np.random.default_rng([perturb, i, len(kind)]).integers(2**31)))
             if perturb is not None else None)
    result = solve(scene, out / "solutions" / name, model_dir, workers=workers,
                   progress=False, exhaustive=exhaustive, quiet=True,
                   time_budget=time_budget, perturb=world, compare_open_loop=True,
                   loop=loop, program=program, rehearse_plan=rehearse)
    ex = result.get("execution") or {}
    open_loop = result.get("open_loop") or {}
    return {"scene": name, "shape": kind, "family": family_of(i, kind),
            "footprint": scene.objects[0].shape.describe(),
            "model": Path(result["model"]).name,
            "status": result["plan_status"], "outcome": result["status"],
            "coverage": float(ex.get("coverage") or 0.0),
            "open_loop_coverage": float(open_loop.get("coverage") or 0.0),
            "execute_seconds": float(ex.get("seconds") or 0.0),
            "open_loop_seconds": float(open_loop.get("seconds") or 0.0),
            "replans": ex.get("replans") or [],
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
                   program: dict | None = None, rehearse: bool = True) -> dict:
    """Solve and execute ``scenes`` scenes per shape type; returns the summary.
    ``model_dir``: the learned dynamics' folder, None for each scene's default.
    ``perturb``: the seed of the perturbed worlds (one per scene), None for the nominal.
    ``loop``: closed-loop settings in place of each scene class's (``LoopSettings`` fields),
    ``program`` its program settings (``ProgramSettings`` fields, e.g. the ablations).
    ``rehearse``: rehearse F_q's plans before the open loop (``robotplan.api.plan``).
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
    done = finished_rows(rows_path)
    todo = [(i, kind) for i in range(scenes) for kind in shapes]
    jobs = [(i, kind, seed, out, model_dir, workers, exhaustive, time_budget, perturb, loop,
             program, rehearse)
            for i, kind in todo if scene_name(i, kind) not in done]
    report = UnitsReport()
    for row in run_units(bench_scene, jobs, 1, ray, report, cpus_per_unit=workers):
        done[row["scene"]] = row
        with rows_path.open("a") as f:
            f.write(json.dumps(row) + "\n")
        print(f"[{len(done)}/{len(todo)}] {row['scene']}: {row['footprint']}\n"
              f"    coverage {row['coverage']:.3f} closed loop ({len(row['replans'])} "
              f"re-plans), {row['open_loop_coverage']:.3f} open loop, "
              f"plan {row['plan_seconds']:.1f} s, "
              f"{row['programs']} programs, {row['skeleton']}", flush=True)
    rows = [done[scene_name(i, kind)] for i, kind in todo]
    summary = summarize(rows)
    summary.update({"seed": seed, "model": str(model_dir) if model_dir else "auto",
                    "exhaustive": exhaustive,
                    "time_budget_s": time_budget, "perturb": perturb,
                    "loop_settings": loop or {}, "program_settings": program or {},
                    "rehearse": rehearse,
                    "units": report.as_dict()})
    buf = io.StringIO()
    flat = [{**{k: v for k, v in r.items() if k not in ("timings", "replans", "footprint")},
             "replans": len(r.get("replans", []))} for r in rows]
    fields = list(dict.fromkeys(k for r in flat for k in r))
    writer = csv.DictWriter(buf, fieldnames=fields)
    writer.writeheader()
    writer.writerows(flat)
    write_atomically(out / "results.csv", lambda tmp: tmp.write_text(buf.getvalue()))
    _box_plot(rows, out / "coverage.png", summary["model"])
    write_atomically(out / "summary.json",
                     lambda tmp: tmp.write_text(json.dumps(summary, indent=1)))
    return summary
