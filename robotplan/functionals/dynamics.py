"""H_F, the learned-dynamics functional (paper eq. 5), evaluated fast for whole trajectories.

H_F(φ1_{t−1:t}, φ2_{t−1:t}) = ∫_X (φ1_t(x) − F(φ1_{t−1}, φ2_{t−1}, φ2_t)(x))² dx, with
F(…)(x) = φ1_{t−1}(x) + F_flow(…)(x) for the flow model (eq. 4).

The fast path (:meth:`LearnedDynamics.evaluate`) computes what the naive path computes
(:meth:`LearnedDynamics.evaluate_naive`: every step on its own, all 19,600 grid points
through the whole network, autograd) in far less time:

* **one encoding per state**: φ1_s(X_h) and φ2_s(X_h) are rendered and encoded once per
  state s and shared by the neighbouring steps (2T + 1 encodings for T steps, not 3T);
* **forward-mode Jacobians of the encoder**: the tangent grids dφ/dq (exact, from ∇φ;
  3 per object grid, 2 per pusher grid) go through the piecewise-linear encoder with the
  primal's ReLU masks, in one batch (a tangent pass costs ~1/2.5 of a reverse pass here);
* **split first layer**: the SDF part is one (600 → 300) product per step, the point part
  (100 → 300) is computed once for the fixed quadrature points;
* **fewer quadrature points**: a :class:`~robotplan.functionals.Quadrature` of the
  caller's choice (see :func:`phase_quadrature`), instead of the 140 × 140 grid;
* **exact sparse Jacobians**: per step, ∂H_t/∂q1_{t−1}, ∂q1_t, ∂q2_{t−1}, ∂q2_t from one
  backward pass through the head (each step's inputs are separate leaves).

The quadrature error against the full-grid integral and the timings are measured by
``robotplan bench functional`` (numbers in its docstring and the project notes).
"""

from __future__ import annotations

import torch
from torch import Tensor

from robotplan.functionals.base import Quadrature
from robotplan.learned.dynamics import PushDynamics
from robotplan.scene.bodies import Body
from robotplan.sdf import Workspace
from robotplan.transforms import planar_to_body

__all__ = ["LearnedDynamics", "grid_with_tangents", "phase_quadrature"]


def grid_with_tangents(body: Body, X_WB: Tensor, points: Tensor, position_only: bool
                       ) -> tuple[Tensor, Tensor]:
    """φ of ``body`` at ``points (N, 2)`` for poses ``X_WB (S, 3|2)`` and dφ/dq.

    Returns ``(S, N)`` values and ``(S, k, N)`` derivatives, k = 2 (x, y) for a
    position-only body, else 3 (x, y, yaw). Exact: from ∇φ in the body frame,
    dφ/dt = −R ∇φ_B and dφ/dθ = ∇φ_B · (p_B,y, −p_B,x).
    """
    p_B = planar_to_body(points, X_WB.detach())  # (S, N, 2)
    phi, g = body.shape.sdf_and_grad(p_B)
    gx, gy = g[..., 0], g[..., 1]
    if position_only or X_WB.shape[-1] == 2:
        return phi, torch.stack((-gx, -gy), dim=1)
    c, s = torch.cos(X_WB[:, 2:3]), torch.sin(X_WB[:, 2:3])
    d_theta = gx * p_B[..., 1] - gy * p_B[..., 0]
    return phi, torch.stack((-(c * gx - s * gy), -(s * gx + c * gy), d_theta), dim=1)


def phase_quadrature(centers: Tensor, radius: float, workspace: Workspace, fine: float = 0.04,
                     coarse: float = 0.14, dtype: torch.dtype = torch.float32) -> Quadrature:
    """A fixed two-level midpoint rule for one phase: ``fine`` spacing within ``radius`` of
    any of the ``centers (C, 2)`` (e.g. the object's positions in the initial guess),
    ``coarse`` spacing over the rest of the workspace. The fine cells tile the coarse cells
    they replace, so the weights still sum to the workspace area."""
    ratio = round(coarse / fine)
    fine = coarse / ratio
    big = Workspace(workspace.center, workspace.size, coarse).points(torch.float64).reshape(-1, 2)
    # a coarse cell is refined when any part of it (half-diagonal ≈ 0.707·coarse) is near
    near = torch.cdist(big, centers.double()).amin(dim=1) <= radius + coarse * 0.7072
    offs = (torch.arange(ratio, dtype=torch.float64) + 0.5) * fine - coarse / 2
    oy, ox = torch.meshgrid(offs, offs, indexing="ij")
    sub = torch.stack((ox, oy), dim=-1).reshape(-1, 2)
    fine_pts = (big[near][:, None, :] + sub[None]).reshape(-1, 2)
    pts = torch.cat((big[~near], fine_pts))
    w = torch.cat((torch.full((int((~near).sum()),), coarse**2, dtype=torch.float64),
                   torch.full((len(fine_pts),), fine**2, dtype=torch.float64)))
    return Quadrature(pts.to(dtype), w.to(dtype))


