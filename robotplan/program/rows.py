"""Rows of a program in Drake's terms: stepwise constraints and costs through the torch
bridge, linear holds, bounds and finite differences (:class:`ProgramRows`)."""

from __future__ import annotations

import numpy as np

from robotplan.program.bridge import bridge, stepwise, stepwise_sparsity
from robotplan.program.row_table import RowSpec, row_spec

__all__ = ["ProgramRows"]


class ProgramRows:
    """Helpers of a program that has ``prog`` (a ``MathematicalProgram``), ``settings``,
    ``timings``, ``N`` states after the start and ``push_steps``."""

    @staticmethod
    def spec(row: str) -> RowSpec:
        """The row ``row`` of the row table (its scale, its constants' names)."""
        return row_spec(row)

    def _hold(self, Q: np.ndarray, t: int) -> None:
        """Pose row t of ``Q`` equals row t − 1."""
        d = Q.shape[1]
        self.prog.AddLinearEqualityConstraint(np.hstack((np.eye(d), -np.eye(d))), np.zeros(d),
                                              np.concatenate((Q[t], Q[t - 1])))

    def _bound_to_workspace(self, *arrays: np.ndarray) -> None:
        """Every row ``(x, y)`` of the variable arrays on the table."""
        x0, x1, y0, y1 = self.scene.workspace.bounds
        for Q in arrays:
            if Q.size:
                self.prog.AddBoundingBoxConstraint(np.tile([x0, y0], (Q.shape[0], 1)).ravel(),
                                                   np.tile([x1, y1], (Q.shape[0], 1)).ravel(),
                                                   Q.ravel())

    def _add_motion_cost(self, Q: np.ndarray) -> None:
        """``object_motion.weight`` · Σ_t |Δq_t|² of poses ``Q`` (yaw in
        ``object_motion.turn_length`` m)."""
        w = self.settings.row("object_motion").weight
        scale = np.array([1.0, 1.0, self.settings.row("object_motion").turn_length])
        D = np.hstack((np.diag(scale), -np.diag(scale)))
        for t in range(1, self.N + 1):
            self.prog.AddQuadraticCost(2 * w * D.T @ D, np.zeros(6),
                                       np.concatenate((Q[t], Q[t - 1])), is_convex=True)

    def _limit_steps(self, Q: np.ndarray, steps: np.ndarray, limits: list[float]) -> None:
        """|Q[t] − Q[t − 1]| ≤ ``limits`` per column for every t of ``steps`` (linear)."""
        d, n = len(limits), len(steps)
        D = np.zeros((d * n, d * (self.N + 1)))
        for i, t in enumerate(steps):
            for k in range(d):
                D[d * i + k, d * t + k], D[d * i + k, d * (t - 1) + k] = 1.0, -1.0
        lim = np.tile(limits, n)
        self.prog.AddLinearConstraint(D, -lim, lim, Q.ravel())

    def _add_step_limits(self, step: float, turn: float) -> None:
        """Pusher travel per push step and axis ≤ ``step`` (m; the speeds of the push data)
        and object rotation per push step ≤ ``turn`` (rad). Reach steps move through free
        space and are not limited (a bound there changes SNOPT's path: the swept clearance
        checks long moves after the solve instead)."""
        if len(self.push_steps):
            self._limit_steps(self.Q2, self.push_steps, [step] * 2)
            self._limit_steps(self.Q1[:, 2:], self.push_steps, [turn])

    def _add_rows(self, H, blocks: list[np.ndarray], m: int, scale: float,
                  bounds: tuple[float | np.ndarray, float | np.ndarray], name: str) -> None:
        """Constraint lb ≤ scale · H(row t) ≤ ub (m residuals each) for every row t of the
        variable blocks, ``bounds = (lb, ub)``: scalars, one per row ``(n,)`` or one per
        residual ``(1, m)``."""
        fn, variables = stepwise(H, blocks, scale)
        n = blocks[0].shape[0]
        lb, ub = (np.broadcast_to(b[:, None] if b.ndim == 1 else b, (n, m)).ravel()
                  for b in (np.asarray(bound, dtype=float) for bound in bounds))
        binding = self.prog.AddConstraint(bridge(fn, self.timings, name), lb, ub, variables,
                                          name)
        if self.settings.sparse_jacobians:
            binding.evaluator().SetGradientSparsityPattern(stepwise_sparsity(fn, m))

    def _add_cost(self, total, variables: np.ndarray, name: str) -> None:
        """A scalar cost ``total(x, jac) → ((1,), J (1, n) | None)`` on ``variables``."""
        bridged = bridge(total, self.timings, name)
        self.prog.AddCost(lambda x: bridged(x)[0], variables, description=name)
