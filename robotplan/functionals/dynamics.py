"""H_F, the learned-dynamics functional (paper eq. 5), evaluated fast for whole trajectories.

H_F(φ1_{t−1:t}, φ2_{t−1:t}) = ∫_X (φ1_t(x) − F(φ1_{t−1}, φ2_{t−1}, φ2_t)(x))² dx, with
F(…)(x) = φ1_{t−1}(x) + F_flow(…)(x) for the flow model (eq. 4).

The fast path (:meth:`LearnedDynamics.evaluate`) computes what the naive path computes
(:meth:`LearnedDynamics.evaluate_naive`: every step on its own, all 19,600 grid points
through the whole network, autograd) in far less time:

* **one rendering per state**: φ1_s(X_h), φ2_s(X_h) and their tangent grids dφ/dq (exact,
  from ∇φ; 3 per object grid, 2 per pusher grid) are rendered once per state s; the
  paper's shared encoder also encodes each grid once (2T + 1 encodings for T steps, not 3T);
* **reverse mode through the encoder**: H_t is a scalar, so one backward pass per step
  (transposed convolutions with the primal's ReLU masks, no autograd graph) gives
  ∂H_t/∂φ(X_h), which is contracted with the tangent grids; forward mode would need one
  pass per tangent (7 per step), and was 1.5× slower overall;
* **split first layer**: the SDF part is one (600 → 300) product per step, the point part
  (100 → 300) is computed once for the fixed quadrature points; for the joint encoder its
  linear layer and this SDF part are folded into one (300 × 5120) map (half the products
  and half the weights to read; bfloat16 would make its backward product 5x faster, 2.2 →
  0.4 ms, but costs gradient precision the solver needs);
* **channels-last convolutions**: oneDNN is about 2x faster on these 3- and 5-channel
  layers in NHWC layout (forward, and the transposed convolutions of the backward pass);
  ReLU masks are applied by multiplying with their ``uint8`` view (exact, 4x faster than
  ``torch.where``);
* **fewer quadrature points**: a :class:`~robotplan.functionals.Quadrature` of the
  caller's choice (see :func:`phase_quadrature`), instead of the 140 × 140 grid;
* **no autograd**: the head's reverse mode is written out (its ReLU masks, like the
  encoder's), and its hidden-to-hidden products run in bfloat16 for a float32 model
  (float32 accumulation; AVX512-BF16 halves their cost): per step 0.5 % on H_t and 2.4 %
  on its gradient at worst over 24 realistic pushes, well below the quadrature's error;
  a float64 model (the tests) computes in float64 throughout;
* **separable rendering**: on the grid a body-frame coordinate is a row term plus a
  column term, and the shapes give φ and ∇φ in closed form (:func:`render_on_grid`);
* **exact sparse Jacobians**: per step, ∂H_t/∂q1_{t−1}, ∂q1_t, ∂q2_{t−1}, ∂q2_t from one
  backward pass through the head (each step's inputs are separate leaves).

The quadrature error against the full-grid integral and the timings are measured by
``robotplan bench functional`` (numbers in its docstring and the project notes).
"""

from __future__ import annotations

import torch
from torch import Tensor

from robotplan.functionals.base import Quadrature, sdf_pose_gradients
from robotplan.learned.dynamics import PushDynamics
from robotplan.scene.bodies import Body
from robotplan.sdf import Circle, Workspace

__all__ = ["LearnedDynamics", "grid_with_tangents", "phase_quadrature", "render_on_grid"]


def grid_with_tangents(body: Body, X_WB: Tensor, points: Tensor, position_only: bool
                       ) -> tuple[Tensor, Tensor]:
    """φ of ``body`` at ``points (N, 2)`` for poses ``X_WB (S, 3|2)`` and dφ/dq
    (:func:`~robotplan.functionals.base.sdf_pose_gradients`, tangents first).

    Returns ``(S, N)`` values and ``(S, k, N)`` derivatives, k = 2 (x, y) for a
    position-only body, else 3 (x, y, yaw).
    """
    phi, d_pose, _ = sdf_pose_gradients(body, points, X_WB, position_only)
    return phi, (d_pose[..., :2] if position_only else d_pose).movedim(-1, 1)