class LearnedDynamics:
    """H_F between an object (φ1, planar pose) and a pusher (φ2, position) for T steps.

    ``evaluate(X1 (T+1, 3), X2 (T+1, 2))`` → ``H (T,)`` (m²), ``J1 (T, 2, 3)`` and
    ``J2 (T, 2, 2)``: row t holds ∂H_t/∂(state t−1) in ``[:, 0]`` and ∂H_t/∂(state t) in
    ``[:, 1]``, where H_t couples states t−1 and t (t = 1…T).
    """

    def __init__(self, model: PushDynamics, obj: Body, pusher: Body,
                 quadrature: Quadrature) -> None:
        self.model, self.obj, self.pusher = model.eval(), obj, pusher
        for p in model.parameters():
            p.requires_grad_(False)
        spec = model.spec
        self.workspace = Workspace(spec.workspace_center, spec.workspace_size,
                                   spec.workspace_size[0] / spec.grid[1])
        self.dtype = next(model.parameters()).dtype  # float32, or float64 for checks
        self.grid = self.workspace.points(self.dtype).reshape(-1, 2)
        self.quadrature = Quadrature(quadrature.points.to(self.dtype),
                                     quadrature.weights.to(self.dtype))
        with torch.no_grad():
            self.point_term = model.point_term(self.quadrature.points[None])  # (1, N, H1)

    # ---------------------------------------------------------------- fast path
    def evaluate(self, X1: Tensor, X2: Tensor, jacobian: bool = True
                 ) -> tuple[Tensor, Tensor | None, Tensor | None]:
        X1, X2 = X1.to(self.dtype), X2.to(self.dtype)
        T = X1.shape[0] - 1
        m, shape = self.model, self.workspace.shape
        # one rendering + encoding per state: φ1 at states 0…T−1, φ2 at states 0…T
        if jacobian:
            phi1, dphi1 = grid_with_tangents(self.obj, X1[:-1], self.grid, position_only=False)
            phi2, dphi2 = grid_with_tangents(self.pusher, X2, self.grid, position_only=True)
        else:  # values only (e.g. a line search): no tangent grids
            with torch.no_grad():
                phi1 = self.obj.sdf(self.grid, X1[:-1])
                phi2 = self.pusher.sdf(self.grid, X2)
        joint = m.spec.encoder == "joint"
        if joint:  # one encoding per step of the stacked φ1_{t−1}, φ2_{t−1}, φ2_t
            stacked = torch.stack((phi1, phi2[:-1], phi2[1:]), dim=1).reshape(T, 3, *shape)
            if jacobian:
                f, df = m.encode_joint_with_tangents(
                    stacked, [dphi1.reshape(T, 3, *shape), dphi2[:-1].reshape(T, 2, *shape),
                              dphi2[1:].reshape(T, 2, *shape)])
            else:
                with torch.no_grad():
                    f = m.encoder(stacked)
            F = m.spec.sdf_features
            f1, f2p, f2n = f[:, :F], f[:, F:2 * F], f[:, 2 * F:]
        elif jacobian:
            # forward mode for every grid, in one batch: object grids with 3 tangents,
            # pusher grids with 2 (each pusher grid feeds two steps)
            (f1, df1), (f2, df2) = m.encode_with_tangents(
                (phi1.reshape(T, *shape), dphi1.reshape(T, 3, *shape)),
                (phi2.reshape(T + 1, *shape), dphi2.reshape(T + 1, 2, *shape)))
            f2p, f2n = f2[:-1], f2[1:]
        else:
            with torch.no_grad():
                f1 = m.encode(phi1.reshape(T, *shape))
                f2 = m.encode(phi2.reshape(T + 1, *shape))
            f2p, f2n = f2[:-1], f2[1:]
        # per-step leaves: every step's inputs are its own, so one backward gives blocks
        leaves = [f1.clone(), f2p.clone(), f2n.clone(), X1[:-1].clone(), X1[1:].clone()]
        with torch.enable_grad():
            for leaf in leaves:
                leaf.requires_grad_(jacobian)
            F1p, F2p, F2n, Q1p, Q1n = leaves
            S = m.sdf_term(torch.cat((F1p, F2p, F2n), dim=1))  # (T, H1)
            out = m.from_terms(S, self.point_term)  # (T, N)
            x = self.quadrature.points
            now = self.obj.sdf(x, Q1n)
            pred = self.obj.sdf(x, Q1p) + out if m.spec.kind == "flow" else out
            H = self.quadrature.integrate((now - pred) ** 2)  # (T,)
            if not jacobian:
                return H.detach(), None, None
            grads = torch.autograd.grad(H.sum(), leaves, allow_unused=True)
            gF1p, gF2p, gF2n, gQ1p, gQ1n = (torch.zeros_like(leaf) if g is None else g
                                            for g, leaf in zip(grads, leaves, strict=True))
        if joint:
            g = torch.cat((gF1p, gF2p, gF2n), dim=1)  # d H_t / d features of step t
            d = torch.einsum("tf,tkf->tk", g, df)  # (T, 7): q1_{t−1} (3), q2_{t−1}, q2_t
            J1 = torch.stack((gQ1p + d[:, :3], gQ1n), dim=1)
            J2 = torch.stack((d[:, 3:5], d[:, 5:7]), dim=1)
            return H.detach(), J1, J2
        J1 = torch.stack((gQ1p + torch.einsum("tf,tkf->tk", gF1p, df1), gQ1n), dim=1)
        J2 = torch.stack((torch.einsum("tf,tkf->tk", gF2p, df2[:-1]),
                          torch.einsum("tf,tkf->tk", gF2n, df2[1:])), dim=1)
        return H.detach(), J1, J2

    # ---------------------------------------------------------------- naive path
    def evaluate_naive(self, X1: Tensor, X2: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        """The paper-faithful evaluation: each step on its own, three encodings, the whole
        concatenated 700-feature MLP at all grid points of X_h, autograd. Same outputs as
        :meth:`evaluate` with the full grid as quadrature."""
        m, shape = self.model, self.workspace.shape
        W = torch.cat((m.first_sdf.weight, m.first_point.weight), dim=1)  # (H1, 700)
        x = self.grid
        area = self.workspace.cell_area
        point_feats = m.point_encoder((x - m.center) / m.half_size)  # (N, 100)
        Hs, J1, J2 = [], [], []
        for t in range(1, X1.shape[0]):
            q1p, q1n = (X1[t - 1].to(self.dtype).clone().requires_grad_(True),
                        X1[t].to(self.dtype).clone().requires_grad_(True))
            q2p, q2n = (X2[t - 1].to(self.dtype).clone().requires_grad_(True),
                        X2[t].to(self.dtype).clone().requires_grad_(True))
            with torch.enable_grad():
                grids = torch.stack((self.obj.sdf(x, q1p), self.pusher.sdf(x, q2p),
                                     self.pusher.sdf(x, q2n))).reshape(3, *shape)
                feats = (m.encoder(grids[None]) if m.spec.encoder == "joint"
                         else m.encode(grids).reshape(1, -1)).expand(len(x), -1)  # (N, 600)
                h = torch.relu(torch.cat((feats, point_feats), dim=1) @ W.T + m.first_sdf.bias)
                out = m.head(h)[:, 0] * m.spec.out_scale
                prev = self.obj.sdf(x, q1p)
                pred = prev + out if m.spec.kind == "flow" else out
                H = ((self.obj.sdf(x, q1n) - pred) ** 2).sum() * area
                g = torch.autograd.grad(H, (q1p, q1n, q2p, q2n))  # q1p feeds φ1_{t−1}(X_h)
            Hs.append(H.detach())
            J1.append(torch.stack(g[:2]))
            J2.append(torch.stack(g[2:]))
        return torch.stack(Hs), torch.stack(J1), torch.stack(J2)
