"""The encoder's linear layer and the head's first layer as one map, read only at the last
convolution's live channels.

Both layers are linear with nothing between them, so ``first(linear(y)) = y A + b`` with
``A = (W_first W_linear)ᵀ`` of shape ``(C'·h·w, H1)``: half the products and half the
weights to read of the two layers, in the forward pass and in reverse mode alike. Dead
channels of the last convolution are zero, so only the rows of ``A`` that read live channels
take part; those rows are gathered once per set of live channels (it rarely changes between
the calls of one program) and the last few sets are kept.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

__all__ = ["LIVE_ROW_SETS", "FoldedLayer"]

LIVE_ROW_SETS = 4  # sets of live channels whose rows are kept (each up to the whole map)


class FoldedLayer:
    """``first ∘ linear`` for inputs laid out as ``(C', h·w)`` channel blocks.

    ``linear``: ``(C'·h·w → F)``, ``first``: ``(F → H1)``; ``channels`` = C'."""

    def __init__(self, linear: nn.Linear, first: nn.Linear, channels: int) -> None:
        with torch.no_grad():
            self.weight = (first.weight @ linear.weight).T.contiguous()  # (C'·h·w, H1)
            self.bias = first(linear.bias)  # (H1,)
        self.channels = channels
        self._rows: dict[tuple[int, ...], Tensor] = {}

    def rows(self, live: Tensor) -> Tensor:
        """The rows ``(len(live)·h·w, H1)`` of the map that read the ``live`` channels
        (indices into C', increasing)."""
        key = tuple(live.tolist())
        if key not in self._rows:
            if len(self._rows) >= LIVE_ROW_SETS:
                del self._rows[next(iter(self._rows))]  # the oldest
            by_channel = self.weight.view(self.channels, -1, self.weight.shape[1])
            self._rows[key] = by_channel[live].reshape(-1, self.weight.shape[1]).contiguous()
        return self._rows[key]

    def __call__(self, y: Tensor, live: Tensor) -> tuple[Tensor, Tensor]:
        """``y (M, len(live)·h·w)``, the live channels flattened → the first layer's
        pre-activation ``(M, H1)`` and the rows used (their transpose pulls gradients back)."""
        rows = self.rows(live)
        return torch.addmm(self.bias, y, rows), rows
