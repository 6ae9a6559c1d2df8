"""The model that ``robotplan train push``'s options describe: its spec fields, and why a
combination of them builds none."""

from __future__ import annotations

import argparse

from robotplan.cli.representation_options import representation_fields, representation_problem

__all__ = ["architecture", "architecture_problem"]


def architecture(args: argparse.Namespace) -> dict:
    """The ``DynamicsSpec`` fields that ``train push`` sets: the encoder, what it reads of the
    objects, and any widths given."""
    spec: dict = {"encoder": args.encoder, **representation_fields(args)}
    for name in ("channels", "kernels", "strides", "sdf_features", "hidden"):
        if getattr(args, name) is not None:
            spec[name] = getattr(args, name)
    if args.frame == "object":
        from robotplan.models.spec import OBJECT_WINDOW

        spec.update(frame="object", **OBJECT_WINDOW)
    return spec


def architecture_problem(args: argparse.Namespace) -> str | None:
    """Why the widths given to ``train push`` cannot build a model, or None."""
    from robotplan.models.spec import DynamicsSpec, conv_output_side
    from robotplan.pushing.training.train import WINDOW_AUGMENTS

    if args.frame == "object":
        if args.augment == "turns":
            return ("--frame object: trains without --augment turns (they leave an "
                    "object-frame model's inputs unchanged)")
        if args.model == "rigid" and args.rigid_loss != "delta":
            return "--frame object: an F_q trains with --rigid-loss delta"
        if args.model != "rigid" and args.augment in WINDOW_AUGMENTS:
            return f"--augment {args.augment}: only with --model rigid (F_q)"
        if args.representation == "pointcloud":
            return "--frame object: not with --representation pointcloud"
    elif args.augment in WINDOW_AUGMENTS:
        return f"--augment {args.augment}: only with --frame object"
    if args.placement_reach is not None:
        if not 0.0 <= args.placement_reach <= 0.2:
            return f"--placement-reach {args.placement_reach}: expected 0 to 0.2 m"
        if args.augment != "placements":
            return "--placement-reach: only with --augment placements"
    default = DynamicsSpec(**{k: v for k, v in architecture(args).items()
                              if k in ("grid", "workspace_size")})
    layers = len(default.kernels)
    for option, values in (("channels", args.channels), ("kernels", args.kernels),
                           ("strides", args.strides)):
        if values is not None and len(values) != layers:
            return f"--{option}: {layers} convolutions, got {len(values)} values"
    side = min(default.grid)
    for k, s in zip(args.kernels or default.kernels, args.strides or default.strides,
                    strict=True):
        if side < k:
            return (f"--kernels/--strides: the {default.grid[0]} x {default.grid[1]} grid "
                    f"shrinks below a {k} x {k} kernel")
        side = conv_output_side(side, k, s)
    if args.sdf_features is not None and args.sdf_features < 1:
        return f"--sdf-features: {args.sdf_features} is not a positive integer"
    if args.representation == "pointcloud" and args.model != "rigid":
        return "--representation pointcloud: only with --model rigid (F_q)"
    return representation_problem(args)
