"""The dynamics model's head at fixed query points, evaluated tile by tile over the live units.

The head's first layer is ``h1(b, x) = ReLU(S_b + P(x))``, where ``P(x)`` (point encoder then
first-layer point part) is an *affine* function of the query point x: each unit u is active
in a half-plane of the table for each step b. Within a small tile of neighbouring points only
the units whose half-plane reaches the tile at some step can be non-zero, so each tile needs
only those columns of the second layer (on real pushes with ~530 points in tiles of ≤ 32:
~110 of 300 units on average, ~125 at most, against ~200 live anywhere in the batch).
Backward, a tile needs only the second layer's outputs that are active somewhere in it
(~60 of 300), so the transposed product shrinks to (~60 × ~125) per tile.

Both are exact: a skipped unit is 0 at every (step, point) of its tile, forward, and passes
no gradient back. The tiles are padded to one size (repeated points with weight 0 in the
caller's quadrature, a unit that is always 0), so that each product is one batched
``bmm`` over all tiles; the second layer's bias rides along as a unit that is always 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor, nn

from robotplan.pushing.models.dynamics import PushDynamics, relu_backward

__all__ = ["TILE_POINTS", "TiledHead", "tile_points"]

TILE_POINTS = 32
"""Query points per tile: smaller tiles leave fewer live units per tile but gather more
weight columns per call (measured: docs/experiments.md#tiled-head)."""


def tile_points(points: Tensor, size: int = TILE_POINTS) -> tuple[Tensor, Tensor]:
    """Split ``points (N, 2)`` into spatially compact tiles of at most ``size`` points by
    halving along the longer side (a k-d split at the median), padded to one size with the
    tile's first point. Returns the indices ``(n_tiles, tile_size)`` and which of them are
    not padding ``(n_tiles, tile_size)``; a padding copy must get weight 0."""
    leaves: list[Tensor] = []
    stack = [torch.arange(len(points))]
    while stack:
        index = stack.pop()
        if len(index) <= size:
            leaves.append(index)
            continue
        sub = points[index]
        axis = int((sub.amax(0) - sub.amin(0)).argmax())
        order = index[sub[:, axis].argsort(stable=True)]
        stack += [order[len(order) // 2:], order[:len(order) // 2]]
    width = max(len(leaf) for leaf in leaves)
    index = torch.stack([torch.cat((leaf, leaf[:1].expand(width - len(leaf))))
                         for leaf in leaves])
    real = torch.stack([torch.arange(width) < len(leaf) for leaf in leaves])
    return index, real


@dataclass(frozen=True)
class BucketCache:
    """What :meth:`TiledHead.input_grad` needs from one group of tiles of the forward pass."""

    tiles: Tensor  # (n_b,) which tiles
    units: Tensor  # (n_b, k) live first-layer units per tile (padded with the zero unit)
    hidden1: Tensor  # (n_b, B·m, k) first-layer ReLU outputs
    weight2: Tensor  # (n_b, k, H2) the second layer's live columns (transposed)
    hidden2: Tensor  # (n_b, B·m, H2) second-layer ReLU outputs


HeadCache = list[BucketCache]

BUCKETS = 2
"""Groups of tiles with similar counts of live first-layer units, one batched product each
(each group padded to its own largest count, not the largest of all): more groups pad
less but add small operations (measured: docs/experiments.md#tiled-head)."""


class TiledHead:
    """The head of a :class:`PushDynamics` with two hidden layers at fixed query points.

    ``points (N', 2)`` must be the tiled order of :func:`tile_points` flattened (``N' =
    n_tiles · tile_size``). :meth:`forward` maps the SDF term ``S (B, H1)`` to the outputs
    ``(B, N')`` in metres; :meth:`input_grad` pulls ``∂/∂output (B, N')`` back to ``(B, H1)``.
    Both equal :meth:`PushDynamics.head_with_activations` / ``head_input_grad`` up to
    rounding. ``matmul_dtype`` as there (bfloat16 only where the user opted in).
    """

    def __init__(self, model: PushDynamics, points: Tensor, tiles: int,
                 matmul_dtype: torch.dtype | None = None, buckets: int = BUCKETS) -> None:
        linears = [mod for mod in model.head if isinstance(mod, nn.Linear)]
        if len(linears) != 2:
            raise ValueError("TiledHead needs a head with two hidden layers (spec.hidden)")
        second, last = linears
        dtype = points.dtype
        self.scale = model.spec.out_scale
        self.matmul_dtype = matmul_dtype or dtype
        H2, H1 = second.weight.shape
        self.H1, self.tiles, self.buckets = H1, tiles, buckets
        self.size = len(points) // tiles
        # two extra units after the H1 real ones: always 1 (carries the bias), always 0
        with torch.no_grad():
            P = model.point_term(points).reshape(tiles, self.size, H1)
            extra = torch.tensor([1.0, -1.0], dtype=dtype).expand(tiles, self.size, 2)
            self.point_term = torch.cat((P, extra), dim=2).contiguous()  # (n, m, H1 + 2)
            self.point_max = P.amax(1)  # (n, H1)
            # rows: first-layer units (then "one": the bias, "zero"); columns: second layer
            self.weight2_t = torch.cat((second.weight.T, second.bias[None],
                                        torch.zeros(1, H2, dtype=dtype))).contiguous()
            self.last = torch.cat((last.weight[0], torch.zeros(1, dtype=dtype)))  # (H2 + 1,)
            self.last_bias = last.bias[0]
        self.zero = H1 + 1  # the padding unit

    @staticmethod
    def _columns(live: Tensor, pad: int) -> Tensor:
        """Indices of the True entries of each row of ``live (n, U)``, padded with ``pad``."""
        count = live.sum(1)
        width = int(count.max())
        order = torch.argsort((~live).to(torch.uint8), dim=1, stable=True)[:, :width]
        return torch.where(torch.arange(width) < count[:, None], order, pad)

    def forward(self, S: Tensor) -> tuple[Tensor, HeadCache]:
        """``S (B, H1)`` → outputs ``(B, N')`` and the cache for :meth:`input_grad`."""
        B, n, m = S.shape[0], self.tiles, self.size
        live = S.amax(0) + self.point_max > 0  # (n, H1): live somewhere in the tile
        live = torch.cat((live, live.new_ones(n, 1)), dim=1)  # + the bias unit
        S_ext = torch.cat((S, S.new_zeros(B, 2)), dim=1)
        out = S.new_empty(n, B * m)
        dtype = self.matmul_dtype
        cache: HeadCache = []
        for tiles in torch.tensor_split(torch.argsort(live.sum(1)), min(self.buckets, n)):
            units = self._columns(live[tiles], self.zero)  # (n_b, k)
            nb, k = units.shape
            S_tile = S_ext.index_select(1, units.flatten()).view(B, nb, k).transpose(0, 1)
            S_tile = S_tile.contiguous()
            P_tile = torch.gather(self.point_term[tiles], 2,
                                  units[:, None, :].expand(nb, m, k))
            h1 = (S_tile[:, :, None, :] + P_tile[:, None]).clamp_min_(0.0).view(nb, B * m, k)
            w2 = self.weight2_t.index_select(0, units.flatten()).view(nb, k, -1)
            h2 = torch.bmm(h1.to(dtype), w2.to(dtype)).to(S.dtype).clamp_min_(0.0)
            out[tiles] = torch.matmul(h2, self.last[:-1])  # (n_b, B·m)
            cache.append(BucketCache(tiles, units, h1, w2, h2))
        out = (out + self.last_bias) * self.scale
        return out.view(n, B, m).transpose(0, 1).reshape(B, n * m), cache

    def input_grad(self, cache: HeadCache, grad_out: Tensor) -> Tensor:
        """``∂(Σ grad_out · output) / ∂S``: ``grad_out (B, N')`` → ``(B, H1)``."""
        B, n, m = grad_out.shape[0], self.tiles, self.size
        g_all = (grad_out * self.scale).view(B, n, m).transpose(0, 1).reshape(n, B * m, 1)
        grad = grad_out.new_zeros(B, self.H1 + 2)
        dtype = self.matmul_dtype
        for b in cache:
            nb, rows, H2 = b.hidden2.shape
            # only the second layer's units active somewhere in the tile pass gradient
            live2 = b.hidden2.sum(1) > 0  # (n_b, H2); ReLU outputs: sum > 0 iff any is
            units2 = self._columns(live2, H2)  # (n_b, k2), padded with H2 (weight 0 in last)
            inside = units2.clamp_max(H2 - 1)
            h2 = torch.gather(b.hidden2, 2, inside[:, None, :].expand(nb, rows, -1))
            g2 = relu_backward(g_all[b.tiles] * self.last[units2][:, None, :], h2)
            w2 = torch.gather(b.weight2, 2, inside[:, None, :].expand(nb, b.units.shape[1], -1))
            g1 = torch.bmm(g2.to(dtype), w2.transpose(1, 2).to(dtype)).to(grad_out.dtype)
            g1 = relu_backward(g1, b.hidden1).view(nb, B, m, -1).sum(2)  # (n_b, B, k)
            grad.index_add_(1, b.units.flatten(), g1.transpose(0, 1).reshape(B, -1))
        return grad[:, :self.H1]
