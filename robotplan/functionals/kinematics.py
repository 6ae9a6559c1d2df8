"""Arms in the programs over joints (paper app. E): batched forward kinematics of each arm's
tip and check points with exact Jacobians (Drake), and the per-step functionals that tie
joint angles to the planar pusher variables of the SDF functionals.

Every functional here follows the per-step contract of :mod:`robotplan.functionals`
(``__call__(*inputs) → (n, m)``, ``jacobians(*inputs) → (r, [(n, m, d_i)])``), so
:func:`robotplan.program.bridge.stepwise` binds it like any other.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import torch
from torch import Tensor

from robotplan.scene.robots import DrakeArm, RobotModel, load_robot_model
from robotplan.scene.schema import RobotSpec

__all__ = ["ArmKinematics", "ArmSeparation", "CheckPointHeights", "TipCoupling", "TipHeight",
           "arm_kinematics",
           "track_tip_path"]

@dataclass
class _FK:
    points: np.ndarray  # (K, 3): tip centre, then the model's check_links origins
    jacobians: np.ndarray  # (K, 3, dof)


class ArmKinematics:
    """One arm of a scene: its robot folder in Drake at the scene's base pose.

    ``fk(q)`` gives the tip centre ``p_WT`` and the check points with their Jacobians; the
    last few hundred configurations are cached, since every functional of a program asks
    for the same states in one solver iteration.
    """

    def __init__(self, spec: RobotSpec) -> None:
        self.spec = spec
        self.model: RobotModel = load_robot_model(spec.model)
        self.arm = DrakeArm(self.model, tuple(spec.base))
        self.q0 = np.asarray(spec.q0 if spec.q0 is not None else self.model.home, dtype=float)
        plant = self.arm.plant
        self._frames = [self.arm.tip_frame] + [
            plant.GetBodyByName(name).body_frame() for name in self.model.check_links]
        self._offsets = [np.asarray(self.model.tip.offset, dtype=float)] + [
            np.zeros(3)] * len(self.model.check_links)
        self._cache: OrderedDict[bytes, _FK] = OrderedDict()

    @property
    def dof(self) -> int:
        return self.model.dof

    @property
    def base_xy(self) -> np.ndarray:
        return np.asarray(self.spec.base[:2], dtype=float)

    def fk(self, q: np.ndarray) -> _FK:
        q = np.ascontiguousarray(q, dtype=float)
        key = q.tobytes()
        hit = self._cache.get(key)
        if hit is not None:
            self._cache.move_to_end(key)
            return hit
        from pydrake.multibody.tree import JacobianWrtVariable

        plant, ctx, world = self.arm.plant, self.arm.context, self.arm.plant.world_frame()
        plant.SetPositions(ctx, q)
        pts, jacs = [], []
        for frame, offset in zip(self._frames, self._offsets, strict=True):
            pts.append(plant.CalcPointsPositions(ctx, frame, offset.reshape(3, 1), world)[:, 0])
            jacs.append(plant.CalcJacobianTranslationalVelocity(
                ctx, JacobianWrtVariable.kQDot, frame, offset, world, world))
        out = _FK(np.array(pts), np.array(jacs))
        self._cache[key] = out
        if len(self._cache) > 512:
            self._cache.popitem(last=False)
        return out

    def batch(self, Q: Tensor | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points ``(S, K, 3)`` and Jacobians ``(S, K, 3, dof)`` for joint angles ``(S, dof)``."""
        Q = Q.detach().numpy() if isinstance(Q, Tensor) else np.asarray(Q)
        res = [self.fk(q) for q in Q.astype(float)]
        return np.array([r.points for r in res]), np.array([r.jacobians for r in res])

    def tip(self, q: np.ndarray) -> np.ndarray:
        return self.fk(q).points[0]


def _out(r: np.ndarray, jacs: list[np.ndarray]) -> tuple[Tensor, list[Tensor]]:
    return torch.from_numpy(r), [torch.from_numpy(J) for J in jacs]


class _OnArm:
    """An arm functional: ``__call__`` is the value part of ``jacobians``."""

    def __init__(self, kin: ArmKinematics) -> None:
        self.kin = kin

    def __call__(self, *inputs: Tensor) -> Tensor:
        return self.jacobians(*inputs)[0]


class TipCoupling(_OnArm):
    """The planar pusher variables are the arm's tip: ``FK_xy(q_t) − x_t = 0``.

    ``(q (n, dof), x (n, 2)) → (n, 2)`` in m."""

    def jacobians(self, q: Tensor, x: Tensor) -> tuple[Tensor, list[Tensor]]:
        P, J = self.kin.batch(q)
        r = P[:, 0, :2] - x.numpy()
        eye = np.broadcast_to(-np.eye(2), (len(r), 2, 2)).copy()
        return _out(r, [J[:, 0, :2, :], eye])


