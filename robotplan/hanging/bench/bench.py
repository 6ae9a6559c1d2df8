"""``robotplan bench hang``: the paper's Tab. 3 on random mug-and-hook scenes.

Scene ``i`` of ``seed`` draws its hook and mug as the data does (``default_rng([seed, i])``,
:mod:`robotplan.hanging.scene.ranges`). Each method looks for a pose within the same budget of
functional evaluations: optimisation + sampling (SNOPT from up to 20 random poses),
optimisation only (one), and sampling only at the thresholds κ1, κ2, κ3. A found pose is
dropped in each simulator asked for (pybullet by default, MuJoCo,
:data:`robotplan.hanging.execution.worlds.HANG_SIMULATORS`): *sim success* when the mug
hangs, *collision free* when it did not start inside the hook; *total* = found and hanging
and collision free. Beside the paper's columns, *in place*: the found poses that hang
without first falling onto the hook
(:meth:`robotplan.hanging.execution.drop.DropResult.in_place`). The three sampling runs share
one stream of random poses (:func:`robotplan.hanging.search.optimise.sample_hang`).

Beside Tab. 3, ``closed_loop`` (on request, ``--methods``): optimisation + sampling that
drops each pose it finds and goes on searching, within the same budget, while the mug falls
(robotplan's default execution, :func:`robotplan.hanging.api.planner.execute_hang`); its starts are
those of optimisation + sampling, so its first found pose is that method's; its drops are
in the first simulator named.

A row's outcomes are the first simulator's; with several, each simulator's are under
``by_simulator``, and the summary's under ``by_simulator`` too.

``DIR/rows.jsonl`` gets one line per finished scene (an interrupted run with the same
settings, ``DIR/run.json``, continues), then ``summary.json``.
"""

from __future__ import annotations

import json
import time
from contextlib import ExitStack
from dataclasses import replace
from pathlib import Path

import numpy as np

from robotplan.base.files import write_atomically
from robotplan.base.units import UnitsReport, check_ray, run_units
from robotplan.hanging.execution.drop import DropResult
from robotplan.hanging.execution.worlds import hang_world
from robotplan.hanging.models.hang_model import HANG_THRESHOLDS, load_hang_model
from robotplan.hanging.program.problem import HANG_DEFAULTS, HangProblem, HangSettings
from robotplan.hanging.scene.ranges import load_hang_ranges
from robotplan.hanging.search.optimise import optimise_hang, sample_hang

__all__ = ["CLOSED_LOOP", "METHODS", "PAPER_HANG", "PAPER_TAB3", "SCENE_SETS", "mesh_pair",
           "run_bench_hang", "summarize_hang"]

METHODS = ("opt_sampling", "opt_only", "sampling_k1", "sampling_k2", "sampling_k3")
CLOSED_LOOP = "closed_loop"  # not in the paper: run when asked for (module docstring)
# paper Tab. 3, SDF rows (fractions of the 150 evaluation scenes): found, sim success (of the
# found), collision free (of the successes), total
PAPER_TAB3 = {"opt_sampling": (0.987, 0.885, 1.0, 0.873),
              "opt_only": (0.513, 0.935, 0.986, 0.473),
              "sampling_k1": (0.838, 0.823, 1.0, 0.689),
              "sampling_k2": (1.0, 0.356, 1.0, 0.356),
              "sampling_k3": (0.260, 0.875, 1.0, 0.228)}
# the paper's protocol (``reproduce``): uniform random starts and no H_thread row; with
# ``check_dir=None``, its one network
PAPER_HANG = replace(HANG_DEFAULTS, threading=False)


SCENE_SETS = ("procedural", "meshes")
"""``procedural``: hooks and mugs drawn as the data draws them; ``meshes``: the mesh mugs and
hooks of ``tasks/meshes/hang/`` (:data:`MESH_MUGS` × :data:`MESH_HOOKS`, scene ``i`` the pair
``i`` mod 6; the seed draws the starts), none of them drawn by the training generator."""
MESH_MUGS = ("mug_tapered.obj", "mug_square_handle.stl", "mug_ring_handle.obj")
MESH_HOOKS = ("hook_square_rod.stl", "hook_curved.obj")


