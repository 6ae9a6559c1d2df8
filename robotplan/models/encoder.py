"""The SDF encoder of the dynamics models (conv 3, 5, 5 channels, kernels 3, 5, 5, strides
1, 2, 2, ReLU, linear to 200 features; app. I.1) and the pieces of its hand-written reverse
pass: ReLU masks, convolution input gradients, live-channel bookkeeping."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import torch
from torch import Tensor, nn

from robotplan.models.spec import DynamicsSpec, conv_output_side

__all__ = ["ConvWithoutOneDNN", "EncoderPass", "SDFEncoder", "channel_sums", "conv_input_grad",
           "live_columns", "no_onednn", "relu_backward", "represent_grids"]


class ConvWithoutOneDNN(torch.autograd.Function):
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
        with no_onednn():
            return nn.functional.conv2d(x, weight, bias, stride)

    @staticmethod
    def backward(ctx, grad: Tensor):
        x, weight = ctx.saved_tensors
        gx = gw = gb = None
        with no_onednn():
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


def live_columns(layers: list[nn.Linear], j: int, units: Tensor) -> Tensor:
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


class no_onednn:
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
    # dψ/dφ of the grids (M, C, H, W) where the encoder reads an occupancy measure ψ of the
    # SDFs, None where it reads the SDFs themselves
    input_slope: Tensor | None = None


def channel_sums(y: Tensor) -> Tensor:
    """``(M, C, h, w)`` → the sum of each channel ``(C,)``, read in memory order. For ReLU
    outputs (≥ 0) a channel is zero everywhere iff its sum is 0 (no cancellation); a sum
    runs ~10x faster than a max over these few channels."""
    if y.is_contiguous(memory_format=torch.channels_last):
        return y.permute(0, 2, 3, 1).reshape(-1, y.shape[1]).sum(0)
    return y.sum((0, 2, 3))


def represent_grids(grids: Tensor, representation: str, sharpness: float,
                    slope: bool = False) -> tuple[Tensor, Tensor | None]:
    """What an encoder reads of SDF grids: the SDFs (``"sdf"``), or the occupancy measure
    ψ = sign(φ) (``"occupancy"``, eq. 10) or ψ_s = tanh(b φ) (``"smooth_occupancy"``, eq. 11,
    b = ``sharpness`` in 1/m); with ``slope`` also dψ/dφ (None for the SDFs: the identity).
    ψ's slope is zero almost everywhere: a model on ψ passes the planner no gradient
    through its grids, the paper's argument for SDFs."""
    if representation == "sdf":
        return grids, None
    if representation == "occupancy":
        return torch.sign(grids), torch.zeros_like(grids) if slope else None
    psi = torch.tanh(sharpness * grids)
    return psi, sharpness * (1.0 - psi * psi) if slope else None


class SDFEncoder(nn.Module):
    """φ(X_h) ``(M, C, H, W)`` → features ``(M, F)``: C = 1, F = sdf_features for the
    paper's shared encoder; C = 3, F = 3 · sdf_features for the joint variant."""

    def __init__(self, spec: DynamicsSpec) -> None:
        super().__init__()
        if spec.representation == "pointcloud":
            raise ValueError("the SDF encoder reads grids: representation 'pointcloud' is "
                             "F_q's PointNet encoder (robotplan.models.pointnet)")
        layers: list[nn.Module] = []
        joint = spec.encoder == "joint"
        c_in, (h, w) = (3 if joint else 1), spec.grid
        for c, k, s in zip(spec.channels, spec.kernels, spec.strides, strict=True):
            layers += [nn.Conv2d(c_in, c, k, stride=s), nn.ReLU()]
            c_in, h, w = c, conv_output_side(h, k, s), conv_output_side(w, k, s)
        self.conv = nn.Sequential(*layers)
        self.linear = nn.Linear(c_in * h * w, spec.sdf_features * (3 if joint else 1))
        self.representation = spec.representation
        self.sharpness = spec.occupancy_sharpness
        # SDF values (m) are scaled to unit range; occupancy measures are in [-1, 1] already
        self.scale = spec.sdf_scale if spec.representation == "sdf" else 1.0

    def represent(self, grids: Tensor, slope: bool = False) -> tuple[Tensor, Tensor | None]:
        """What the first convolution reads of SDF grids ``(M, C, H, W)``:
        :func:`represent_grids` of the spec's ``representation``."""
        return represent_grids(grids, self.representation, self.sharpness, slope)

    def forward(self, grids: Tensor) -> Tensor:
        first = self.conv[0]
        grids, _ = self.represent(grids)
        weight = first.weight * self.scale  # the input scaling, folded into the first layer
        if grids.device.type == "cpu":
            x = ConvWithoutOneDNN.apply(grids, weight, first.bias, first.stride[0])
        else:
            x = nn.functional.conv2d(grids, weight, first.bias, first.stride)
        return self.linear(self.conv[1:](x).flatten(1))
