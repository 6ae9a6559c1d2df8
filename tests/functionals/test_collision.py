import pytest
import shapely
import torch

from robotplan.functionals import Collision, Quadrature
from robotplan.functionals.collision import face_contact_overlap
from robotplan.scene.bodies import Body
from tests.functionals.conftest import F64, central_difference_jacobian


def poses(*rows):
    return torch.tensor(rows, dtype=F64)


def test_gradcheck_in_both_poses(box, pusher, coarse):
    H = Collision(box, pusher, coarse, a=500.0)
    X1 = poses([0.0, 0.0, 0.1], [0.02, -0.01, 0.5]).requires_grad_(True)
    X2 = poses([-0.11, 0.01], [-0.1, 0.05]).requires_grad_(True)
    assert torch.autograd.gradcheck(H, (X1, X2))


def test_jacobians_match_finite_differences(ell, pusher, coarse):
    H = Collision(ell, pusher, coarse, a=500.0)
    X1 = poses([0.0, 0.0, 0.3], [0.01, 0.02, -0.4], [0.0, 0.0, 1.0])
    X2 = poses([-0.1, -0.05], [-0.08, -0.1], [0.05, 0.0])
    r, (J1, J2) = H.jacobians(X1, X2)
    assert r.shape == (3, 1) and J1.shape == (3, 1, 3) and J2.shape == (3, 1, 2)
    for J, which in ((J1, 0), (J2, 1)):
        fd = central_difference_jacobian(H, (X1, X2), which)
        assert torch.allclose(J, fd, rtol=1e-5, atol=1e-9), (J - fd).abs().max()
    assert (J1.abs() > 1e-6).any()  # the test would notice a zero Jacobian


def test_zero_when_apart_beyond_the_smoothing_band(box, pusher, fine):
    H = Collision(box, pusher, fine, a=500.0)
    gap = 0.05  # 25 / a: far beyond the ~2 mm sigmoid edge
    value = H(poses([0.0, 0.0, 0.0]), poses([-0.1 - 0.03 - gap, 0.0]))
    assert value.item() < 1e-9


def test_positive_and_growing_with_overlap_depth(box, pusher, fine):
    H = Collision(box, pusher, fine, a=500.0)
    depths = [0.0, 0.005, 0.01, 0.02, 0.04, 0.06]
    X2 = poses(*[[-0.1 - 0.03 + d, 0.0] for d in depths])
    values = H(poses([0.0, 0.0, 0.0]).expand(len(depths), 3), X2)[:, 0]
    assert (values > 0).all()
    assert (values.diff() > 0).all(), values
    # deep in, the smoothed integral is close to the exact overlap area
    exact = shapely.box(-0.1, -0.06, 0.1, 0.06).intersection(
        shapely.Point(-0.1 - 0.03 + 0.06, 0.0).buffer(0.03, 256)).area
    assert abs(values[-1].item() - exact) / exact < 0.02


def test_batched_steps_equal_single_steps(box, pusher, coarse):
    H = Collision(box, pusher, coarse)
    X1 = poses([0.0, 0.0, 0.2], [0.01, 0.0, 0.3])
    X2 = poses([-0.12, 0.0], [-0.1, 0.02])
    batched = H(X1, X2)
    single = torch.cat([H(X1[i:i + 1], X2[i:i + 1]) for i in range(2)])
    assert torch.allclose(batched, single, rtol=0, atol=1e-15)


def test_float32_works(box, pusher):
    q = Quadrature.box((0.0, 0.0), (0.7, 0.7), 0.004, dtype=torch.float32)
    H = Collision(box, pusher, q)
    v = H(torch.tensor([[0.0, 0.0, 0.0]]), torch.tensor([[-0.11, 0.0]]))
    assert v.dtype == torch.float32 and v.item() > 0


def test_face_contact_overlap_is_what_touching_costs(box, pusher, fine):
    """The planner's collision bound: a face contact pressed in ``depth`` stays within it, a
    deeper one does not, and for a 3 cm pusher it exceeds 2e-5 m² (``coll_area``, a floor
    below what touching costs: docs/experiments.md#collision-bound)."""
    bound = face_contact_overlap(pusher, a=500.0, depth=0.0005)
    H = Collision(box, pusher, fine, a=500.0)
    X_box = poses([0.0, 0.0, 0.0])

    def pressed(depth):  # pusher on the box's −x face (half width 0.1 m)
        return H(X_box, poses([-0.1 - 0.03 + depth, 0.0])).item()

    assert pressed(0.0) < bound < pressed(0.002)
    assert abs(pressed(0.0005) - bound) < 0.02 * bound
    assert bound > 2e-5
    with pytest.raises(ValueError, match="disc"):
        face_contact_overlap(box)


def test_fixed_collision_is_the_pair_with_the_obstacle_held(box, ell):
    from robotplan.functionals.collision import FixedCollision

    wall = Body("wall", "obstacle", ell.shape, (0.12, 0.03, 0.4), 0.0, 0.06)
    H = FixedCollision(box, wall, a=500.0)
    X = poses([0.0, 0.0, 0.1], [0.02, 0.01, 0.5], [-0.3, 0.0, 0.0])
    pair = Collision(box, wall, a=500.0)(X, torch.tensor([wall.pose] * 3, dtype=F64))
    assert torch.allclose(H(X), pair) and pair[0, 0] > 1e-4 and pair[2, 0] == 0.0
    _, (J,) = H.jacobians(X)
    fd = central_difference_jacobian(H, (X,), 0)
    assert torch.allclose(J, fd, rtol=1e-4, atol=1e-9), (J - fd).abs().max()
    assert (J[:2].abs() > 1e-6).any()


def test_swept_clearance_sees_a_move_through_the_object_and_has_exact_gradients():
    from robotplan.functionals.collision import SweptClearance
    from robotplan.sdf import Box, Circle

    box = Body("box", "object", Box((0.2, 0.1)), (0.0, 0.0, 0.3), 0.0, 0.06)
    disc = Body("p", "pusher", Circle(0.03), (0.0, 0.0, 0.0), 0.0, 0.06)
    H = SweptClearance(box, disc, samples=5)
    X = torch.tensor([[0.0, 0.0, 0.3], [0.0, 0.0, 0.3]], dtype=torch.float64)
    a = torch.tensor([[-0.3, 0.0], [-0.3, 0.2]], dtype=torch.float64)
    b = torch.tensor([[0.3, 0.0], [0.3, 0.2]], dtype=torch.float64)  # through / beside it
    r = H(X, a, b)
    assert r.shape == (2, 5)
    assert r[0].min() < -0.05 and r[0, 2] < -0.05  # the middle sample is inside the box
    assert r[1].min() > 0.0  # 20 cm to the side passes clear
    # gradients against central differences in float64
    r_jac, jac = H.jacobians(X, a, b)
    assert (r_jac - r).abs().max() < 1e-14  # the written-out path computes the same gaps
    for which, J in enumerate(jac):
        fd = central_difference_jacobian(H, (X, a, b), which)
        assert torch.allclose(J, fd, atol=1e-6), which
