"""``robotplan bench plan``: the push scenes of ``bench push`` planned and profiled."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from robotplan.cli.common import (
    EXIT_BAD_INPUT,
    add_dynamics_options,
    add_program_option,
    model_folder,
    not_a_model,
    program_overrides,
)

__all__ = ["add_bench_plan_parser", "cmd_bench_plan"]

SHAPES = ("box", "lshape", "ood", "pose", "mesh")


def add_bench_plan_parser(bsub) -> None:
    """``bench plan`` under the ``bench`` subparsers ``bsub``."""
    bp = bsub.add_parser("plan", help="plan the random push scenes without executing them: "
                         "time per stage, row and solver; why each failed program failed")
    bp.add_argument("--scenes", type=int, default=20, help="scenes per shape type")
    bp.add_argument("--seed", type=int, default=0)
    bp.add_argument("--out", required=True, metavar="DIR",
                    help="scenes, rows.jsonl per scene (continues a partial run), summary.json")
    add_dynamics_options(bp)
    bp.add_argument("--shapes", default="box,lshape",
                    help=f"comma-separated: {', '.join(SHAPES)} (as bench push)")
    bp.add_argument("--workers", type=int, default=2)
    bp.add_argument("--time-budget", type=float, default=None, metavar="S",
                    help="per scene: start no program after S seconds (best so far wins)")
    bp.add_argument("--overwrite", action="store_true")
    bp.add_argument("--json", action="store_true")
    add_program_option(bp)
    bp.set_defaults(run=cmd_bench_plan)


def cmd_bench_plan(args: argparse.Namespace) -> int:
    from robotplan.pushing.bench.plan_profile import run_bench_plan
    from robotplan.pushing.bench.push_summary import time_profile_line

    program = program_overrides(args)
    if program is None:
        return EXIT_BAD_INPUT
    model = model_folder(args)
    if not_a_model(model):
        return EXIT_BAD_INPUT
    shapes = tuple(args.shapes.split(","))
    bad = sorted(set(shapes) - set(SHAPES))
    problem = ("--scenes: must be at least 1" if args.scenes < 1
               else "--workers: must be at least 1" if args.workers < 1
               else f"--shapes: unknown shape type {bad[0]!r} ({', '.join(SHAPES)})" if bad
               else None)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    out = Path(args.out)
    if (out / "summary.json").exists() and not args.overwrite:
        print(f"error: {out}: --out: holds a finished profile; pass --overwrite to redo it",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.overwrite:
        for name in ("summary.json", "rows.jsonl"):
            (out / name).unlink(missing_ok=True)
    search = {"workers": args.workers, "time_budget": args.time_budget, "program": program}
    summary = run_bench_plan(args.scenes, args.seed, out, model, shapes, search)
    if args.json:
        print(json.dumps(summary))
        return 0
    for kind, s in summary["by_shape"].items():
        t, n = s["plan_seconds"], s["programs"]
        print(f"{kind:>7}: plan time median {t['median']:.1f} s (quartiles {t['q1']:.1f}–"
              f"{t['q3']:.1f}, max {t['max']:.1f}); {s['unsolved_searches']} of {t['n']} "
              f"searches without a solved plan; programs per search median {n['median']:.0f};"
              f" {s['failed_programs']} failed programs took {s['failed_seconds']:.0f} of "
              f"{s['program_seconds']:.0f} s")
    failed = summary["failed"]
    if failed["programs"]:
        rows = ", ".join(f"{name} ×{v['programs']} (median {v['median']:.3g})"
                         for name, v in list(failed["violated_rows"].items())[:5])
        print(f"failed programs: SNOPT exit {failed['snopt_info']}, stage {failed['stage']}; "
              f"rows left violated: {rows or 'none'}")
    line = time_profile_line(summary["time_profile"], top=8)
    if line:
        print(line)
    print(f"wrote {out / 'summary.json'}, {out / 'rows.jsonl'}")
    return 0
