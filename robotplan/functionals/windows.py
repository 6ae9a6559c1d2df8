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


@lru_cache(maxsize=256)
def _outline(shape: Shape2D, dtype: torch.dtype) -> Tensor:
    return torch.as_tensor(shape.outline(), dtype=dtype)


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
    verts = _outline(body.shape, X.dtype)  # (V, 2) body frame
    yaw = X[:, 2:3] if k == 3 else torch.zeros_like(X[:, :1])
    c, s = torch.cos(yaw), torch.sin(yaw)
    rx = c * verts[:, 0] - s * verts[:, 1]  # (T, V) rotated, not yet translated
    ry = s * verts[:, 0] + c * verts[:, 1]
    W = torch.stack((rx, ry), dim=1) + X[:, :2, None]  # (T, 2, V) world vertices
    lo, hi = W.amin(2), W.amax(2)
    if not jacobians:
        return lo, hi
    eye = torch.eye(2, k, dtype=X.dtype).expand(T, 2, k)
    if k == 2:  # a shape held at yaw 0
        return lo, hi, eye, eye
    # ∂(vertex)/∂yaw = (−ry, rx); vertices tied for an extreme share it, as autograd's
    # amin/amax do (e.g. a face parallel to the axis: the mean of the one-sided slopes)
    W, d_yaw = W.detach(), torch.stack((-ry, rx), dim=1).detach()  # (T, 2, V)
    bounds = torch.stack((lo, hi), dim=1).detach()  # (T, 2 bounds, 2 axes)
    tied = (W[:, None] == bounds[..., None]).to(X.dtype)  # (T, 2, 2, V)
    slope = (tied * d_yaw[:, None]).sum(-1) / tied.sum(-1)  # (T, 2, 2)
    J = torch.cat((eye[:, None, :, :2].expand(T, 2, 2, 2), slope[..., None]), dim=-1)
    return lo, hi, J[:, 0], J[:, 1]


def _smoothstep(u: Tensor) -> Tensor:
    u = u.clamp(0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def _smoothstep_slope(u: Tensor) -> Tensor:
    inside = (u > 0.0) & (u < 1.0)
    return torch.where(inside, 6.0 * u * (1.0 - u), torch.zeros_like(u))


class WindowFactors(NamedTuple):
    """The separable weights of :func:`window_points` (rows y, columns x) and their slopes
    with respect to the window's bounds: ``w (T, n)``, ``d_lo``, ``d_hi`` per axis."""

    wx: Tensor
    wy: Tensor
    wx_lo: Tensor
    wx_hi: Tensor
    wy_lo: Tensor
    wy_hi: Tensor


def window_bound_gradients(f: Tensor, factors: WindowFactors) -> tuple[Tensor, Tensor]:
    """∂(Σ_p f_p w_p)/∂lo and /∂hi ``(T, 2)`` for an integrand ``f (T, P)`` held fixed on
    the lattice of :func:`window_points` (the taper's part of the integral's gradient)."""
    F = f.reshape(f.shape[0], factors.wy.shape[1], factors.wx.shape[1])  # (T, ny, nx)
    Fx = torch.einsum("tyx,ty->tx", F, factors.wy)  # integrated over rows
    Fy = torch.einsum("tyx,tx->ty", F, factors.wx)
    d_lo = torch.stack(((Fx * factors.wx_lo).sum(1), (Fy * factors.wy_lo).sum(1)), dim=1)
    d_hi = torch.stack(((Fx * factors.wx_hi).sum(1), (Fy * factors.wy_hi).sum(1)), dim=1)
    return d_lo, d_hi


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
    slopes = []
    if taper > 0:
        ramps = []
        for g, w, axis in ((gx, wx, 0), (gy, wy, 1)):
            u_lo, u_hi = (g - lo[:, axis:axis + 1]) / taper, (hi[:, axis:axis + 1] - g) / taper
            r_lo, r_hi = _smoothstep(u_lo), _smoothstep(u_hi)
            ramps.append(w * r_lo * r_hi)
            if factors:
                slopes += [-w * _smoothstep_slope(u_lo.detach()) * r_hi.detach() / taper,
                           w * r_lo.detach() * _smoothstep_slope(u_hi.detach()) / taper]
        wx, wy = ramps
    elif factors:
        slopes = [torch.zeros_like(wx), torch.zeros_like(wx), torch.zeros_like(wy),
                  torch.zeros_like(wy)]
    pts = torch.stack(torch.broadcast_tensors(gx[:, None, :], gy[:, :, None]), dim=-1)
    weights = (wy[:, :, None] * wx[:, None, :]).reshape(T, -1)
    if factors:
        return pts.reshape(T, -1, 2), weights, WindowFactors(wx, wy, *slopes)
    return pts.reshape(T, -1, 2), weights