def render_on_grid(body: Body, X_WB: Tensor, workspace: Workspace, tangents: bool = True
                   ) -> tuple[Tensor, Tensor | None]:
    """:func:`grid_with_tangents` on the workspace grid X_h, using its separable structure:
    a body-frame coordinate is the sum of a term per column and a term per row, so the
    transform costs one broadcast add per coordinate. ``(S, H·W)``, ``(S, k, H·W)``; k = 2
    for positions ``(S, 2)``, else 3 (0 along yaw for a disc); no tangents if not asked.
    """
    X = X_WB.detach()
    x0, _, y0, _ = workspace.bounds
    rows, cols = workspace.shape
    r = workspace.resolution
    dx = x0 + (torch.arange(cols, dtype=X.dtype) + 0.5) * r - X[:, 0:1]  # (S, W)
    dy = y0 + (torch.arange(rows, dtype=X.dtype) + 0.5) * r - X[:, 1:2]  # (S, H)
    turns = X.shape[-1] == 3 and not isinstance(body.shape, Circle)
    if turns:
        c, s = torch.cos(X[:, 2:3]), torch.sin(X[:, 2:3])
        px = (c * dx)[:, None, :] + (s * dy)[:, :, None]  # (S, H, W)
        py = (c * dy)[:, :, None] - (s * dx)[:, None, :]
    else:
        px, py = torch.broadcast_tensors(dx[:, None, :], dy[:, :, None])
    if not tangents:
        return body.shape.sdf(torch.stack((px, py), dim=-1)).flatten(1), None
    phi, gx, gy = body.shape.sdf_and_grad_planes(px.contiguous(), py.contiguous())
    gx, gy = gx.flatten(1), gy.flatten(1)
    if not turns:
        rows_k = [-gx, -gy] + ([torch.zeros_like(gx)] if X.shape[-1] == 3 else [])
        return phi.flatten(1), torch.stack(rows_k, dim=1)
    d_theta = gx * py.flatten(1) - gy * px.flatten(1)
    return phi.flatten(1), torch.stack((-(c * gx - s * gy), -(s * gx + c * gy), d_theta), dim=1)


QUADRATURE_LEVELS = ((0.10, 0.07), (0.02, 0.035))
"""The default refinement of :func:`phase_quadrature`: ``(margin, spacing)`` pairs, coarse to
fine; a cell is refined to ``spacing`` when it comes within the object's bounding radius
plus ``margin`` of the object's path."""


def phase_quadrature(centers: Tensor, bound_radius: float, workspace: Workspace,
                     levels: tuple[tuple[float, float], ...] = QUADRATURE_LEVELS,
                     coarse: float = 0.14, dtype: torch.dtype = torch.float32) -> Quadrature:
    """A fixed multi-level midpoint rule for one phase.

    The workspace is tiled with ``coarse`` cells; level by level, a cell that comes within
    ``bound_radius + margin`` of any of the ``centers (C, 2)`` (e.g. the object's positions
    in the phase's initial guess) is split into square sub-cells of that level's spacing.
    Every point is a cell centre weighted by the cell's area, so the weights sum to the
    workspace area. The default, 14 / 7 / 3.5 cm, uses ~200–330 points for the objects
    of the data ranges (19,600 for the 1 cm grid X_h).
    """
    cells = Workspace(workspace.center, workspace.size, coarse).points(torch.float64)
    cells, size = cells.reshape(-1, 2), coarse
    centers = centers.to(torch.float64)
    points, weights = [], []
    for margin, spacing in levels:
        # a cell is near when any part of it (half-diagonal ≈ 0.707·size) is within reach
        near = torch.cdist(cells, centers).amin(dim=1) <= bound_radius + margin + 0.7072 * size
        points.append(cells[~near])
        weights.append(torch.full((len(points[-1]),), size**2, dtype=torch.float64))
        ratio = max(1, round(size / spacing))
        offs = (torch.arange(ratio, dtype=torch.float64) + 0.5) * (size / ratio) - size / 2
        oy, ox = torch.meshgrid(offs, offs, indexing="ij")
        sub = torch.stack((ox, oy), dim=-1).reshape(-1, 2)
        cells, size = (cells[near][:, None, :] + sub[None]).reshape(-1, 2), size / ratio
    points.append(cells)
    weights.append(torch.full((len(cells),), size**2, dtype=torch.float64))
    return Quadrature(torch.cat(points).to(dtype), torch.cat(weights).to(dtype))


