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

import functools
import json
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Literal

import torch
from torch import Tensor, nn

from robotplan.base.native import conv_relu_forward, conv_relu_input_grad

__all__ = ["DynamicsSpec", "EncoderPass", "PushDynamics", "cpu_multiplies_bfloat16",
           "head_matmul_dtype", "load_model", "save_model"]

BFLOAT16_CPU_FLAGS = ("avx512_bf16", "amx_bf16")
"""CPU features (``/proc/cpuinfo`` flags) with native bfloat16 dot products."""


def cpu_multiplies_bfloat16(cpuinfo: str | None = None) -> bool:
    """Whether the CPU has native bfloat16 dot products (:data:`BFLOAT16_CPU_FLAGS`).

    Without them oneDNN emulates bfloat16 products, far slower than float32: on an AVX2-only
    AMD EPYC a (5320 × 230)·(230 × 300) product took 160 ms in bfloat16 against 20 ms in
    float32, and one H_F phase 460 ms against 41 ms. ``cpuinfo``: the text of
    ``/proc/cpuinfo`` (read once per process when not given; False where it is missing).
    """
    if cpuinfo is None:
        return _this_cpu_multiplies_bfloat16()
    flags: set[str] = set()
    for line in cpuinfo.splitlines():
        key, _, value = line.partition(":")
        if key.strip() == "flags":
            flags.update(value.split())
    return any(flag in flags for flag in BFLOAT16_CPU_FLAGS)


@functools.cache
def _this_cpu_multiplies_bfloat16() -> bool:
    try:
        with open("/proc/cpuinfo") as f:
            return cpu_multiplies_bfloat16(f.read())
    except OSError:
        return False


def head_matmul_dtype(model_dtype: torch.dtype) -> torch.dtype:
    """The dtype of the head's hidden-to-hidden products on the CPU: bfloat16 for a float32
    model where the CPU multiplies bfloat16 natively (half the cost, float32 accumulation),
    else the model's own dtype (a float64 model, the tests', always computes in float64)."""
    if model_dtype == torch.float32 and cpu_multiplies_bfloat16():
        return torch.bfloat16
    return model_dtype


@dataclass(frozen=True)
class DynamicsSpec:
    """Constructor arguments of :class:`PushDynamics` (written to ``spec.json``)."""

    kind: Literal["flow", "direct"] = "flow"
    grid: tuple[int, int] = (140, 140)
    workspace_center: tuple[float, float] = (0.0, 0.0)
    workspace_size: tuple[float, float] = (1.4, 1.4)
    channels: tuple[int, ...] = (3, 5, 5)
    kernels: tuple[int, ...] = (3, 5, 5)
    strides: tuple[int, ...] = (1, 2, 2)
    sdf_features: int = 200
    point_features: int = 100
    hidden: tuple[int, ...] = (300, 300)
    encoder: Literal["shared", "joint"] = "shared"  # joint: one encoder sees all 3 SDFs
    sdf_scale: float = 5.0  # input SDF values (m) are multiplied by this
    out_scale: float = 0.01  # the network's output is multiplied by this (m)
    extra: dict = field(default_factory=dict)  # free-form notes (not used by the network)

    @classmethod
    def from_json(cls, data: dict) -> DynamicsSpec:
        kw = dict(data)
        for k in ("grid", "workspace_center", "workspace_size", "channels", "kernels",
                  "strides", "hidden"):
            if k in kw:
                kw[k] = tuple(kw[k])
        return cls(**kw)


class _ConvWithoutOneDNN(torch.autograd.Function):
    """conv2d whose forward and backward both bypass oneDNN (mkldnn).

    For the one-channel first convolution on the 140 × 140 grid this is ~5x faster on the
    CPU, forward and backward (weights and input); the later convolutions are faster with
    oneDNN, so the switch is per layer. The backward must be pinned too: autograd picks
    its kernels from the global flags at backward time.
    """

    @staticmethod
    def forward(ctx, x: Tensor, weight: Tensor, bias: Tensor, stride: int) -> Tensor:
        ctx.save_for_backward(x, weight)
        ctx.stride = stride
        with _no_onednn():
            return nn.functional.conv2d(x, weight, bias, stride)

    @staticmethod
    def backward(ctx, grad: Tensor):
        x, weight = ctx.saved_tensors
        gx = gw = gb = None
        with _no_onednn():
            if ctx.needs_input_grad[0]:
                gx = nn.grad.conv2d_input(x.shape, weight, grad, ctx.stride)
            if ctx.needs_input_grad[1]:
                gw = nn.grad.conv2d_weight(x, weight.shape, grad, ctx.stride)
        if ctx.needs_input_grad[2]:
            gb = grad.sum((0, 2, 3))
        return gx, gw, gb, None


