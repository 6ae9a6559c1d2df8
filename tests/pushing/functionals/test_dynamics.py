"""H_F: the fast path computes what the naive path computes; Jacobians are exact."""

import pytest
import torch

from robotplan.functionals import Quadrature
from robotplan.pushing.functionals.dynamics import (
    LearnedDynamics,
    grid_with_tangents,
    phase_quadrature,
    render_on_grid,
)
from robotplan.pushing.models.dynamics import DynamicsSpec, PushDynamics
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle, LShape, Workspace
from tests.functionals.conftest import F64, assert_step_jacobians

SPEC = {"channels": (2, 3, 3), "sdf_features": 16, "point_features": 8, "hidden": (24, 24)}


def trajectory(T=3):
    X1 = torch.zeros(T + 1, 3, dtype=F64)
    X1[:, 0] = torch.linspace(0.0, 0.03, T + 1)
    X1[:, 2] = torch.linspace(0.1, 0.2, T + 1)
    X2 = torch.zeros(T + 1, 2, dtype=F64)
    X2[:, 0] = torch.linspace(-0.16, -0.12, T + 1)
    X2[:, 1] = 0.013
    return X1, X2


def kill_channels(model: PushDynamics) -> PushDynamics:
    """Channel 1 of the first and channel 0 of the last convolution dead (zero on every
    input, as some are in the shipped model): the fast path skips them."""
    convs = [m for m in model.encoder.conv if isinstance(m, torch.nn.Conv2d)]
    with torch.no_grad():
        convs[0].bias[1] = convs[-1].bias[0] = -1e3
    return model


@pytest.fixture(params=[("flow", "shared"), ("direct", "shared"), ("flow", "joint"),
                        ("flow", "joint-dead")],
                ids=["flow", "direct", "flow-joint", "flow-joint-dead-channels"])
def model(request):
    torch.manual_seed(7)
    kind, encoder = request.param
    model = PushDynamics(DynamicsSpec(kind=kind, encoder=encoder.removesuffix("-dead"),
                                      **SPEC)).double()
    return kill_channels(model) if encoder.endswith("-dead") else model


@pytest.fixture(params=[Box((0.2, 0.12)), LShape((0.24, 0.18), 0.07)], ids=["box", "lshape"])
def obj(request):
    return Body("obj", "object", request.param, (0, 0, 0), 0.0, 0.06)


PUSHER = Body("pusher", "pusher", Circle(0.03), (0, 0, 0), 0.0, 0.06)


def test_fast_full_grid_equals_naive(model, obj):
    X1, X2 = trajectory()
    H = LearnedDynamics(model, obj, PUSHER, Quadrature.grid(Workspace()))
    h, j1, j2 = H.evaluate(X1, X2)
    hn, j1n, j2n = H.evaluate_naive(X1, X2)
    assert h.shape == (3,) and j1.shape == (3, 2, 3) and j2.shape == (3, 2, 2)
    assert torch.allclose(h, hn, rtol=1e-9, atol=0)
    assert torch.allclose(j1, j1n, rtol=1e-7, atol=1e-12)
    assert torch.allclose(j2, j2n, rtol=1e-7, atol=1e-12)
    assert (j2.abs() > 0).any() and (j1[:, 0].abs() > 0).any()


def test_jacobian_matches_finite_differences(model, obj):
    X1, X2 = trajectory()
    q = phase_quadrature(X1[:, :2], 0.15, Workspace(), dtype=torch.float64)
    H = LearnedDynamics(model, obj, PUSHER, q)
    _, j1, j2 = H.evaluate(X1, X2)
    # ReLU kinks and SDF medial axes make FD accurate to O(h) only
    assert_step_jacobians(H, X1, X2, j1, j2, h=1e-6, tol=1e-3)


def test_grid_tangents_are_exact(obj):
    X = torch.tensor([[0.02, -0.01, 0.3], [0.1, 0.05, -1.0]], dtype=F64)
    pts = torch.rand(50, 2, dtype=F64) - 0.5
    _phi, dphi = grid_with_tangents(obj, X, pts, position_only=False)
    for k in range(3):
        e = torch.zeros(3, dtype=F64)
        e[k] = 1e-6
        fd = (obj.sdf(pts, X + e) - obj.sdf(pts, X - e)) / 2e-6
        assert (fd - dphi[:, k]).abs().max() < 1e-7
    phi2, dphi2 = grid_with_tangents(PUSHER, X[:, :2], pts, position_only=True)
    assert torch.allclose(phi2, PUSHER.sdf(pts, X[:, :2]))
    fd = (PUSHER.sdf(pts, X[:, :2] + torch.tensor([1e-6, 0], dtype=F64))
          - PUSHER.sdf(pts, X[:, :2] - torch.tensor([1e-6, 0], dtype=F64))) / 2e-6
    assert (fd - dphi2[:, 0]).abs().max() < 1e-7


