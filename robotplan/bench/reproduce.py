"""``robotplan reproduce``: the paper's tables and figures from our code, beside its numbers.

Each item is a step (data, training, evaluation, benchmark: :mod:`robotplan.bench.steps`),
kept and reused while its inputs do not change. The report (``OUT/report.md`` and
``.html`` at the standard and full sizes, ``OUT/quick.md`` at the quick size) is written
from the step results.
"""

from __future__ import annotations

import json
import re
import shutil
import time
from collections.abc import Callable
from dataclasses import asdict
from fnmatch import fnmatch
from pathlib import Path

from robotplan.base.files import write_atomically
from robotplan.base.resources import DYNAMICS_FOLDERS, OBJECT_FRAME_FOLDERS, learned_dir
from robotplan.bench.paper import REPRESENTATIONS
from robotplan.bench.report import write_report
from robotplan.bench.reproduce_models import (
    PUSH_TRAINING,
    flow_representations,
    rigid_representations,
)
from robotplan.bench.reproduce_report import report_blocks
from robotplan.bench.reproduce_sizes import FULL, QUICK, ReproduceSizes
from robotplan.bench.steps import Steps
from robotplan.hanging.bench.bench import PAPER_HANG
from robotplan.hanging.bench.reproduce import hang_representations

__all__ = ["ABLATIONS", "ANALYTIC", "FULL", "QUICK", "ReproduceSizes", "ledger_dir",
           "reproduce", "reproduce_status", "step_filter"]

# the paper's Fig. 11: the push program with every row, without H_coll, without H_PoC,
# without both; searched by the paper's optimiser alone (PAPER_SEARCH): a push fitted in
# closed form meets the rows before any of them is optimised, so leaving one out changes
# nothing there (docs/experiments.md#ablation-search)
ABLATIONS = {"every_row": {}, "no_collision": {"with_collision": False},
             "no_contact": {"with_contact": False},
             "dynamics_and_goal_only": {"with_collision": False, "with_contact": False}}
PAPER_SEARCH = ("plain",)
# the paper's Fig. 6: the analytic pushing model in place of the learned one (the kinematic
# program's quasi-static push is the plan)
ANALYTIC = {"learned_stage": False}


def ledger_dir(sizes: ReproduceSizes) -> Path:
    """Where the finished steps of a run at ``sizes`` are kept with the code:
    ``docs/reproduce/ledger/<sizes.name>/``."""
    return learned_dir("x").parents[1] / "docs" / "reproduce" / "ledger" / sizes.name


def step_filter(patterns: tuple[str, ...] = (), hours: float | None = None
                ) -> Callable[[str], bool] | None:
    """Which steps a run in parts may start: those whose name matches one of ``patterns``
    (shell patterns; none: every step), while fewer than ``hours`` have passed since this
    call (None: no limit). None where neither limits anything."""
    if not patterns and hours is None:
        return None
    start = time.monotonic()

    def allow(name: str) -> bool:
        within = hours is None or time.monotonic() - start < 3600 * hours
        return within and (not patterns or any(fnmatch(name, p) for p in patterns))

    return allow


