"""What every command shares: exit statuses, printing, argument checks."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from robotplan.base.resources import DYNAMICS_FOLDERS, learned_dir

__all__ = [
    "EXIT_BAD_INPUT",
    "SOLVE_EXIT",
    "add_data_options",
    "add_dynamics_options",
    "add_ray_option",
    "device_name",
    "load_footprint_scene",
    "model_folder",
    "not_a_model",
    "positive_ints",
    "print_result",
    "training_folders_problem",
]


EXIT_BAD_INPUT = 2
# ``solve``'s exit status per result status: 0 the plan is solved and (executed) reached the
# goal; 3 the goal was reached although the plan misses a constraint; 1 the goal was not
# reached or nothing was planned; 2 (EXIT_BAD_INPUT) bad input
SOLVE_EXIT = {"solved": 0, "reached": 3, "missed": 1, "no_solution": 1}


def load_footprint_scene(path: str, command: str):
    """A scene for a command that works on footprints (table-top SDFs on X_h); a hang scene is
    refused with SceneError naming the goal (exit 2 through ``main``)."""
    from robotplan.scene import SceneError, load_scene
    from robotplan.scene.task import family_of

    scene = load_scene(path)
    if family_of(scene) == "hang":
        raise SceneError(path, "goal", f"{command} works on table-top footprints; the mug and "
                         "hook of a hang scene are 3D (robotplan solve plans it and writes its "
                         "playback)")
    return scene


def training_folders_problem(data: str, out: str, resume: bool, overwrite: bool) -> str | None:
    """What is wrong with a training run's folders, in one line, or None."""
    if not Path(data).is_dir():
        return f"{data}: --data: no such folder"
    ckpt = Path(out) / "checkpoint.pt"
    if resume and not ckpt.is_file():
        return f"{ckpt}: --resume: no checkpoint to resume from"
    if not resume and Path(out).exists() and any(Path(out).iterdir()) and not overwrite:
        return f"{out}: --out: the folder is not empty; --resume it or pass --overwrite"
    return None


def print_result(result: dict, as_json: bool) -> None:
    """One JSON object (``--json``), or aligned ``key: value`` lines for a person."""
    if as_json:
        print(json.dumps(result))
        return
    width = max(map(len, result), default=0)
    for k, v in result.items():
        print(f"{k:>{width}}: {v}")


def model_folder_problem(folder: str, flag: str = "--model") -> str | None:
    """What is wrong with a model folder given by ``flag``, in one line, or None."""
    if (Path(folder) / "spec.json").is_file():
        return None
    return f"{folder}: {flag}: not a model folder (no spec.json)"


def not_a_model(folder: str | None) -> bool:
    """True (after the one-line error) when ``--model`` is not a model folder."""
    problem = None if folder is None else model_folder_problem(folder)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
    return problem is not None


def add_dynamics_options(parser, several: bool = False) -> None:
    """Which learned dynamics a plan uses: a shipped kind, or a model folder; ``several``:
    a comma-separated list of kinds may be given (checked by the command)."""
    kinds = ["auto", *sorted(DYNAMICS_FOLDERS)]
    parser.add_argument("--dynamics", choices=None if several else kinds, default="auto",
                        help="the shipped learned dynamics to plan with: flow (F_flow, "
                        "H_F), rigid (F_q, its rigid step), direct (F, H_F); default auto: "
                        "the one measured best for the scene's class "
                        "(skeletons/dynamics.yaml)"
                        + ("; several, e.g. flow,rigid,direct: each on the same scenes, "
                           "side by side" if several else ""))
    parser.add_argument("--model", default=None, metavar="DIR",
                        help="a model folder of any kind instead (overrides --dynamics)")


def model_folder(args) -> str | None:
    """The folder of ``--model``, else of the shipped ``--dynamics`` kind; None for
    ``auto`` (each scene's default)."""
    if args.model:
        return args.model
    return None if args.dynamics == "auto" else str(learned_dir(DYNAMICS_FOLDERS[args.dynamics]))


def add_ray_option(parser) -> None:
    """``--ray``: run the command's units (shards, scenes) as Ray tasks."""
    parser.add_argument("--ray", default=None, metavar="ADDRESS",
                        help="run the units (data shards, benchmark scenes) as Ray tasks: "
                             "'local' starts Ray on this machine, 'auto' or HOST:PORT joins a "
                             "running cluster (needs the ray package); where and how long "
                             "they ran is kept apart from the results")


def positive_ints(text: str) -> tuple[int, ...]:
    """An argparse type: ``"8,16,16"`` → ``(8, 16, 16)``, every item a positive integer."""
    import argparse

    try:
        values = tuple(int(v) for v in text.split(","))
    except ValueError:
        values = ()
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: expected positive integers separated "
                                         "by commas, e.g. 8,16,16")
    return values


