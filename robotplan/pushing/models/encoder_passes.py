"""Reverse mode through the SDF encoder without autograd, for every model built on it
(F_flow and F in :mod:`robotplan.pushing.models.dynamics`, F_q in
:mod:`robotplan.pushing.models.rigid`): a forward pass that keeps each layer's ReLU outputs
and live channels, and the transposed pass that pulls feature gradients back to the input
grids."""

from __future__ import annotations

import torch
from torch import Tensor, nn

from robotplan.base.native import conv_relu_forward, conv_relu_input_grad
from robotplan.models.encoder import (
    EncoderPass,
    channel_sums,
    conv_input_grad,
    no_onednn,
    relu_backward,
)

__all__ = ["EncoderPasses"]


class EncoderPasses:
    """For a model with an ``encoder`` (:class:`~robotplan.models.encoder.SDFEncoder`) and
    a ``spec`` (:class:`~robotplan.models.spec.DynamicsSpec`)."""

    @torch.no_grad()
    def encode_with_activations(self, grids: Tensor, linear: bool = True
                                ) -> tuple[Tensor, EncoderPass]:
        """Features ``(M, F)`` of grids ``(M, C, H, W)`` and what :meth:`encoder_input_grad`
        needs to pull feature gradients back to the grids (:class:`EncoderPass`).

        Records each layer's live channels (non-zero somewhere in the batch): reverse mode
        skips the others exactly, as they pass no gradient back (in the shipped F_flow 1 of
        3, 2 of 5 and 1 of 5 are dead on real pushes). Float32 on the CPU runs our own
        kernels (:mod:`robotplan.base.native`), whose next layer also skips them at no cost;
        through PyTorch that would need a gather costing what it saves. ``linear=False`` stops
        before the encoder's linear layer: the last convolution's live channels, flattened
        ``(M, C'·h·w)`` in the (C', h, w) order of the linear layer's inputs.
        """
        enc = self.encoder
        convs = [m for m in enc.conv if isinstance(m, nn.Conv2d)]
        activations: list[Tensor] = []
        lives: list[Tensor] = []
        y, slope = enc.represent(grids, slope=True)
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
                with no_onednn():
                    y = nn.functional.conv2d(y, weight, conv.bias, conv.stride)
            else:  # oneDNN in channels-last layout: ~2x faster for these few channels
                y = nn.functional.conv2d(y.contiguous(memory_format=torch.channels_last),
                                         weight.contiguous(memory_format=torch.channels_last),
                                         conv.bias, conv.stride)
            y = y.clamp_min_(0)
            live = torch.nonzero(channel_sums(y) > 0)[:, 0]
            activations.append(y)
            lives.append(live)
        cache = EncoderPass(activations, lives, slope)
        if linear:  # dead channels are zeros: the linear layer reads all of them
            return enc.linear(y.flatten(1)), cache
        return y[:, lives[-1]].flatten(1), cache

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
        between the live channels only; times dψ/dφ where it reads an occupancy measure.
        """
        g = self._input_grad(cache, grad_features, index, linear)
        slope = cache.input_slope
        if slope is None:
            return g
        return g * (slope if index is None else slope[index])

    def _input_grad(self, cache: EncoderPass, grad_features: Tensor, index: Tensor | None,
                    linear: bool) -> Tensor:
        """:meth:`encoder_input_grad` with respect to what the first convolution reads."""
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
