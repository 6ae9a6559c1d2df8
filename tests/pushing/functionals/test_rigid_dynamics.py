"""H_q: the F_q row's value is the footprint's displacement from the predicted step, and its
Jacobians are exact (float64 against central differences)."""

import math

import pytest
import torch

from robotplan.pushing.functionals.rigid_dynamics import RigidDynamics, footprint_moments
from robotplan.pushing.models.dynamics import DynamicsSpec
from robotplan.pushing.models.rigid import RigidMotion
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


def pushed_by(actor: str) -> tuple[Body, torch.Tensor, torch.Tensor]:
    """The pusher and the trajectories: a disc (positions) or an object that pushes (poses,
    a chain)."""
    X1, X2 = trajectory()
    if actor == "disc":
        return PUSHER, X1, X2
    X2 = torch.cat((X2 - torch.tensor([0.03, 0.0], dtype=F64),
                    torch.linspace(0.05, 0.09, len(X2), dtype=F64)[:, None]), 1)
    return Body("red", "object", Box((0.08, 0.08)), (0, 0, 0), 0.0, 0.06), X1, X2


@pytest.mark.parametrize("actor", ["disc", "object"])
def test_jacobian_matches_finite_differences(model, obj, actor):
    """For a disc pusher (positions) and for an object that pushes (poses, a chain)."""
    pusher, X1, X2 = pushed_by(actor)
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


# a point-cloud F_q (paper app. A.2) on a coarse grid (1.67 cm), cheap to evaluate. Which
# edges carry the cloud's vertices, farthest-point sampling and the nearest neighbours are
# discrete choices, and an SDF's kink (a medial axis) at a grid point is one too: on this
# grid no step of the differences below crosses any of them for either footprint (on a
# 1.5 cm grid the L-shape's does, as do PointNet++'s picks with 12 or more centroids)
CLOUD = {"representation": "pointcloud", "grid": (36, 36), "workspace_size": (0.6, 0.6),
         "cloud_points": 32, "cloud_widths": (8, 16), "sdf_features": 8, "hidden": (16,),
         "cloud_centroids": 8, "cloud_neighbours": 6, "cloud_local_widths": (8,)}
# the pusher off the grid's mirror lines too: there farthest-point sampling meets exact ties
PUSHER_OFFSET = torch.tensor([0.0017, 0.0009], dtype=F64)


def step_jacobians_by_differences(H, X1: torch.Tensor, X2: torch.Tensor, h: float
                                  ) -> tuple[torch.Tensor, torch.Tensor]:
    """J1, J2 in :meth:`RigidDynamics.evaluate`'s layout by central differences of H's
    values; asserts that a state moves no step but its own two."""
    out = []
    for which, X in enumerate((X1, X2)):
        T = X.shape[0] - 1
        J = torch.zeros(T, 2, X.shape[1], dtype=X.dtype)
        for s in range(T + 1):
            for k in range(X.shape[1]):
                plus, minus = X.clone(), X.clone()
                plus[s, k] += h
                minus[s, k] -= h
                args_p = (plus, X2) if which == 0 else (X1, plus)
                args_m = (minus, X2) if which == 0 else (X1, minus)
                fd = (H.evaluate(*args_p, jacobian=False)[0]
                      - H.evaluate(*args_m, jacobian=False)[0]) / (2 * h)
                if s >= 1:  # state s is step s − 1's "now"
                    J[s - 1, 1, k] = fd[s - 1]
                if s < T:  # and step s's "prev"
                    J[s, 0, k] = fd[s]
                others = [t for t in range(T) if t not in (s - 1, s)]
                assert (fd[others] == 0).all(), (which, s, k)
        out.append(J)
    return out[0], out[1]


@pytest.mark.parametrize("encoder", ["pointnet", "pointnet2"])
def test_jacobian_through_a_point_cloud_f_q(obj, encoder):
    """G by autograd through the marching-squares vertices: H_q's Jacobians match central
    differences (h = 1e-6, float64) to 1e-5 of the part F_q contributes, J2's size: a
    wrong G would miss by that whole part. The F_q's grid values pass it the pusher's
    state in both states of every step."""
    torch.manual_seed(7)
    spec = DynamicsSpec(kind="rigid", encoder="joint", cloud_encoder=encoder, **CLOUD)
    H = RigidDynamics(RigidMotion(spec).double(), obj, PUSHER)
    X1, X2 = trajectory()
    X2 = X2 + PUSHER_OFFSET
    values, j1, j2 = H.evaluate(X1, X2)
    assert (values > 0).all()
    torch.testing.assert_close(H.evaluate(X1, X2, jacobian=False)[0], values, rtol=1e-12,
                               atol=0.0)
    assert j1.shape == (3, 2, 3) and j2.shape == (3, 2, 2)
    assert (j2.abs().amax(2) > 0).all()
    fd1, fd2 = step_jacobians_by_differences(H, X1, X2, h=1e-6)
    atol = 1e-5 * float(j2.abs().max())
    torch.testing.assert_close(j2, fd2, rtol=0.0, atol=atol)
    torch.testing.assert_close(j1, fd1, rtol=0.0, atol=atol)


# an F_q on a grid attached to the object (spec.frame "object"), coarse enough to be cheap
OBJECT_FRAME = {**SPEC, "frame": "object", "grid": (32, 32), "workspace_size": (0.64, 0.64)}


@pytest.fixture
def object_frame_model() -> RigidMotion:
    torch.manual_seed(8)
    return RigidMotion(DynamicsSpec(kind="rigid", encoder="joint", **OBJECT_FRAME)).double()


@pytest.mark.parametrize("actor", ["disc", "object"])
def test_object_frame_jacobian_matches_finite_differences(object_frame_model, obj, actor):
    """The object's state t − 1 moves F_t, so the pusher's grids and the predicted shift's
    direction: its Jacobian column carries both. Against central differences (float64) to
    1e-5 of J2's size, the part that passes through F_q's grids: a term of F_t missing
    there would miss by about that whole part."""
    pusher, X1, X2 = pushed_by(actor)
    H = RigidDynamics(object_frame_model, obj, pusher)
    values, j1, j2 = H.evaluate(X1, X2)
    assert (values > 0).all() and (j2.abs().amax(2) > 0).all()
    fd1, fd2 = step_jacobians_by_differences(H, X1, X2, h=1e-7)
    atol = 1e-5 * float(j2.abs().max())
    torch.testing.assert_close(j2, fd2, rtol=0.0, atol=atol)
    torch.testing.assert_close(j1, fd1, rtol=0.0, atol=atol)


def test_object_frame_prediction_moves_and_turns_with_the_scene(object_frame_model, obj):
    """Moving and turning the whole scene (object and pusher) moves and turns F_q's
    table-frame step with it and leaves its turn: the symmetry the object frame builds in."""
    X1, X2 = trajectory()
    H = RigidDynamics(object_frame_model, obj, PUSHER)
    delta = H.predict(X1, X2)
    assert delta.abs().max() > 0
    angle, shift = 0.7, torch.tensor([0.11, -0.05], dtype=F64)
    c, s = math.cos(angle), math.sin(angle)
    R = torch.tensor([[c, -s], [s, c]], dtype=F64)
    moved1 = torch.cat((X1[:, :2] @ R.T + shift, X1[:, 2:] + angle), 1)
    moved = H.predict(moved1, X2 @ R.T + shift)
    torch.testing.assert_close(moved[:, :2], delta[:, :2] @ R.T, rtol=0, atol=1e-9)
    torch.testing.assert_close(moved[:, 2], delta[:, 2], rtol=0, atol=1e-9)
