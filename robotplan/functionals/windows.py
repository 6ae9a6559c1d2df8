"""Local quadrature windows for the analytic functionals (H_coll, H_g).

Their integrands vanish (to a tolerance ε) away from the bodies: σ(−aφ) < ε once
φ > ln(1/ε)/a. Each step therefore integrates only over a window (the intersection of the
bodies' bounding boxes, grown by that margin) with the midpoint rule on a lattice fixed in
the table frame, fine enough for the sigmoid edge. The lattice does not move with the
bodies; a smooth taper over the window's outer third (where the integrand is below ε^⅔)
brings every point's weight to zero on the window's edge, so the integral stays
continuous (and differentiable almost everywhere) as points enter and leave.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import torch
from torch import Tensor

from robotplan.scene.bodies import Body
from robotplan.sdf import Circle, Shape2D

__all__ = ["WindowFactors", "body_aabb", "margin", "window_bound_gradients", "window_points"]


def margin(a: float, eps: float = 1e-4) -> float:
    """Distance beyond which σ(−a φ) < ε."""
    return math.log(1.0 / eps) / a


@lru_cache(maxsize=8)
def _eye(dtype: torch.dtype) -> Tensor:
    return torch.eye(2, dtype=dtype)


@lru_cache(maxsize=256)
def _outline(shape: Shape2D, dtype: torch.dtype) -> Tensor:
    """The shape's outline vertices ``(2, V)`` (columns) in its frame."""
    return torch.as_tensor(shape.outline().T.copy(), dtype=dtype)


def body_aabb(body: Body, X_WB: Tensor, jacobians: bool = False
              ) -> tuple[Tensor, Tensor] | tuple[Tensor, Tensor, Tensor, Tensor]:
    """Axis-aligned bounding boxes ``lo, hi (T, 2)`` of a body at poses ``X_WB (T, 3|2)``
    (differentiable almost everywhere in the poses). ``jacobians=True`` also returns
    ∂lo/∂X_WB and ∂hi/∂X_WB ``(T, 2, k)`` (k = X_WB's width), for gradients without
    autograd: each bound follows its extreme vertex, a disc's its centre."""
    X = X_WB
    T, k = X.shape
    if isinstance(body.shape, Circle):
        r = body.shape.radius
        lo, hi = X[:, :2] - r, X[:, :2] + r
        if not jacobians:
            return lo, hi
        eye = torch.eye(2, k, dtype=X.dtype).expand(T, 2, k)
        return lo, hi, eye, eye
    verts = _outline(body.shape, X.dtype)  # (2, V) body frame
    if k == 2:  # a shape held at yaw 0
        W = verts + X[:, :, None]
        lo, hi = W.amin(2), W.amax(2)
        if not jacobians:
            return lo, hi
        eye = torch.eye(2, dtype=X.dtype).expand(T, 2, 2)
        return lo, hi, eye, eye
    yaw = X[:, 2]
    c, s = torch.cos(yaw), torch.sin(yaw)
    ns = -s
    # rows: R (rotated vertices) and ∂R/∂yaw (their yaw slopes (−ry, rx)), one product
    R = torch.stack((c, ns, s, c, ns, -c, c, ns), dim=1).view(T, 4, 2)
    rotated = R @ verts  # (T, 4, V)
    W = rotated[:, :2] + X[:, :2, None]  # (T, 2, V) world vertices
    lo, hi = W.amin(2), W.amax(2)
    if not jacobians:
        return lo, hi
    # vertices tied for an extreme share it, as autograd's amin/amax do (e.g. a face
    # parallel to the axis: the mean of the one-sided slopes)
    bounds = torch.stack((lo, hi), dim=1).detach()  # (T, 2 bounds, 2 axes)
    tied = W.detach()[:, None] == bounds[..., None]  # (T, 2, 2, V)
    slope = (tied * rotated[:, None, 2:].detach()).sum(-1) / tied.sum(-1)  # (T, 2, 2)
    J = torch.cat((_eye(X.dtype).expand(T, 2, 2, 2), slope[..., None]), dim=-1)
    return lo, hi, J[:, 0], J[:, 1]


