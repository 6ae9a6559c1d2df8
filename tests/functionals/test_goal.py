import torch

from robotplan.functionals import GoalRegion, Quadrature
from tests.functionals.conftest import F64, central_difference_jacobian


def test_gradcheck(box, region, coarse):
    H = GoalRegion(box, region, coarse, a=100.0)
    X = torch.tensor([[0.15, 0.0, 0.3], [0.2, 0.1, -0.2]], dtype=F64, requires_grad=True)
    assert torch.autograd.gradcheck(H, (X,))


def test_jacobian_matches_finite_differences(ell, region, coarse):
    H = GoalRegion(ell, region, coarse)
    X = torch.tensor([[0.15, 0.0, 0.3], [0.25, 0.1, -0.2], [0.013, 0.007, 0.1]], dtype=F64)
    _, (J,) = H.jacobians(X)
    fd = central_difference_jacobian(H, (X,), 0)
    assert torch.allclose(J, fd, rtol=1e-5, atol=1e-10), (J - fd).abs().max()
    assert (J[:2].abs() > 1e-5).any()


def test_zero_well_inside_and_area_outside_otherwise(box, region):
    wide = Quadrature.box((0.0, 0.0), (1.0, 1.0), 0.002)
    H = GoalRegion(box, region, wide, a=100.0)
    X = torch.tensor([[0.0, 0.0, 0.0], [0.2, 0.0, 0.0], [0.36, 0.0, 0.0]], dtype=F64)
    inside, half, out = H(X)[:, 0].tolist()
    assert inside < 1e-4 * box.area
    assert abs(half - 0.5 * box.area) < 0.05 * box.area  # half the box crosses x = 0.2
    assert abs(out - box.area) < 0.05 * box.area
    assert inside < half < out


def test_inset_measures_against_the_shrunk_region(box, region):
    wide = Quadrature.box((0.0, 0.0), (1.0, 1.0), 0.002)
    plain = GoalRegion(box, region, wide, a=100.0)
    inset = GoalRegion(box, region, wide, a=100.0, inset=0.03)
    X = torch.tensor([[0.0, 0.0, 0.0], [0.07, 0.0, 0.0]], dtype=F64)  # centre; 3 cm to edge
    centre, near_edge = inset(X)[:, 0].tolist()
    assert centre < 1e-3 * box.area  # 4 cm of room on the tight side: still inside
    outside = plain(X)[1, 0].item()
    assert outside < 0.02 * box.area  # inside the region itself (up to the sigmoid tail) …
    assert near_edge > 5 * outside  # … but much more outside the inset one
    windowed = GoalRegion(box, region, a=100.0, inset=0.03)  # the fast path agrees
    assert torch.allclose(windowed(X), inset(X), rtol=0.02, atol=1e-4 * box.area)
