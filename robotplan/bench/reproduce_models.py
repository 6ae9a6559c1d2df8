"""The steps of ``robotplan reproduce`` that train a push model per object representation
and score it: F_q for Tabs. 5 and 6 (and Fig. 5's pushes), F_flow for Tab. 4. Each model
is trained alike (the same data, steps and settings) once per training seed of the size."""

from __future__ import annotations

from pathlib import Path

from robotplan.bench.paper import FLOW_REPRESENTATIONS, REPRESENTATIONS, spec_flags
from robotplan.bench.reproduce_sizes import ReproduceSizes
from robotplan.bench.steps import Steps

__all__ = ["flow_representations", "rigid_representations", "seeded", "training_config"]

PUSH_TRAINING = "robotplan.pushing.training"
# TrainConfig fields a size may set for the representation models, and their flags
TRAINING_FLAGS = {"batch": "--batch", "lr": "--lr", "augment": "--augment"}


def seeded(name: str, seed: int) -> str:
    """A step's name for training seed ``seed``: the name itself for seed 0."""
    return name if seed == 0 else f"{name}_seed{seed}"


def training_config(steps: int, seed: int, spec: dict, training: tuple = (), **extra
                    ) -> dict:
    """The TrainConfig fields of one representation model (only those that differ from
    TrainConfig's defaults, so a step's key names what was chosen): ``training`` pairs of
    fields (``sizes.representation_training``), ``extra`` fields."""
    cfg = {"steps": steps, "warmup": min(500, steps // 10), "val_every": steps, **extra,
           **dict(training), "spec": spec}
    if seed:
        cfg["seed"] = seed
    return cfg


def _trained(steps: Steps, kind: str, key: str, cfg: dict, data: Path) -> Path:
    """Train (or reuse) one ``kind`` model (``"rigid"``: F_q, ``"flow"``: F_flow) of
    representation ``key`` on ``data`` with the TrainConfig fields ``cfg``: its folder."""
    from robotplan.pushing.training.rigid import train_rigid
    from robotplan.pushing.training.train import TrainConfig, train

    fit = train_rigid if kind == "rigid" else train
    spec = dict(cfg["spec"])
    flags = f" --encoder {spec.pop('encoder')}" if "encoder" in spec else ""
    flags += "".join(f" {flag} {cfg[k]}" for k, flag in TRAINING_FLAGS.items() if k in cfg)
    flags += f" --seed {cfg['seed']}" if "seed" in cfg else ""
    res = steps.run(
        seeded(f"train_{kind}_{key}", cfg.get("seed", 0)), cfg,
        lambda f: fit(TrainConfig(data=str(data), out=str(f / "model"), kind=kind,
                                  device=steps.device, **cfg), progress=False),
        f"robotplan train push --model {kind}{flags} --data DATA --steps {cfg['steps']} "
        f"--warmup {cfg['warmup']}{spec_flags(spec)}",
        runs=(f"{PUSH_TRAINING}.{'rigid' if kind == 'rigid' else 'train'}",),
        **steps.uses(data))
    return steps.out / res["folder"] / "model"


def rigid_representations(steps: Steps, sizes: ReproduceSizes, train: Path,
                          sets: dict[str, Path]) -> tuple[dict[str, dict], dict[str, Path]]:
    """F_q trained alike on each of :data:`REPRESENTATIONS` (the shipped F_q's architecture,
    ``sizes.representation_training``) once per seed of ``sizes.training_seeds``, evaluated
    on each set: ``reps_<set>`` → key → the evaluation steps' results, one per seed; and
    each key's first seed's model folder."""
    from robotplan.pushing.training.rigid_evaluation import evaluate_rigid

    n, per = sizes.representation_steps, sizes.per_scene
    results: dict[str, dict] = {f"reps_{name}": {} for name in sets}
    models: dict[str, Path] = {}
    for key, (_label, fields) in REPRESENTATIONS.items():
        for seed in sizes.training_seeds:
            cfg = training_config(n, seed, {"encoder": "joint", **fields},
                                  sizes.representation_training)
            model = _trained(steps, "rigid", key, cfg, train)
            models.setdefault(key, model)
            for name, folder in sets.items():
                results[f"reps_{name}"].setdefault(key, []).append(steps.run(
                    seeded(f"eval_rigid_{key}_{name}", seed), {"per_scene": per},
                    lambda f, m=model, d=folder: evaluate_rigid(m, d, per_scene=per),
                    f"robotplan eval push --model MODEL --data DATA --per-scene {per}",
                    runs=(f"{PUSH_TRAINING}.rigid_evaluation",), **steps.uses(model, folder)))
    return results, models


def flow_representations(steps: Steps, sizes: ReproduceSizes, data: Path, test: Path
                         ) -> dict[str, list[dict]]:
    """Tab. 4: F_flow trained alike on the SDFs and on each occupancy measure once per seed
    of ``sizes.training_seeds``, scored on the held-out set in what it reads (φ in mm,
    ψ × 1000): key → the evaluation steps' results, one per seed."""
    from robotplan.pushing.training.evaluation import evaluate_push

    n, per = sizes.flow_steps, sizes.per_scene
    results: dict[str, list[dict]] = {}
    for key in FLOW_REPRESENTATIONS:
        for seed in sizes.training_seeds:
            cfg = training_config(n, seed, dict(REPRESENTATIONS[key][1]),
                                  val_samples=min(128, n))
            model = _trained(steps, "flow", key, cfg, data)
            results.setdefault(key, []).append(steps.run(
                seeded(f"eval_flow_{key}", seed), {"per_scene": per},
                lambda f, m=model: evaluate_push(m, test, per_scene=per, progress=False),
                f"robotplan eval push --model MODEL --data DATA --per-scene {per}",
                runs=(f"{PUSH_TRAINING}.evaluation",), **steps.uses(model, test)))
    return results
