"""H_coll, the pair-collision functional (paper §6.1, eq. 7)."""

from __future__ import annotations

import math

import torch
from torch import Tensor

from robotplan.functionals.base import Functional, Quadrature, sdf_pose_gradients
from robotplan.functionals.windows import body_aabb, margin, window_bound_gradients, window_points
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle

__all__ = ["Collision", "FixedCollision", "SweptClearance", "crossing_depth",
           "face_contact_overlap"]


class Collision(Functional):
    """H_coll(φ1, φ2) = ∫_X σ(−a φ1(x)) σ(−a φ2(x)) dx (eq. 7): the overlap area of two bodies,
    smoothed by a sigmoid of sharpness ``a`` (1/m; paper a = 500, so the edge is ~2 mm wide).

    ``residual(X_W1 (T, 3|2), X_W2 (T, 3|2)) → (T, 1)`` in m². It is ≈ 0 when the bodies are
    apart by more than the smoothing band and grows with the overlap.

    With a ``quadrature`` the integral runs over its points (e.g. the grid X_h). Without
    one (the fast path) each step integrates over the window where both sigmoids exceed
    ``eps`` (the overlap of the grown bounding boxes), at ``resolution`` (default
    1.5/a: 3 mm for a = 500; within 0.4 % of a 0.4 mm full grid for boxes, L-shapes and
    discs touching or overlapping, edges aligned with the lattice included); steps whose
    windows are empty cost nothing.
    """

    def __init__(self, body1: Body, body2: Body, quadrature: Quadrature | None = None,
                 a: float = 500.0, resolution: float | None = None, eps: float = 1e-4):
        self.body1, self.body2, self.quadrature, self.a = body1, body2, quadrature, a
        self.resolution = resolution or 1.5 / a
        self.margin = margin(a, eps)

    def residual(self, X_W1: Tensor, X_W2: Tensor) -> Tensor:
        if self.quadrature is not None:
            x = self.quadrature.points.to(X_W1)
            inside1 = torch.sigmoid(-self.a * self.body1.sdf(x, X_W1))  # (T, N)
            inside2 = torch.sigmoid(-self.a * self.body2.sdf(x, X_W2))
            return self.quadrature.integrate(inside1 * inside2)[:, None]
        lo, hi, active, _, _ = self._windows(X_W1, X_W2)
        out = torch.zeros(X_W1.shape[0], 1, dtype=X_W1.dtype)
        if len(active) == 0:
            return out + 0.0 * (X_W1.sum() + X_W2.sum())  # keeps the graph for autograd
        x, w = window_points(lo[active], hi[active], self.resolution, self.margin / 3)
        inside1 = torch.sigmoid(-self.a * self.body1.sdf(x, X_W1[active]))  # (A, P)
        inside2 = torch.sigmoid(-self.a * self.body2.sdf(x, X_W2[active]))
        return out.index_put((active,), (inside1 * inside2 * w).sum(1, keepdim=True))

    def _windows(self, X_W1: Tensor, X_W2: Tensor, jacobians: bool = False) -> tuple:
        """Each step's window ``lo, hi (T, 2)`` (the overlap of the bounding boxes grown by
        the margin), the steps where it is not empty, and the two bodies' own
        :func:`body_aabb` results."""
        box1 = body_aabb(self.body1, X_W1, jacobians)
        box2 = body_aabb(self.body2, X_W2, jacobians)
        lo = torch.maximum(box1[0], box2[0]) - self.margin
        hi = torch.minimum(box1[1], box2[1]) + self.margin
        return lo, hi, (hi > lo).all(dim=1).nonzero()[:, 0], box1, box2

    def jacobians(self, X_W1: Tensor, X_W2: Tensor) -> tuple[Tensor, list[Tensor]]:
        """The fast path's value and exact Jacobians ``(T, 1, k_i)`` without autograd: the
        sigmoids' slopes along ∂φ/∂X, plus the taper's slope where the window's bounds
        follow the bodies' extreme vertices."""
        if self.quadrature is not None:
            return super().jacobians(X_W1, X_W2)
        X1, X2 = X_W1.detach(), X_W2.detach()
        r = torch.zeros(X1.shape[0], 1, dtype=X1.dtype)
        J1 = torch.zeros(X1.shape[0], 1, X1.shape[1], dtype=X1.dtype)
        J2 = torch.zeros(X2.shape[0], 1, X2.shape[1], dtype=X1.dtype)
        lo, hi, active, box1, box2 = self._windows(X1, X2, jacobians=True)
        if len(active) == 0:
            return r, [J1, J2]
        A1, A2 = X1[active], X2[active]
        x, w, factors = window_points(lo[active], hi[active], self.resolution,
                                      self.margin / 3, factors=True)
        phi1, d1, _ = sdf_pose_gradients(self.body1, x, A1)
        phi2, d2, _ = sdf_pose_gradients(self.body2, x, A2)
        s1, s2 = torch.sigmoid(-self.a * phi1), torch.sigmoid(-self.a * phi2)
        f = s1 * s2
        fw = f * w
        r[active, 0] = fw.sum(1)
        slope1 = (-self.a) * (1.0 - s1) * fw  # ∂(f w)/∂φ1 = −a σ1 (1 − σ1) σ2 w
        slope2 = (-self.a) * (1.0 - s2) * fw
        g = torch.stack(window_bound_gradients(f, factors), dim=1)  # (A, lo/hi, axis)
        # which body sets each bound
        own1 = torch.stack((box1[0] >= box2[0], box1[1] <= box2[1]), dim=1)[active]
        for J, d, slope, box, own in ((J1, d1, slope1, box1, own1), (J2, d2, slope2, box2, ~own1)):
            J_bounds = torch.stack((box[2], box[3]), dim=1)[active]  # (A, lo/hi, axis, k)
            J[active, 0] = (torch.bmm(slope[:, None, :], d)[:, 0]
                            + ((g * own)[..., None] * J_bounds).sum((1, 2)))
        return r, [J1, J2]


