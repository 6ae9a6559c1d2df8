import pytest
import torch

from robotplan.pushing.models.dynamics import DynamicsSpec, PushDynamics
from robotplan.pushing.models.tiled_head import TiledHead, tile_points
from tests.conftest import TINY_SPEC

F64 = torch.float64


def test_tiles_cover_every_point_once_and_stay_compact():
    g = torch.Generator().manual_seed(5)
    points = torch.rand(203, 2, dtype=F64, generator=g) - 0.5
    index, real = tile_points(points, size=16)
    assert index.shape == real.shape and index.shape[1] <= 16
    assert sorted(index[real].tolist()) == list(range(203))  # each point once, padding aside
    assert (real.sum(1) >= 8).all()  # median splits: no tile below half the size
    # a tile spans far less of the table than the table does
    spans = [(points[row].amax(0) - points[row].amin(0)).max().item() for row in index]
    assert max(spans) < 0.5


@pytest.mark.parametrize("size", [4, 32], ids=["many-tiles", "one-tile"])
def test_tiled_head_equals_the_dense_head(size):
    m = PushDynamics(DynamicsSpec(**dict(TINY_SPEC, hidden=(24, 20)))).double()
    g = torch.Generator().manual_seed(8)
    points = torch.rand(29, 2, dtype=F64, generator=g) * 1.2 - 0.6
    index, real = tile_points(points, size)
    tiled_points = points[index.flatten()]
    head = TiledHead(m, tiled_points, len(index))
    S = torch.randn(5, 24, dtype=F64, generator=g)
    S[:, :4] -= 20.0  # units dead everywhere
    out, cache = head.forward(S)
    expected = m.from_terms(S, m.point_term(tiled_points[None]))
    assert out.shape == (5, len(tiled_points))
    assert (out - expected).abs().max() < 1e-12
    # live units per tile: never more than anywhere in the batch, fewer with small tiles
    assert all(b.units.shape[1] <= 24 + 1 for b in cache)
    c = torch.randn(5, len(tiled_points), dtype=F64, generator=g) * real.flatten()
    S_ = S.clone().requires_grad_(True)
    (grad_expected,) = torch.autograd.grad(
        (m.from_terms(S_, m.point_term(tiled_points[None])) * c).sum(), S_)
    grad = head.input_grad(cache, c)
    assert (grad - grad_expected).abs().max() < 1e-12 * max(1.0, grad_expected.abs().max().item())
    assert (grad[:, :4] == 0).all() and grad.abs().sum() > 0


def test_tiled_head_needs_two_hidden_layers():
    m = PushDynamics(DynamicsSpec(**dict(TINY_SPEC, hidden=(16,)))).double()
    with pytest.raises(ValueError, match="two hidden layers"):
        TiledHead(m, torch.zeros(4, 2, dtype=F64), 1)
