"""The ``robotplan`` command line: ``check``, ``render``, ``bench``.

Exit status: 0 success, 1 failure of the work itself, 2 bad input (one line on stderr naming
the file and the field, no traceback).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from robotplan.scene import SceneError, load_scene

EXIT_BAD_INPUT = 2


def _cmd_check(args: argparse.Namespace) -> int:
    status = 0
    for f in args.files:
        try:
            scene = load_scene(f)
        except SceneError as err:
            print(f"error: {err}", file=sys.stderr)
            status = EXIT_BAD_INPUT
            continue
        print(f"ok {f}: {scene.summary()}")
    return status


def _cmd_render(args: argparse.Namespace) -> int:
    from robotplan.render import render_scene_sdf

    scenes = [load_scene(f) for f in args.files]  # refuse bad input before writing anything
    out = Path(args.out)
    targets = [out / f"{Path(f).stem}_sdf.png" for f in args.files]
    if not args.overwrite:
        existing = [str(t) for t in targets if t.exists()]
        if existing:
            print(f"error: {existing[0]}: exists; pass --overwrite to replace it",
                  file=sys.stderr)
            return EXIT_BAD_INPUT
    for scene, target in zip(scenes, targets, strict=False):
        render_scene_sdf(scene, target)
        print(f"wrote {target}")
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    import torch

    from robotplan.bench import bench_sdf

    torch.set_num_threads(args.threads)
    scene = load_scene(args.scene)
    dtype = {"float32": torch.float32, "float64": torch.float64}[args.dtype]
    result = bench_sdf(scene, steps=args.steps, repeats=args.repeats, dtype=dtype)
    if args.json:
        print(json.dumps(result))
    else:
        for k, v in result.items():
            print(f"{k:>10}: {v}")
    return 0


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="robotplan", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)

    c = sub.add_parser("check", help="validate scene files; one 'ok' line per good file")
    c.add_argument("files", nargs="+", metavar="FILE")
    c.set_defaults(run=_cmd_check)

    r = sub.add_parser("render", help="render the SDFs of scenes on X_h to PNG")
    r.add_argument("files", nargs="+", metavar="FILE")
    r.add_argument("--out", required=True, metavar="DIR", help="folder for <scene>_sdf.png")
    r.add_argument("--overwrite", action="store_true", help="replace existing pictures")
    r.set_defaults(run=_cmd_render)

    b = sub.add_parser("bench", help="benchmarks (speed targets)")
    bsub = b.add_subparsers(dest="what", required=True)
    bs = bsub.add_parser("sdf", help="render every body of a scene at T steps on X_h")
    default_scene = Path(__file__).resolve().parents[1] / "tasks" / "box_push.yaml"
    bs.add_argument("--scene", default=str(default_scene), metavar="FILE")
    bs.add_argument("--steps", type=int, default=40)
    bs.add_argument("--repeats", type=int, default=20)
    bs.add_argument("--threads", type=int, default=1)
    bs.add_argument("--dtype", choices=["float32", "float64"], default="float32")
    bs.add_argument("--json", action="store_true", help="print one JSON object")
    bs.set_defaults(run=_cmd_bench)
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        return args.run(args)
    except SceneError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
