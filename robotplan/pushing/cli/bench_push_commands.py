"""``robotplan bench push``: its checks of the options, the run and the printed summary."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from robotplan.base.resources import DYNAMICS_FOLDERS
from robotplan.cli.common import (
    EXIT_BAD_INPUT,
    loop_overrides,
    model_folder,
    not_a_model,
    program_overrides,
    simulators,
)
from robotplan.pushing.cli.plan_commands import SHAPES

__all__ = ["cmd_bench_push", "dynamics_list_problem"]


def dynamics_list_problem(kinds: list[str], model: str | None) -> str | None:
    """What is wrong with ``--dynamics`` given as ``kinds`` (None: nothing)."""
    known = ["auto", *sorted(DYNAMICS_FOLDERS)]
    bad = next((k for k in kinds if k not in known), None)
    if bad is not None:
        return f"{bad!r} is not one of {', '.join(known)}"
    if len(kinds) > 1 and ("auto" in kinds or model):
        return "a list names shipped kinds only (flow, rigid, direct), without auto or --model"
    return None


def cmd_bench_push(args: argparse.Namespace) -> int:
    from robotplan.pushing.bench.push import run_bench_push
    from robotplan.pushing.bench.push_summary import time_profile_line

    kinds = args.dynamics.split(",")
    problem = dynamics_list_problem(kinds, args.model)
    if problem:
        print(f"error: --dynamics: {problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    args.loop, args.program = loop_overrides(args), program_overrides(args)
    sims = simulators(args.sim)
    if args.loop is None or args.program is None or sims is None:
        return EXIT_BAD_INPUT
    if len(kinds) > 1 and sims != ["pybullet"]:
        print("error: --sim: several --dynamics are compared in pybullet alone",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    if len(kinds) == 1:
        args.model = model_folder(args)
    if not_a_model(args.model):
        return EXIT_BAD_INPUT
    if args.scenes < 1:
        print("error: --scenes: must be at least 1", file=sys.stderr)
        return EXIT_BAD_INPUT
    bad = set(args.shapes.split(",")) - set(SHAPES)
    if bad:
        print(f"error: --shapes: unknown shape type {sorted(bad)[0]!r} "
              f"({', '.join(SHAPES)})", file=sys.stderr)
        return EXIT_BAD_INPUT
    candidate_kinds = None
    if args.candidates is not None:
        from robotplan.pushing.search.tiers import load_tiers

        candidate_kinds = tuple(k for k in args.candidates.split(",") if k)
        known = sorted({t.candidates for t in load_tiers()})
        bad = sorted(set(candidate_kinds) - set(known))
        if bad or not candidate_kinds:
            print(f"error: --candidates: {bad[0] if bad else 'none given'!r} is not a kind "
                  f"of candidates ({', '.join(known)})", file=sys.stderr)
            return EXIT_BAD_INPUT
    out = Path(args.out)
    if len(kinds) > 1:
        if candidate_kinds is not None:
            print("error: --candidates: several --dynamics are compared with every kind",
                  file=sys.stderr)
            return EXIT_BAD_INPUT
        return _bench_compare(args, kinds, out)
    summary_path = out / "summary.json"
    if summary_path.exists() and not args.overwrite:
        print(f"error: {out}: --out: holds a finished benchmark; pass --overwrite to redo it",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.overwrite and out.exists():
        for name in ("summary.json", "rows.jsonl", "results.csv", "coverage.png",
                     *(f"coverage_{sim}.png" for sim in sims)):
            (out / name).unlink(missing_ok=True)
    summary = run_bench_push(args.scenes, args.seed, out, args.model, args.workers,
                             tuple(args.shapes.split(",")), args.exhaustive, args.time_budget,
                             args.perturb, args.loop, args.ray, args.program,
                             rehearse=not args.no_rehearse, sims=tuple(sims),
                             candidate_kinds=candidate_kinds)
    if args.json:
        print(json.dumps(summary))
        return 0
    _print_bench_push(summary)
    for line in _simulator_lines(summary["simulators"]):
        print(line)
    line = time_profile_line(summary["time_profile"])
    if line:
        print(line)
    plots = ", ".join(str(out / ("coverage.png" if k == 0 else f"coverage_{sim}.png"))
                      for k, sim in enumerate(sims))
    print(f"wrote {out / 'results.csv'}, {plots}, {summary_path}")
    return 0


def _simulator_lines(sims: dict) -> list[str]:
    """With several simulators: each one's coverage per shape type and each one's parting
    from the first."""
    if len(sims["names"]) < 2:
        return []
    lines = []
    for sim, part in sims["by_simulator"].items():
        for kind, q in part["coverage"].items():
            o, r = part["open_loop_coverage"][kind], part["replans"][kind]
            lines.append(f"{sim:>9} {kind:>7}: closed loop median {q['median']:.3f} (q1 "
                         f"{q['q1']:.3f}, min {q['min']:.3f}), open loop median "
                         f"{o['median']:.3f} (q1 {o['q1']:.3f}, min {o['min']:.3f}); re-plans "
                         f"per scene median {r['median']:.0f}")
    for pair, gaps in sims["disagreement"].items():
        c, o = gaps["coverage"], gaps["open_loop_coverage"]
        lines.append(f"{pair}: coverage differs by {c['abs_mean']:.3f} on average closed "
                     f"loop (range {c['quartiles']['min']:+.3f} to {c['quartiles']['max']:+.3f}), "
                     f"{o['abs_mean']:.3f} open loop (range {o['quartiles']['min']:+.3f} to "
                     f"{o['quartiles']['max']:+.3f})")
    return lines


def _print_bench_push(summary: dict) -> None:
    """The first simulator's coverage, re-plans and times per shape type."""
    sim = summary["simulators"]["names"][0]
    for kind, q in summary["coverage"].items():
        o = summary["open_loop_coverage"][kind]
        t = summary["plan_seconds"][kind]
        r, a = summary["replans"][kind], summary["replans_adopted"][kind]
        c, w = summary["closed_loop_seconds"][kind], summary["open_loop_seconds"][kind]
        print(f"{kind:>7}: coverage in {sim} median closed loop {q['median']:.3f} (quartiles "
              f"{q['q1']:.3f}–{q['q3']:.3f}, min {q['min']:.3f}), open loop "
              f"{o['median']:.3f} ({o['q1']:.3f}–{o['q3']:.3f}, min {o['min']:.3f}), "
              f"n={q['n']}; re-plans per scene median {r['median']:.0f} ({a['adopted']} "
              f"of {a['of']} adopted); plan time median "
              f"{t['median']:.1f} s; plan + execution median {c['median']:.1f} s closed, "
              f"{w['median']:.1f} s open loop")