def mesh_pair(index: int) -> tuple[Path, Path]:
    """The mug and hook mesh files of mesh scene ``index``."""
    from robotplan.base.resources import tasks_dir

    folder = tasks_dir() / "meshes" / "hang"
    pair = index % (len(MESH_MUGS) * len(MESH_HOOKS))
    return folder / MESH_MUGS[pair % len(MESH_MUGS)], folder / MESH_HOOKS[pair // len(MESH_MUGS)]


def _scene(index: int, seed: int, scene_set: str = "procedural"):
    """The hook and the mug of scene ``index``."""
    if scene_set == "meshes":
        from robotplan.geometry.meshes import read_mesh
        from robotplan.sdf.mesh_solids import MeshHook, MeshMug

        mug_file, hook_file = mesh_pair(index)
        return (MeshHook(read_mesh(hook_file), hook_file),
                MeshMug(read_mesh(mug_file), mug_file))
    ranges = load_hang_ranges()
    rng = np.random.default_rng([seed, index])
    return ranges.hook.sample(rng), ranges.mug.sample(rng)


def bench_scene(index: int, seed: int, model_dir: str | Path,
                settings: HangSettings = HANG_DEFAULTS,
                methods: tuple[str, ...] = METHODS, check_dir: str | Path | None = None,
                scene_set: str = "procedural",
                simulators: tuple[str, ...] = ("pybullet",)) -> dict:
    """Every method on scene ``index`` of ``scene_set`` (:data:`SCENE_SETS`); the found poses
    checked by a drop in each of ``simulators`` (module docstring). ``check_dir``: the check
    network the optimisation's found poses must satisfy too (HangSettings.check_kappa; not
    the closed loop's, whose drops are its check)."""
    from robotplan.base.threads import one_thread

    one_thread()
    hook, mug = _scene(index, seed, scene_set)
    check = load_hang_model(check_dir) if check_dir is not None else None
    problem = HangProblem(load_hang_model(model_dir), mug, hook, settings.collision, check)
    rng = np.random.default_rng([seed, index, 1])
    row = {"scene": index}
    found = {}
    for method in methods:
        if method.startswith("opt"):
            found[method] = optimise_hang(problem, rng, settings,
                                          restarts=1 if method == "opt_only" else None)
    sampling = [m for m in methods if m.startswith("sampling")]
    if sampling:
        kappas = tuple(HANG_THRESHOLDS[m.split("_")[1]] for m in sampling)
        found.update(zip(sampling, sample_hang(problem, rng, kappas, settings), strict=True))
    with ExitStack() as stack:
        worlds = [stack.enter_context(hang_world(hook, mug, sim)) for sim in simulators]
        world = worlds[0]
        drops = 0

        def hangs(sol) -> bool:
            nonlocal drops
            drops += 1
            return world.drop(sol.pose).hangs

        if CLOSED_LOOP in methods:  # the drops are its check (solve_hang's rule)
            found[CLOSED_LOOP] = optimise_hang(problem.unchecked(),
                                               np.random.default_rng([seed, index, 1]),
                                               settings, accept=hangs)
        for method in methods:
            sol = found[method]
            outcomes = [_outcome(w.drop(sol.pose) if sol.feasible else None, w.physics)
                        for w in worlds]
            row[method] = {"found": sol.feasible, **outcomes[0],
                           "h_hang": round(sol.h_hang, 4),
                           "h_coll_cm3": round(sol.h_coll_cm3, 5),
                           "evaluations": sol.evaluations, "restarts": sol.restarts,
                           "robust_h": (None if sol.robust_h is None
                                        else round(sol.robust_h, 4)),
                           "check_h": None if sol.check_h is None else round(sol.check_h, 4),
                           "thread_mm": (None if sol.thread_mm is None
                                         else round(sol.thread_mm, 3)),
                           "seconds": round(sol.seconds, 2),
                           "pose": [round(float(v), 5) for v in sol.pose]}
            if len(simulators) > 1:
                row[method]["by_simulator"] = dict(zip(simulators, outcomes, strict=True))
        if CLOSED_LOOP in methods:
            row[CLOSED_LOOP]["drops"] = drops
    return row


def _outcome(drop: DropResult | None, physics) -> dict:
    """A found pose's drop (None: no pose found) as a row's outcome fields."""
    return {"sim_success": bool(drop and drop.hangs),
            "in_place": bool(drop and drop.in_place(physics)),
            "collision_free": bool(drop and not drop.collision_at_start)}


def summarize_hang(rows: list[dict], simulator: str | None = None) -> dict:
    """Tab. 3's columns per method (fractions as the paper counts them), the in-place
    fraction of the found poses, and the median seconds of optimisation + sampling per
    scene (of the closed loop, and its median number of drops, under its own key); the
    drops' outcomes those of ``simulator`` (a row's ``by_simulator``; None: the row's own,
    the first simulator's)."""
    out: dict = {"scenes": len(rows)}
    for method in (*METHODS, CLOSED_LOOP):
        runs = [r[method] if simulator is None else {**r[method],
                                                     **r[method]["by_simulator"][simulator]}
                for r in rows if method in r]
        if not runs:
            continue
        found = [r for r in runs if r["found"]]
        hung = [r for r in found if r["sim_success"]]
        total = [r for r in hung if r["collision_free"]]
        out[method] = {"found": round(len(found) / len(runs), 4),
                       "sim_success": round(len(hung) / len(found), 4) if found else 0.0,
                       "collision_free": round(len(total) / len(hung), 4) if hung else 0.0,
                       "total": round(len(total) / len(runs), 4),
                       "in_place": round(sum(r.get("in_place", False) for r in found)
                                         / len(found), 4) if found else 0.0}
    loops = [r[CLOSED_LOOP] for r in rows if CLOSED_LOOP in r]
    if loops:
        out[CLOSED_LOOP].update(
            median_seconds=round(float(np.median([r["seconds"] for r in loops])), 2),
            median_drops=float(np.median([r.get("drops", 0) for r in loops])))
    seconds = [r["opt_sampling"]["seconds"] for r in rows if "opt_sampling" in r]
    out["median_seconds"] = round(float(np.median(seconds)), 2) if seconds else None
    return out


def _summaries(rows: list[dict], simulators: tuple[str, ...]) -> dict:
    """The first simulator's summary (:func:`summarize_hang`), with each simulator's under
    ``by_simulator`` when there are several."""
    rows = sorted(rows, key=lambda r: r["scene"])
    summary = summarize_hang(rows)
    if len(simulators) > 1:
        summary["by_simulator"] = {sim: summarize_hang(rows, sim) for sim in simulators}
    return summary


def _run(args: tuple) -> dict:
    return bench_scene(*args)


def run_bench_hang(scenes: int, seed: int, out: Path, model_dir: str | Path,
                   workers: int = 2, progress: bool = True,
                   methods: tuple[str, ...] = METHODS,
                   settings: HangSettings = HANG_DEFAULTS, ray: str | None = None,
                   check_dir: str | Path | None = None, scene_set: str = "procedural",
                   simulators: tuple[str, ...] = ("pybullet",)) -> dict:
    """Run (or continue) the benchmark in ``out``, its scenes in ``workers`` local processes
    or as Ray tasks (``ray``: :func:`robotplan.base.units.run_units`), with the check network
    in ``check_dir`` (None: none, the paper's), on the scenes of ``scene_set``
    (:data:`SCENE_SETS`), the found poses dropped in each of ``simulators``; returns the
    summary (its ``simulators`` named), with where and how long the scenes ran under
    ``units``. A run of pybullet alone keeps ``run.json`` as it was before simulators
    could be chosen (so its folders continue); another names its ``simulators`` there."""
    from tqdm import tqdm

    check_ray(ray)
    out.mkdir(parents=True, exist_ok=True)
    run = {"seed": seed, "model": str(model_dir), "evaluations": settings.evaluations,
           "start_pool": settings.start_pool, "robust_samples": settings.robust_samples,
           "approach_iterations": settings.approach_iterations,
           "threading": settings.threading,
           "methods": list(methods), "collision": settings.collision,
           "check": None if check_dir is None else str(check_dir),
           "check_kappa": settings.check_kappa, "scene_set": scene_set}
    simulators = tuple(simulators)
    if simulators != ("pybullet",):
        run["simulators"] = list(simulators)
    run_path = out / "run.json"
    if run_path.is_file() and json.loads(run_path.read_text()) != run:
        raise ValueError(f"{out}: holds a run with other settings ({run_path}); "
                         "choose another --out")
    write_atomically(run_path, lambda p: p.write_text(json.dumps(run, indent=1)))
    rows_path = out / "rows.jsonl"
    rows = [json.loads(line) for line in rows_path.read_text().splitlines()] \
        if rows_path.is_file() else []
    done = {r["scene"] for r in rows}
    todo = [(i, seed, str(model_dir), settings, methods,
             None if check_dir is None else str(check_dir), scene_set, simulators)
            for i in range(scenes) if i not in done]
    t0 = time.time()
    with tqdm(total=scenes, initial=len(done), unit="scene", desc="bench hang",
              disable=not progress) as bar, rows_path.open("a") as log:
        report = UnitsReport()
        for row in run_units(_run, todo, workers, ray, report):
            rows.append(row)
            log.write(json.dumps(row) + "\n")
            log.flush()
            bar.update()
    summary = _summaries(rows, simulators)
    summary.update(simulators=list(simulators), seed=seed, model=str(model_dir),
                   check=run["check"], scene_set=scene_set,
                   evaluations=settings.evaluations,
                   collision=settings.collision,
                   wall_seconds=round(time.time() - t0, 1), paper=PAPER_TAB3,
                   units=report.as_dict())
    write_atomically(out / "summary.json", lambda p: p.write_text(json.dumps(summary,
                                                                            indent=1)))
    return summary
