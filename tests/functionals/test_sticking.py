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


def test_quasi_static_push_turn_and_friction_cone():
    """A push through the centroid along the normal translates the object (all rows
    satisfied); the same push turning the object, or pushing 30° off the normal, violates
    the turn equation or leaves the friction cone (μ = 0.15: ±8.5°)."""
    from robotplan.functionals.sticking import QuasiStaticPush, limit_surface_radius

    corners = np.array([[0.1, 0.05], [-0.1, 0.05], [-0.1, -0.05], [0.1, -0.05]])
    c = limit_surface_radius(corners, np.zeros(2))
    assert abs(c - math.hypot(0.1, 0.05)) < 1e-12
    H = QuasiStaticPush(np.zeros(2), c, 0.15)
    X0 = torch.tensor([[0.0, 0.0, 0.0]], dtype=F64)
    x, p = torch.tensor([[-0.13, 0.0]], dtype=F64), torch.tensor([[-0.1, 0.0]], dtype=F64)
    straight = H(X0, torch.tensor([[0.02, 0.0, 0.0]], dtype=F64), x, p)[0]
    assert abs(straight[0]) < 1e-12 and (straight[1:] > 0).all()
    turned = H(X0, torch.tensor([[0.02, 0.0, 0.1]], dtype=F64), x, p)[0]
    assert abs(turned[0]) > 1e-3
    a = math.radians(30)
    off = H(X0, torch.tensor([[0.02 * math.cos(a), 0.02 * math.sin(a), 0.0]], dtype=F64),
            x, p)[0]
    assert min(off[1], off[2]) < 0
    # an off-centre push turns the object by its moment: c² Δθ = r × Δc
    p_off = torch.tensor([[-0.1, 0.03]], dtype=F64)
    dth = (-0.1 * 0.0 - 0.03 * 0.02) / c**2
    ok = H(X0, torch.tensor([[0.02, 0.0, dth]], dtype=F64), x + p_off - p, p_off)[0]
    assert abs(ok[0]) < 1e-12
    Xs = torch.tensor([[0.0, 0.0, 0.1], [0.01, -0.02, 0.5]], dtype=F64)
    Xt = Xs + torch.tensor([[0.02, 0.005, 0.03], [0.0, 0.02, -0.05]], dtype=F64)
    xs = torch.tensor([[-0.14, 0.01], [0.02, -0.12]], dtype=F64)
    ps = torch.tensor([[-0.1, 0.02], [0.03, -0.08]], dtype=F64)
    _, Js = H.jacobians(Xs, Xt, xs, ps)
    for i, J in enumerate(Js):
        fd = central_difference_jacobian(H, (Xs, Xt, xs, ps), i)
        assert torch.allclose(J, fd, rtol=1e-5, atol=1e-9), (i, (J - fd).abs().max())