class FixedCollision(Functional):
    """H_coll between a moving body and a fixed one (an obstacle at its scene pose):
    ``residual(X_W1 (T, 3|2)) → (T, 1)`` in m², :class:`Collision` with the second pose
    held."""

    def __init__(self, moving: Body, fixed: Body, a: float = 500.0) -> None:
        self.pair = Collision(moving, fixed, a=a)
        self.pose = torch.as_tensor(fixed.pose, dtype=torch.float64)

    def residual(self, X_W1: Tensor) -> Tensor:
        return self.pair(X_W1, self.pose.to(X_W1).expand(X_W1.shape[0], -1))


class SweptClearance(Functional):
    """The gap (m) between a body and a disc at ``samples`` points inside the disc's straight
    move: ``residual(X_WB (T, 3), x_prev (T, 2), x (T, 2)) → (T, samples)`` =
    φ_B(x_prev + s_j (x − x_prev)) − radius, s_j = j / (samples + 1).

    H_coll sees the planned states only; a pusher that follows a reach step in a straight line
    can pass through the object between two clear states (in pybullet it then drags the
    object along). The SDF's gradient is a unit vector everywhere, so a bound on this gap
    points out of the object even deep inside it, where H_coll's sigmoids are flat.
    """

    def __init__(self, body: Body, disc: Body, samples: int = 7) -> None:
        if not isinstance(disc.shape, Circle):
            raise ValueError("SweptClearance: the second body must be a disc (a pusher)")
        self.body, self.radius = body, disc.shape.radius
        self.s = torch.arange(1, samples + 1, dtype=torch.float64) / (samples + 1)

    def _points(self, x_prev: Tensor, x: Tensor) -> tuple[Tensor, Tensor]:
        """The sample points ``(T, S, 2)`` and their fractions s ``(1, S, 1)`` of the move."""
        s = self.s.to(x)[None, :, None]
        return x_prev[:, None, :2] + s * (x[:, None, :2] - x_prev[:, None, :2]), s

    def residual(self, X_WB: Tensor, x_prev: Tensor, x: Tensor) -> Tensor:
        return self.body.sdf(self._points(x_prev, x)[0], X_WB) - self.radius

    def jacobians(self, X_WB: Tensor, x_prev: Tensor, x: Tensor
                  ) -> tuple[Tensor, list[Tensor]]:
        """Gaps ``(T, S)`` and exact Jacobians from ∇φ (no autograd)."""
        points, s = self._points(x_prev.detach(), x.detach())
        phi, d_pose, d_point = sdf_pose_gradients(self.body, points, X_WB.detach())
        J_prev = torch.zeros(*phi.shape, x_prev.shape[1], dtype=phi.dtype)
        J_now = torch.zeros(*phi.shape, x.shape[1], dtype=phi.dtype)
        J_prev[..., :2] = (1.0 - s) * d_point
        J_now[..., :2] = s * d_point
        return phi - self.radius, [d_pose, J_prev, J_now]


def crossing_depth(body: Body, disc: Body, X_WB: Tensor, x_prev: Tensor, x: Tensor,
                   spacing: float, samples: int = 7) -> float:
    """How deep (m) a disc's straight moves ``x_prev → x`` ``(T, 2)`` cross ``body`` at
    ``X_WB`` ``(T, 3)`` (:class:`SweptClearance` at points ``spacing`` apart, at least
    ``samples`` per move); 0 where every move stays clear."""
    longest = float(torch.linalg.vector_norm(x - x_prev, dim=-1).max()) if len(x) else 0.0
    count = max(samples, math.ceil(longest / spacing))
    gaps = SweptClearance(body, disc, count)(X_WB, x_prev, x)
    return max(0.0, -float(gaps.min())) if gaps.numel() else 0.0


def face_contact_overlap(body: Body, a: float = 500.0, depth: float = 0.0) -> float:
    """H_coll (m²) between the disc ``body`` and a flat face it presses ``depth`` into: what
    touching itself costs. The sigmoids' tails make it
    large (a 2.7 cm disc touching a face: 0.49 cm² at a = 500), so a collision bound below
    it forbids the contact that H_PoC asks for."""
    if not isinstance(body.shape, Circle):
        raise ValueError("face_contact_overlap: defined for disc bodies (pushers, tips)")
    wall = Body("wall", "obstacle", Box((1.0, 1.0)), (0.0, 0.0, 0.0), 0.0, 1.0)
    X_wall = torch.zeros(1, 3, dtype=torch.float64)
    X_body = torch.tensor([[0.5 + body.shape.radius - depth, 0.0, 0.0]], dtype=torch.float64)
    return float(Collision(wall, body, a=a)(X_wall, X_body)[0, 0])
