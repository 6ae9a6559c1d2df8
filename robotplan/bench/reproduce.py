"""``robotplan reproduce``: the paper's tables and figures from our code, beside its numbers.

Each item is a step (data, training, evaluation, benchmark: :mod:`robotplan.bench.steps`),
kept and reused while its inputs do not change. The report (``OUT/report.md``,
``OUT/report.html``) is written from the step results.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import asdict
from pathlib import Path

from robotplan.base.files import write_atomically
from robotplan.base.resources import DYNAMICS_FOLDERS, OBJECT_FRAME_FOLDERS, learned_dir
from robotplan.bench.paper import FLOW_REPRESENTATIONS, REPRESENTATIONS, spec_flags
from robotplan.bench.report import write_report
from robotplan.bench.reproduce_report import report_blocks
from robotplan.bench.reproduce_sizes import FULL, QUICK, ReproduceSizes
from robotplan.bench.steps import Steps
from robotplan.hanging.bench.bench import PAPER_HANG
from robotplan.hanging.bench.reproduce import hang_representations

__all__ = ["ABLATIONS", "ANALYTIC", "FULL", "QUICK", "ReproduceSizes", "ledger_dir",
           "reproduce", "reproduce_status"]

PUSH_TRAINING = "robotplan.pushing.training"

# the paper's Fig. 11: the push program without H_coll, without H_PoC, without both
ABLATIONS = {"no_collision": {"with_collision": False}, "no_contact": {"with_contact": False},
             "dynamics_and_goal_only": {"with_collision": False, "with_contact": False}}
# the paper's Fig. 6: the analytic pushing model in place of the learned one (the kinematic
# program's quasi-static push is the plan)
ANALYTIC = {"learned_stage": False}


def _trained(steps: Steps, kind: str, key: str, cfg: dict, data: Path) -> str:
    """Train (or reuse) one ``kind`` model (``"rigid"``: F_q, ``"flow"``: F_flow) of
    representation ``key`` on ``data`` with the TrainConfig fields ``cfg``: the step's
    folder (under the output folder)."""
    from robotplan.pushing.training.rigid import train_rigid
    from robotplan.pushing.training.train import TrainConfig, train

    fit = train_rigid if kind == "rigid" else train
    spec = dict(cfg["spec"])
    encoder = f" --encoder {spec.pop('encoder')}" if "encoder" in spec else ""
    return steps.run(
        f"train_{kind}_{key}", cfg,
        lambda f: fit(TrainConfig(data=str(data), out=str(f / "model"), kind=kind, **cfg),
                      progress=False),
        f"robotplan train push --model {kind}{encoder} --data DATA --steps {cfg['steps']} "
        f"--warmup {cfg['warmup']}{spec_flags(spec)}",
        runs=(f"{PUSH_TRAINING}.{'rigid' if kind == 'rigid' else 'train'}",),
        **steps.uses(data))["folder"]


def _representations(steps: Steps, sizes: ReproduceSizes, train: Path,
                     sets: dict[str, Path]) -> tuple[dict[str, dict], dict[str, Path]]:
    """F_q trained alike on each of :data:`REPRESENTATIONS` (the shipped F_q's architecture,
    the same ``train`` data, seed and steps) and evaluated on each set: ``reps_<set>`` →
    key → the step result, and each key's model folder."""
    from robotplan.pushing.training.rigid_evaluation import evaluate_rigid

    n, per = sizes.representation_steps, sizes.per_scene
    results: dict[str, dict] = {f"reps_{name}": {} for name in sets}
    models: dict[str, Path] = {}
    for key, (_label, fields) in REPRESENTATIONS.items():
        cfg = {"steps": n, "warmup": min(500, n // 10), "val_every": n,
               "spec": {"encoder": "joint", **fields}}
        trained = _trained(steps, "rigid", key, cfg, train)
        model = models[key] = steps.out / trained / "model"
        for name, folder in sets.items():
            results[f"reps_{name}"][key] = steps.run(
                f"eval_rigid_{key}_{name}", {"per_scene": per},
                lambda f, m=model, d=folder: evaluate_rigid(m, d, per_scene=per),
                f"robotplan eval push --model MODEL --data DATA --per-scene {per}",
                runs=(f"{PUSH_TRAINING}.rigid_evaluation",), **steps.uses(model, folder))
    return results, models


def _flow_representations(steps: Steps, sizes: ReproduceSizes, data: Path, test: Path
                          ) -> dict[str, dict]:
    """Tab. 4: F_flow trained alike on the SDFs and on each occupancy measure (the same data,
    seed and steps), scored on the held-out set in what it reads (φ in mm, ψ × 1000): key →
    the evaluation step's result."""
    from robotplan.pushing.training.evaluation import evaluate_push

    n, per = sizes.flow_steps, sizes.per_scene
    results: dict[str, dict] = {}
    for key in FLOW_REPRESENTATIONS:
        cfg = {"steps": n, "warmup": min(500, n // 10), "val_every": n,
               "val_samples": min(128, n), "spec": dict(REPRESENTATIONS[key][1])}
        trained = _trained(steps, "flow", key, cfg, data)
        model = steps.out / trained / "model"
        results[key] = steps.run(
            f"eval_flow_{key}", {"per_scene": per},
            lambda f, m=model: evaluate_push(m, test, per_scene=per, progress=False),
            f"robotplan eval push --model MODEL --data DATA --per-scene {per}",
            runs=(f"{PUSH_TRAINING}.evaluation",), **steps.uses(model, test))
    return results


def ledger_dir(sizes: ReproduceSizes) -> Path:
    """Where the finished steps of a run at ``sizes`` are kept with the code:
    ``docs/reproduce/ledger/<sizes.name>/``."""
    return learned_dir("x").parents[1] / "docs" / "reproduce" / "ledger" / sizes.name


def reproduce(out: Path, sizes: ReproduceSizes = QUICK, workers: int = 2,
              ray: str | None = None, progress: bool = True,
              ledger: Path | None = None) -> Path:
    """Run (or reuse, from ``out`` or the ``ledger``) every item at ``sizes`` and write
    ``out/report.md`` and ``out/report.html``; returns the Markdown report's path.
    ``workers`` and ``ray`` as for ``data push`` and ``bench push``."""
    out.mkdir(parents=True, exist_ok=True)
    steps = Steps(out, progress, ledger)
    results = _run_steps(steps, sizes, workers, ray)
    if results["fig5"]:
        plot_contact_pushes_of(results["fig5"], out)
    for key in ("fig3", "fig8"):  # the box plots sit beside the report
        plot = out / results[key]["folder"] / "bench" / "coverage.png"
        if plot.is_file():
            shutil.copyfile(plot, out / f"{key}_coverage.png")
        elif results[key]["result"].get("rows"):  # a step kept in the ledger alone
            from robotplan.pushing.bench.push_summary import box_plot

            box_plot(results[key]["result"]["rows"], out / f"{key}_coverage.png", "auto")
    run = {"sizes": asdict(sizes), "workers": workers, "ray": ray, "steps": steps.log}
    write_atomically(out / "run.json", lambda tmp: tmp.write_text(json.dumps(run, indent=1)))
    md, _ = write_report(report_blocks(results, sizes, steps.log, out), out,
                         "robotplan: the paper reproduced")
    return md


def reproduce_status(out: Path, sizes: ReproduceSizes = QUICK, workers: int = 2,
                     ledger: Path | None = None) -> list[dict]:
    """Every step of a run at ``sizes`` without running any: its ``state`` (``done``,
    ``stale``, ``missing``; :class:`~robotplan.bench.steps.Steps`), the seconds it last took
    where the ledger knows them, else (``estimated``) those of the same step in another
    size's ledger scaled by its size (:func:`scaled_seconds`)."""
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


def scaled_seconds(name: str, params: dict, ledgers: list[Path]) -> float | None:
    """The seconds step ``name`` took in one of ``ledgers``, times the ratio of its first
    size parameter (:data:`SIZE_PARAMS`) here and there; None where no ledger has it."""
    for folder in ledgers:
        path = folder / f"{name}.json"
        if not path.is_file():
            continue
        entry = json.loads(path.read_text())
        there = entry.get("params", {})
        size = next((k for k in SIZE_PARAMS if k in params and there.get(k)), None)
        ratio = params[size] / there[size] if size else 1.0
        return float(entry["seconds"]) * ratio
    return None


ROW_FIELDS = ("scene", "shape", "family", "model", "status", "coverage", "open_loop_coverage")


def with_rows(summary: dict, bench: Path) -> dict:
    """A benchmark's summary with its scenes' outcomes (``ROW_FIELDS`` of ``rows.jsonl``):
    what the report draws and tabulates per scene, kept with the step's result."""
    lines = (bench / "rows.jsonl").read_text().splitlines()
    rows = [json.loads(line) for line in lines if line.strip()]
    return {**summary, "rows": [{k: r.get(k) for k in ROW_FIELDS} for r in rows]}


def plot_contact_pushes_of(fig5: dict, out: Path) -> None:
    """Fig. 5's picture from its steps' results."""
    from robotplan.pushing.bench.contact_push import plot_contact_pushes

    plot_contact_pushes({k: v["result"] for k, v in fig5.items()},
                        {k: REPRESENTATIONS[k][0] for k in fig5}, out / "fig5_contact_push.png")


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
    reps, rep_models = _representations(steps, sizes, train, {"test": test, "ood": ood})
    results.update(reps)
    results["tab4"] = _flow_representations(steps, sizes, train, test)
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
              loop: dict | None = None, rehearse: bool = True) -> dict:
        """``rehearse``: robotplan's open loop (the plan rehearsed in F_q), or the paper's
        (the plan as searched), for the baselines and ablations of the paper's protocol."""
        params = {"scenes": scenes, "seed": 0, "shapes": shapes,
                  "time_budget": sizes.time_budget, "workers": workers,
                  "program": program or {}, "rehearse": rehearse,
                  **({"loop": loop} if loop else {})}
        flags = "".join(f" --{kind} {k}={str(v).lower()}"
                        for kind, settings in (("program", program), ("loop", loop))
                        for k, v in (settings or {}).items())
        flags += "" if rehearse else " --no-rehearse"
        return steps.run(name, params, lambda f: with_rows(run_bench_push(
            scenes, 0, f / "bench", None, workers, tuple(shapes.split(",")),
            time_budget=sizes.time_budget, ray=ray, program=program, loop=loop,
            rehearse=rehearse), f / "bench"),
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
                                    replans, rehearse=False)
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
