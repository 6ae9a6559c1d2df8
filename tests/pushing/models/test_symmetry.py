"""The quarter turns and mirrors of a square X_h, and models averaged over them (float64)."""

import math

import pytest
import torch

from robotplan.models.spec import DynamicsSpec
from robotplan.pushing.models.dynamics import PushDynamics
from robotplan.pushing.models.rigid import RigidMotion
from robotplan.pushing.models.symmetry import grid_views, symmetric_delta_q, symmetric_field
from robotplan.sdf import Workspace
from tests.conftest import TINY_SPEC

SPEC = DynamicsSpec(grid=(40, 40), workspace_size=(0.4, 0.4), kind="rigid", encoder="joint",
                    **{k: v for k, v in TINY_SPEC.items() if k != "point_features"})


def _coordinates() -> torch.Tensor:
    """The table coordinates of X_h's points as two grids ``(2, H, W)``."""
    ws = Workspace(SPEC.workspace_center, SPEC.workspace_size,
                   SPEC.workspace_size[0] / SPEC.grid[1])
    return ws.points(torch.float64).permute(2, 0, 1)


def test_the_views_are_the_group_of_the_square():
    assert [len(grid_views(n)) for n in (1, 4, 8)] == [1, 4, 8]
    matrices = {tuple(v.matrix(torch.zeros(1)).flatten().tolist()) for v in grid_views(8)}
    assert len(matrices) == 8
    with pytest.raises(ValueError, match="views 3"):
        grid_views(3)


def test_each_view_moves_the_grid_as_its_matrix_moves_the_table():
    """The view of the scene g · s shows at point p what s shows at g⁻¹ p: applied to the
    coordinate grids it gives g⁻¹ p = Mᵀ p at every point."""
    coords = _coordinates()
    for view in grid_views(8):
        M = view.matrix(coords)
        expected = torch.einsum("ji,jhw->ihw", M, coords)
        assert (view.images(coords) - expected).abs().max() < 1e-12, view
        assert torch.equal(view.images_back(view.images(coords)), coords)


def test_a_non_square_grid_is_refused():
    with pytest.raises(ValueError, match="square"):
        grid_views(4)[1].images(torch.zeros(1, 3, 4, 5))


def _inputs(seed: int) -> torch.Tensor:
    g = torch.Generator().manual_seed(seed)
    return torch.rand(3, 3, *SPEC.grid, generator=g, dtype=torch.float64) - 0.3


def test_f_q_averaged_over_the_views_turns_and_mirrors_with_the_scene():
    """Turning the inputs by a quarter turn turns the averaged Δq's shift with them and keeps
    its turn; mirroring them mirrors the shift and flips the turn. A single network does
    neither."""
    torch.manual_seed(0)
    model = RigidMotion(SPEC).double().eval()
    x = _inputs(1)
    with torch.no_grad():
        for count in (1, 4, 8):
            base = symmetric_delta_q(model, x, count)
            turned = symmetric_delta_q(model, grid_views(4)[1].images(x), count)
            quarter = torch.stack((-base[:, 1], base[:, 0], base[:, 2]), 1)
            mirrored = symmetric_delta_q(model, x.flip(-1), count)
            flipped = base * base.new_tensor([-1.0, 1.0, -1.0])
            turn_ok = (turned - quarter).abs().max() < 1e-12
            mirror_ok = (mirrored - flipped).abs().max() < 1e-12
            assert turn_ok == (count >= 4), count
            assert mirror_ok == (count == 8), count


def test_f_flow_averaged_over_the_views_moves_its_field_with_the_scene():
    torch.manual_seed(0)
    spec = DynamicsSpec(grid=SPEC.grid, workspace_size=SPEC.workspace_size, kind="flow",
                        encoder="joint", **TINY_SPEC)
    model = PushDynamics(spec).double().eval()
    ws = spec.workspace()
    point_term = model.point_term(ws.points(torch.float64).reshape(1, -1, 2))

    def field(inputs):
        return model.from_terms(model.sdf_term(model.features(inputs)), point_term)

    x, view = _inputs(2), grid_views(8)[6]  # a mirror and two quarter turns
    with torch.no_grad():
        for count, equivariant in ((4, False), (8, True)):
            base = symmetric_field(field, x, count).reshape(len(x), *spec.grid)
            moved = symmetric_field(field, view.images(x), count).reshape(len(x), *spec.grid)
            assert ((moved - view.images(base)).abs().max() < 1e-12) == equivariant
        single = field(x)
        assert torch.equal(symmetric_field(field, x, 1), single)
    assert math.isfinite(float(single.abs().max()))
