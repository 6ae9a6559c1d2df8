"""Commands of the mug-hanging task: data hang."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from robotplan.cli.common import EXIT_BAD_INPUT

__all__ = ["cmd_data_hang"]


def cmd_data_hang(args: argparse.Namespace) -> int:
    from robotplan.training.hang_data import HangDataSpec, generate_hang

    if args.scenes < 1 or args.per_scene < 2:
        print("error: --scenes must be ≥ 1 and --per-scene ≥ 2", file=sys.stderr)
        return EXIT_BAD_INPUT
    t0 = time.time()
    try:
        summary = generate_hang(Path(args.out), args.scenes, args.seed, workers=args.workers,
                                shard_size=args.shard_size,
                                spec=HangDataSpec(per_scene=args.per_scene))
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    summary["seconds"] = round(time.time() - t0, 1)
    if summary["made_shards"]:
        summary["scenes_per_second"] = round(
            summary["new_samples"] / args.per_scene / max(summary["seconds"], 1e-9), 3)
    print(json.dumps(summary))
    return 0
