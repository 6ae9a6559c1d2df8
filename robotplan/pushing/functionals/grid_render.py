"""SDFs of posed bodies on the grid X_h with their tangents (∂φ/∂pose), as H_F needs them:
our C kernels for circles, boxes and L-shapes in float32, PyTorch otherwise."""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from robotplan.base.native import render_planes
from robotplan.functionals.base import sdf_pose_gradients
from robotplan.scene.bodies import Body
from robotplan.sdf import Circle, Workspace

__all__ = ["GridTangents", "grid_with_tangents", "render_on_grid"]


def grid_with_tangents(body: Body, X_WB: Tensor, points: Tensor, position_only: bool
                       ) -> tuple[Tensor, Tensor]:
    """φ of ``body`` at ``points (N, 2)`` for poses ``X_WB (S, 3|2)`` and dφ/dq
    (:func:`~robotplan.functionals.base.sdf_pose_gradients`, tangents first).

    Returns ``(S, N)`` values and ``(S, k, N)`` derivatives, k = 2 (x, y) for a
    position-only body, else 3 (x, y, yaw).
    """
    phi, d_pose, _ = sdf_pose_gradients(body, points, X_WB, position_only)
    return phi, (d_pose[..., :2] if position_only else d_pose).movedim(-1, 1)


@dataclass(frozen=True)
class GridTangents:
    """dφ/dq of a body rendered on the grid, kept factored (nothing per tangent is stored).

    With body-frame coordinates p = R(θ)ᵀ(x − c) and the body-frame gradient g = ∇φ(p):
    dφ/dc = −R g and dφ/dθ = g_x p_y − g_y p_x. :meth:`contract` needs only G·g_x and
    G·g_y and four sums, where the dense form is 3 planes and ~11 operations on them.
    """

    gx: Tensor  # (S, N) body-frame ∂φ/∂x
    gy: Tensor  # (S, N)
    dofs: int  # 2: position (x, y); 3: pose (x, y, yaw)
    px: Tensor | None = None  # (S, N) body-frame coordinates, for a turning body only
    py: Tensor | None = None
    cos: Tensor | None = None  # (S, 1)
    sin: Tensor | None = None

    def __getitem__(self, rows: slice) -> GridTangents:
        turning = [None if v is None else v[rows] for v in (self.px, self.py, self.cos, self.sin)]
        return GridTangents(self.gx[rows], self.gy[rows], self.dofs, *turning)

    def contract(self, G: Tensor) -> Tensor:
        """``Σ_n G[s, n] · dφ_s(x_n)/dq`` for ``G (S, N)`` → ``(S, dofs)``."""
        a, b = G * self.gx, G * self.gy
        A, B = a.sum(1), b.sum(1)
        if self.px is None:
            cols = [-A, -B] + ([torch.zeros_like(A)] if self.dofs == 3 else [])
            return torch.stack(cols, dim=1)
        c, s = self.cos[:, 0], self.sin[:, 0]
        turn = torch.linalg.vecdot(a, self.py) - torch.linalg.vecdot(b, self.px)
        return torch.stack((-(c * A - s * B), -(s * A + c * B), turn), dim=1)

    def dense(self) -> Tensor:
        """The tangent planes ``(S, dofs, N)`` (for checks; :meth:`contract` is cheaper)."""
        gx, gy = self.gx, self.gy
        if self.px is None:
            rows = [-gx, -gy] + ([torch.zeros_like(gx)] if self.dofs == 3 else [])
            return torch.stack(rows, dim=1)
        c, s = self.cos, self.sin
        return torch.stack((-(c * gx - s * gy), -(s * gx + c * gy),
                            gx * self.py - gy * self.px), dim=1)


def render_on_grid(body: Body, X_WB: Tensor, workspace: Workspace, tangents: bool = True
                   ) -> tuple[Tensor, GridTangents | None]:
    """:func:`grid_with_tangents` on the workspace grid X_h, using its separable structure:
    a body-frame coordinate is the sum of a term per column and a term per row, so the
    transform costs one broadcast add per coordinate. Returns φ ``(S, H·W)`` and its
    :class:`GridTangents` (k = 2 for positions ``(S, 2)``, else 3, 0 along yaw for a disc);
    no tangents if not asked.
    """
    X = X_WB.detach()
    x0, _, y0, _ = workspace.bounds
    rows, cols = workspace.shape
    r = workspace.resolution
    turns = X.shape[-1] == 3 and not isinstance(body.shape, Circle)
    if turns:
        c, s = torch.cos(X[:, 2:3]), torch.sin(X[:, 2:3])
    # our own kernel (float32 circles, boxes, L-shapes): one pass, far faster
    # (measured: docs/experiments.md#native-kernels)
    native = render_planes(body.shape.kernel_shape, X, torch.cat((c, s), 1) if turns else None,
                           (x0, y0), r, (rows, cols), coordinates=tangents)
    if native is not None:
        phi, gx, gy, px, py = native
        if not tangents:
            return phi, None
        if not turns:
            return phi, GridTangents(gx, gy, X.shape[-1])
        return phi, GridTangents(gx, gy, 3, px, py, c, s)
    dx = x0 + (torch.arange(cols, dtype=X.dtype) + 0.5) * r - X[:, 0:1]  # (S, W)
    dy = y0 + (torch.arange(rows, dtype=X.dtype) + 0.5) * r - X[:, 1:2]  # (S, H)
    if turns:
        px = (c * dx)[:, None, :] + (s * dy)[:, :, None]  # (S, H, W)
        py = (c * dy)[:, :, None] - (s * dx)[:, None, :]
    else:
        px, py = torch.broadcast_tensors(dx[:, None, :], dy[:, :, None])
    if not tangents:
        return body.shape.sdf(torch.stack((px, py), dim=-1)).flatten(1), None
    phi, gx, gy = body.shape.sdf_and_grad_planes(px.contiguous(), py.contiguous())
    gx, gy = gx.flatten(1), gy.flatten(1)
    if not turns:
        return phi.flatten(1), GridTangents(gx, gy, X.shape[-1])
    return phi.flatten(1), GridTangents(gx, gy, 3, px.flatten(1), py.flatten(1), c, s)
