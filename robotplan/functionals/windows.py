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

import torch
from torch import Tensor

from robotplan.scene.bodies import Body
from robotplan.sdf import Circle, Shape2D

__all__ = ["body_aabb", "margin", "window_points"]


def margin(a: float, eps: float = 1e-4) -> float:
    """Distance beyond which σ(−a φ) < ε."""
    return math.log(1.0 / eps) / a


@lru_cache(maxsize=256)
def _outline(shape: Shape2D, dtype: torch.dtype) -> Tensor:
    return torch.as_tensor(shape.outline(), dtype=dtype)


def body_aabb(body: Body, X_WB: Tensor) -> tuple[Tensor, Tensor]:
    """Axis-aligned bounding boxes ``lo, hi (T, 2)`` of a body at poses ``X_WB (T, 3|2)``
    (differentiable almost everywhere in the poses)."""
    X = X_WB
    if isinstance(body.shape, Circle):
        r = body.shape.radius
        return X[:, :2] - r, X[:, :2] + r
    verts = _outline(body.shape, X.dtype)  # (V, 2) body frame
    yaw = X[:, 2:3] if X.shape[-1] == 3 else torch.zeros_like(X[:, :1])
    c, s = torch.cos(yaw), torch.sin(yaw)
    wx = c * verts[:, 0] - s * verts[:, 1] + X[:, 0:1]  # (T, V)
    wy = s * verts[:, 0] + c * verts[:, 1] + X[:, 1:2]
    return (torch.stack((wx.amin(1), wy.amin(1)), 1), torch.stack((wx.amax(1), wy.amax(1)), 1))


def _smoothstep(u: Tensor) -> Tensor:
    u = u.clamp(0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def window_points(lo: Tensor, hi: Tensor, resolution: float, taper: float = 0.0
                  ) -> tuple[Tensor, Tensor]:
    """Lattice cell centres ``(i + ½) h`` inside each window ``[lo_t, hi_t]``.

    Returns points ``(T, P, 2)`` and weights ``(T, P)``: h² times, with ``taper`` > 0, a
    C¹ ramp from 0 on the window's edge to 1 at ``taper`` inside it (separable, so it costs
    one ramp per lattice row and column); 0 for padding and for empty windows. The lattice
    is chosen from the detached bounds; the ramp follows ``lo``/``hi`` with their gradients,
    so that the windowed integral is continuous as points enter and leave. P is the
    largest window's point count.
    """
    h = resolution
    lo_d, hi_d = lo.detach(), hi.detach()
    i0 = torch.floor(lo_d / h)  # first cell index per axis
    n = (torch.ceil(hi_d / h) - i0).clamp_min(0).long()  # (T, 2) cells per axis
    n[(hi_d <= lo_d).any(dim=1)] = 0
    T = lo.shape[0]
    nx, ny = (int(n[:, 0].max()), int(n[:, 1].max())) if T else (0, 0)
    ix = torch.arange(max(nx, 1), dtype=lo.dtype)
    iy = torch.arange(max(ny, 1), dtype=lo.dtype)
    gx = (i0[:, 0:1] + ix + 0.5) * h  # (T, nx)
    gy = (i0[:, 1:2] + iy + 0.5) * h  # (T, ny)
    wx = (ix < n[:, 0:1]).to(lo.dtype) * h
    wy = (iy < n[:, 1:2]).to(lo.dtype) * h
    if taper > 0:
        wx = wx * _smoothstep((gx - lo[:, 0:1]) / taper) * _smoothstep((hi[:, 0:1] - gx) / taper)
        wy = wy * _smoothstep((gy - lo[:, 1:2]) / taper) * _smoothstep((hi[:, 1:2] - gy) / taper)
    pts = torch.stack(torch.broadcast_tensors(gx[:, None, :], gy[:, :, None]), dim=-1)
    return pts.reshape(T, -1, 2), (wy[:, :, None] * wx[:, None, :]).reshape(T, -1)