def reproduce(out: Path, sizes: ReproduceSizes = QUICK, workers: int = 2,
              ray: str | None = None, progress: bool = True,
              ledger: Path | None = None, allow: Callable[[str], bool] | None = None,
              device: str = "cpu") -> Path | None:
    """Run (or reuse, from ``out`` or the ``ledger``) every item at ``sizes`` and write
    ``out/R.md`` and ``out/R.html`` (R: ``sizes.report``); returns the Markdown report's
    path. ``allow`` (:func:`step_filter`): run only the steps it allows; where it leaves
    some for a later run, no report is written and None is returned. ``workers`` and
    ``ray`` as for ``data push`` and ``bench push``; ``device``: the training steps'
    (``cpu`` or ``cuda``)."""
    out.mkdir(parents=True, exist_ok=True)
    steps = Steps(out, progress, ledger, allow=allow, device=device)
    results = _run_steps(steps, sizes, workers, ray)
    run = {"sizes": asdict(sizes), "workers": workers, "ray": ray, "steps": steps.log}
    write_atomically(out / "run.json", lambda tmp: tmp.write_text(json.dumps(run, indent=1)))
    if not steps.complete:
        return None
    if results["fig5"]:
        plot_contact_pushes_of(results["fig5"], out / sizes.figure("fig5_contact_push.png"))
    for key in ("fig3", "fig8"):  # the box plots sit beside the report
        plot = out / results[key]["folder"] / "bench" / "coverage.png"
        if plot.is_file():
            shutil.copyfile(plot, out / sizes.figure(f"{key}_coverage.png"))
        elif results[key]["result"].get("rows"):  # a step kept in the ledger alone
            from robotplan.pushing.bench.push_summary import box_plot

            box_plot(results[key]["result"]["rows"], out / sizes.figure(f"{key}_coverage.png"),
                     "auto")
    md, _ = write_report(report_blocks(results, sizes, steps.log, out), out,
                         "robotplan: the paper reproduced", sizes.report)
    return md


def reproduce_status(out: Path, sizes: ReproduceSizes = QUICK, workers: int = 2,
                     ledger: Path | None = None) -> list[dict]:
    """Every step of a run at ``sizes`` without running any: its ``state`` (``done``,
    ``stale``, ``missing``, ``running``; :class:`~robotplan.bench.steps.Steps`), the seconds
    it last took where the ledger knows them, else (``estimated``) those of the same step in
    another size's ledger scaled by its size (:func:`scaled_seconds`)."""
    steps = Steps(out, False, ledger, dry=True)
    _run_steps(steps, sizes, workers, None)
    others = [p for p in (ledger.parent.glob("*") if ledger is not None else ())
              if p.is_dir() and p != ledger]
    for step, params in zip(steps.log, steps.params_log, strict=True):
        if step["seconds"] is None:
            step["seconds"] = scaled_seconds(step["name"], params, others)
            step["estimated"] = step["seconds"] is not None
    return steps.log


SIZE_PARAMS = ("steps", "scenes", "samples")  # what a step's time grows with
DEFAULT_BATCH = 32  # TrainConfig's batch, where a step's parameters name none


def _measured_like(name: str, folder: Path) -> Path | None:
    """The ledger entry of step ``name`` in ``folder``, else of the same step for seed 0
    (``NAME_seedK``), else of a step of the same kind (its name up to the last ``_``, two
    words at least: the same training or evaluation on another representation)."""
    base = re.sub(r"_seed\d+$", "", name)
    for candidate in dict.fromkeys((name, base)):
        if (folder / f"{candidate}.json").is_file():
            return folder / f"{candidate}.json"
    kind = base.rsplit("_", 1)[0]
    if "_" not in kind:  # a kind is two words at least: "train_rigid", "bench_hang"
        return None
    return next(iter(sorted(folder.glob(f"{kind}_*.json"))), None)


def scaled_seconds(name: str, params: dict, ledgers: list[Path]) -> float | None:
    """The seconds step ``name`` (or the nearest like it, :func:`_measured_like`) took in one
    of ``ledgers``, times the ratio of its first size parameter (:data:`SIZE_PARAMS`) here
    and there, and of its batch; None where no ledger has one like it."""
    for folder in ledgers:
        path = _measured_like(name, folder)
        if path is None:
            continue
        entry = json.loads(path.read_text())
        there = entry.get("params", {})
        size = next((k for k in SIZE_PARAMS if k in params and there.get(k)), None)
        ratio = params[size] / there[size] if size else 1.0
        ratio *= params.get("batch", DEFAULT_BATCH) / there.get("batch", DEFAULT_BATCH)
        return float(entry["seconds"]) * ratio
    return None


ROW_FIELDS = ("scene", "shape", "family", "model", "status", "coverage", "open_loop_coverage")