def _bench_compare(args: argparse.Namespace, kinds: list[str], out: Path) -> int:
    """``bench push --dynamics A,B,…``: one benchmark per kind, then the comparison."""
    from robotplan.pushing.bench.compare import run_bench_compare

    if (out / "compare.json").exists() and not args.overwrite:
        print(f"error: {out}: --out: holds a finished comparison; pass --overwrite to redo it",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.overwrite:
        for kind in kinds:
            for name in ("summary.json", "rows.jsonl", "results.csv", "coverage.png"):
                (out / kind / name).unlink(missing_ok=True)
    result = run_bench_compare(kinds, args.scenes, args.seed, out, args.workers,
                               tuple(args.shapes.split(",")), args.exhaustive,
                               args.time_budget, args.perturb, args.loop, args.ray,
                               args.program, rehearse=not args.no_rehearse)
    if args.json:
        print(json.dumps(result))
        return 0
    for kind, shapes in result["models"].items():
        for shape, v in shapes.items():
            c, o, t = v["closed_loop"], v["open_loop"], v["plan_seconds"]
            print(f"{kind:>7} {shape:>7}: closed loop {c['median']:.3f} (q1 {c['q1']:.3f}), "
                  f"open loop {o['median']:.3f} (q1 {o['q1']:.3f}); below 0.9 "
                  f"{v['below_0_9']['closed_loop']} / {v['below_0_9']['open_loop']}; "
                  f"unsolved {v['unsolved']} of {c['n']}; plan time median {t['median']:.1f} s")
    print(f"wrote {out / 'compare.json'}, {out / 'compare.png'}")
    return 0
