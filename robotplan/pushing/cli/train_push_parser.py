"""The options of ``robotplan train push`` (F_flow, F and F_q on push data)."""

from __future__ import annotations

import os

from robotplan.cli.common import positive_ints
from robotplan.cli.representation_options import add_representation_options
from robotplan.pushing.cli.model_commands import cmd_train_push

__all__ = ["add_train_push_parser"]


def add_train_push_parser(tsub) -> None:
    """``robotplan train push`` under the ``train`` subparsers ``tsub``."""
    tp = tsub.add_parser("push", help="train F_flow, F or F_q on push data")
    tp.add_argument("--data", required=True, metavar="DIR")
    tp.add_argument("--model", choices=["flow", "direct", "rigid"], default="flow",
                    help="flow: F_flow (eq. 4); direct: F (eq. 3); rigid: F_q, the "
                         "object's rigid motion Δq (app. eq. 15)")
    tp.add_argument("--encoder", choices=["shared", "joint"], default="shared",
                    help="shared: the paper's (one encoder per SDF, shared weights); "
                         "joint: one encoder over the three SDFs stacked as channels")
    tp.add_argument("--out", required=True, metavar="DIR", help="e.g. learned/push_flow")
    tp.add_argument("--channels", type=positive_ints, default=None, metavar="C1,C2,C3",
                    help="the SDF encoder's convolution channels (default 3,5,5, app. I.1)")
    tp.add_argument("--kernels", type=positive_ints, default=None, metavar="K1,K2,K3",
                    help="the convolutions' kernel sizes (default 3,5,5)")
    tp.add_argument("--strides", type=positive_ints, default=None, metavar="S1,S2,S3",
                    help="the convolutions' strides (default 1,2,2); 2,2,2 quarters the "
                         "first convolution's work, and F_q's H_q with it")
    tp.add_argument("--sdf-features", type=int, default=None, metavar="N",
                    help="features per SDF after the encoder's linear layer (default 200)")
    tp.add_argument("--hidden", type=positive_ints, default=None, metavar="H1,H2",
                    help="the MLP's hidden widths (default 300,300)")
    tp.add_argument("--frame", choices=["table", "object"], default="table",
                    help="the encoder's grid X_h: table, fixed on the table (the paper's); "
                         "object, 64 x 64 cm attached to the object (origin at its "
                         "footprint's centroid, the body's axes): F_q's Δq and F_flow's / "
                         "F's query points in that frame")
    add_representation_options(tp, 100.0, "the boundary's marching-squares vertices through "
                               "a PointNet (eq. 12; --model rigid only)")
    tp.add_argument("--steps", type=int, default=60_000, help="total optimiser steps")
    tp.add_argument("--batch", type=int, default=32)
    tp.add_argument("--lr", type=float, default=5e-4)
    tp.add_argument("--warmup", type=int, default=500, help="steps of linear learning-rate "
                    "warm-up before the cosine decay")
    tp.add_argument("--rigid-loss", choices=["delta", "sdf"], default="delta",
                    help="F_q's loss: delta, the simulator's Δq; sdf, eq. (5) through the "
                         "transform on the SDFs alone")
    tp.add_argument("--points", type=int, default=256, help="query points per sample")
    tp.add_argument("--scenes", type=int, default=None, help="use only the first N scenes")
    tp.add_argument("--seed", type=int, default=0)
    tp.add_argument("--device", default="auto", help="cpu, cuda or auto")
    tp.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    tp.add_argument("--minutes", type=float, default=None, help="stop after this wall time")
    tp.add_argument("--val-every", type=int, default=2000)
    tp.add_argument("--init-weights", default=None, metavar="FILE",
                    help="start from these weights (e.g. a previous run's weights.pt)")
    tp.add_argument("--contact-share", type=float, default=None,
                    help="balanced batches with this share of contact samples")
    tp.add_argument("--near-share", type=float, default=0.25,
                    help="share of the query points drawn within 10 cm of the object (the "
                         "rest uniform on the table); more resolves the object's turning")
    tp.add_argument("--augment", choices=["none", "turns", "headings", "placements"],
                    default="none",
                    help="turns: show each push with the scene turned by a random multiple "
                         "of 90 degrees about the grid's centre (an exact symmetry); "
                         "headings (--frame object): the grid's axes at a random heading "
                         "about the object, so that each footprint is seen at every heading; "
                         "placements (--frame object): also the grid's origin, the pivot, "
                         "moved up to --placement-reach from the centroid")
    tp.add_argument("--placement-reach", type=float, default=None, metavar="M",
                    help="with --augment placements: how far (m) the grid's origin may move "
                         "from the footprint's centroid (default 0.06)")
    tp.add_argument("--anneal-by-time", action="store_true",
                    help="with --minutes: the learning rate reaches its floor when the "
                         "minutes run out, even if fewer steps fit")
    tp.add_argument("--resume", action="store_true", help="continue from checkpoint.pt")
    tp.add_argument("--overwrite", action="store_true", help="start over in a used folder")
    tp.set_defaults(run=cmd_train_push)