def device_name(name: str) -> str:
    """``--device``: ``auto`` is the GPU when torch sees one, else the CPU."""
    import torch

    if name == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    return name


def add_execution_options(parser) -> None:
    """How a plan is executed: closed loop (default) or the paper's open loop, in the
    nominal world or a perturbed one."""
    parser.add_argument("--open-loop", action="store_true",
                        help="execute the plan as it is, without re-planning (the paper's "
                        "protocol); default: closed loop, re-planning from the observed scene "
                        "(a hang scene: the search goes on while the mug falls from the "
                        "poses it finds)")
    parser.add_argument("--perturb", type=int, nargs="?", const=0, default=None,
                        metavar="SEED", help="execute in a perturbed world: friction and "
                        "mass ±20 %%, observation noise 1 mm / 0.5°, drawn from SEED "
                        "(default 0)")
    add_sim_option(parser)
    add_loop_option(parser)
    add_rehearse_option(parser)


def add_sim_option(parser, several: bool = False, role: str = "executes the plan") -> None:
    """``--sim``: the simulator that does ``role`` (``several``: a comma-separated list,
    each executing the same plans)."""
    from robotplan.execution.physics import SIMULATORS

    names = ", ".join(SIMULATORS)
    parser.add_argument("--sim", default="pybullet", metavar="NAMES" if several else "NAME",
                        help=(f"comma-separated simulators, each executing the same plans "
                              f"({names}; default pybullet)" if several else
                              f"the simulator that {role} ({names}; default pybullet)"))


def simulators(value: str) -> list[str] | None:
    """The simulators of ``--sim`` (a comma-separated list), or None after printing why
    they are not."""
    from robotplan.execution.physics import simulator_problem

    names = [v.strip() for v in value.split(",") if v.strip()]
    problem = simulator_problem(names) if names else "no simulator given"
    if problem is not None:
        print(f"error: --sim: {problem}", file=sys.stderr)
        return None
    return names


def add_rehearse_option(parser) -> None:
    """``--no-rehearse``: run F_q's plan open loop as the search left it."""
    parser.add_argument("--no-rehearse", action="store_true",
                        help="open loop: run the plan as the search left it (the paper's "
                        "protocol); default with F_q, one pusher, one object, no "
                        "obstacles and a region goal: the pusher's states of the plan "
                        "rehearsed closed loop in F_q")


def add_loop_option(parser) -> None:
    """``--loop NAME=VALUE``: closed-loop settings in place of the scene class's."""
    parser.add_argument("--loop", action="append", default=[], metavar="NAME=VALUE",
                        help="a closed-loop setting in place of the scene class's (a field "
                        "of LoopSettings, e.g. last_resort_violation=0.03; repeatable)")


def loop_overrides(args) -> dict | None:
    """The ``--loop`` settings as LoopSettings fields; None after printing one line on a
    bad item (the caller exits with status 2)."""
    from robotplan.pushing.execution.loop_settings import parse_loop_overrides

    try:
        return parse_loop_overrides(args.loop)
    except ValueError as err:
        print(f"error: --loop: {err}", file=sys.stderr)
        return None


def add_program_option(parser) -> None:
    """``--program NAME=VALUE``: program settings in place of the scene class's."""
    parser.add_argument("--program", action="append", default=[], metavar="NAME=VALUE",
                        help="a program setting in place of the scene class's (a field of "
                        "ProgramSettings, e.g. with_contact=false for the paper's ablation "
                        "without H_PoC, or a row's constant ROW.NAME of skeletons/rows.yaml, "
                        "e.g. goal.tol=0.01; repeatable; re-plans keep it)")


def program_overrides(args) -> dict | None:
    """The ``--program`` settings (ProgramSettings fields, rows' ROW.NAME); None after
    printing one line on a bad item (the caller exits with status 2)."""
    from robotplan.pushing.program.settings import parse_program_overrides

    try:
        return parse_program_overrides(args.program)
    except ValueError as err:
        print(f"error: --program: {err}", file=sys.stderr)
        return None


def perturbation(seed: int | None):
    """The perturbed world of ``--perturb SEED`` (None without it)."""
    if seed is None:
        return None
    from robotplan.pushing.execution.perturb import Perturbation

    return Perturbation(seed)


def add_data_options(parser: argparse.ArgumentParser, shard_size: int) -> None:
    """What every ``data`` command takes: a sharded, resumable, seeded folder."""
    parser.add_argument("--scenes", type=int, required=True)
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--out", required=True, metavar="DIR")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--shard-size", type=int, default=shard_size)
    add_ray_option(parser)
