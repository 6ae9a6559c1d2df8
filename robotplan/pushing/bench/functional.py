"""``robotplan bench functional``: speed and accuracy of the fast functional evaluators.

Realistic configurations come from real pybullet pushes (``simulate_scene``, fixed seeds):
windows of T + 1 consecutive kept states in which the pusher touches the object.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import torch

from robotplan.base.native import kernels
from robotplan.base.resources import learned_dir
from robotplan.functionals import Collision, GoalRegion, Quadrature
from robotplan.models.spec import read_spec
from robotplan.pushing.functionals.dynamics import (
    QUADRATURE_COARSE,
    QUADRATURE_LEVELS,
    LearnedDynamics,
    phase_quadrature,
)
from robotplan.pushing.functionals.framed_dynamics import FramedDynamics
from robotplan.pushing.functionals.rigid_dynamics import RigidDynamics
from robotplan.pushing.models.dynamics import DynamicsSpec, load_model
from robotplan.pushing.models.loading import dynamics_kind
from robotplan.pushing.models.rigid import load_rigid
from robotplan.pushing.training.push_data import simulate_scene
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle, Workspace

__all__ = ["bench_analytic", "bench_functional", "bench_rigid", "realistic_pushes"]

DEFAULT_MODEL = learned_dir("push_flow")


def realistic_pushes(count: int, steps: int = 10, seed: int = 321, min_contacts: int = 5
                     ) -> list[tuple[Body, Body, torch.Tensor, torch.Tensor]]:
    """``count`` windows ``(object, pusher, X1 (T+1, 3), X2 (T+1, 2))`` of real pushes."""
    found: list[tuple[Body, Body, torch.Tensor, torch.Tensor]] = []
    index = 0
    while len(found) < count and index < 50 * count:
        rec = simulate_scene(index, seed)
        index += 1
        K = len(rec.object_pose)
        for start in range(0, K - steps, steps):
            window = slice(start, start + steps + 1)
            if rec.contact[window][1:].sum() >= min_contacts:
                obj = Body("object", "object", rec.shape, (0.0, 0.0, 0.0), 0.0, 0.06)
                pusher = Body("pusher", "pusher", Circle(rec.pusher_radius), (0.0, 0.0, 0.0),
                              0.0, 2 * rec.pusher_radius)
                found.append((obj, pusher, torch.tensor(rec.object_pose[window]),
                              torch.tensor(rec.pusher_xy[window])))
                break
    return found


def _time(fn, repeats: int) -> float:
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def phase_quadrature_for(obj: Body, X1: torch.Tensor, workspace: Workspace) -> Quadrature:
    """The quadrature a planner fixes for a phase: finer near the object's path."""
    return phase_quadrature(X1[:, :2].float(), obj.shape.bound_radius, workspace)


def _describe_quadrature(coarse: float = QUADRATURE_COARSE) -> str:
    """The default of :func:`phase_quadrature` in words (from its constants)."""
    finer = ", ".join(f"{spacing * 100:g} cm within r_object + {margin * 100:g} cm"
                      for margin, spacing in QUADRATURE_LEVELS)
    return f"multi-level midpoint: {coarse * 100:g} cm cells, {finer} of the phase's object path"


def _rss_mb() -> tuple[float, float]:
    """(current, peak) resident memory of this process in MB."""
    import resource

    with open("/proc/self/statm") as f:
        current = int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    return current, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def bench_analytic(repeats: int = 30) -> dict:
    """H_coll for all pairs of 3 bodies over 20 steps (object, pusher of a real push, and a
    wall beside the object's path) and H_g at the last step, value + Jacobian."""
    obj, pusher, X1, X2 = realistic_pushes(1, steps=19, seed=654)[0]
    X1, X2 = X1.float(), X2.float()
    end = X1[-1, :2]
    wall = Body("wall", "obstacle", Box((0.06, 0.30)), (0.0, 0.0, 0.0), 0.0, 0.06)
    direction = (X1[-1, :2] - X1[0, :2]) / (X1[-1, :2] - X1[0, :2]).norm().clamp_min(1e-9)
    reach = obj.shape.bound_radius + 0.03
    Xw = torch.cat((end + reach * direction, torch.atan2(direction[1:], direction[:1])))
    Xw = Xw.expand(X1.shape[0], 3)
    region = Body("goal", "region", Box((0.4, 0.4)), (float(end[0]), float(end[1]), 0.0),
                  0.0, 0.0)
    pairs = [(Collision(obj, pusher), X1, X2), (Collision(obj, wall), X1, Xw),
             (Collision(pusher, wall), X2, Xw)]
    goal = GoalRegion(obj, region)

    def all_pairs() -> None:
        for H, A, B in pairs:
            H.jacobians(A, B)

    return {"coll_phase_ms": round(_time(all_pairs, repeats), 2),
            "coll_pairs": 3, "coll_steps": X1.shape[0],
            "goal_ms": round(_time(lambda: goal.jacobians(X1[-1:]), repeats), 2)}


