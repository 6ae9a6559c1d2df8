"""The windowed fast path of H_coll and H_g against fine full grids."""

import torch

from robotplan.functionals import Collision, GoalRegion, Quadrature
from robotplan.functionals.windows import body_aabb, window_points
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle
from tests.functionals.conftest import F64, central_difference_jacobian


def test_window_points_cover_the_window_on_a_fixed_lattice():
    lo = torch.tensor([[0.0, 0.0], [0.1, 0.1], [0.5, 0.5]], dtype=F64)
    hi = torch.tensor([[0.01, 0.02], [0.1, 0.2], [0.4, 0.6]], dtype=F64)  # 2nd, 3rd empty
    pts, w = window_points(lo, hi, 0.005)
    assert w[0].sum().item() == torch.tensor(0.01 * 0.02, dtype=F64).item()
    assert w[1:].sum() == 0
    inside = pts[0][w[0] > 0]
    assert (inside >= lo[0]).all() and (inside <= hi[0]).all()
    assert torch.allclose((inside / 0.005 - 0.5).round(), inside / 0.005 - 0.5)


def test_a_nan_pose_gives_a_nan_value_not_an_error(ell, region):
    X = torch.tensor([[0.0, 0.0, 0.1], [float("nan"), 0.0, 0.1]], dtype=F64)
    value = GoalRegion(ell, region)(X)
    assert torch.isfinite(value[0]).all() and torch.isnan(value[1]).all()
    r, (J,) = GoalRegion(ell, region).jacobians(X)
    assert torch.isfinite(r[0]).all() and torch.isnan(r[1]).all()
    assert torch.isfinite(J[0]).all()  # the valid step's Jacobian is untouched


def test_aabb_of_rotated_box():
    box = Body("b", "object", Box((0.2, 0.1)), (0, 0, 0), 0.0, 0.06)
    lo, hi = body_aabb(box, torch.tensor([[1.0, 2.0, torch.pi / 2]], dtype=F64))
    assert torch.allclose(lo, torch.tensor([[0.95, 1.9]], dtype=F64))
    assert torch.allclose(hi, torch.tensor([[1.05, 2.1]], dtype=F64))


def test_windowed_collision_matches_a_fine_full_grid(box, ell, pusher):
    wall = Body("wall", "obstacle", Box((0.06, 0.3)), (0, 0, 0), 0.0, 0.06)
    reference = Quadrature.box((0.0, 0.0), (0.6, 0.6), 0.0005)
    for other, X2 in ((pusher, torch.tensor([[-0.128, 0.01], [-0.125, -0.02]], dtype=F64)),
                      (wall, torch.tensor([[0.125, 0.0, 0.0], [0.121, 0.003, 0.05]], dtype=F64))):
        for body in (box, ell):
            X1 = torch.tensor([[0.0, 0.0, 0.0], [0.002, 0.001, 0.1]], dtype=F64)
            fast = Collision(body, other)(X1, X2)
            ref = Collision(body, other, reference)(X1, X2)
            assert (ref > 1e-6).all()
            assert ((fast - ref).abs() / ref).max() < 0.01


def test_windowed_collision_is_zero_and_flat_when_apart(box, pusher):
    H = Collision(box, pusher)
    X1 = torch.zeros(3, 3, dtype=F64)
    X2 = torch.tensor([[-0.3, 0.0], [0.0, 0.3], [0.5, 0.5]], dtype=F64)
    r, (J1, J2) = H.jacobians(X1, X2)
    assert (r == 0).all() and (J1 == 0).all() and (J2 == 0).all()


def test_windowed_jacobians_match_finite_differences(ell, pusher):
    H = Collision(ell, pusher)
    X1 = torch.tensor([[0.01, 0.0, 0.2], [0.0, 0.02, -0.3]], dtype=F64)
    X2 = torch.tensor([[-0.125, -0.05], [-0.12, -0.06]], dtype=F64)
    r, (J1, J2) = H.jacobians(X1, X2)
    assert (r > 0).all()
    for J, which in ((J1, 0), (J2, 1)):
        fd = central_difference_jacobian(H, (X1, X2), which, h=1e-7)
        assert torch.allclose(J, fd, rtol=1e-4, atol=1e-9), (J - fd).abs().max()


def test_windowed_goal_matches_a_fine_full_grid(ell):
    region = Body("goal", "region", Box((0.4, 0.4)), (0.25, 0.0, 0.0), 0.0, 0.0)
    X = torch.tensor([[0.1, 0.0, 0.3], [0.35, 0.1, -0.5], [0.0, 0.0, 0.0]], dtype=F64)
    fast = GoalRegion(ell, region, a=100.0)(X)
    ref = GoalRegion(ell, region, Quadrature.box((0.0, 0.0), (1.4, 1.4), 0.001), a=100.0)(X)
    assert ((fast - ref).abs() / ref).max() < 0.01
    # off-lattice poses: a window edge crossing a lattice line moves a point whose
    # integrand is below eps (a jump of at most eps · h² in H)
    X = X + torch.tensor([0.0013, 0.0007, 0.0], dtype=F64)
    _, (J,) = GoalRegion(ell, region, a=100.0).jacobians(X)
    fd = central_difference_jacobian(GoalRegion(ell, region, a=100.0), (X,), 0, h=1e-7)
    assert torch.allclose(J, fd, rtol=1e-4, atol=1e-9)


def test_circle_pusher_with_position_only_pose():
    pusher = Body("p", "pusher", Circle(0.03), (0, 0, 0), 0.0, 0.06)
    lo, hi = body_aabb(pusher, torch.tensor([[0.1, 0.2]], dtype=F64))
    assert torch.allclose(hi - lo, torch.tensor([[0.06, 0.06]], dtype=F64))