class LearnedDynamics:
    """H_F between an object (φ1, planar pose) and a pusher (φ2, position) for T steps.

    ``evaluate(X1 (T+1, 3), X2 (T+1, 2))`` → ``H (T,)`` (m²), ``J1 (T, 2, 3)`` and
    ``J2 (T, 2, 2)``: row t holds ∂H_t/∂(state t−1) in ``[:, 0]`` and ∂H_t/∂(state t) in
    ``[:, 1]``, where H_t couples states t−1 and t (t = 1…T).
    """

    def __init__(self, model: PushDynamics, obj: Body, pusher: Body,
                 quadrature: Quadrature, matmul_dtype: torch.dtype | None = None) -> None:
        self.model, self.obj, self.pusher = model.eval(), obj, pusher
        for p in model.parameters():
            p.requires_grad_(False)
        spec = model.spec
        self.workspace = Workspace(spec.workspace_center, spec.workspace_size,
                                   spec.workspace_size[0] / spec.grid[1])
        self.dtype = next(model.parameters()).dtype  # float32, or float64 for checks
        # the head's hidden products: bfloat16 for a float32 model (see the module notes)
        self.matmul_dtype = matmul_dtype or (
            torch.bfloat16 if self.dtype == torch.float32 else self.dtype)
        self.grid = self.workspace.points(self.dtype).reshape(-1, 2)
        self.quadrature = Quadrature(quadrature.points.to(self.dtype),
                                     quadrature.weights.to(self.dtype))
        with torch.no_grad():
            self.point_term = model.point_term(self.quadrature.points[None])  # (1, N, H1)
            # joint encoder: its linear layer and the head's SDF part folded into one
            # (H1, C'·h·w) map; half the products and half the weights to read per call
            first, linear = model.first_sdf, model.encoder.linear
            self.conv_to_hidden = ((first.weight @ linear.weight, first(linear.bias))
                                   if model.spec.encoder == "joint" else None)

    # ---------------------------------------------------------------- fast path
    def evaluate(self, X1: Tensor, X2: Tensor, jacobian: bool = True
                 ) -> tuple[Tensor, Tensor | None, Tensor | None]:
        X1, X2 = X1.to(self.dtype), X2.to(self.dtype)
        T = X1.shape[0] - 1
        m, shape = self.model, self.workspace.shape
        joint = m.spec.encoder == "joint"
        # one rendering per state: φ1 at states 0…T−1, φ2 at states 0…T (+ tangent grids)
        phi1, dphi1 = render_on_grid(self.obj, X1[:-1], self.workspace, jacobian)
        phi2, dphi2 = render_on_grid(self.pusher, X2, self.workspace, jacobian)
        if joint:  # one encoding per step of the stacked φ1_{t−1}, φ2_{t−1}, φ2_t
            images = torch.stack((phi1, phi2[:-1], phi2[1:]), dim=1).reshape(T, 3, *shape)
        else:  # one encoding per grid; each pusher grid feeds two steps
            images = torch.cat((phi1, phi2)).reshape(2 * T + 1, 1, *shape)
        f, masks = m.encode_with_masks(images, linear=not joint)
        if joint:
            S = torch.addmm(self.conv_to_hidden[1], f, self.conv_to_hidden[0].T)  # (T, H1)
        else:
            f = torch.cat((f[:T], f[T:2 * T], f[T + 1:]), dim=1)  # (T, 3F) per step
            S = m.sdf_term(f)
        out, head_masks = m.head_with_masks(S, self.point_term, self.matmul_dtype)  # (T, N)
        # φ1 at the quadrature points for states 0…T: state t is "now" of step t and
        # "prev" of step t + 1
        x, w = self.quadrature.points, self.quadrature.weights
        if jacobian:
            phi_q, dphi_q = grid_with_tangents(self.obj, X1, x, position_only=False)
        else:
            phi_q, dphi_q = self.obj.sdf(x, X1), None
        flow = m.spec.kind == "flow"
        residual = phi_q[1:] - (phi_q[:-1] + out if flow else out)  # (T, N)
        H = (residual * residual) @ w
        if not jacobian:
            return H, None, None
        c = 2.0 * residual * w  # ∂H_t/∂φ1_t(x_n); −c is ∂H_t/∂output(x_n)
        g_hidden = m.head_input_grad(head_masks, -c, self.matmul_dtype)  # ∂H_t/∂S_t (T, H1)
        g_now = torch.einsum("tn,tkn->tk", c, dphi_q[1:])
        g_prev = -torch.einsum("tn,tkn->tk", c, dphi_q[:-1]) if flow else torch.zeros_like(g_now)
        # reverse mode through the encoder to the input grids, then along the tangent grids
        if joint:
            G = m.encoder_input_grad(masks, g_hidden @ self.conv_to_hidden[0],
                                     linear=False).flatten(2)
            G1, G2p, G2n = G[:, 0], G[:, 1], G[:, 2]  # each (T, N)
        else:
            steps = torch.arange(T)
            index = torch.cat((steps, T + steps, T + 1 + steps))
            F = m.spec.sdf_features
            g_features = g_hidden @ m.first_sdf.weight
            g_split = torch.cat((g_features[:, :F], g_features[:, F:2 * F], g_features[:, 2 * F:]))
            G = m.encoder_input_grad(masks, g_split, index).flatten(1)
            G1, G2p, G2n = G[:T], G[T:2 * T], G[2 * T:]
        J1 = torch.stack((g_prev + torch.einsum("tn,tkn->tk", G1, dphi1), g_now), dim=1)
        J2 = torch.stack((torch.einsum("tn,tkn->tk", G2p, dphi2[:-1]),
                          torch.einsum("tn,tkn->tk", G2n, dphi2[1:])), dim=1)
        return H, J1, J2

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
                feats = m.features(grids[None]).expand(len(x), -1)  # (N, 600)
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
