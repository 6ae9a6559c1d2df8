"""Analytic pieces of a push, beside the learned dynamics.

A kinematic model of a quasi-static push, used to warm-start the learned program: the
contact point sticks to the object (:class:`StickingContact`) and the pusher moves into the
object, never pulls it (:class:`PushingDirection`). Cheap, exact gradients, no physics; the
learned H_F (eq. 5) decides the real motion afterwards. :class:`PushLever` prefers pushes
whose line of force passes through the object's centroid: they translate the object with
little turning, the motions the model predicts best and that open-loop execution repeats.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor

from robotplan.functionals.base import Functional
from robotplan.sdf.footprint import support_corners

__all__ = ["PushLever", "PushingDirection", "QuasiStaticObjectPush", "QuasiStaticPush",
           "StickingContact", "centroid", "limit_surface_radius", "turning_radius"]


def centroid(outline: np.ndarray) -> np.ndarray:
    """Area centroid ``(2,)`` of a simple polygon ``(V, 2)`` (shoelace formula)."""
    x, y = outline[:, 0], outline[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = cross.sum() / 2
    return np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6 * area)


def limit_surface_radius(support_B: np.ndarray, centroid_B: np.ndarray) -> float:
    """Characteristic length ``c = m_max / f_max`` (m) of the ellipsoidal limit surface of an
    object resting on the points ``support_B (K, 2)`` with equal loads: their mean distance
    from the centroid."""
    return float(np.linalg.norm(np.asarray(support_B) - centroid_B, axis=1).mean())


def turning_radius(shape, turn_gain: float = 1.0) -> float:
    """The c of the turning law ``c² Δθ = r × Δc`` for ``shape`` with the gain g folded in
    (``c² Δθ = g · r × Δc`` ⟺ c' = c/√g): the limit surface radius of its support points
    (:func:`limit_surface_radius`) over √turn_gain."""
    c = limit_surface_radius(support_corners(shape), centroid(shape.outline()))
    return c / float(np.sqrt(turn_gain))


def _in_body_frame(X_WB: Tensor, p_W: Tensor) -> Tensor:
    """p_B = R(θ)ᵀ (p_W − o): ``X_WB (T, 3)``, ``p_W (T, 2)`` → ``(T, 2)``."""
    c, s = torch.cos(X_WB[:, 2]), torch.sin(X_WB[:, 2])
    d = p_W - X_WB[:, :2]
    return torch.stack((c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]), dim=-1)


class StickingContact(Functional):
    """The contact point does not slide on the object between two push steps.

    ``residual(X_WB_prev (T, 3), p_W_prev (T, 2), X_WB (T, 3), p_W (T, 2)) → (T, 2)`` in m:
    the contact point in the object frame B at t minus the same at t − 1.
    """

    def residual(self, X_prev: Tensor, p_prev: Tensor, X: Tensor, p: Tensor) -> Tensor:
        return _in_body_frame(X, p) - _in_body_frame(X_prev, p_prev)


class PushingDirection(Functional):
    """The pusher's step along the contact normal, ≥ 0 when it pushes.

    ``residual(x_prev (T, 2), x (T, 2), p_W (T, 2)) → (T, 1)`` in m: (x − x_prev) · n with
    n = (p − x)/|p − x| pointing from the pusher's centre x to the contact point p.
    """

    def residual(self, x_prev: Tensor, x: Tensor, p: Tensor) -> Tensor:
        n = p - x
        n = n / n.norm(dim=-1, keepdim=True).clamp_min(1e-9)
        return ((x - x_prev) * n).sum(-1, keepdim=True)


class PushLever(Functional):
    """Lever arm of the push about the object's centroid: the distance (m, signed) from the
    centroid to the line through the contact point p along the contact normal
    n = (p − x)/|p − x|.

    ``residual(X_WB (T, 3), x (T, 2), p_W (T, 2)) → (T, 1) = n × (c_W − p)`` with
    ``c_W = o + R(θ) c_B`` and ``c_B`` the centroid in the body frame.
    """

    def __init__(self, centroid_B: np.ndarray):
        self.c_B = torch.as_tensor(np.asarray(centroid_B, dtype=float))

    def residual(self, X_WB: Tensor, x: Tensor, p: Tensor) -> Tensor:
        c, s = torch.cos(X_WB[:, 2]), torch.sin(X_WB[:, 2])
        cB = self.c_B.to(X_WB)
        c_W = X_WB[:, :2] + torch.stack((c * cB[0] - s * cB[1], s * cB[0] + c * cB[1]), -1)
        n = p - x
        n = n / n.norm(dim=-1, keepdim=True).clamp_min(1e-9)
        d = c_W - p
        return (n[:, 0] * d[:, 1] - n[:, 1] * d[:, 0])[:, None]


class QuasiStaticPush(Functional):
    """Quasi-static pushing with a sticking point contact (ellipsoidal limit surface of
    characteristic length ``c``, pusher–object friction ``μ``): the object's centroid moves
    along the pushing force, which lies in the friction cone about the contact normal, and
    the object turns by the force's moment, ``c² Δθ = r × Δc``.

    ``residual(X_prev (T, 3), X (T, 3), x (T, 2), p_W (T, 2)) → (T, 3)``:
    ``[c Δθ − (r × Δc)/c (= 0), μ Δc·n − Δc × n (≥ 0), μ Δc·n + Δc × n (≥ 0)]`` in m
    with ``Δc`` the centroid's step, ``r = p − c_W`` and ``n = (p − x)/|p − x|``. Pushes
    outside this cone slide along the face and turn the object in pybullet in ways the
    sticking model (and often the learned H_F's tolerance) does not see. ``turn=False``
    keeps the two cone rows only, ``(T, 2)``.
    """

    def __init__(self, centroid_B: np.ndarray, radius: float, mu: float,
                 turn: bool = True) -> None:
        self.c_B = torch.as_tensor(np.asarray(centroid_B, dtype=float))
        self.c, self.mu, self.turn = radius, mu, turn

    def _centroid(self, X: Tensor) -> Tensor:
        c, s = torch.cos(X[:, 2]), torch.sin(X[:, 2])
        cB = self.c_B.to(X)
        return X[:, :2] + torch.stack((c * cB[0] - s * cB[1], s * cB[0] + c * cB[1]), -1)

    def residual(self, X_prev: Tensor, X: Tensor, x: Tensor, p: Tensor) -> Tensor:
        n = p - x
        return self._rows(X_prev, X, p, n / n.norm(dim=-1, keepdim=True).clamp_min(1e-9))

    def _rows(self, X_prev: Tensor, X: Tensor, p: Tensor, n: Tensor) -> Tensor:
        """The rows for a push at ``p (T, 2)`` along the unit normal ``n (T, 2)``."""
        c_W = self._centroid(X)
        d = c_W - self._centroid(X_prev)
        r = p - c_W
        turn = self.c * (X[:, 2] - X_prev[:, 2]) - (r[:, 0] * d[:, 1] - r[:, 1] * d[:, 0]) / self.c
        along = (d * n).sum(-1)
        across = d[:, 0] * n[:, 1] - d[:, 1] * n[:, 0]
        rows = (turn, self.mu * along - across, self.mu * along + across)
        return torch.stack(rows if self.turn else rows[1:], -1)


class QuasiStaticObjectPush(QuasiStaticPush):
    """:class:`QuasiStaticPush` of ``body`` by another object touching it at ``p``: the
    pushing normal is ``body``'s inward surface normal at p, −R(θ) ∇φ_B(p_B)/|∇φ_B|, its
    body-frame part held fixed in the derivatives (exact on a face, where it is constant).

    ``residual(X_prev (T, 3), X (T, 3), p_W (T, 2)) → (T, 3 | 2)`` as QuasiStaticPush.
    """

    def __init__(self, body, radius: float, mu: float, turn: bool = True) -> None:
        super().__init__(centroid(body.shape.outline()), radius, mu, turn)
        self.body = body

    def residual(self, X_prev: Tensor, X: Tensor, p: Tensor) -> Tensor:
        p_B = _in_body_frame(X, p).detach()
        _, gx, gy = self.body.shape.sdf_and_grad_planes(p_B[:, 0], p_B[:, 1])
        g = torch.stack((gx, gy), -1)
        g = g / g.norm(dim=-1, keepdim=True).clamp_min(1e-9)
        c, s = torch.cos(X[:, 2]), torch.sin(X[:, 2])
        n = -torch.stack((c * g[:, 0] - s * g[:, 1], s * g[:, 0] + c * g[:, 1]), -1)
        return self._rows(X_prev, X, p, n)

