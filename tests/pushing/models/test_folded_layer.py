"""The folded linear layers: the same numbers as the two layers, rows kept per live set."""

import torch
from torch import nn

from robotplan.pushing.models.folded_layer import LIVE_ROW_SETS, FoldedLayer


def test_folded_layer_equals_the_two_layers_on_live_channels():
    torch.manual_seed(3)
    channels, cells = 3, 20
    linear, first = nn.Linear(channels * cells, 16).double(), nn.Linear(16, 8).double()
    folded = FoldedLayer(linear, first, channels)
    y = torch.randn(5, channels, cells, dtype=torch.float64)
    y[:, 1] = 0.0  # a dead channel
    live = torch.tensor([0, 2])
    out, rows = folded(y[:, live].flatten(1), live)
    with torch.no_grad():
        expected = first(linear(y.flatten(1)))
    assert torch.allclose(out, expected, atol=1e-12)
    assert rows.shape == (2 * cells, 8)


def test_folded_layer_keeps_rows_for_a_few_live_channel_sets_only():
    torch.manual_seed(7)
    folded = FoldedLayer(nn.Linear(3 * 4, 6), nn.Linear(6, 5), 3)
    full = folded.weight.view(3, -1, 5)  # (C, h·w, H1)
    sets = [torch.tensor(s) for s in ([0], [1], [2], [0, 1], [0, 2], [1, 2], [0, 1, 2])]
    for live in sets:
        rows = folded.rows(live)
        assert torch.equal(rows, full[live].reshape(-1, 5))
        assert len(folded._rows) <= LIVE_ROW_SETS
    assert list(folded._rows)[-1] == (0, 1, 2)  # the newest kept, the oldest dropped
    assert folded.rows(torch.tensor([0, 1, 2])) is folded.rows(torch.tensor([0, 1, 2]))