class _PointHeights(_OnArm):
    """Heights of the FK points ``points`` (a slice of tip, then the check links),
    ``q (n, dof) → (n, k)`` in m."""

    points: slice

    def jacobians(self, q: Tensor) -> tuple[Tensor, list[Tensor]]:
        P, J = self.kin.batch(q)
        return _out(P[:, self.points, 2], [J[:, self.points, 2, :]])


class TipHeight(_PointHeights):
    """Height of the tip centre above the table, ``q (n, dof) → (n, 1)`` in m."""

    points = slice(0, 1)


class CheckPointHeights(_PointHeights):
    """Heights of the check links' origins (flange first), ``q (n, dof) → (n, K−1)``."""

    points = slice(1, None)


class ArmSeparation(_OnArm):
    """Smooth minimum distance between the check points (tip included) of two arms,
    ``−(1/β) log Σ_ij exp(−β d_ij)`` (≤ the true minimum, so a bound on it is safe):
    ``(qA (n, dof), qB (n, dof)) → (n, 1)`` in m."""

    def __init__(self, a: ArmKinematics, b: ArmKinematics, beta: float = 60.0) -> None:
        super().__init__(a)
        self.a, self.b, self.beta = a, b, beta

    def jacobians(self, qa: Tensor, qb: Tensor) -> tuple[Tensor, list[Tensor]]:
        Pa, Ja = self.a.batch(qa)
        Pb, Jb = self.b.batch(qb)
        diff = Pa[:, :, None, :] - Pb[:, None, :, :]  # (n, Ka, Kb, 3)
        d = np.sqrt((diff**2).sum(-1) + 1e-12)
        m = d.min(axis=(1, 2), keepdims=True)
        w = np.exp(-self.beta * (d - m))
        s = w.sum(axis=(1, 2), keepdims=True)
        value = m[:, 0, 0] - np.log(s[:, 0, 0]) / self.beta
        weights = w / s  # ∂value/∂d_ij
        unit = diff / d[..., None]
        g_pa = np.einsum("nij,nijc->nic", weights, unit)  # ∂value/∂Pa_i
        g_pb = -np.einsum("nij,nijc->njc", weights, unit)
        Jqa = np.einsum("nic,nicd->nd", g_pa, Ja)[:, None, :]
        Jqb = np.einsum("njc,njcd->nd", g_pb, Jb)[:, None, :]
        return _out(value[:, None], [Jqa, Jqb])


def track_tip_path(kin: ArmKinematics, targets: np.ndarray, q_start: np.ndarray,
                   flange_min: float, link_min: float) -> np.ndarray:
    """Joint angles ``(S, dof)`` whose tip follows ``targets (S, 3)`` (NaN rows: hold the
    previous angles), each step an inverse-kinematics program started from the last answer,
    with the flange and the check links kept above ``flange_min`` / ``link_min``. A target
    out of reach gives the nearest configuration the solver finds (the program fixes it)."""
    from pydrake.multibody.inverse_kinematics import InverseKinematics
    from pydrake.solvers import Solve

    plant, world = kin.arm.plant, kin.arm.plant.world_frame()
    out, q = [], np.asarray(q_start, dtype=float)
    lower, upper = np.array(kin.model.joint_lower), np.array(kin.model.joint_upper)
    for target in targets:
        if np.isnan(target).any():
            out.append(q.copy())
            continue
        ik = InverseKinematics(plant)
        ik.AddPositionCost(kin._frames[0], kin._offsets[0], world, target, np.eye(3) * 100.0)
        for i, frame in enumerate(kin._frames[1:]):
            low = flange_min if i == 0 else link_min
            ik.AddPositionConstraint(frame, np.zeros(3), world, [-9.0, -9.0, low],
                                     [9.0, 9.0, 9.0])
        prog = ik.get_mutable_prog()
        prog.AddQuadraticErrorCost(0.01 * np.eye(kin.dof), q, ik.q())
        prog.SetInitialGuess(ik.q(), q)
        result = Solve(prog)
        q = np.clip(result.GetSolution(ik.q()), lower, upper)
        out.append(q.copy())
    return np.array(out)


_KINEMATICS: dict = {}


def arm_kinematics(spec: RobotSpec) -> ArmKinematics:
    """One Drake plant per arm and process (building one takes ~0.1 s)."""
    key = (spec.name, spec.model, tuple(spec.base), spec.q0)
    if key not in _KINEMATICS:
        _KINEMATICS[key] = ArmKinematics(spec)
    return _KINEMATICS[key]