class WindowFactors(NamedTuple):
    """The separable weights of :func:`window_points` and their slopes: per axis (x, y) the
    weights ``w (T, 2, m)`` of the lattice columns and rows and their derivatives
    ``slopes (T, 2, m, 2)`` with respect to the window's (lo, hi) bound on that axis; the
    first ``nx`` columns and ``ny`` rows are the lattice's."""

    w: Tensor
    slopes: Tensor
    nx: int
    ny: int


def window_bound_gradients(f: Tensor, factors: WindowFactors) -> tuple[Tensor, Tensor]:
    """∂(Σ_p f_p w_p)/∂lo and /∂hi ``(T, 2)`` for an integrand ``f (T, P)`` held fixed on
    the lattice of :func:`window_points` (the taper's part of the integral's gradient)."""
    nx, ny = factors.nx, factors.ny
    F = f.reshape(f.shape[0], ny, nx)  # (T, rows y, columns x)
    wx, wy = factors.w[:, 0, :nx, None], factors.w[:, 1, None, :ny]  # column, row
    d_x = torch.bmm(torch.bmm(wy, F), factors.slopes[:, 0, :nx])  # (T, 1, lo/hi)
    d_y = torch.bmm(torch.bmm(F, wx).mT, factors.slopes[:, 1, :ny])
    d = torch.cat((d_x, d_y), dim=1)  # (T, axis, lo/hi)
    return d[..., 0], d[..., 1]


def window_points(lo: Tensor, hi: Tensor, resolution: float, taper: float = 0.0,
                  factors: bool = False
                  ) -> tuple[Tensor, Tensor] | tuple[Tensor, Tensor, WindowFactors]:
    """Lattice cell centres ``(i + ½) h`` inside each window ``[lo_t, hi_t]``.

    Returns points ``(T, P, 2)`` and weights ``(T, P)``: h² times, with ``taper`` > 0, a
    C¹ ramp from 0 on the window's edge to 1 at ``taper`` inside it (separable, so it costs
    one ramp per lattice row and column); 0 for padding and for empty windows. The lattice
    is chosen from the detached bounds; the ramp follows ``lo``/``hi`` with their gradients,
    so that the windowed integral is continuous as points enter and leave. P is the
    largest window's point count. ``factors=True`` also returns the
    :class:`WindowFactors` (for gradients without autograd).
    """
    h, T = resolution, lo.shape[0]
    lo_d, hi_d = lo.detach(), hi.detach()
    i0 = torch.floor(lo_d / h)  # (T, 2) first cell index per axis
    # cells per axis; none on an empty axis (or a NaN bound: the NaN then reaches the sum)
    n = torch.where(hi_d > lo_d, torch.ceil(hi_d / h) - i0, 0.0)
    nx, ny = (max(int(v), 1) for v in n.amax(0).tolist()) if T else (1, 1)
    index = torch.arange(max(nx, ny), dtype=lo.dtype)
    g = (i0[..., None] + index + 0.5) * h  # (T, 2, m) cell centres per axis
    w = (index < n[..., None]).to(lo.dtype) * h
    slopes = None
    if taper > 0:
        u = (torch.stack((g - lo[..., None], hi[..., None] - g)) / taper).clamp(0.0, 1.0)
        ramp = u * u * (3.0 - 2.0 * u)  # (lo/hi side, T, 2, m) smoothstep
        if factors:
            slope = (6.0 / taper) * u.detach() * (1.0 - u.detach())  # 0 where clamped
            ramp_d = ramp.detach()
            slopes = torch.stack((-w * slope[0] * ramp_d[1], w * ramp_d[0] * slope[1]), dim=-1)
        w = w * ramp[0] * ramp[1]
    elif factors:
        slopes = torch.zeros(*w.shape, 2, dtype=lo.dtype)
    gx, gy = g[:, 0, :nx], g[:, 1, :ny]
    pts = torch.stack(torch.broadcast_tensors(gx[:, None, :], gy[:, :, None]), dim=-1)
    weights = (w[:, 1, :ny, None] * w[:, 0, None, :nx]).reshape(T, -1)
    if factors:
        return pts.reshape(T, -1, 2), weights, WindowFactors(w, slopes, nx, ny)
    return pts.reshape(T, -1, 2), weights
