"""Many small bound-constrained least-squares problems solved at once.

``min_x ½‖r(x)‖²`` subject to ``lo ≤ x ≤ hi`` for a batch of P problems of the same size:
Levenberg–Marquardt steps (Marquardt's scaling by the diagonal of JᵀJ) restricted to the
variables not held at a bound by the gradient, projected onto the box; Jacobians by
forward differences in one batched call of the residuals. One call of a vectorised residual
serves every problem, where one solver per problem pays its overhead per problem.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["BatchFit", "forward_jacobian", "least_squares_batch"]

Residuals = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""``(points (B, R, n), problems (B,)) → (B, R, m)``: the residuals of problem
``problems[b]`` at each of its R points ``points[b]``."""


@dataclass(frozen=True)
class BatchFit:
    """Per problem: the solution ``x (P, n)``, its residuals ``fun (P, m)``, its cost
    ``½‖fun‖² (P,)`` and the iterations it took ``(P,)``."""

    x: np.ndarray
    fun: np.ndarray
    cost: np.ndarray
    iterations: np.ndarray


def forward_jacobian(residuals: Residuals, x: np.ndarray, r: np.ndarray, hi: np.ndarray,
                     problems: np.ndarray) -> np.ndarray:
    """``(B, m, n)`` forward differences of ``residuals`` of ``problems (B,)`` at ``x (B, n)``
    (residuals ``r (B, m)`` there) in one call, stepping down where a step up would leave
    ``hi (n,)``."""
    n = x.shape[1]
    h = 1e-7 * np.maximum(1.0, np.abs(x))
    h = np.where(x + h > hi, -h, h)
    points = x[:, None, :] + h[:, :, None] * np.eye(n)  # (B, n, n): row j steps x_j
    values = residuals(points, problems)  # (B, n, m)
    return np.swapaxes((values - r[:, None, :]) / h[:, :, None], 1, 2)


def least_squares_batch(residuals: Residuals, x0: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                        max_iterations: int = 100, xtol: float = 1e-10, ftol: float = 1e-8
                        ) -> BatchFit:
    """Solve the P problems of ``residuals`` from ``x0 (P, n)`` within ``lo, hi (n,)``.

    A problem stops when its accepted step is below ``xtol`` relative to ``x``, its cost
    falls by less than ``ftol`` relative to itself, or its damping grows past any use."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    x = np.clip(np.asarray(x0, dtype=float), lo, hi)
    P, n = x.shape
    every = np.arange(P)
    r = residuals(x[:, None, :], every)[:, 0]
    cost = 0.5 * np.einsum("pm,pm->p", r, r)
    damping = np.full(P, 1e-3)
    active = np.ones(P, dtype=bool)
    iterations = np.zeros(P, dtype=int)
    for _ in range(max_iterations):
        idx = np.flatnonzero(active)
        if not len(idx):
            break
        xa, ra = x[idx], r[idx]
        J = forward_jacobian(residuals, xa, ra, hi, idx)
        g = np.einsum("pmn,pm->pn", J, ra)
        # a variable at a bound that the gradient presses against stays there
        held = ((xa <= lo) & (g > 0)) | ((xa >= hi) & (g < 0))
        free = ~held
        Jf = J * free[:, None, :]
        H = np.einsum("pmi,pmj->pij", Jf, Jf)
        scale = np.maximum(np.einsum("pii->pi", H), 1e-12)
        A = H + (damping[idx, None] * scale)[:, :, None] * np.eye(n)
        A[:, np.arange(n), np.arange(n)] += held  # held variables: a zero step
        step = -np.linalg.solve(A, (g * free)[..., None])[..., 0]
        trial = np.clip(xa + step, lo, hi)
        rt = residuals(trial[:, None, :], idx)[:, 0]
        ct = 0.5 * np.einsum("pm,pm->p", rt, rt)
        better = ct < cost[idx]
        iterations[idx] += 1
        moved = np.linalg.norm(trial - xa, axis=1)
        small_step = moved <= xtol * (xtol + np.linalg.norm(xa, axis=1))
        small_gain = (cost[idx] - ct) <= ftol * np.maximum(cost[idx], 1e-300)
        took = idx[better]
        x[took], r[took], cost[took] = trial[better], rt[better], ct[better]
        damping[idx] = np.where(better, damping[idx] / 3.0, damping[idx] * 4.0)
        done = (better & (small_step | small_gain)) | (~better & small_step) \
            | (damping[idx] > 1e12)
        active[idx[done]] = False
    return BatchFit(x, r, cost, iterations)

