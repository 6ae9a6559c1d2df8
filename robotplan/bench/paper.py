"""The paper's numbers that ``robotplan reproduce`` sets ours beside (its tables and figures,
as printed there), and the parts of its evaluation that robotplan does not run yet."""

from __future__ import annotations

__all__ = ["FIG3", "FIG5", "FIG8", "FLOW_REPRESENTATIONS", "NOT_RUN",
           "PAPER_TAB3_BASELINES",
           "REPRESENTATIONS", "SPEC_FLAGS", "TAB2", "TAB4", "TAB5", "TAB6", "spec_flags"]

# Tab. 2: one-step RMSE of φ1_t over X_h, mm, (mean, std), with / without pusher contact
TAB2 = {"F_flow": {"contact": (3.4, 1.6), "free": (1.4, 1.8)},
        "F": {"contact": (5.8, 1.7), "free": (5.2, 1.6)},
        "no motion": {"contact": (10.8, 3.4), "free": (0.0, 0.0)}}

# Tab. 4: F_flow on each representation, one-step RMSE over X_h of what it reads (φ in mm,
# ψ × 1000), (mean, std) with / without contact, and its no-motion baseline
TAB4 = {"sdf": {"F_flow": ((3.4, 1.6), (1.4, 1.8)), "no motion": ((10.8, 3.4), (0.0, 0.0))},
        "smooth100": {"F_flow": ((59.0, 16.6), (10.0, 11.7)),
                      "no motion": ((83.6, 25.1), (0.0, 0.0))},
        "smooth1000": {"F_flow": ((100.2, 19.5), (13.1, 16.7)),
                       "no motion": ((127.1, 27.0), (0.0, 0.0))},
        "occupancy": {"F_flow": ((109.7, 18.3), (13.5, 19.5)),
                      "no motion": ((134.9, 25.7), (0.0, 0.0))}}

# Tab. 5 / Tab. 6: F_q's one-step |Δq| error, (x mm, y mm, α °), by input representation
TAB5 = {"SDF": (2.1, 2.1, 0.63), "image-conditioned SDF": (2.2, 2.1, 0.63),
        "occupancy ψ_s (b = 100)": (2.7, 2.7, 0.76), "PointNet": (3.3, 3.3, 0.88),
        "PointNet++": (2.7, 2.6, 0.79)}
TAB6 = {"SDF": (2.3, 2.3, 0.81), "occupancy ψ_s (b = 100)": (3.0, 3.2, 0.99),
        "PointNet": (4.9, 5.1, 0.99), "PointNet++": (4.5, 4.6, 0.77)}

# the paper's app. A (Tabs. 5, 6): F_q trained alike on each object representation; key →
# (the paper's row, DynamicsSpec fields)
REPRESENTATIONS = {
    "sdf": ("SDF", {}),
    "occupancy": ("occupancy ψ = sign(φ)", {"representation": "occupancy"}),
    "smooth100": ("occupancy ψ_s (b = 100)", {"representation": "smooth_occupancy",
                                              "occupancy_sharpness": 100.0}),
    "smooth1000": ("occupancy ψ_s (b = 1000)", {"representation": "smooth_occupancy",
                                                "occupancy_sharpness": 1000.0}),
    "pointnet": ("PointNet", {"representation": "pointcloud"}),
    "pointnet2": ("PointNet++", {"representation": "pointcloud", "cloud_encoder": "pointnet2"}),
}

# the representations of Tab. 4's F_flow rows (keys of REPRESENTATIONS)
FLOW_REPRESENTATIONS = ("sdf", "occupancy", "smooth100", "smooth1000")

# the `train push` / `train hang` option of each spec field a representation sets
SPEC_FLAGS = {"representation": "--representation", "occupancy_sharpness": "--sharpness",
              "cloud_encoder": "--cloud-encoder"}


def spec_flags(fields: dict) -> str:
    """The ``train push`` / ``train hang`` options that set these spec ``fields``."""
    return "".join(f" {SPEC_FLAGS[k]} {v:g}" if isinstance(v, float)
                   else f" {SPEC_FLAGS[k]} {v}" for k, v in fields.items())


# Fig. 3 / Fig. 8: median share of the object inside the goal, open loop, by model
FIG3 = {"box": {"F_flow": 0.997, "F": 0.966}, "lshape": {"F_flow": 0.984, "F": 0.915}}
FIG8 = {"F_flow": 0.997, "F": 0.920}  # 7 unseen shapes × 3 scenes

# Fig. 5: what the paper's planner did from contact with each representation (its text
# gives outcomes, no numbers; its occupancy row does not say which ψ)
FIG5 = {"sdf": "pushed to the goal", "occupancy": "the pusher does not move",
        "smooth100": "the pusher does not move (occupancy)",
        "smooth1000": "the pusher does not move (occupancy)",
        "pointnet": "some movement, the task not solved (point cloud)",
        "pointnet2": "some movement, the task not solved (point cloud)"}

# the paper's best row of each baseline (app. A.5 and Tab. 1; its Tab. 3 gives every row)
PAPER_TAB3_BASELINES = {
    "sdf": "opt. + sampling: 98.7 / 88.5 / 100.0 / 87.3",
    "occupancy": "sampling κ3: found 100.0, total 34.0",
    "smooth1000": "opt. + sampling: found 34.0, sim success 51.0, total 17.3",
    "pointnet": "opt. + sampling with the SDF collision row: total 66.7 (25.3 without it)",
    "pointnet2": "sampling κ1: total 52.0; optimisation found none",
}

# what the paper evaluates that robotplan has no code for yet: (item, what it needs)
NOT_RUN: list[tuple[str, str]] = []