def with_rows(summary: dict, bench: Path) -> dict:
    """A benchmark's summary with its scenes' outcomes (``ROW_FIELDS`` of ``rows.jsonl``):
    what the report draws and tabulates per scene, kept with the step's result."""
    lines = (bench / "rows.jsonl").read_text().splitlines()
    rows = [json.loads(line) for line in lines if line.strip()]
    return {**summary, "rows": [{k: r.get(k) for k in ROW_FIELDS} for r in rows]}


def plot_contact_pushes_of(fig5: dict, path: Path) -> None:
    """Fig. 5's picture from its steps' results, written to ``path``."""
    from robotplan.pushing.bench.contact_push import plot_contact_pushes

    plot_contact_pushes({k: v["result"] for k, v in fig5.items()},
                        {k: REPRESENTATIONS[k][0] for k in fig5}, path)


def _run_steps(steps: Steps, sizes: ReproduceSizes, workers: int, ray: str | None) -> dict:
    """Every step at ``sizes`` (run, reused or, dry, looked up): their results by item."""
    from robotplan.hanging.bench.bench import run_bench_hang
    from robotplan.pushing.bench.contact_push import plan_from_contact
    from robotplan.pushing.bench.push import run_bench_push
    from robotplan.pushing.training.evaluation import evaluate_push
    from robotplan.pushing.training.pose_fit import evaluate_pose_fit
    from robotplan.pushing.training.push_data import PushDataSpec, generate
    from robotplan.pushing.training.rigid_evaluation import evaluate_rigid

    out = steps.out
    models = {kind: learned_dir(folder) for kind, folder in DYNAMICS_FOLDERS.items()}

    def data(name: str, scenes: int, seed: int, shapes: str) -> Path:
        params = {"scenes": scenes, "seed": seed, "shapes": shapes}
        res = steps.run(name, params, lambda f: generate(
            f / "data", scenes, seed, workers=workers, spec=PushDataSpec(shapes=shapes),
            progress=False, ray=ray),
            f"robotplan data push --scenes {scenes} --seed {seed} --shapes {shapes}",
            runs=(f"{PUSH_TRAINING}.push_data",))
        return out / res["folder"] / "data"

    test = data("data_test", sizes.test_scenes, 2, "train")
    ood = data("data_ood", sizes.ood_scenes, 3, "ood")
    results: dict[str, dict] = {}
    per = sizes.per_scene
    for set_name, folder in (("test", test), ("ood", ood)):
        for kind in ("flow", "direct"):
            results[f"rmse_{kind}_{set_name}"] = steps.run(
                f"eval_{kind}_{set_name}", {"per_scene": per},
                lambda f, k=kind, d=folder: evaluate_push(models[k], d, per_scene=per,
                                                          progress=False),
                f"robotplan eval push --model learned/push_{kind} --data DATA --per-scene {per}",
                runs=(f"{PUSH_TRAINING}.evaluation",), **steps.uses(models[kind], folder))
            framed = learned_dir(OBJECT_FRAME_FOLDERS[kind])
            if (framed / "spec.json").is_file():
                results[f"rmse_{kind}_object_{set_name}"] = steps.run(
                    f"eval_{kind}_object_{set_name}", {"per_scene": per},
                    lambda f, m=framed, d=folder: evaluate_push(m, d, per_scene=per,
                                                                progress=False),
                    f"robotplan eval push --model learned/{framed.name} --data DATA "
                    f"--per-scene {per}",
                    runs=(f"{PUSH_TRAINING}.evaluation",), **steps.uses(framed, folder))
        results[f"rigid_{set_name}"] = steps.run(
            f"eval_rigid_{set_name}", {"per_scene": per},
            lambda f, d=folder: evaluate_rigid(models["rigid"], d, per_scene=per),
            f"robotplan eval push --model learned/push_rigid --data DATA --per-scene {per}",
            runs=(f"{PUSH_TRAINING}.rigid_evaluation",), **steps.uses(models["rigid"], folder))
    train = data("data_train_representations", sizes.representation_scenes, 4, "train")
    reps, rep_models = rigid_representations(steps, sizes, train, {"test": test, "ood": ood})
    results.update(reps)
    results["tab4"] = flow_representations(steps, sizes, train, test)
    results["fig5"] = {key: steps.run(
        f"contact_push_{key}", {}, lambda f, m=rep_models[key]: plan_from_contact(m),
        "robotplan bench contact-push --model MODEL",
        runs=("robotplan.pushing.bench.contact_push",), **steps.uses(rep_models[key]))
        for key in sizes.contact_push}
    results["pose_fit_flow"] = steps.run(
        "pose_fit_flow", {"samples": sizes.pose_fit},
        lambda f: evaluate_pose_fit(models["flow"], test, samples=sizes.pose_fit,
                                    progress=False),
        f"robotplan eval push --model learned/push_flow --data DATA --pose-fit {sizes.pose_fit}",
        runs=(f"{PUSH_TRAINING}.pose_fit",), **steps.uses(models["flow"], test))

    # a benchmark's searches read each scene's default pushing models
    push_models = tuple(sorted(learned_dir("x").parent.glob("push_*")))

    def bench(name: str, scenes: int, shapes: str, program: dict | None = None,
              loop: dict | None = None, rehearse: bool = True,
              kinds: tuple[str, ...] | None = None) -> dict:
        """``rehearse``: robotplan's open loop (the plan rehearsed in F_q), or the paper's
        (the plan as searched), for the baselines and ablations of the paper's protocol;
        ``kinds``: the kinds of candidates the searches may try (None: every kind)."""
        params = {"scenes": scenes, "seed": 0, "shapes": shapes,
                  "time_budget": sizes.time_budget, "workers": workers,
                  "program": program or {}, "rehearse": rehearse,
                  **({"loop": loop} if loop else {}),
                  **({"candidates": list(kinds)} if kinds else {})}
        flags = "".join(f" --{kind} {k}={str(v).lower()}"
                        for kind, settings in (("program", program), ("loop", loop))
                        for k, v in (settings or {}).items())
        flags += "" if rehearse else " --no-rehearse"
        flags += f" --candidates {','.join(kinds)}" if kinds else ""
        return steps.run(name, params, lambda f: with_rows(run_bench_push(
            scenes, 0, f / "bench", None, workers, tuple(shapes.split(",")),
            time_budget=sizes.time_budget, ray=ray, program=program, loop=loop,
            rehearse=rehearse, candidate_kinds=kinds), f / "bench"),
            f"robotplan bench push --scenes {scenes} --seed 0 --shapes {shapes} "
            f"--time-budget {sizes.time_budget:g} --workers {workers}{flags}",
            runs=("robotplan.pushing.bench.push",), reads=push_models)

    results["fig3"] = bench("bench_push", sizes.push_scenes, "box,lshape")
    results["fig8"] = bench("bench_push_ood", sizes.ood_push_scenes, "ood")
    results["fig6"] = bench("bench_push_analytic", sizes.push_scenes, "box,lshape",
                            ANALYTIC, rehearse=False)
    replans = ({"max_replans": sizes.ablation_replans}
               if sizes.ablation_replans is not None else None)
    results["fig11"] = {name: bench(f"ablation_{name}", sizes.ablation_scenes, "box", program,
                                    replans, rehearse=False, kinds=PAPER_SEARCH)
                        for name, program in ABLATIONS.items()}
    methods = ",".join(sizes.hang_methods)
    results["tab3"] = steps.run(
        "bench_hang", {"scenes": sizes.hang_scenes, "seed": 2, "methods": methods},
        lambda f: run_bench_hang(sizes.hang_scenes, 2, f / "bench", learned_dir("hang"),
                                 workers=workers, progress=False,
                                 methods=sizes.hang_methods, ray=ray, settings=PAPER_HANG),
        f"robotplan bench hang --scenes {sizes.hang_scenes} --seed 2 --methods {methods} "
        "--check none --no-threading",
        runs=("robotplan.hanging.bench.bench",), reads=(learned_dir("hang"),))
    results["tab3_representations"] = hang_representations(steps, sizes, workers, ray)
    return results
