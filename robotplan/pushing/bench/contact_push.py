"""The paper's Fig. 5: planning one straight push from contact with a learned model on each
object representation.

The pusher starts touching the middle of a box's face and the box should end 20 cm straight
ahead (a pose goal). The learned program alone plans it: the dynamics row of the model
under test and the goal row, no H_coll, no H_PoC, no quasi-static rows, no kinematic warm
start, and a start in which nothing moves (the paper: "the only constraint of the
optimization problem apart from the goal specification is H_F"). The plan is then run open
loop in pybullet. A model whose grids pass the optimiser no gradient (ψ = sign φ) leaves the
pusher where it is; one on SDFs pushes the box to the goal. A point-cloud F_q (PointNet,
PointNet++) passes it a gradient only through the grid points next to each boundary (its
clouds' marching-squares vertices, differentiated by autograd in H_q).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import torch

from robotplan.api import PushPlan, execute
from robotplan.geometry.transforms import planar_to_world
from robotplan.pushing.models.loading import load_dynamics
from robotplan.pushing.program.push_program import PushProgram
from robotplan.pushing.program.settings import DEFAULT_SETTINGS, ProgramSettings
from robotplan.pushing.program.skeleton import Phase, Skeleton, space_for
from robotplan.scene import Scene, parse_scene
from robotplan.scene.task import make_task
from robotplan.sdf import Box

__all__ = ["CONTACT_PUSH_SETTINGS", "contact_push_scene", "plan_from_contact",
           "plot_contact_pushes", "still_guess"]

BOX = (0.20, 0.12)  # m: the box's sides
PUSHER_RADIUS = 0.03  # m
GAP = 0.002  # m between the pusher and the face at the start (the scene check needs air)
TRAVEL = 0.20  # m straight ahead to the goal
SUCCESS = 0.95  # coverage of the goal footprint that counts as pushed there (Push-T's)

# the learned program alone, as in the paper's Fig. 5 (see the module docstring), with the
# kinematic stage's iteration budget, as nothing starts it near a plan; the dynamics row a
# cost of weight 1 per mm²: as a hard row SNOPT does not leave the still start, and at the
# default 0.01 the box reaches the goal in the plan without the pusher (measured:
# docs/experiments.md#contact-push)
CONTACT_PUSH_SETTINGS: ProgramSettings = DEFAULT_SETTINGS.with_values({
    "warm_start": False, "with_collision": False, "with_contact": False,
    "friction_cone.active": False, "friction_cone.turn": False, "lever.weight": 0.0,
    "H_F.weight": 1.0, "iterations": DEFAULT_SETTINGS.warm_iterations})


def contact_push_scene() -> Scene:
    """The box at the origin, the pusher at its west face, the goal ``TRAVEL`` east."""
    start = -(BOX[0] / 2 + PUSHER_RADIUS + GAP)
    doc = {"version": 1, "name": "contact_push",
           "workspace": {"center": [0.0, 0.0], "size": [1.4, 1.4], "resolution": 0.01},
           "objects": [{"name": "box", "shape": {"type": "box", "size": list(BOX)},
                        "pose": [0.0, 0.0, 0.0]}],
           "pushers": [{"name": "pusher", "radius": PUSHER_RADIUS,
                        "position": [start, 0.0]}],
           "goal": {"type": "pose", "object": "box", "pose": [TRAVEL, 0.0, 0.0]}}
    return parse_scene(doc, Path("contact_push.yaml"))


def still_guess(scene: Scene, steps: int) -> dict[str, np.ndarray]:
    """The start of a push of ``steps`` steps in which nothing moves: every state at the
    scene's start, the contact points on the pusher's surface facing the box."""
    q_obj = np.tile(np.asarray(scene.bodies["box"].pose, dtype=float), (steps + 1, 1))
    q_pusher = np.tile(np.asarray(scene.bodies["pusher"].pose[:2], dtype=float),
                       (steps + 1, 1))
    toward = q_obj[0, :2] - q_pusher[0]
    toward /= np.linalg.norm(toward)
    p = np.tile(q_pusher[0] + PUSHER_RADIUS * toward, (steps, 1))
    return {"q_obj": q_obj, "q_pusher": q_pusher, "p": p}


def plan_from_contact(model_dir: str | Path,
                      settings: ProgramSettings = CONTACT_PUSH_SETTINGS) -> dict:
    """Plan :func:`contact_push_scene` with the model in ``model_dir`` (an F_q on grids or on
    point clouds, an F_flow or an F on grids) from :func:`still_guess`, run the plan open
    loop; returns how far the pusher and the box moved in the plan and in pybullet (m), the
    coverage of the goal footprint, the program's violation and dynamics residual, and
    seconds."""
    scene = contact_push_scene()
    task = make_task(scene)
    space = space_for(task)
    # one push phase (init 0: straight behind the box, as it starts)
    skeleton = Skeleton((Phase("push", "pusher", "box", init=0),))
    model = load_dynamics(model_dir).double()
    t0 = time.perf_counter()
    program = PushProgram(task, skeleton, model, space, settings,
                          guess=still_guess(scene, space.steps_per_phase))
    sol = program.solve()
    seconds = time.perf_counter() - t0
    executed = execute(PushPlan(task, sol, sol.success), mode="open_loop")
    goal = np.array([TRAVEL, 0.0])
    return {"model": str(model_dir), "violation": float(sol.violation),
            "solved": bool(sol.success), "dynamics_rms_mm": float(sol.dynamics_rms_mm),
            "planned_pusher_travel_m": float(np.linalg.norm(sol.q_pusher[-1] - sol.q_pusher[0])),
            "planned_box_travel_m": float(np.linalg.norm(sol.q_obj[-1, :2] - sol.q_obj[0, :2])),
            "box_travel_m": float(np.linalg.norm(executed.final_pose[:2] - sol.q_obj[0, :2])),
            "box_goal_distance_m": float(np.linalg.norm(executed.final_pose[:2] - goal)),
            "coverage": float(executed.coverage or 0.0),
            "success": bool((executed.coverage or 0.0) >= SUCCESS),
            "seconds": round(seconds, 2),
            "q_obj": np.round(executed.object_poses, 5).tolist(),
            "q_pusher": np.round(executed.pusher_positions, 5).tolist()}


def plot_contact_pushes(results: dict[str, dict], labels: dict[str, str], path: Path) -> None:
    """One panel per model: the box at its start (grey), at the goal (dashed) and where
    pybullet left it (coloured), and the pusher's executed path; ``results``: key → the
    result of :func:`plan_from_contact`, ``labels``: key → panel title."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon

    corners = torch.as_tensor(Box(BOX).outline(), dtype=torch.float64)

    def outline(pose) -> np.ndarray:
        return planar_to_world(corners, torch.as_tensor(pose, dtype=torch.float64)).numpy()

    fig, axes = plt.subplots(1, len(results), figsize=(3.2 * len(results), 2.6), dpi=120,
                             squeeze=False)
    for ax, (key, r) in zip(axes[0], results.items(), strict=True):
        q_obj, q_pusher = np.asarray(r["q_obj"]), np.asarray(r["q_pusher"])
        ax.add_patch(Polygon(outline(q_obj[0]), closed=True, fc="0.85", ec="0.5"))
        ax.add_patch(Polygon(outline((TRAVEL, 0.0, 0.0)), closed=True, fill=False,
                             ec="tab:green", ls="--"))
        ax.add_patch(Polygon(outline(q_obj[-1]), closed=True, fc="tab:blue", alpha=0.5,
                             ec="tab:blue"))
        ax.plot(q_pusher[:, 0], q_pusher[:, 1], color="tab:red", lw=1.5)
        ax.add_patch(plt.Circle(tuple(q_pusher[-1]), PUSHER_RADIUS, color="tab:red",
                                alpha=0.6))
        ax.set_title(f"{labels.get(key, key)}\ncoverage {r['coverage']:.2f}", fontsize=8)
        ax.set_xlim(-0.25, 0.5)
        ax.set_ylim(-0.15, 0.15)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=6)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
