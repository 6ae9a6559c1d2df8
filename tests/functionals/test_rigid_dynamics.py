"""H_q: the F_q row's value is the footprint's displacement from the predicted step, and its
Jacobians are exact (float64 against central differences)."""

import math

import pytest
import torch

from robotplan.functionals.rigid_dynamics import RigidDynamics, footprint_moments
from robotplan.models.dynamics import DynamicsSpec
from robotplan.models.rigid import RigidMotion
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle, LShape
from tests.functionals.conftest import F64, assert_step_jacobians

SPEC = {"channels": (2, 3, 3), "sdf_features": 16, "hidden": (24, 24)}
PUSHER = Body("pusher", "pusher", Circle(0.03), (0, 0, 0), 0.0, 0.06)
# off the grid's cell centres, so that no grid point sits on the SDF's medial axis
OFFSET = torch.tensor([0.0013, 0.0021, 0.013], dtype=F64)


@pytest.fixture
def model() -> RigidMotion:
    torch.manual_seed(5)
    return RigidMotion(DynamicsSpec(kind="rigid", encoder="joint", **SPEC)).double()


@pytest.fixture(params=[Box((0.2, 0.12)), LShape((0.24, 0.18), 0.07)], ids=["box", "lshape"])
def obj(request) -> Body:
    return Body("obj", "object", request.param, (0, 0, 0), 0.0, 0.06)


def trajectory(T: int = 3) -> tuple[torch.Tensor, torch.Tensor]:
    X1 = torch.zeros(T + 1, 3, dtype=F64)
    X1[:, 0] = torch.linspace(0.0, 0.03, T + 1)
    X1[:, 2] = torch.linspace(0.1, 0.2, T + 1)
    X2 = torch.zeros(T + 1, 2, dtype=F64)
    X2[:, 0] = torch.linspace(-0.16, -0.12, T + 1)
    X2[:, 1] = 0.013
    return X1 + OFFSET, X2


def test_footprint_moments_of_a_box_and_an_l_shape():
    box = Body("b", "object", Box((0.2, 0.12)), (0, 0, 0), 0.0, 0.06)
    centre, rho = footprint_moments(box)
    assert centre.abs().max() < 1e-4
    assert rho == pytest.approx(math.sqrt((0.2 ** 2 + 0.12 ** 2) / 12), rel=5e-3)
    ell = Body("l", "object", LShape((0.24, 0.18), 0.07), (0, 0, 0), 0.0, 0.06)
    centre, _ = footprint_moments(ell)
    # two strips: bottom 0.24 × 0.07, left 0.07 × 0.11 above it
    a1, a2 = 0.24 * 0.07, 0.07 * 0.11
    expected = torch.tensor([(a1 * 0.0 + a2 * (-0.12 + 0.035)) / (a1 + a2),
                             (a1 * (-0.09 + 0.035) + a2 * (-0.09 + 0.07 + 0.055)) / (a1 + a2)],
                            dtype=F64)
    assert (centre - expected).abs().max() < 2e-4


def _pivot(q: torch.Tensor, centre: torch.Tensor) -> torch.Tensor:
    c, s = torch.cos(q[2]), torch.sin(q[2])
    return q[:2] + torch.stack((c * centre[0] - s * centre[1], s * centre[0] + c * centre[1]))


def test_the_predicted_step_has_no_residual(model, obj):
    """The first step's F_q input is the first pose only: a plan that puts the second pose
    where F_q predicts has H_q,1 = 0; turned by a further θ about the same pivot,
    H_q,1 = ρ² θ²."""
    X1, X2 = trajectory()
    H = RigidDynamics(model, obj, PUSHER)
    delta = H.predict(X1, X2)[0]
    assert delta.abs().max() > 0
    X = X1.clone()
    pivot = _pivot(X[0], H.centre) + delta[:2]
    for theta, expected in ((0.0, 0.0), (0.05, H.rho ** 2 * 0.05 ** 2)):
        X[1, 2] = X[0, 2] + delta[2] + theta
        X[1, :2] = pivot - (_pivot(X[1], H.centre) - X[1, :2])
        first = H.evaluate(X, X2, jacobian=False)[0][0]
        assert first == pytest.approx(expected, rel=1e-9, abs=1e-20)


@pytest.mark.parametrize("actor", ["disc", "object"])
def test_jacobian_matches_finite_differences(model, obj, actor):
    """For a disc pusher (positions) and for an object that pushes (poses, a chain)."""
    X1, X2 = trajectory()
    pusher = PUSHER
    if actor == "object":
        pusher = Body("red", "object", Box((0.08, 0.08)), (0, 0, 0), 0.0, 0.06)
        X2 = torch.cat((X2 - torch.tensor([0.03, 0.0], dtype=F64),
                        torch.linspace(0.05, 0.09, len(X2), dtype=F64)[:, None]), 1)
    H = RigidDynamics(model, obj, pusher)
    values, j1, j2 = H.evaluate(X1, X2)
    d2 = X2.shape[1]
    assert j1.shape == (3, 2, 3) and j2.shape == (3, 2, d2) and (values > 0).all()
    assert (j2.abs() > 0).any() and (j1[:, 0].abs() > 0).any()
    # small steps: a ReLU kink or an SDF medial axis within h makes FD accurate to O(h)
    assert_step_jacobians(H, X1, X2, j1, j2, h=1e-7, tol=1e-5, scale_with_jacobian=True)


def test_the_shared_encoder_is_refused(obj):
    shared = RigidMotion(DynamicsSpec(kind="rigid", encoder="shared", **SPEC))
    with pytest.raises(ValueError, match="joint"):
        RigidDynamics(shared, obj, PUSHER)


def test_jacobian_through_the_smooth_occupancy_baseline(obj):
    """An F_q on ψ_s = tanh(b φ) (paper eq. 11): H_q's Jacobians are exact there too."""
    torch.manual_seed(6)
    spec = DynamicsSpec(kind="rigid", encoder="joint", representation="smooth_occupancy",
                        occupancy_sharpness=100.0, **SPEC)
    H = RigidDynamics(RigidMotion(spec).double(), obj, PUSHER)
    X1, X2 = trajectory()
    values, j1, j2 = H.evaluate(X1, X2)
    assert (j2.abs() > 0).any() and (values > 0).all()
    assert_step_jacobians(H, X1, X2, j1, j2, h=1e-7, tol=1e-5, scale_with_jacobian=True)