def bench_rigid(model_dir: str | Path, repeats: int = 20) -> dict:
    """H_q (F_q's row) of a 10-step phase of a real push: value + Jacobian, value only."""
    obj, pusher, X1, X2 = realistic_pushes(1)[0]
    H = RigidDynamics(load_rigid(model_dir), obj, pusher)
    return {"model": str(model_dir), "threads": torch.get_num_threads(),
            "native_kernels": kernels() is not None, "steps": X1.shape[0] - 1,
            "hq_phase_ms": round(_time(lambda: H.evaluate(X1, X2), repeats), 2),
            "hq_value_only_ms": round(_time(lambda: H.evaluate(X1, X2, jacobian=False),
                                            repeats), 2)}


def bench_framed(model_dir: str | Path, repeats: int = 20) -> dict:
    """H_F with an object-frame F_flow or F (:class:`FramedDynamics`, autograd) on a
    10-step phase of a real push, on the planner's phase quadrature: value + Jacobian,
    value only."""
    model = load_model(model_dir)
    obj, pusher, X1, X2 = realistic_pushes(1)[0]
    quad = phase_quadrature_for(obj, X1, DynamicsSpec().workspace())
    H = FramedDynamics(model, obj, pusher, quad)
    return {"model": str(model_dir), "threads": torch.get_num_threads(), "frame": "object",
            "steps": X1.shape[0] - 1, "quadrature_points": len(quad.points),
            "hf_phase_ms": round(_time(lambda: H.evaluate(X1, X2), repeats), 2),
            "hf_value_only_ms": round(_time(lambda: H.evaluate(X1, X2, jacobian=False),
                                            repeats), 2)}


def bench_functional(model_dir: str | Path = DEFAULT_MODEL, configurations: int = 24,
                     repeats: int = 20, naive: bool = True) -> dict:
    """H_F's speed and its quadrature's accuracy (or H_q's speed for an F_q folder), and
    the analytic functionals' speed."""
    if dynamics_kind(model_dir) == "rigid":
        return {**bench_rigid(model_dir, repeats), **bench_analytic(repeats)}
    if read_spec(model_dir).frame == "object":
        return {**bench_framed(model_dir, repeats), **bench_analytic(repeats)}
    model = load_model(model_dir)
    ws = model.spec.workspace()
    # memory first, while the process's high-water mark is still low: 40 steps in one call
    obj, pusher, X1, X2 = realistic_pushes(1, steps=40, seed=987, min_contacts=10)[0]
    before, _ = _rss_mb()
    LearnedDynamics(model, obj, pusher, phase_quadrature_for(obj, X1, ws)
                    ).evaluate(X1, X2)
    _, peak = _rss_mb()
    memory = {"hf_40_steps_peak_rss_mb": round(peak, 1),
              "hf_40_steps_rss_growth_mb": round(max(0.0, peak - before), 1)}
    pushes = realistic_pushes(configurations)
    obj, pusher, X1, X2 = pushes[0]
    quad = phase_quadrature_for(obj, X1, ws)
    fast = LearnedDynamics(model, obj, pusher, quad)
    result: dict = {"model": str(model_dir), "threads": torch.get_num_threads(),
                    "native_kernels": kernels() is not None,  # robotplan/base/kernels.c in use
                    "head_matmul_dtype": str(fast.matmul_dtype).removeprefix("torch."),
                    "steps": X1.shape[0] - 1, "quadrature_points": len(quad.points),
                    "quadrature": _describe_quadrature()}
    result["hf_phase_ms"] = round(_time(lambda: fast.evaluate(X1, X2), repeats), 2)
    result["hf_value_only_ms"] = round(
        _time(lambda: fast.evaluate(X1, X2, jacobian=False), repeats), 2)
    if naive:
        result["hf_naive_phase_ms"] = round(_time(lambda: fast.evaluate_naive(X1, X2), 1), 1)
        result["speedup"] = round(result["hf_naive_phase_ms"] / result["hf_phase_ms"], 1)
    # accuracy of the quadrature against the full grid X_h, per step, worst case
    rel, rel_phase, jac, rel_all = [], [], [], []
    full = Quadrature.grid(ws)
    for obj, pusher, X1, X2 in pushes:
        q = phase_quadrature_for(obj, X1, ws)
        h_fast, j1, j2 = LearnedDynamics(model, obj, pusher, q).evaluate(X1, X2)
        h_full, k1, k2 = LearnedDynamics(model, obj, pusher, full,
                                         matmul_dtype=torch.float32).evaluate(X1, X2)
        step_rel = (h_fast - h_full).abs() / h_full
        rel.append(step_rel.max().item())
        rel_all.append(step_rel)
        rel_phase.append(abs(h_fast.sum() - h_full.sum()).item() / h_full.sum().item())
        jf = torch.cat((j1.flatten(1), j2.flatten(1)), 1)
        jg = torch.cat((k1.flatten(1), k2.flatten(1)), 1)
        jac.append(((jf - jg).norm(dim=1) / jg.norm(dim=1)).max().item())
    result["configurations"] = len(pushes)
    result["integral_rel_error"] = round(max(rel), 4)
    result["integral_rel_error_median"] = round(torch.cat(rel_all).median().item(), 4)
    result["integral_rel_error_phase"] = round(max(rel_phase), 4)
    result["jacobian_rel_error"] = round(max(jac), 4)
    result.update(bench_analytic(repeats))
    result.update(memory)
    return result