def test_phase_quadrature_weights_sum_to_the_workspace_area():
    centers = torch.tensor([[0.0, 0.0], [0.3, 0.1]])
    q = phase_quadrature(centers, 0.1, Workspace(), levels=((0.1, 0.07), (0.02, 0.035)),
                         coarse=0.14)
    assert abs(q.weights.sum().item() - 1.96) < 1e-4
    assert sorted(q.weights.unique().tolist()) == pytest.approx([0.035**2, 0.07**2, 0.14**2])
    for spacing, reach in ((0.07, 0.2), (0.035, 0.12)):
        level = (q.weights - spacing**2).abs() < 1e-9
        near = torch.cdist(q.points[level], centers).amin(1)
        assert near.max() < reach + 2 * spacing * 1.5
    # every point within the finest reach is on the finest level
    close = torch.cdist(q.points, centers).amin(1) < 0.12
    assert torch.allclose(q.weights[close], torch.tensor(0.035**2))
    assert 100 < len(q.points) < 1000


@pytest.mark.parametrize("shape", [Box((0.2, 0.12)), LShape((0.24, 0.18), 0.07), Circle(0.05)],
                         ids=["box", "lshape", "disc"])
def test_render_on_grid_matches_the_pointwise_rendering(shape):
    body = Body("b", "object", shape, (0, 0, 0), 0.0, 0.06)
    ws = Workspace()
    X = torch.tensor([[0.02, -0.01, 0.3], [0.1, 0.05, -1.0]], dtype=F64)
    phi, tangents = render_on_grid(body, X, ws)
    dphi = tangents.dense()
    phi_p, dphi_p = grid_with_tangents(body, X, ws.points(F64).reshape(-1, 2), False)
    assert phi.shape == (2, 19600) and dphi.shape == (2, 3, 19600)
    assert (phi - phi_p).abs().max() < 1e-12
    assert (dphi - dphi_p).abs().max() < 1e-9
    # the factored contraction equals the dense one, for poses and for positions
    G = torch.randn(2, 19600, dtype=F64, generator=torch.Generator().manual_seed(5))
    for t in (tangents, render_on_grid(body, X[:, :2], ws)[1], tangents[1:]):
        dense = torch.einsum("sn,skn->sk", G[:len(t.gx)], t.dense())
        assert (t.contract(G[:len(t.gx)]) - dense).abs().max() < 1e-9 * dense.abs().max()
    values, none = render_on_grid(body, X[:, :2], ws, tangents=False)
    expected = body.sdf(ws.points(F64).reshape(-1, 2), X[:, :2])
    assert none is None and (values - expected).abs().max() < 1e-12


def test_bfloat16_head_products_only_where_opted_in_and_the_cpu_multiplies_them(monkeypatch):
    from robotplan.base import arith
    from robotplan.models import spec as model_spec

    avx2 = "processor\t: 0\nflags\t\t: fpu sse2 avx avx2 fma\n"
    bf16 = avx2.replace("fma", "fma avx512_bf16")
    monkeypatch.delenv("ROBOTPLAN_HEAD_BFLOAT16", raising=False)
    assert not arith.bfloat16_head(bf16)  # the default: float32 on every CPU
    monkeypatch.setenv("ROBOTPLAN_HEAD_BFLOAT16", "1")
    assert not arith.bfloat16_head(avx2)
    assert arith.bfloat16_head(bf16)
    assert arith.bfloat16_head(avx2.replace("fma", "amx_bf16 amx_tile"))
    assert not arith.bfloat16_head("")

    torch.manual_seed(7)
    model32 = PushDynamics(DynamicsSpec(**SPEC)).float()
    obj = Body("o", "object", Box((0.2, 0.12)), (0.0, 0.0, 0.0), 0.0, 0.06)
    pusher = Body("p", "pusher", Circle(0.03), (0.0, 0.0, 0.0), 0.0, 0.06)
    quad = Quadrature(torch.zeros(4, 2), torch.ones(4))
    for native, expected in ((False, torch.float32), (True, torch.bfloat16)):
        monkeypatch.setattr(model_spec, "bfloat16_head", lambda n=native: n)
        assert LearnedDynamics(model32, obj, pusher, quad).matmul_dtype == expected
        assert LearnedDynamics(model32.double(), obj, pusher,
                               quad).matmul_dtype == torch.float64
        model32.float()


def test_h_f_refuses_a_model_on_an_occupancy_measure():
    """H_F compares SDF values; a model on ψ predicts ψ (the paper's Tab. 4 baseline)."""
    model = PushDynamics(DynamicsSpec(kind="flow", representation="occupancy", **SPEC))
    obj = Body("obj", "object", Box((0.2, 0.12)), (0, 0, 0), 0.0, 0.06)
    with pytest.raises(ValueError, match="occupancy"):
        LearnedDynamics(model, obj, PUSHER, Quadrature.grid(Workspace()))


def test_h_f_refuses_an_object_frame_model():
    """H_F renders X_h on the table; an object-frame F_flow reads its grid about the object."""
    from robotplan.models.spec import OBJECT_WINDOW

    spec = DynamicsSpec(kind="flow", frame="object", **{**SPEC, **OBJECT_WINDOW})
    obj = Body("obj", "object", Box((0.2, 0.12)), (0, 0, 0), 0.0, 0.06)
    with pytest.raises(ValueError, match="table-frame"):
        LearnedDynamics(PushDynamics(spec), obj, PUSHER, Quadrature.grid(Workspace()))
