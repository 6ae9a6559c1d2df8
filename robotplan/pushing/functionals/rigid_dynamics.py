"""H_q, the learned rigid-motion functional: how far a planned step of an object departs
from the step F_q predicts (paper app., eqs. 15, 17), evaluated for whole trajectories.

F_q reads φ1_{t−1}, φ2_{t−1}, φ2_t on X_h and predicts Δq_t = (Δx, Δy, Δα): a turn by Δα
about the pivot (the centroid of the object's footprint), then a shift of the pivot by
(Δx, Δy). With c_t the pivot of the planned pose q1_t (x, y, yaw), the residual of step t is

    r_t = (c_t − c_{t−1} − (Δx, Δy),  α_t − α_{t−1} − Δα),
    H_q,t = |r_t,xy|² + ρ² r_t,α²                                       (m²),

with ρ the footprint's radius of gyration about the pivot: H_q,t is then the mean squared
displacement between the footprint where the plan puts it and where F_q puts it (to first
order in the angle). The row is the same kind of number as H_F's mean squared SDF residual,
and plays the same part in a program (:mod:`robotplan.pushing.program.rows_dynamics`).

Gradients: the three grids of a step are rendered with their tangents
(:class:`~robotplan.pushing.functionals.grid_render.GridTangents`) and the gradient G of the
network's outputs with respect to the grid values is contracted with them. For an F_q on
grids (SDFs or occupancy), G comes without autograd through the grids: the small head is
differentiated by autograd, the encoder in reverse mode by hand
(:class:`~robotplan.pushing.models.encoder_passes.EncoderPasses`), one pass back per step. A
point-cloud F_q (:mod:`robotplan.models.pointnet`) is differentiated by autograd through
the whole model, the marching-squares vertices included: each vertex is the linear
interpolation of φ on a grid edge where φ changes sign, so G reaches only the grid points
of those edges (which edges they are is a discrete choice, with no gradient).

An object-frame F_q (``spec.frame == "object"``) reads its grids in the frame F_t of the
object at t − 1 (origin c_{t−1}, heading α_{t−1}): there φ1_{t−1} is the footprint's own SDF,
the same every step, and φ2 is the pusher's SDF at its pose relative to F_t,
u = R(α_{t−1})ᵀ(p2 − c_{t−1}). The predicted shift R(α_{t−1}) Δq_xy is turned back to the table.
The Jacobians then reach the object's state t − 1 through F_t: through u and through that
turn.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

from robotplan.pushing.functionals.grid_render import render_on_grid
from robotplan.pushing.models.folded_layer import FoldedLayer
from robotplan.pushing.models.rigid import RigidMotion, delta_in_frame
from robotplan.scene.bodies import Body

__all__ = ["RigidDynamics", "footprint_moments"]

MOMENT_CELL = 5e-4  # m: cell of the sampling that finds a footprint's centroid and ρ


def footprint_moments(body: Body, dtype: torch.dtype = torch.float64) -> tuple[Tensor, float]:
    """The body-frame centroid ``(2,)`` of ``body``'s footprint (φ < 0) and its radius of
    gyration ρ about it (m), from the SDF sampled on 0.5 mm cells."""
    r = body.shape.bound_radius
    n = max(8, math.ceil(2 * r / MOMENT_CELL))
    axis = (torch.arange(n, dtype=dtype) + 0.5) * (2 * r / n) - r
    points = torch.stack(torch.meshgrid(axis, axis, indexing="xy"), -1).reshape(-1, 2)
    inside = points[body.shape.sdf(points) < 0]
    if len(inside) == 0:
        return torch.zeros(2, dtype=dtype), r
    centre = inside.mean(0)
    rho = float(((inside - centre) ** 2).sum(1).mean().sqrt())
    return centre, rho


def _turn(v: Tensor, yaw: Tensor) -> Tensor:
    """R(yaw_t) v_t row by row: ``v (T, 2)``, ``yaw (T,)`` → ``(T, 2)``."""
    c, s = torch.cos(yaw), torch.sin(yaw)
    return torch.stack((c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]), 1)


def _rotate(yaw: Tensor, v: Tensor) -> tuple[Tensor, Tensor]:
    """R(yaw) v and dR/dyaw v for ``yaw (S,)`` and a body-frame vector ``v (2,)``."""
    c, s = torch.cos(yaw), torch.sin(yaw)
    rotated = torch.stack((c * v[0] - s * v[1], s * v[0] + c * v[1]), 1)
    turned = torch.stack((-s * v[0] - c * v[1], c * v[0] - s * v[1]), 1)
    return rotated, turned


class RigidDynamics:
    """H_q between an object (φ1, planar pose) and a pusher (φ2: a disc's position or an
    object's pose) for T steps, for an F_q with the joint encoder, on grids or on point
    clouds (see the module docstring), with the interface of
    :class:`~robotplan.pushing.functionals.dynamics.LearnedDynamics`:

    ``evaluate(X1 (T+1, 3), X2 (T+1, d))`` → ``H (T,)`` (m²), ``J1 (T, 2, 3)`` and
    ``J2 (T, 2, d)``: row t holds ∂H_t/∂(state t−1) in ``[:, 0]`` and ∂H_t/∂(state t) in
    ``[:, 1]``.
    """

    integral = False  # H is a mean squared displacement, not an integral over the table

    def __init__(self, model: RigidMotion, obj: Body, pusher: Body) -> None:
        if model.spec.encoder != "joint":
            raise ValueError("H_q needs an F_q with the joint encoder (spec.encoder 'joint')")
        self.model, self.obj, self.pusher = model.eval(), obj, pusher
        for p in model.parameters():
            p.requires_grad_(False)
        spec = model.spec
        self.workspace = spec.workspace()
        self.dtype = next(model.parameters()).dtype
        self.centre, self.rho = footprint_moments(obj, self.dtype)
        self.frame = spec.frame
        if self.frame == "object":  # φ1_{t−1} in the object's frame: its footprint's SDF
            at_origin = torch.cat((-self.centre, torch.zeros(1, dtype=self.dtype)))[None]
            self.phi1_window = render_on_grid(obj, at_origin, self.workspace, False)[0]
        self.folded = None  # a point-cloud F_q: autograd through the whole model
        if spec.representation != "pointcloud":
            # the encoder's linear layer and the head's first layer folded into one map
            self.folded = FoldedLayer(model.encoder.linear, model.head[0], spec.channels[-1])
            self.rest = model.head[1:]  # ReLU, then the remaining layers

    def predict(self, X1: Tensor, X2: Tensor) -> Tensor:
        """F_q's Δq ``(T, 3)`` in the table frame for every step of the trajectories (no
        gradients)."""
        X1, X2 = X1.to(self.dtype), X2.to(self.dtype)
        if self.frame == "object":
            return delta_in_frame(self._forward_in_object_frame(X1, X2, False)[0], X1[:-1, 2])
        return self._forward(X1, X2, False)[0]

    def _forward(self, X1: Tensor, X2: Tensor, tangents: bool):
        """Δq ``(T, 3)``; the map ``g (T, 3) ↦ G (T, 3, H·W)``, the gradient of Σ g · (the
        network's outputs) with respect to the grids (to be called only with
        ``tangents``); and the grids' tangents."""
        phi1, dphi1 = render_on_grid(self.obj, X1[:-1], self.workspace, tangents)
        phi2, dphi2 = render_on_grid(self.pusher, X2, self.workspace, tangents)
        delta, grid_gradient = self._passes(phi1, phi2[:-1], phi2[1:], tangents)
        return delta, grid_gradient, dphi1, dphi2

    def _forward_in_object_frame(self, X1: Tensor, X2: Tensor, tangents: bool):
        """As :meth:`_forward` on the grids of F_t (see the module docstring): Δq ``(T, 3)``
        in F_t, the map to G, the pusher's poses relative to F_t at t − 1 and at t
        (``(2T, d)``, the steps' t − 1 first) and their grids' tangents."""
        T = X1.shape[0] - 1
        yaw = X1[:-1, 2]
        origin = X1[:-1, :2] + _rotate(yaw, self.centre)[0]
        relative = []
        for X in (X2[:-1], X2[1:]):
            u = _turn(X[:, :2] - origin, -yaw)
            relative.append(u if X.shape[1] == 2 else torch.cat((u, X[:, 2:] - yaw[:, None]), 1))
        relative = torch.cat(relative)
        phi2, dphi2 = render_on_grid(self.pusher, relative, self.workspace, tangents)
        delta, grid_gradient = self._passes(self.phi1_window.expand(T, -1), phi2[:T], phi2[T:],
                                            tangents)
        return delta, grid_gradient, relative, dphi2

    def _passes(self, phi1: Tensor, phi2_prev: Tensor, phi2_now: Tensor, tangents: bool):
        """F_q on the three grids ``(T, H·W)`` of each step: Δq and the map to G."""
        T = phi1.shape[0]
        images = torch.stack((phi1, phi2_prev, phi2_now), 1).reshape(T, 3,
                                                                      *self.workspace.shape)
        if self.folded is None:
            delta, grid_gradient = self._cloud_pass(images, tangents)
        else:
            delta, grid_gradient = self._grid_pass(images)
        return delta, grid_gradient

    def _grid_pass(self, images: Tensor):
        """F_q on grids: the last convolution's live channels, flattened, through the
        folded map; G by the head's autograd and the encoder's pass back by hand."""
        y, acts = self.model.encode_with_activations(images, linear=False)
        hidden, rows = self.folded(y, acts.live[-1])  # (T, H1) before the first ReLU
        with torch.no_grad():
            delta = self.rest(hidden) * self.model.scale

        def grid_gradient(g_out: Tensor) -> Tensor:
            with torch.enable_grad():
                h = hidden.detach().requires_grad_(True)
                (g_hidden,) = torch.autograd.grad(self.rest(h), h, g_out)
            return self.model.encoder_input_grad(acts, g_hidden @ rows.T,
                                                 linear=False).flatten(2)

        return delta, grid_gradient

    def _cloud_pass(self, images: Tensor, tangents: bool):
        """A point-cloud F_q: G by autograd through the whole model, the clouds' vertices
        included (see the module docstring)."""
        model = self.model
        with torch.set_grad_enabled(tangents):
            grids = images.detach().requires_grad_(tangents)
            out = model.head(model.features(grids))
        delta = out.detach() * model.scale

        def grid_gradient(g_out: Tensor) -> Tensor:
            return torch.autograd.grad(out, grids, g_out)[0].flatten(2)

        return delta, grid_gradient

    def _residual(self, X1: Tensor, shift: Tensor, turn: Tensor, jacobian: bool):
        """H_q ``(T,)`` of the planned poses ``X1 (T+1, 3)`` against the predicted steps
        (table-frame ``shift (T, 2)`` of the pivot, ``turn (T,)``) and, with ``jacobian``,
        ∂H/∂r (``g_xy (T, 2)``, ``g_a (T,)``) and the explicit terms of ∂H/∂(state t − 1)
        and ∂H/∂(state t) through the pivots and angles (``(T, 3)`` each)."""
        pivot_offset, turned = _rotate(X1[:, 2], self.centre)  # R c and dR/dα c, (T+1, 2)
        pivots = X1[:, :2] + pivot_offset
        r_xy = pivots[1:] - pivots[:-1] - shift  # (T, 2)
        r_a = X1[1:, 2] - X1[:-1, 2] - turn  # (T,)
        rho2 = self.rho ** 2
        H = (r_xy * r_xy).sum(1) + rho2 * r_a * r_a
        if not jacobian:
            return H, None
        g_xy, g_a = 2.0 * r_xy, 2.0 * rho2 * r_a  # ∂H/∂r
        now = torch.cat((g_xy, ((g_xy * turned[1:]).sum(1) + g_a)[:, None]), 1)
        prev = -torch.cat((g_xy, ((g_xy * turned[:-1]).sum(1) + g_a)[:, None]), 1)
        return H, (g_xy, g_a, prev, now)

    def evaluate(self, X1: Tensor, X2: Tensor, jacobian: bool = True
                 ) -> tuple[Tensor, Tensor | None, Tensor | None]:
        X1, X2 = X1.to(self.dtype), X2.to(self.dtype)
        if self.frame == "object":
            return self._evaluate_in_object_frame(X1, X2, jacobian)
        delta, grid_gradient, dphi1, dphi2 = self._forward(X1, X2, jacobian)  # Δq (T, 3)
        H, explicit = self._residual(X1, delta[:, :2], delta[:, 2], jacobian)
        if not jacobian:
            return H, None, None
        g_xy, g_a, prev, now = explicit
        # through F_q: ∂H/∂Δq = −(g_xy, g_a), times the scale: ∂H/∂(the network's outputs)
        g_delta = -torch.cat((g_xy, g_a[:, None]), 1) * self.model.scale
        G = grid_gradient(g_delta)  # (T, 3, H·W)
        prev = prev + dphi1.contract(G[:, 0])
        J1 = torch.stack((prev, now), 1)
        J2 = torch.stack((dphi2[:-1].contract(G[:, 1]), dphi2[1:].contract(G[:, 2])), 1)
        return H, J1, J2

    def _evaluate_in_object_frame(self, X1: Tensor, X2: Tensor, jacobian: bool
                                  ) -> tuple[Tensor, Tensor | None, Tensor | None]:
        """:meth:`evaluate` for an object-frame F_q (see the module docstring)."""
        T = X1.shape[0] - 1
        delta, grid_gradient, relative, dphi2 = self._forward_in_object_frame(X1, X2, jacobian)
        yaw = X1[:-1, 2]
        shift = _turn(delta[:, :2], yaw)  # R(α_{t−1}) Δq_xy, (T, 2)
        H, explicit = self._residual(X1, shift, delta[:, 2], jacobian)
        if not jacobian:
            return H, None, None
        g_xy, g_a, prev, now = explicit
        # the shift turns with F_t: ∂(−g · R(α) d)/∂α = −g · (−shift_y, shift_x)
        prev[:, 2] += g_xy[:, 0] * shift[:, 1] - g_xy[:, 1] * shift[:, 0]
        # through F_q: ∂H/∂Δq_xy = −R(α)ᵀ g_xy, ∂H/∂Δα = −g_a; times the outputs' scale
        g_delta = -torch.cat((_turn(g_xy, -yaw), g_a[:, None]), 1)
        G = grid_gradient(g_delta * self.model.scale)  # (T, 3, H·W); φ1's grid is fixed
        d2 = X2.shape[1]
        J2 = []
        for k, which in ((0, slice(0, T)), (1, slice(T, 2 * T))):
            a = dphi2[which].contract(G[:, 1 + k])  # ∂H/∂(the pusher's pose in F_t), (T, d)
            u = relative[which, :2] + self.centre  # R(α)ᵀ(p2 − p1)
            a_xy = _turn(a[:, :2], yaw)
            # u = R(α)ᵀ(p2 − p1) − c: ∂u/∂p2 = R(α)ᵀ, ∂u/∂p1 = −R(α)ᵀ, ∂u/∂α = (u_y, −u_x)
            prev[:, :2] -= a_xy
            prev[:, 2] += a[:, 0] * u[:, 1] - a[:, 1] * u[:, 0]
            if d2 == 3:  # the pusher's heading in F_t is its own less α_{t−1}
                prev[:, 2] -= a[:, 2]
            J2.append(torch.cat((a_xy, a[:, 2:]), 1) if d2 == 3 else a_xy)
        return H, torch.stack((prev, now), 1), torch.stack(J2, 1)
