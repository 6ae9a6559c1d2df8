"""Learned pushing dynamics in SDF space: F (eq. 3) and F_flow (eq. 4), network of app. I.1.

Each of φ1_{t−1}, φ2_{t−1}, φ2_t, rendered on the table grid X_h (140 × 140), is encoded by
one shared encoder (conv 3, 5, 5 channels, kernels 3, 5, 5, strides 1, 2, 2, ReLU, then a
linear layer to 200 features); the query point x is encoded by a linear layer to 100
features; the 700 features go through an MLP (300, 300, ReLU) to one output:

* ``kind="flow"``: F_flow, so that φ1_t(x) = φ1_{t−1}(x) + F_flow(…)(x)   (eq. 4)
* ``kind="direct"``: F, so that φ1_t(x) = F(…)(x)                          (eq. 3)

The first MLP layer is split into its SDF part (600 → 300, the same for every query point)
and its point part (100 → 300), so that planning evaluates the SDF part once per step and
the point part once per quadrature point.
"""

from __future__ import annotations

from pathlib import Path

import torch
from torch import Tensor, nn

from robotplan.models.encoder import EncoderPass, SDFEncoder, live_columns, relu_backward
from robotplan.models.spec import (
    DynamicsSpec,
    head_matmul_dtype,
    read_model_folder,
    write_model_folder,
)
from robotplan.pushing.models.encoder_passes import EncoderPasses

__all__ = ["DynamicsSpec", "EncoderPass", "PushDynamics", "head_matmul_dtype", "load_model",
           "relu_backward", "save_model"]


