"""The options of ``train push`` and ``train hang`` that choose what a network reads of each
object: the SDF (the paper's proposal) or one of the baselines of its app. A."""

from __future__ import annotations

import argparse

__all__ = ["add_representation_options", "representation_fields", "representation_problem"]

REPRESENTATIONS = ("sdf", "occupancy", "smooth_occupancy", "pointcloud")


def add_representation_options(parser: argparse.ArgumentParser, default_sharpness: float,
                               cloud: str) -> None:
    """``--representation``, ``--cloud-encoder`` and ``--sharpness``; ``cloud`` says how the
    boundary cloud is made and where it may be used."""
    parser.add_argument("--representation", choices=REPRESENTATIONS, default="sdf",
                        help="what the network reads of each object: sdf (the paper's "
                             "proposal); occupancy, ψ = sign(φ) (eq. 10); smooth_occupancy, "
                             f"ψ_s = tanh(b φ) (eq. 11); pointcloud, {cloud}: the paper's "
                             "baselines (app. A)")
    parser.add_argument("--cloud-encoder", choices=["pointnet", "pointnet2"], default=None,
                        help="the point-cloud encoder of --representation pointcloud: "
                             "pointnet (default) or pointnet2, a PointNet++ with one "
                             "set-abstraction level")
    parser.add_argument("--sharpness", type=float, default=None, metavar="B",
                        help=f"b of smooth_occupancy in 1/m (default {default_sharpness:g}; "
                             "the paper tests 100 and 1000)")


def representation_fields(args: argparse.Namespace) -> dict:
    """The spec fields (of a dynamics or a hang model) these options set."""
    spec: dict = {}
    if args.representation != "sdf":
        spec["representation"] = args.representation
    if args.sharpness is not None:
        spec["occupancy_sharpness"] = args.sharpness
    if args.cloud_encoder is not None:
        spec["cloud_encoder"] = args.cloud_encoder
    return spec


def representation_problem(args: argparse.Namespace) -> str | None:
    """Why these options describe no model, or None."""
    if args.cloud_encoder is not None and args.representation != "pointcloud":
        return "--cloud-encoder: only with --representation pointcloud"
    if args.sharpness is not None and args.representation != "smooth_occupancy":
        return "--sharpness: only with --representation smooth_occupancy"
    if args.sharpness is not None and not 0 < args.sharpness < float("inf"):
        return f"--sharpness: {args.sharpness} is not a positive number (1/m)"
    return None
