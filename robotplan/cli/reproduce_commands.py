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
                    help="report.md, report.html and every step's result (kept and reused "
                         "while the code and models are unchanged)")
    rp.add_argument("--quick", action="store_true",
                    help="small sets, within 30 minutes on 2 cores (the report says so)")
    rp.add_argument("--workers", type=int, default=2)
    add_ray_option(rp)
    rp.set_defaults(run=cmd_reproduce)


def cmd_reproduce(args: argparse.Namespace) -> int:
    from robotplan.bench.reproduce import FULL, QUICK, reproduce

    out = Path(args.out)
    if out.exists() and any(out.iterdir()) and not (out / "run.json").is_file():
        print(f"error: {out}: --out: a folder with other files in it (reproduce keeps its "
              "steps in a folder of its own and reuses them)", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.workers < 1:
        print("error: --workers must be ≥ 1", file=sys.stderr)
        return EXIT_BAD_INPUT
    report = reproduce(out, QUICK if args.quick else FULL, workers=args.workers, ray=args.ray)
    print(f"report: {report} (and {report.with_suffix('.html')})")
    return 0
