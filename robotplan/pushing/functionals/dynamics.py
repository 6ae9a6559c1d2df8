"""H_F, the learned-dynamics functional (paper eq. 5), evaluated fast for whole trajectories.

H_F(φ1_{t−1:t}, φ2_{t−1:t}) = ∫_X (φ1_t(x) − F(φ1_{t−1}, φ2_{t−1}, φ2_t)(x))² dx, with
F(…)(x) = φ1_{t−1}(x) + F_flow(…)(x) for the flow model (eq. 4).

The fast path (:meth:`LearnedDynamics.evaluate`) computes what the naive path computes
(:meth:`LearnedDynamics.evaluate_naive`: every step on its own, all 19,600 grid points
through the whole network, autograd) in far less time:

* **one rendering per state**: φ1_s(X_h), φ2_s(X_h) and their tangents dφ/dq (exact, from
  ∇φ, kept factored as :class:`GridTangents`) are rendered once per state s; the paper's
  shared encoder also encodes each grid once (2T + 1 encodings for T steps, not 3T);
* **reverse mode through the encoder**: H_t is a scalar, so one backward pass per step
  (transposed convolutions masked by the primal's ReLU outputs, no autograd graph) gives
  ∂H_t/∂φ(X_h), which is contracted with the tangents; forward mode would need one pass
  per tangent (7 per step). The transposed convolutions run as ordinary ones in polyphase
  form (``conv_input_grad``), and only between channels that are non-zero somewhere in the
  batch (F_flow's encoder has 1, 2 and 1 dead channels on real pushes);
* **split first layer**: the SDF part is one (600 → 300) product per step, the point part
  (100 → 300) is computed once for the fixed quadrature points; for the joint encoder its
  linear layer and this SDF part are folded into one (5120 × 300) map (half the products
  and half the weights to read; it stays float32: bfloat16 would cost gradient precision
  the solver needs);
* **only live hidden units, tile by tile**
  (:class:`~robotplan.pushing.models.tiled_head.TiledHead`): the first layer's point part is affine
  in the query point, so each unit is active in a half-plane per step; the quadrature points are
  split into compact tiles of ≤ 32 and each tile's products use only the units that can be active in
  it (~110 of 300 forward, against ~200 live anywhere in the phase) and, backward, only the second
  layer's units active in it (~60 of 300). Exact, with far fewer multiply-adds in the head;
* **convolutions of our own** (``robotplan/base/kernels.c``, :mod:`robotplan.base.native`,
  float32 on the CPU): each block of pixels keeps every output channel in registers; bias,
  ReLU and the live-channel sums are fused into the forward pass, the ReLU mask into the
  backward one, and a layer skips the previous layer's dead channels. PyTorch's
  convolutions (channels-last oneDNN) remain the fallback and the float64 path;
* **fewer quadrature points**: a :class:`~robotplan.functionals.Quadrature` of the
  caller's choice, by default :func:`phase_quadrature` (10 cm cells, 5 cm within r + 5 cm
  and 2.5 cm within r + 1 cm of the object's path; ~350–650 points, worst per-step error
  of H_t below 5 % against the 19,600-point grid), instead of X_h;
* **no autograd**: the head's reverse mode is written out (through its ReLU outputs, like the
  encoder's). Its hidden-to-hidden products run in the model's dtype: float32, or bfloat16
  (float32 accumulation) only where the user opts in (``ROBOTPLAN_HEAD_BFLOAT16=1``) and
  the CPU multiplies bfloat16 natively
  (:func:`~robotplan.pushing.models.dynamics.head_matmul_dtype`); a float64 model (the tests)
  computes in float64 throughout;
* **one-pass rendering**: circles, boxes and L-shapes are rendered on the grid by the same
  C kernels (φ, ∇φ and the body-frame coordinates in one vectorized pass over the
  pixels); other shapes use the separable PyTorch form (a body-frame coordinate is a row
  term plus a column term; closed-form φ and ∇φ; :func:`render_on_grid`);
* **exact sparse Jacobians**: per step, ∂H_t/∂q1_{t−1}, ∂q1_t, ∂q2_{t−1}, ∂q2_t from one
  backward pass through the head (each step's inputs are separate leaves);
* **no page faults**: the ~20 MB of short-lived tensors per call stay in the heap
  (:func:`~robotplan.base.memory.keep_freed_memory`) instead of being fresh ``mmap`` pages
  every call.

``robotplan bench functional`` measures the quadrature error against the full-grid integral
and the timings (measured: docs/experiments.md#hf-evaluation).
"""

from __future__ import annotations

import torch
from torch import Tensor

from robotplan.base.memory import keep_freed_memory
from robotplan.functionals.base import Quadrature
from robotplan.pushing.functionals.grid_render import (
    GridTangents,
    grid_with_tangents,
    render_on_grid,
)
from robotplan.pushing.functionals.quadrature import (
    QUADRATURE_COARSE,
    QUADRATURE_LEVELS,
    phase_quadrature,
)
from robotplan.pushing.models.dynamics import PushDynamics, head_matmul_dtype
from robotplan.pushing.models.folded_layer import FoldedLayer
from robotplan.pushing.models.tiled_head import TiledHead, tile_points
from robotplan.scene.bodies import Body

__all__ = ["QUADRATURE_COARSE", "QUADRATURE_LEVELS", "GridTangents", "LearnedDynamics",
           "grid_with_tangents", "phase_quadrature", "render_on_grid"]