class PushDynamics(EncoderPasses, nn.Module):
    """F_flow or F for a pusher (φ2) moving an object (φ1); see the module docstring."""

    def __init__(self, spec: DynamicsSpec | None = None) -> None:
        super().__init__()
        spec = self.spec = spec or DynamicsSpec()
        self.encoder = SDFEncoder(spec)
        self.point_encoder = nn.Linear(2, spec.point_features)
        first = spec.hidden[0]
        self.first_sdf = nn.Linear(3 * spec.sdf_features, first)  # carries the bias
        self.first_point = nn.Linear(spec.point_features, first, bias=False)
        rest: list[nn.Module] = []
        for a, b in zip(spec.hidden[:-1], spec.hidden[1:], strict=True):
            rest += [nn.Linear(a, b), nn.ReLU()]
        rest.append(nn.Linear(spec.hidden[-1], 1))
        self.head = nn.Sequential(*rest)
        self.register_buffer("center", torch.tensor(spec.workspace_center))
        self.register_buffer("half_size", torch.tensor(spec.workspace_size) / 2)

    def values_read(self, phi: Tensor) -> Tensor:
        """SDF values as the model reads and predicts them: φ, or the occupancy measure of
        its spec (ψ = sign φ, ψ_s = tanh(b φ)), so that a model on ψ predicts ψ1_t (the
        paper's Tab. 4)."""
        return self.encoder.represent(phi)[0]

    # --- the split pieces (used as they are by the fast planner path) ---
    def encode(self, grids: Tensor) -> Tensor:
        """Encode single SDF grids ``(M, H, W)`` → ``(M, sdf_features)``."""
        return self.encoder(grids[:, None])

    @torch.no_grad()
    def head_with_activations(self, sdf_term: Tensor, point_term: Tensor,
                              matmul_dtype: torch.dtype | None = None
                              ) -> tuple[Tensor, tuple[Tensor, list[Tensor]]]:
        """:meth:`from_terms` without autograd, keeping what :meth:`head_input_grad` needs.

        Only the first layer's units that are active somewhere in the batch are carried
        (exact: a unit that is 0 at every (b, p) adds nothing forward and passes no gradient
        back; on real pushes ~25 % of them are dead, and their columns drop out of the
        second layer's products both ways). A unit u can be active only if
        max_b S[b, u] + max_p P[p, u] > 0 (iff, for a shared point term, as every pair
        (b, p) occurs), so the selection costs nothing. The hidden-to-hidden products run in
        ``matmul_dtype`` (default the model's; bfloat16 halves their cost on CPUs with
        AVX512-BF16, where they accumulate in float32); everything else stays in the
        model's dtype.

        Returns the output ``(B, P)`` and ``(the first layer's active units (k,), the ReLU
        outputs [(B, P, k), (B, P, H2), …])``.
        """
        dtype = matmul_dtype or sdf_term.dtype
        layers = [mod for mod in self.head if isinstance(mod, nn.Linear)]
        units = torch.nonzero(sdf_term.amax(0) + point_term.amax((0, 1)) > 0)[:, 0]
        x = (sdf_term[:, None, units] + point_term[..., units]).clamp_min_(0.0)  # (B, P, k)
        activations = [x]
        for j, lin in enumerate(layers[:-1]):
            weight = live_columns(layers, j, units).to(dtype)
            x = torch.matmul(x.to(dtype), weight.T).to(sdf_term.dtype)
            x = x.add_(lin.bias).clamp_min_(0.0)
            activations.append(x)
        out = torch.matmul(x, live_columns(layers, len(layers) - 1, units)[0])
        return (out + layers[-1].bias[0]) * self.spec.out_scale, (units, activations)

    @torch.no_grad()
    def head_input_grad(self, cache: tuple[Tensor, list[Tensor]], grad_out: Tensor,
                        matmul_dtype: torch.dtype | None = None) -> Tensor:
        """Reverse mode through the head: ``∂(Σ grad_out · output) / ∂sdf_term``.

        ``cache`` from :meth:`head_with_activations`, ``grad_out (B, P)`` → ``(B, H1)``; the
        point term is fixed, so its gradient is summed away at once. Exact (piecewise
        linear; inactive units pass nothing), in ``matmul_dtype`` as the forward pass.
        """
        dtype = matmul_dtype or grad_out.dtype
        layers = [mod for mod in self.head if isinstance(mod, nn.Linear)]
        units, activations = cache
        last = live_columns(layers, len(layers) - 1, units)[0]
        g = (grad_out * self.spec.out_scale)[..., None] * last  # (B, P, H_last)
        for j in range(len(layers) - 2, -1, -1):
            g = relu_backward(g, activations[j + 1])
            weight = live_columns(layers, j, units).to(dtype)
            g = torch.matmul(g.to(dtype), weight).to(grad_out.dtype)
        grad = grad_out.new_zeros(grad_out.shape[0], layers[0].in_features)
        grad[:, units] = relu_backward(g, activations[0]).sum(1)
        return grad

    def sdf_term(self, features: Tensor) -> Tensor:
        """``(B, 3 · sdf_features)`` (φ1_{t−1}, φ2_{t−1}, φ2_t) → first-layer term ``(B, H1)``."""
        return self.first_sdf(features)

    def point_term(self, points: Tensor) -> Tensor:
        """Query points ``(..., P, 2)`` in the table frame → first-layer term ``(..., P, H1)``."""
        return self.first_point(self.point_encoder((points - self.center) / self.half_size))

    def from_terms(self, sdf_term: Tensor, point_term: Tensor) -> Tensor:
        """``(B, H1)`` and ``(B or 1, P, H1)`` → the output ``(B, P)`` in metres."""
        h = torch.relu(sdf_term[:, None, :] + point_term)
        return self.head(h)[..., 0] * self.spec.out_scale

    # --- the whole model ---
    def features(self, inputs: Tensor) -> Tensor:
        """``inputs (B, 3, H, W)`` = φ1_{t−1}, φ2_{t−1}, φ2_t on X_h → ``(B, 3 · sdf_features)``,
        with either encoder (shared: each grid alone; joint: the three as channels)."""
        if self.spec.encoder == "joint":
            return self.encoder(inputs)
        return self.encode(inputs.flatten(0, 1)).reshape(inputs.shape[0], -1)

    def forward(self, inputs: Tensor, points: Tensor) -> Tensor:
        """``inputs (B, 3, H, W)`` = φ1_{t−1}, φ2_{t−1}, φ2_t on X_h; ``points (B or 1, P, 2)``.

        Returns ``(B, P)``: F_flow(x) for ``kind="flow"``, φ1_t(x) for ``kind="direct"``.
        """
        return self.from_terms(self.sdf_term(self.features(inputs)), self.point_term(points))

    def predict_next(self, inputs: Tensor, points: Tensor, phi1_prev_at_points: Tensor
                     ) -> Tensor:
        """φ1_t at the points ``(B, P)``, for either kind."""
        out = self.forward(inputs, points)
        return phi1_prev_at_points + out if self.spec.kind == "flow" else out


def save_model(model: PushDynamics, folder: Path) -> None:
    """Write ``weights.pt`` (state_dict) and ``spec.json`` into ``folder``, each whole."""
    write_model_folder(model, model.spec, folder)


def load_model(folder: str | Path, device: str | torch.device = "cpu") -> PushDynamics:
    """Load an F_flow or F model folder (``spec.json`` + ``weights.pt``, read with
    ``weights_only=True``)."""
    spec, state = read_model_folder(folder, ("flow", "direct"), device)
    model = PushDynamics(spec)
    model.load_state_dict(state)
    return model.to(device).eval()
