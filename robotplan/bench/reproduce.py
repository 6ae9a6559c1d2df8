"""``robotplan reproduce``: the paper's tables and figures from our code, beside its numbers.

Each item is a step (data, training, evaluation, benchmark: :mod:`robotplan.bench.steps`),
kept and reused while its inputs do not change. The report (``OUT/report.md``,
``OUT/report.html``) is written from the step results.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import asdict, dataclass
from pathlib import Path

from robotplan.base.files import write_atomically
from robotplan.base.resources import DYNAMICS_FOLDERS, OBJECT_FRAME_FOLDERS, learned_dir
from robotplan.bench.paper import FLOW_REPRESENTATIONS, REPRESENTATIONS, spec_flags
from robotplan.bench.report import write_report
from robotplan.bench.reproduce_report import report_blocks
from robotplan.bench.steps import Steps, inputs_digest
from robotplan.hanging.bench.bench import METHODS, PAPER_HANG
from robotplan.hanging.bench.reproduce import HANG_REPRESENTATIONS, hang_representations

__all__ = ["ABLATIONS", "ANALYTIC", "FULL", "QUICK", "ReproduceSizes", "inputs_digest", "reproduce"]

# the paper's Fig. 11: the push program without H_coll, without H_PoC, without both
ABLATIONS = {"no_collision": {"with_collision": False}, "no_contact": {"with_contact": False},
             "dynamics_and_goal_only": {"with_collision": False, "with_contact": False}}
# the paper's Fig. 6: the analytic pushing model in place of the learned one (the kinematic
# program's quasi-static push is the plan)
ANALYTIC = {"learned_stage": False}


@dataclass(frozen=True)
class ReproduceSizes:
    """How much of each item runs (``QUICK``: small sets within 30 min on 2 cores)."""

    name: str
    test_scenes: int  # held-out push scenes (seed 2) for Tabs. 2 and 5
    ood_scenes: int  # unseen-footprint scenes (seed 3) for Tab. 6
    per_scene: int  # samples per held-out scene
    pose_fit: int  # contact samples F_flow's step is fitted on (Tab. 5 terms)
    push_scenes: int  # benchmark scenes per shape (Fig. 3; the paper: 50)
    ood_push_scenes: int  # unseen-footprint benchmark scenes (Fig. 8; scene i: family i mod 8)
    ablation_scenes: int  # box scenes per ablation (Fig. 11; the paper: 20)
    hang_scenes: int  # mug-and-hook scenes (Tab. 3; the paper: 150)
    hang_methods: tuple[str, ...]
    time_budget: float  # per push scene: no program starts after this many seconds
    representation_scenes: int  # push training scenes (seed 4) of the representation rows
    representation_steps: int  # F_q's training steps per representation (batch 32)
    contact_push: tuple[str, ...]  # the representations' F_q planned from contact (Fig. 5)
    flow_steps: int  # F_flow's training steps per representation (Tab. 4; batch 32)
    # Tab. 3's representation rows: H_hang trained alike on each of these keys of
    # HANG_REPRESENTATIONS
    hang_representations: tuple[str, ...]
    hang_train_scenes: int  # hanging data scenes (seed 0; the paper: 1,600)
    hang_test_scenes: int  # held-out hanging scenes each is scored on (seed 1)
    hang_train_steps: int  # training steps per representation (batch 32)
    hang_representation_scenes: int  # mug scenes each is planned with (seed 2)
    hang_representation_methods: tuple[str, ...]
    hang_evaluations: int  # functional evaluations per method and scene (the paper: 20,000)
    hang_every_collision_row: bool  # each representation's other collision rows too
    # re-plans of the ablation's closed loops (None: the scene class's): re-planning plans
    # through the object dominates a quick run's time (docs/experiments.md#reproduce-quick)
    ablation_replans: int | None = None


# one scene per shape: the next scenes' searches alone took 9 of a 45-minute quick run
# (measured: docs/experiments.md#reproduce-quick)
QUICK = ReproduceSizes("quick", test_scenes=40, ood_scenes=40, per_scene=10, pose_fit=20,
                       push_scenes=1, ood_push_scenes=4, ablation_scenes=1, hang_scenes=2,
                       hang_methods=("opt_sampling", "opt_only"), time_budget=30.0,
                       representation_scenes=600, representation_steps=250,
                       contact_push=("sdf", "occupancy", "pointnet"), flow_steps=100,
                       hang_representations=("sdf", "occupancy", "pointnet"),
                       hang_train_scenes=24, hang_test_scenes=8, hang_train_steps=100,
                       hang_representation_scenes=1,
                       hang_representation_methods=("opt_sampling", "sampling_k1"),
                       hang_evaluations=1_000, hang_every_collision_row=False,
                       ablation_replans=2)
FULL = ReproduceSizes("full", test_scenes=300, ood_scenes=300, per_scene=10, pose_fit=100,
                      push_scenes=50, ood_push_scenes=24, ablation_scenes=20,
                      hang_scenes=150,
                      hang_methods=METHODS, time_budget=100.0,
                      representation_scenes=15_000, representation_steps=20_000,
                      contact_push=tuple(REPRESENTATIONS),
                      flow_steps=20_000, hang_representations=tuple(HANG_REPRESENTATIONS),
                      hang_train_scenes=1_600, hang_test_scenes=400,
                      hang_train_steps=20_000,
                      hang_representation_scenes=150, hang_representation_methods=METHODS,
                      hang_evaluations=20_000, hang_every_collision_row=True)


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
        f"train_{kind}_{key}", {**cfg, "data": data.parent.name},
        lambda f: fit(TrainConfig(data=str(data), out=str(f / "model"), kind=kind, **cfg),
                      progress=False),
        f"robotplan train push --model {kind}{encoder} --data DATA --steps {cfg['steps']} "
        f"--warmup {cfg['warmup']}{spec_flags(spec)}")["folder"]


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
                f"eval_rigid_{key}_{name}", {"per_scene": per, "data": folder.parent.name,
                                             "model": trained},
                lambda f, m=model, d=folder: evaluate_rigid(m, d, per_scene=per),
                f"robotplan eval push --model MODEL --data DATA --per-scene {per}")
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
            f"eval_flow_{key}", {"per_scene": per, "data": test.parent.name,
                                 "model": trained},
            lambda f, m=model: evaluate_push(m, test, per_scene=per, progress=False),
            f"robotplan eval push --model MODEL --data DATA --per-scene {per}")
    return results


def reproduce(out: Path, sizes: ReproduceSizes = QUICK, workers: int = 2,
              ray: str | None = None, progress: bool = True) -> Path:
    """Run (or reuse) every item at ``sizes`` and write ``out/report.md`` and
    ``out/report.html``; returns the Markdown report's path. ``workers`` and ``ray`` as for
    ``data push`` and ``bench push``."""
    from robotplan.hanging.bench.bench import run_bench_hang
    from robotplan.pushing.bench.contact_push import plan_from_contact, plot_contact_pushes
    from robotplan.pushing.bench.push import run_bench_push
    from robotplan.pushing.training.evaluation import evaluate_push
    from robotplan.pushing.training.pose_fit import evaluate_pose_fit
    from robotplan.pushing.training.push_data import PushDataSpec, generate
    from robotplan.pushing.training.rigid_evaluation import evaluate_rigid

    out.mkdir(parents=True, exist_ok=True)
    steps = Steps(out, inputs_digest(), progress)
    models = {kind: learned_dir(folder) for kind, folder in DYNAMICS_FOLDERS.items()}

    def data(name: str, scenes: int, seed: int, shapes: str) -> Path:
        params = {"scenes": scenes, "seed": seed, "shapes": shapes}
        res = steps.run(name, params, lambda f: generate(
            f / "data", scenes, seed, workers=workers, spec=PushDataSpec(shapes=shapes),
            progress=False, ray=ray),
            f"robotplan data push --scenes {scenes} --seed {seed} --shapes {shapes}")
        return out / res["folder"] / "data"

    test = data("data_test", sizes.test_scenes, 2, "train")
    ood = data("data_ood", sizes.ood_scenes, 3, "ood")
    results: dict[str, dict] = {}
    per = sizes.per_scene
    for set_name, folder in (("test", test), ("ood", ood)):
        for kind in ("flow", "direct"):
            results[f"rmse_{kind}_{set_name}"] = steps.run(
                f"eval_{kind}_{set_name}", {"per_scene": per, "data": folder.parent.name},
                lambda f, k=kind, d=folder: evaluate_push(models[k], d, per_scene=per,
                                                          progress=False),
                f"robotplan eval push --model learned/push_{kind} --data DATA --per-scene {per}")
            framed = learned_dir(OBJECT_FRAME_FOLDERS[kind])
            if (framed / "spec.json").is_file():
                results[f"rmse_{kind}_object_{set_name}"] = steps.run(
                    f"eval_{kind}_object_{set_name}",
                    {"per_scene": per, "data": folder.parent.name},
                    lambda f, m=framed, d=folder: evaluate_push(m, d, per_scene=per,
                                                                progress=False),
                    f"robotplan eval push --model learned/{framed.name} --data DATA "
                    f"--per-scene {per}")
        results[f"rigid_{set_name}"] = steps.run(
            f"eval_rigid_{set_name}", {"per_scene": per, "data": folder.parent.name},
            lambda f, d=folder: evaluate_rigid(models["rigid"], d, per_scene=per),
            f"robotplan eval push --model learned/push_rigid --data DATA --per-scene {per}")
    train = data("data_train_representations", sizes.representation_scenes, 4, "train")
    reps, rep_models = _representations(steps, sizes, train, {"test": test, "ood": ood})
    results.update(reps)
    results["tab4"] = _flow_representations(steps, sizes, train, test)
    results["fig5"] = {key: steps.run(
        f"contact_push_{key}", {"model": str(rep_models[key].relative_to(out))},
        lambda f, m=rep_models[key]: plan_from_contact(m),
        "robotplan bench contact-push --model MODEL") for key in sizes.contact_push}
    results["pose_fit_flow"] = steps.run(
        "pose_fit_flow", {"samples": sizes.pose_fit, "data": test.parent.name},
        lambda f: evaluate_pose_fit(models["flow"], test, samples=sizes.pose_fit,
                                    progress=False),
        f"robotplan eval push --model learned/push_flow --data DATA --pose-fit {sizes.pose_fit}")

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
        return steps.run(name, params, lambda f: run_bench_push(
            scenes, 0, f / "bench", None, workers, tuple(shapes.split(",")),
            time_budget=sizes.time_budget, ray=ray, program=program, loop=loop,
            rehearse=rehearse),
            f"robotplan bench push --scenes {scenes} --seed 0 --shapes {shapes} "
            f"--time-budget {sizes.time_budget:g} --workers {workers}{flags}")

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
        "--check none --no-threading")
    results["tab3_representations"] = hang_representations(steps, sizes, workers, ray)
    if results["fig5"]:
        plot_contact_pushes({k: v["result"] for k, v in results["fig5"].items()},
                            {k: REPRESENTATIONS[k][0] for k in results["fig5"]},
                            out / "fig5_contact_push.png")
    for key in ("fig3", "fig8"):  # the box plots sit beside the report
        plot = out / results[key]["folder"] / "bench" / "coverage.png"
        if plot.is_file():
            shutil.copyfile(plot, out / f"{key}_coverage.png")
    run = {"sizes": asdict(sizes), "workers": workers, "ray": ray, "steps": steps.log,
           "inputs_sha256": steps.digest}
    write_atomically(out / "run.json", lambda tmp: tmp.write_text(json.dumps(run, indent=1)))
    md, _ = write_report(report_blocks(results, sizes, steps.log, out), out,
                         "robotplan: the paper reproduced")
    return md
