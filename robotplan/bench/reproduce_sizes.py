"""How much of each item ``robotplan reproduce`` runs: the quick size (small sets within 30
minutes on 2 cores) and the paper's full size."""

from __future__ import annotations

from dataclasses import dataclass

from robotplan.bench.paper import REPRESENTATIONS
from robotplan.hanging.bench.bench import METHODS
from robotplan.hanging.bench.reproduce import HANG_REPRESENTATIONS

__all__ = ["FULL", "QUICK", "SIZES", "STANDARD", "ReproduceSizes"]


@dataclass(frozen=True)
class ReproduceSizes:
    """How much of each item runs (``QUICK``: small sets within 30 min on 2 cores)."""

    name: str
    test_scenes: int  # held-out push scenes (seed 2) for Tabs. 2 and 5
    ood_scenes: int  # unseen-footprint scenes (seed 3) for Tab. 6
    per_scene: int  # samples per held-out scene
    pose_fit: int  # contact samples F_flow's step is fitted on (Tab. 5 terms)
    push_scenes: int  # benchmark scenes per shape (Fig. 3; the paper: 50)
    ood_push_scenes: int  # unseen-footprint benchmark scenes (Fig. 8; scene i: family i mod 8)
    ablation_scenes: int  # box scenes per ablation (Fig. 11; the paper: 20)
    hang_scenes: int  # mug-and-hook scenes (Tab. 3; the paper: 150)
    hang_methods: tuple[str, ...]
    time_budget: float  # per push scene: no program starts after this many seconds
    representation_scenes: int  # push training scenes (seed 4) of the representation rows
    representation_steps: int  # F_q's training steps per representation (batch 32)
    contact_push: tuple[str, ...]  # the representations' F_q planned from contact (Fig. 5)
    flow_steps: int  # F_flow's training steps per representation (Tab. 4; batch 32)
    # Tab. 3's representation rows: H_hang trained alike on each of these keys of
    # HANG_REPRESENTATIONS
    hang_representations: tuple[str, ...]
    hang_train_scenes: int  # hanging data scenes (seed 0; the paper: 1,600)
    hang_test_scenes: int  # held-out hanging scenes each is scored on (seed 1)
    hang_train_steps: int  # training steps per representation (batch 32)
    hang_representation_scenes: int  # mug scenes each is planned with (seed 2)
    hang_representation_methods: tuple[str, ...]
    hang_evaluations: int  # functional evaluations per method and scene (the paper: 20,000)
    hang_every_collision_row: bool  # each representation's other collision rows too
    # re-plans of the ablation's closed loops (None: the scene class's): re-planning plans
    # through the object dominates a quick run's time (docs/experiments.md#reproduce-quick)
    ablation_replans: int | None = None
    # the training seeds of each representation model of Tabs. 4–6 (one model per seed)
    training_seeds: tuple[int, ...] = (0,)
    # TrainConfig fields of those models beyond the steps (batch, lr, augment), as pairs
    representation_training: tuple[tuple[str, object], ...] = ()
    # the report's file name (NAME.md, NAME.html); its figures are SIZE_fig….png
    report: str = "report"

    def figure(self, name: str) -> str:
        """The file name of figure ``name`` (e.g. ``fig3_coverage.png``) at this size."""
        return f"{self.name}_{name}"


# one scene per shape: the next scenes' searches alone took 9 of a 45-minute quick run
# (measured: docs/experiments.md#reproduce-quick)
QUICK = ReproduceSizes("quick", test_scenes=40, ood_scenes=40, per_scene=10, pose_fit=20,
                       push_scenes=1, ood_push_scenes=4, ablation_scenes=1, hang_scenes=2,
                       hang_methods=("opt_sampling", "opt_only"), time_budget=30.0,
                       representation_scenes=600, representation_steps=250,
                       contact_push=("sdf", "occupancy", "pointnet"), flow_steps=100,
                       hang_representations=("sdf", "occupancy", "pointnet"),
                       hang_train_scenes=24, hang_test_scenes=8, hang_train_steps=100,
                       hang_representation_scenes=1,
                       hang_representation_methods=("opt_sampling", "sampling_k1"),
                       hang_evaluations=1_000, hang_every_collision_row=False,
                       ablation_replans=2, report="quick")
# between the two: enough scenes per table that "ours vs the paper" says something on this
# CPU (the held-out sets of the model cards, 20 + 20 push scenes, the paper's 150 mug
# scenes); the F_q of Tabs. 5–6 trained as the GPU runs that learned to turn, two seeds
# each (docs/experiments.md#reproduce-standard); `reproduce --size standard --status` gives
# its cost
TURNING = (("batch", 128), ("lr", 1e-3), ("augment", "turns"))
STANDARD = ReproduceSizes("standard", test_scenes=300, ood_scenes=300, per_scene=10,
                          pose_fit=100, push_scenes=20, ood_push_scenes=16,
                          ablation_scenes=10, hang_scenes=150, hang_methods=METHODS,
                          time_budget=30.0, representation_scenes=15_000,
                          representation_steps=10_000, contact_push=tuple(REPRESENTATIONS),
                          flow_steps=5_000, hang_representations=tuple(HANG_REPRESENTATIONS),
                          hang_train_scenes=800, hang_test_scenes=100, hang_train_steps=5_000,
                          hang_representation_scenes=30,
                          hang_representation_methods=("opt_sampling", "sampling_k1"),
                          hang_evaluations=20_000, hang_every_collision_row=False,
                          training_seeds=(0, 1), representation_training=TURNING)
FULL = ReproduceSizes("full", test_scenes=300, ood_scenes=300, per_scene=10, pose_fit=100,
                      push_scenes=50, ood_push_scenes=24, ablation_scenes=20,
                      hang_scenes=150,
                      hang_methods=METHODS, time_budget=100.0,
                      representation_scenes=15_000, representation_steps=20_000,
                      contact_push=tuple(REPRESENTATIONS),
                      flow_steps=20_000, hang_representations=tuple(HANG_REPRESENTATIONS),
                      hang_train_scenes=1_600, hang_test_scenes=400,
                      hang_train_steps=20_000,
                      hang_representation_scenes=150, hang_representation_methods=METHODS,
                      hang_evaluations=20_000, hang_every_collision_row=True,
                      training_seeds=(0, 1), representation_training=TURNING, report="full")
SIZES = {size.name: size for size in (QUICK, STANDARD, FULL)}
