import math

import numpy as np
import torch

from robotplan.functionals.sticking import PushingDirection, PushLever, StickingContact
from tests.functionals.conftest import F64, central_difference_jacobian


def rigid(X, p, dx, dy, dth):
    """Move object pose X (T, 3) and a point p (T, 2) attached to it by one rigid motion
    about the object's origin."""
    c, s = math.cos(dth), math.sin(dth)
    d = p - X[:, :2]
    p_new = X[:, :2] + torch.tensor([dx, dy], dtype=F64) + torch.stack(
        (c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]), -1)
    return X + torch.tensor([dx, dy, dth], dtype=F64), p_new


def test_sticking_is_zero_for_a_rigid_motion_and_not_for_sliding():
    H = StickingContact()
    X = torch.tensor([[0.1, -0.2, 0.3], [0.0, 0.0, -1.0]], dtype=F64)
    p = torch.tensor([[0.2, -0.2], [0.05, 0.1]], dtype=F64)
    X1, p1 = rigid(X, p, 0.02, -0.01, 0.2)
    assert H(X, p, X1, p1).abs().max() < 1e-12
    slid = H(X, p, X1, p1 + torch.tensor([0.01, 0.0], dtype=F64))
    assert torch.allclose(slid.norm(dim=-1), torch.full((2,), 0.01, dtype=F64))


def test_pushing_direction_sign_and_jacobians():
    H = PushingDirection()
    x_prev = torch.tensor([[0.0, 0.0], [0.0, 0.0]], dtype=F64)
    x = torch.tensor([[0.01, 0.0], [-0.01, 0.002]], dtype=F64)
    p = torch.tensor([[0.04, 0.0], [0.03, 0.0]], dtype=F64)  # contact to the +x side
    into, away = H(x_prev, x, p)[:, 0].tolist()
    assert abs(into - 0.01) < 1e-12 and away < 0
    for which in range(3):
        _, Js = H.jacobians(x_prev, x, p)
        fd = central_difference_jacobian(H, (x_prev, x, p), which)
        assert torch.allclose(Js[which], fd, rtol=1e-5, atol=1e-9)
    S = StickingContact()
    X = torch.tensor([[0.1, -0.2, 0.3]], dtype=F64)
    q = torch.tensor([[0.2, -0.1]], dtype=F64)
    inputs = (X, q, X + 0.01, q - 0.02)
    _, Js = S.jacobians(*inputs)
    for which in range(4):
        fd = central_difference_jacobian(S, inputs, which)
        assert torch.allclose(Js[which], fd, rtol=1e-5, atol=1e-9)


def test_push_lever_is_the_distance_of_the_force_line_from_the_centroid():
    H = PushLever(np.array([0.02, 0.0]))  # centroid 2 cm along the body's x axis
    X = torch.tensor([[0.0, 0.0, math.pi / 2]], dtype=F64)  # → centroid at (0, 0.02)
    x = torch.tensor([[-0.1, 0.05]], dtype=F64)
    p = torch.tensor([[-0.07, 0.05]], dtype=F64)  # pushing along +x at y = 0.05
    assert abs(H(X, x, p).item() - (0.02 - 0.05)) < 1e-12
    inputs = (X + 0.1, x, p + 0.01)
    _, Js = H.jacobians(*inputs)
    for which in range(3):
        fd = central_difference_jacobian(H, inputs, which)
        assert torch.allclose(Js[which], fd, rtol=1e-5, atol=1e-9)