def relu_backward(grad: Tensor, relu_output: Tensor) -> Tensor:
    """``grad`` where the ReLU was active (``relu_output > 0``), else 0: exact, through
    PyTorch's own ReLU-backward kernel (no stored bool masks)."""
    return torch.ops.aten.threshold_backward(grad, relu_output, 0)


def _live_columns(layers: list[nn.Linear], j: int, units: Tensor) -> Tensor:
    """Layer j's weight, restricted to the live first-layer ``units`` if it reads them
    (the layer after the first hidden one: j = 0)."""
    return layers[j].weight[:, units] if j == 0 else layers[j].weight


def conv_input_grad(grad: Tensor, weight: Tensor, stride: int, size: tuple[int, int]
                    ) -> Tensor:
    """∂(Σ grad · conv2d(x, weight, stride)) / ∂x for x of spatial ``size``: the transposed
    convolution, computed as one ordinary (forward) convolution in polyphase form.

    ``grad (M, C_out, h, w)`` → ``(M, C_in, *size)`` in channels-last layout. With
    D = ⌈k / s⌉, output pixel (s·m + a, s·n + b) is a D × D correlation of the zero-padded
    ``grad`` with the taps of phase (a, b), w[s·(D−1−v) + a, s·(D−1−u) + b]; all s² phases
    are the output channels of one convolution, interleaved afterwards. oneDNN runs this
    2–3x faster than its transposed convolution of stride 2 on these few channels.
    At stride 1 it is the full correlation with the flipped kernel, computed in NCHW layout
    (oneDNN's direct kernel there: 2.4 ms against 4.1 ms channels-last for the 3 → 3
    first layer of the joint encoder at T = 10), and the result is NCHW.
    """
    c_out, c_in, k, _ = weight.shape
    if stride == 1:
        flipped = weight.flip(2, 3).transpose(0, 1)
        return nn.functional.conv2d(grad.contiguous(), flipped, None, 1, k - 1)
    s, D = stride, -(-weight.shape[-1] // stride)
    padded = weight.new_zeros(c_out, c_in, s * D, s * D)
    padded[..., :k, :k] = weight
    taps = padded.reshape(c_out, c_in, D, s, D, s).flip(2, 4)  # [o, i, v, a, u, b]
    taps = taps.permute(3, 5, 1, 0, 2, 4).reshape(s * s * c_in, c_out, D, D)
    y = nn.functional.conv2d(grad.contiguous(memory_format=torch.channels_last),
                             taps.contiguous(memory_format=torch.channels_last), None, 1, D - 1)
    M, _, h, w = y.shape
    y = y.permute(0, 2, 3, 1).reshape(M, h, w, s, s, c_in).transpose(2, 3)
    y = y.reshape(M, h * s, w * s, c_in)[:, :size[0], :size[1]]
    return y.permute(0, 3, 1, 2)


class _no_onednn:
    def __enter__(self) -> None:
        self._warn = warnings.catch_warnings()
        self._warn.__enter__()
        warnings.simplefilter("ignore", UserWarning)
        self._flags = torch.backends.mkldnn.flags(enabled=False)
        self._flags.__enter__()

    def __exit__(self, *exc: object) -> None:
        self._flags.__exit__(*exc)
        self._warn.__exit__(*exc)


@dataclass(frozen=True)
class EncoderPass:
    """What reverse mode through the encoder needs from its forward pass."""

    activations: list[Tensor]  # per convolution: its ReLU outputs (M, C_j, h_j, w_j)
    live: list[Tensor]  # per convolution: its channels that are non-zero somewhere (C_j',)


def _channel_sums(y: Tensor) -> Tensor:
    """``(M, C, h, w)`` → the sum of each channel ``(C,)``, read in memory order. For ReLU
    outputs (≥ 0) a channel is zero everywhere iff its sum is 0 (no cancellation); a sum
    runs ~10x faster than a max over these few channels."""
    if y.is_contiguous(memory_format=torch.channels_last):
        return y.permute(0, 2, 3, 1).reshape(-1, y.shape[1]).sum(0)
    return y.sum((0, 2, 3))


class SDFEncoder(nn.Module):
    """φ(X_h) ``(M, C, H, W)`` → features ``(M, F)``: C = 1, F = sdf_features for the
    paper's shared encoder; C = 3, F = 3 · sdf_features for the joint variant."""

    def __init__(self, spec: DynamicsSpec) -> None:
        super().__init__()
        layers: list[nn.Module] = []
        joint = spec.encoder == "joint"
        c_in, (h, w) = (3 if joint else 1), spec.grid
        for c, k, s in zip(spec.channels, spec.kernels, spec.strides, strict=True):
            layers += [nn.Conv2d(c_in, c, k, stride=s), nn.ReLU()]
            c_in, h, w = c, (h - k) // s + 1, (w - k) // s + 1
        self.conv = nn.Sequential(*layers)
        self.linear = nn.Linear(c_in * h * w, spec.sdf_features * (3 if joint else 1))
        self.scale = spec.sdf_scale

    def forward(self, grids: Tensor) -> Tensor:
        first = self.conv[0]
        weight = first.weight * self.scale  # the input scaling, folded into the first layer
        if grids.device.type == "cpu":
            x = _ConvWithoutOneDNN.apply(grids, weight, first.bias, first.stride[0])
        else:
            x = nn.functional.conv2d(grids, weight, first.bias, first.stride)
        return self.linear(self.conv[1:](x).flatten(1))


class PushDynamics(nn.Module):
    """F_flow or F for a pusher (φ2) moving an object (φ1); see the module docstring."""

    def __init__(self, spec: DynamicsSpec = DynamicsSpec()) -> None:
        super().__init__()
        self.spec = spec
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

    # --- the split pieces (used as they are by the fast planner path) ---
    def encode(self, grids: Tensor) -> Tensor:
        """Encode single SDF grids ``(M, H, W)`` → ``(M, sdf_features)``."""
        return self.encoder(grids[:, None])

    @torch.no_grad()
    def encode_with_activations(self, grids: Tensor, linear: bool = True
                                ) -> tuple[Tensor, EncoderPass]:
        """Features ``(M, F)`` of grids ``(M, C, H, W)`` and what :meth:`encoder_input_grad`
        needs to pull feature gradients back to the grids (:class:`EncoderPass`).

        Records each layer's live channels (non-zero somewhere in the batch): reverse mode
        skips the others exactly, as they pass no gradient back (in the shipped F_flow 1 of
        3, 2 of 5 and 1 of 5 are dead on real pushes). Float32 on the CPU runs our own
        kernels (:mod:`robotplan.base.native`), whose next layer also skips them at no cost;
        through PyTorch that needed a gather costing what it saved. ``linear=False`` stops
        before the encoder's linear layer: the last convolution's live channels, flattened
        ``(M, C'·h·w)`` in the (C', h, w) order of the linear layer's inputs.
        """
        enc = self.encoder
        convs = [m for m in enc.conv if isinstance(m, nn.Conv2d)]
        activations: list[Tensor] = []
        lives: list[Tensor] = []
        y = grids
        for j, conv in enumerate(convs):
            weight = conv.weight * enc.scale if j == 0 else conv.weight
            # our own kernels (float32 CPU): bias, ReLU and channel sums in one pass, and
            # the previous layer's dead channels skipped
            native = conv_relu_forward(y, weight, conv.bias, conv.stride[0],
                                       lives[-1] if lives else None)
            if native is not None:
                y, sums = native
                activations.append(y)
                lives.append(torch.nonzero(sums > 0)[:, 0])
                continue
            if j == 0 and conv.in_channels == 1:  # oneDNN is slower for one input channel
                with _no_onednn():
                    y = nn.functional.conv2d(y, weight, conv.bias, conv.stride)
            else:  # oneDNN in channels-last layout: ~2x faster for these few channels
                y = nn.functional.conv2d(y.contiguous(memory_format=torch.channels_last),
                                         weight.contiguous(memory_format=torch.channels_last),
                                         conv.bias, conv.stride)
            y = y.clamp_min_(0)
            live = torch.nonzero(_channel_sums(y) > 0)[:, 0]
            activations.append(y)
            lives.append(live)
        if linear:  # dead channels are zeros: the linear layer reads all of them
            return enc.linear(y.flatten(1)), EncoderPass(activations, lives)
        return y[:, lives[-1]].flatten(1), EncoderPass(activations, lives)

    @torch.no_grad()
    def encoder_input_grad(self, cache: EncoderPass, grad_features: Tensor,
                           index: Tensor | None = None, linear: bool = True) -> Tensor:
        """Reverse mode through the encoder: ``∂(Σ grad_features · features) / ∂grids``.

        Args:
            cache: from :meth:`encode_with_activations`.
            grad_features: ``(M', F)`` gradients with respect to the features (with
                ``linear=False``: to its flattened live channels of the last convolution).
            index: ``(M',)`` which encoded grid each row belongs to (default: row i ↔ grid i);
                a grid may appear several times (e.g. a pusher grid used by two steps).
        Returns:
            ``(M', C, H, W)``: one gradient image per row of ``grad_features``.
        The encoder is piecewise linear, so this is exact: transposed convolutions masked by
        the primal's ReLU pattern (one pass per image, about the cost of a forward pass),
        between the live channels only.
        """
        enc = self.encoder
        convs = [m for m in enc.conv if isinstance(m, nn.Conv2d)]
        activations, lives = cache.activations, cache.live
        if index is not None:
            activations = [a[index] for a in activations]
        last = activations[-1]
        if any(len(live) == 0 for live in lives):  # a layer all zeros: no gradient passes
            return last.new_zeros(grad_features.shape[0], convs[0].in_channels, *self.spec.grid)
        if linear:
            g = (grad_features @ enc.linear.weight).reshape(last.shape)[:, lives[-1]]
        else:
            g = grad_features.reshape(last.shape[0], len(lives[-1]), *last.shape[2:])
        for j in range(len(convs) - 1, -1, -1):
            conv = convs[j]
            size = tuple(activations[j - 1].shape[-2:] if j > 0 else self.spec.grid)
            weight = (conv.weight * enc.scale if j == 0 else conv.weight)[lives[j]]
            if j > 0:  # only the previous layer's live channels pass gradient further
                weight = weight[:, lives[j - 1]]
            native = conv_relu_input_grad(g, activations[j], lives[j], weight,
                                          conv.stride[0], size)
            if native is not None:  # our own kernel, the ReLU mask fused
                g = native
                continue
            g = relu_backward(g, activations[j][:, lives[j]])
            g = conv_input_grad(g, weight, conv.stride[0], size)
        return g

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
            weight = _live_columns(layers, j, units).to(dtype)
            x = torch.matmul(x.to(dtype), weight.T).to(sdf_term.dtype)
            x = x.add_(lin.bias).clamp_min_(0.0)
            activations.append(x)
        out = torch.matmul(x, _live_columns(layers, len(layers) - 1, units)[0])
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
        last = _live_columns(layers, len(layers) - 1, units)[0]
        g = (grad_out * self.spec.out_scale)[..., None] * last  # (B, P, H_last)
        for j in range(len(layers) - 2, -1, -1):
            g = relu_backward(g, activations[j + 1])
            weight = _live_columns(layers, j, units).to(dtype)
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
    """Write ``weights.pt`` (state_dict) and ``spec.json`` into ``folder``."""
    import os

    folder.mkdir(parents=True, exist_ok=True)
    tmp = folder / ".weights.pt.tmp"
    torch.save(model.state_dict(), tmp)
    os.replace(tmp, folder / "weights.pt")
    tmp = folder / ".spec.json.tmp"
    tmp.write_text(json.dumps(asdict(model.spec), indent=1))
    os.replace(tmp, folder / "spec.json")


def load_model(folder: str | Path, device: str | torch.device = "cpu") -> PushDynamics:
    """Load a model folder (``spec.json`` + ``weights.pt``, read with ``weights_only=True``)."""
    folder = Path(folder)
    for name in ("spec.json", "weights.pt"):
        if not (folder / name).is_file():
            raise FileNotFoundError(f"{folder}: no {name}; not a robotplan model folder")
    spec = DynamicsSpec.from_json(json.loads((folder / "spec.json").read_text()))
    model = PushDynamics(spec)
    state = torch.load(folder / "weights.pt", map_location=device, weights_only=True)
    model.load_state_dict(state)
    return model.to(device).eval()
