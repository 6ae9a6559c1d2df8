"""H_F with an object-frame F_flow or F: the training's prediction, the scene's symmetry,
and Jacobians against central differences (float64)."""

import math

import pytest
import torch

from robotplan.functionals import Quadrature
from robotplan.models.spec import OBJECT_WINDOW
from robotplan.pushing.functionals.framed_dynamics import FramedDynamics
from robotplan.pushing.models.dynamics import DynamicsSpec, PushDynamics
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle, LShape
from tests.functionals.conftest import F64, assert_step_jacobians

SPEC = {"channels": (2, 3, 3), "sdf_features": 16, "point_features": 8, "hidden": (24, 24)}
L_SIZE, L_THICKNESS = (0.2, 0.16), 0.07


def model(kind: str) -> PushDynamics:
    torch.manual_seed(4)
    return PushDynamics(DynamicsSpec(kind=kind, frame="object", **{**SPEC, **OBJECT_WINDOW})
                        ).double()


def trajectory(T=3):
    X1 = torch.zeros(T + 1, 3, dtype=F64)
    X1[:, 0] = torch.linspace(0.02, 0.05, T + 1)
    X1[:, 1] = -0.01
    X1[:, 2] = torch.linspace(0.3, 0.4, T + 1)
    X2 = torch.zeros(T + 1, 2, dtype=F64)
    X2[:, 0] = torch.linspace(-0.14, -0.10, T + 1)
    X2[:, 1] = 0.02
    return X1, X2


def quadrature(centre=(0.03, -0.01), half=0.3, n=12) -> Quadrature:
    return Quadrature.box(centre, (2 * half, 2 * half), 2 * half / n, F64)


def bodies():
    obj = Body("obj", "object", LShape(L_SIZE, L_THICKNESS), (0, 0, 0), 0.0, 0.06)
    return obj, Body("pusher", "pusher", Circle(0.025), (0, 0, 0), 0.0, 0.06)


@pytest.mark.parametrize("kind", ["flow", "direct"])
def test_h_f_is_the_training_loss_of_the_step(kind):
    """Per step, H_t is Σ_n w_n (φ1_t(x_n) − F̂_t(x_n))² with F̂_t what training predicts
    for the same push (``robotplan.pushing.training.train.framed``: the window placed at the
    footprint's centroid, the points read in its frame)."""
    from robotplan.pushing.training.samples import SampleBatch
    from robotplan.pushing.training.train import framed
    from robotplan.sdf.footprint import footprint_centroid

    m, (obj, pusher) = model(kind), bodies()
    X1, X2 = trajectory()
    quad = quadrature()
    H, _, _ = FramedDynamics(m, obj, pusher, quad).evaluate(X1, X2, jacobian=False)
    T = len(H)
    batch = SampleBatch(
        params=torch.tensor([[L_SIZE[0] / 2, L_SIZE[1] / 2, L_THICKNESS]] * T, dtype=F64),
        object_prev=X1[:-1], object_now=X1[1:], radius=torch.full((T,), 0.025, dtype=F64),
        pusher_prev=X2[:-1], pusher_now=X2[1:], contact=torch.ones(T, dtype=torch.bool),
        centroid=torch.tensor(footprint_centroid(obj.shape), dtype=F64).repeat(T, 1))
    grid = m.spec.workspace().points(F64).reshape(-1, 2)
    x = quad.points[None]
    with torch.no_grad():
        out = m(*framed(m.spec, batch, grid, x))
    predicted = batch.phi1_prev(x) + out if kind == "flow" else out
    expected = ((batch.phi1_now(x) - predicted) ** 2) @ quad.weights
    assert H.abs().max() > 0
    assert (H - expected).abs().max() < 1e-12 * H.abs().max().clamp_min(1.0)


def test_h_f_does_not_change_when_the_whole_scene_moves():
    """Moving and turning the object, the pusher and the quadrature together leaves every
    H_t as it was: the model reads the push in the object's frame."""
    m, (obj, pusher) = model("flow"), bodies()
    X1, X2 = trajectory()
    angle, shift = 0.9, torch.tensor([0.11, -0.07], dtype=F64)
    c, s = math.cos(angle), math.sin(angle)
    R = torch.tensor([[c, -s], [s, c]], dtype=F64)
    quad = quadrature()
    moved_quad = Quadrature(quad.points @ R.T + shift, quad.weights)
    Y1 = torch.cat((X1[:, :2] @ R.T + shift, X1[:, 2:] + angle), 1)
    Y2 = X2 @ R.T + shift
    here = FramedDynamics(m, obj, pusher, quad).evaluate(X1, X2, jacobian=False)[0]
    there = FramedDynamics(m, obj, pusher, moved_quad).evaluate(Y1, Y2, jacobian=False)[0]
    assert here.abs().max() > 0
    assert (there - here).abs().max() < 1e-9 * here.abs().max()


@pytest.mark.parametrize("kind", ["flow", "direct"])
@pytest.mark.parametrize("actor", ["disc", "box"])
def test_jacobians_match_central_differences(kind, actor):
    """J1 and J2 (an actor disc's positions, or a pushing box's poses) against central
    differences of the values, float64."""
    m, (obj, pusher) = model(kind), bodies()
    X1, X2 = trajectory()
    if actor == "box":
        pusher = Body("pusher", "object", Box((0.06, 0.05)), (0, 0, 0), 0.0, 0.06)
        X2 = torch.cat((X2, torch.linspace(0.0, 0.2, len(X2), dtype=F64)[:, None]), 1)
    H = FramedDynamics(m, obj, pusher, quadrature())
    _, J1, J2 = H.evaluate(X1, X2)
    assert J1.shape == (3, 2, 3) and J2.shape == (3, 2, X2.shape[1])
    assert J1.abs().max() > 0 and J2.abs().max() > 0
    assert_step_jacobians(H, X1, X2, J1, J2, h=1e-6, tol=1e-5, scale_with_jacobian=True)


def test_a_table_frame_model_is_refused():
    m = PushDynamics(DynamicsSpec(kind="flow", **SPEC))
    obj, pusher = bodies()
    with pytest.raises(ValueError, match="object-frame"):
        FramedDynamics(m, obj, pusher, quadrature())