class LearnedDynamics:
    """H_F between an object (φ1, planar pose) and a pusher (φ2, position) for T steps.

    ``evaluate(X1 (T+1, 3), X2 (T+1, 2))`` → ``H (T,)`` (m²), ``J1 (T, 2, 3)`` and
    ``J2 (T, 2, 2)``: row t holds ∂H_t/∂(state t−1) in ``[:, 0]`` and ∂H_t/∂(state t) in
    ``[:, 1]``, where H_t couples states t−1 and t (t = 1…T).

    Quadrature: the caller's, by default :func:`phase_quadrature` (multi-level midpoint,
    10 cm cells, 5 cm within r + 5 cm and 2.5 cm within r + 1 cm of the object's path;
    ~350–650 points). Speed against :meth:`evaluate_naive` and the quadrature's error
    against the 19,600-point grid: docs/experiments.md#hf-evaluation.
    """

    integral = True  # H is an integral over the table (m⁴), see ``mm2_per_unit``

    def __init__(self, model: PushDynamics, obj: Body, pusher: Body,
                 quadrature: Quadrature, matmul_dtype: torch.dtype | None = None) -> None:
        if model.spec.representation != "sdf":
            raise ValueError("H_F needs an F_flow or F on SDFs: a model on occupancy "
                             f"measures (representation {model.spec.representation!r}) "
                             "predicts ψ, not φ")
        if model.spec.frame != "table":
            raise ValueError("LearnedDynamics renders X_h on the table: it needs a "
                             "table-frame F_flow or F; an object-frame one is "
                             "robotplan.pushing.functionals.framed_dynamics.FramedDynamics's")
        self.model, self.obj, self.pusher = model.eval(), obj, pusher
        keep_freed_memory()  # its short-lived ~MB tensors would page-fault on every call
        for p in model.parameters():
            p.requires_grad_(False)
        spec = model.spec
        self.workspace = spec.workspace()
        self.dtype = next(model.parameters()).dtype  # float32, or float64 for checks
        # the head's hidden products: the model's dtype, or bfloat16 for a float32 model where
        # the user opted in and the CPU multiplies bfloat16 natively (see the module notes)
        self.matmul_dtype = matmul_dtype or head_matmul_dtype(self.dtype)
        self.grid = self.workspace.points(self.dtype).reshape(-1, 2)
        points, weights = quadrature.points.to(self.dtype), quadrature.weights.to(self.dtype)
        self.tiled_head: TiledHead | None = None
        if len(model.spec.hidden) == 2:  # the paper's head: evaluated tile by tile
            index, real = tile_points(points)
            points, weights = points[index.flatten()], (weights[index] * real).flatten()
            self.tiled_head = TiledHead(model, points, len(index), self.matmul_dtype)
        self.quadrature = Quadrature(points, weights)  # in tile order, padding weighs 0
        with torch.no_grad():
            # the dense head's point part (the tiled head keeps its own, tile by tile)
            self.point_term = (None if self.tiled_head is not None
                               else model.point_term(self.quadrature.points[None]))  # (1, N, H1)
        # joint encoder: its linear layer and the head's SDF part folded into one map
        self.conv_to_hidden = (FoldedLayer(model.encoder.linear, model.first_sdf,
                                           model.spec.channels[-1])
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
        f, acts = m.encode_with_activations(images, linear=not joint)
        if joint:
            S, rows = self.conv_to_hidden(f, acts.live[-1])  # (T, H1)
        else:
            f = torch.cat((f[:T], f[T:2 * T], f[T + 1:]), dim=1)  # (T, 3F) per step
            S = m.sdf_term(f)
        if self.tiled_head is not None:
            out, head_acts = self.tiled_head.forward(S)  # (T, N)
        else:
            out, head_acts = m.head_with_activations(S, self.point_term, self.matmul_dtype)
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
        if self.tiled_head is not None:  # ∂H_t/∂S_t (T, H1)
            g_hidden = self.tiled_head.input_grad(head_acts, -c)
        else:
            g_hidden = m.head_input_grad(head_acts, -c, self.matmul_dtype)
        g_now = torch.einsum("tn,tkn->tk", c, dphi_q[1:])
        g_prev = -torch.einsum("tn,tkn->tk", c, dphi_q[:-1]) if flow else torch.zeros_like(g_now)
        # reverse mode through the encoder to the input grids, then along the tangent grids
        if joint:
            G = m.encoder_input_grad(acts, g_hidden @ rows.T, linear=False).flatten(2)
            G1, G2p, G2n = G[:, 0], G[:, 1], G[:, 2]  # each (T, N)
        else:
            steps = torch.arange(T)
            index = torch.cat((steps, T + steps, T + 1 + steps))
            F = m.spec.sdf_features
            g_features = g_hidden @ m.first_sdf.weight
            g_split = torch.cat((g_features[:, :F], g_features[:, F:2 * F], g_features[:, 2 * F:]))
            G = m.encoder_input_grad(acts, g_split, index).flatten(1)
            G1, G2p, G2n = G[:T], G[T:2 * T], G[2 * T:]
        J1 = torch.stack((g_prev + dphi1.contract(G1), g_now), dim=1)
        J2 = torch.stack((dphi2[:-1].contract(G2p), dphi2[1:].contract(G2n)), dim=1)
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
