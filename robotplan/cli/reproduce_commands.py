"""``robotplan reproduce``: every table and figure of the paper that robotplan runs, beside
the paper's numbers, in one report."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from robotplan.cli.common import EXIT_BAD_INPUT, add_ray_option

__all__ = ["add_reproduce_parser", "cmd_reproduce"]


def add_reproduce_parser(sub) -> None:
    """``robotplan reproduce`` under the command line's subparsers ``sub``."""
    rp = sub.add_parser("reproduce", help="the paper's tables and figures beside its numbers: "
                        "data, evaluations and benchmarks run (or reused) and one report")
    rp.add_argument("--out", required=True, metavar="DIR",
                    help="the report (report.md and .html; quick.md at --quick) and every "
                         "step's result and outputs (kept "
                         "and reused while what the step reads is unchanged)")
    rp.add_argument("--size", choices=["quick", "standard", "full"], default="full",
                    help="how much runs: quick (small sets, within 30 minutes on 2 cores), "
                         "standard (the tables at a size that says something on this CPU) "
                         "or full (the paper's; default)")
    rp.add_argument("--quick", action="store_true", help="the same as --size quick")
    rp.add_argument("--ledger", default=None, metavar="DIR|none",
                    help="finished steps' results kept with the code and reused from there "
                         "(default docs/reproduce/ledger/SIZE; none: only --out's)")
    rp.add_argument("--status", action="store_true",
                    help="run nothing: list each step as done, stale (something it reads "
                         "changed), missing or running (in another run on --out), with the "
                         "seconds it last took")
    rp.add_argument("--steps", default="", metavar="PATTERN[,PATTERN]",
                    help="run only the steps whose names match (shell patterns, e.g. "
                         "'bench_*'); the others are reused where done, else left for a later "
                         "run, and the report waits until every step is done; runs on other "
                         "steps may share --out side by side (see --threads)")
    rp.add_argument("--hours", type=float, default=None, metavar="H",
                    help="start no step after H hours: a long run in parts, each part's "
                         "finished steps kept in the ledger")
    rp.add_argument("--workers", type=int, default=2)
    rp.add_argument("--threads", type=int, default=None, metavar="N",
                    help="torch threads of this run's training steps (default: torch's, one a "
                         "core); runs side by side on one machine: the cores shared out, e.g. "
                         "--threads 1 each on two cores")
    rp.add_argument("--device", choices=("cpu", "cuda"), default="cpu",
                    help="where the training steps run their networks (default cpu); a step "
                         "made on either is reused on the other")
    add_ray_option(rp)
    rp.set_defaults(run=cmd_reproduce)


def cmd_reproduce(args: argparse.Namespace) -> int:
    from robotplan.bench.reproduce import ledger_dir, reproduce, reproduce_status, step_filter
    from robotplan.bench.reproduce_sizes import SIZES

    out = Path(args.out)
    if out.exists() and any(out.iterdir()) and not (out / "run.json").is_file() and not (
            out / "steps").is_dir():
        print(f"error: {out}: --out: a folder with other files in it (reproduce keeps its "
              "steps in a folder of its own and reuses them)", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.workers < 1:
        print("error: --workers must be ≥ 1", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.hours is not None and args.hours <= 0:
        print("error: --hours must be > 0", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.threads is not None and args.threads < 1:
        print("error: --threads must be ≥ 1", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.device == "cuda" and not args.status:
        import torch

        if not torch.cuda.is_available():
            print("error: --device cuda: this torch sees no CUDA device", file=sys.stderr)
            return EXIT_BAD_INPUT
    sizes = SIZES["quick" if args.quick else args.size]
    ledger = (None if args.ledger == "none"
              else Path(args.ledger) if args.ledger else ledger_dir(sizes))
    if args.status:
        log = reproduce_status(out, sizes, args.workers, ledger)
        for step in log:
            seconds = ("" if step["seconds"] is None else
                       f" ({'~' if step.get('estimated') else ''}{step['seconds']:.0f} s)")
            print(f"{step['state']:>8}  {step['name']}{seconds}")
        todo = [s for s in log if s["state"] != "done"]
        known = sum(s["seconds"] or 0.0 for s in todo)
        unknown = sum(s["seconds"] is None for s in todo)
        print(f"{sizes.name}: {len(log) - len(todo)} of {len(log)} steps done; to run: "
              f"{len(todo)}, {known / 3600:.1f} CPU hours as last measured or scaled (~)"
              + (f", {unknown} never run" if unknown else ""))
        return 0
    if args.threads is not None:
        import torch

        torch.set_num_threads(args.threads)
    patterns = tuple(p for p in args.steps.split(",") if p)
    report = reproduce(out, sizes, workers=args.workers, ray=args.ray, ledger=ledger,
                       allow=step_filter(patterns, args.hours), device=args.device)
    if report is None:
        print(f"{sizes.name}: steps left for a later run (`robotplan reproduce --out {out} "
              f"--size {sizes.name} --status` lists them); finished steps are in "
              f"{ledger or out}")
        return 0
    print(f"report: {report} (and {report.with_suffix('.html')})")
    return 0
