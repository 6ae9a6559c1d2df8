import math

import pytest
import torch

from robotplan.functionals import GoalRegion, Quadrature
from robotplan.functionals.goal import PoseError, gyration_radius
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


def _grid_points(body, step=0.002):
    """Points of a fine grid inside ``body``'s footprint (body frame), ``(P, 2)``."""
    lo, hi = body.shape.outline().min(0), body.shape.outline().max(0)
    xs = torch.arange(lo[0] + step / 2, hi[0], step, dtype=F64)  # cell centres
    ys = torch.arange(lo[1] + step / 2, hi[1], step, dtype=F64)
    p = torch.cartesian_prod(xs, ys)
    phi, _ = body.shape.sdf_and_grad(p)
    return p[phi < 0]


@pytest.mark.parametrize("name", ["box", "ell"])
def test_pose_error_is_the_rms_displacement_of_the_footprint(name, request):
    body = request.getfixturevalue(name)
    goal = (0.3, -0.1, 0.7)
    H = PoseError(body.shape.outline(), goal)
    X = torch.tensor([[0.3, -0.1, 0.7], [0.32, -0.09, 0.9], [0.25, 0.0, -0.4]], dtype=F64)
    r = H(X)
    assert r[0].abs().max() < 1e-12  # zero at the target
    p = _grid_points(body)

    def world(pose):
        c, s = math.cos(pose[2]), math.sin(pose[2])
        return p @ torch.tensor([[c, s], [-s, c]], dtype=F64) + torch.tensor(pose[:2], dtype=F64)

    for k in (1, 2):
        msd = ((world(X[k].tolist()) - world(goal)) ** 2).sum(1).mean()
        assert abs(float((r[k] ** 2).sum()) - float(msd)) < 0.01 * float(msd)


def test_pose_error_jacobian_matches_finite_differences(ell):
    H = PoseError(ell.shape.outline(), (0.1, 0.2, -0.3))
    X = torch.tensor([[0.15, 0.0, 0.3], [0.1, 0.21, -0.25]], dtype=F64)
    _, (J,) = H.jacobians(X)
    fd = central_difference_jacobian(H, (X,), 0)
    assert torch.allclose(J, fd, rtol=1e-6, atol=1e-10), (J - fd).abs().max()


def test_pose_tolerance_bounds_the_share_moved_off_target(box):
    """A translation of the tolerance along either axis uncovers at most the share."""
    outline = box.shape.outline()
    H = PoseError(outline, (0.0, 0.0, 0.0))
    tol = H.tolerance(outline, 0.02)
    p = _grid_points(box, 0.001)
    for d in ((tol, 0.0), (0.0, tol), (tol / math.sqrt(2), tol / math.sqrt(2))):
        moved = p + torch.tensor(d, dtype=F64)
        phi, _ = box.shape.sdf_and_grad(moved)
        assert float((phi > 0).double().mean()) <= 0.02
    assert abs(gyration_radius(outline) - math.sqrt((0.2**2 + 0.12**2) / 12)) < 1e-9
