"""The occupancy-measure baselines of the encoder (paper app. A.1, eqs. 10, 11): what the
first convolution reads, and reverse mode through ψ against autograd (float64)."""

import pytest
import torch

from robotplan.pushing.models.dynamics import DynamicsSpec, PushDynamics
from robotplan.pushing.models.rigid import RigidMotion

TINY_SPEC = {"channels": (2, 3, 3), "sdf_features": 8, "point_features": 8,
             "hidden": (16, 16)}


@pytest.fixture
def grids() -> torch.Tensor:
    torch.manual_seed(11)
    # SDF-like values: a few cm either side of the boundary
    return (torch.rand(2, 3, 140, 140, dtype=torch.float64) - 0.5) * 0.1


@pytest.mark.parametrize("representation", ["occupancy", "smooth_occupancy"])
def test_the_encoder_reads_the_occupancy_measure(grids, representation):
    spec = DynamicsSpec(encoder="joint", representation=representation,
                        occupancy_sharpness=300.0, **TINY_SPEC)
    m = PushDynamics(spec).double()
    psi = torch.sign(grids) if representation == "occupancy" else torch.tanh(300.0 * grids)
    plain = PushDynamics(DynamicsSpec(encoder="joint", sdf_scale=1.0, **TINY_SPEC)).double()
    plain.load_state_dict(m.state_dict())
    with torch.no_grad():
        # the same weights reading ψ as if it were an SDF at unit scale
        assert torch.allclose(m.encoder(grids), plain.encoder(psi), rtol=0, atol=1e-12)
        assert not torch.allclose(m.encoder(grids), plain.encoder(grids), atol=1e-6)


def test_reverse_mode_through_the_smooth_occupancy_matches_autograd(grids):
    torch.manual_seed(2)
    spec = DynamicsSpec(kind="rigid", encoder="joint", representation="smooth_occupancy",
                        occupancy_sharpness=40.0, **TINY_SPEC)
    m = RigidMotion(spec).double()
    f, cache = m.encode_with_activations(grids)
    g = torch.rand_like(f)
    grad = m.encoder_input_grad(cache, g)
    xr = grids.clone().requires_grad_(True)
    (m.encoder(xr) * g).sum().backward()
    assert torch.allclose(f, m.encoder(grids).detach(), atol=1e-12)
    assert torch.allclose(grad, xr.grad, rtol=1e-9, atol=1e-12)
    assert grad.abs().sum() > 0
    index = torch.tensor([1, 1, 0])  # rows that reuse a grid take its slope
    grad_rows = m.encoder_input_grad(cache, g[index], index=index)
    assert torch.allclose(grad_rows, grad[index], rtol=1e-12, atol=1e-15)


def test_the_sign_occupancy_passes_no_gradient(grids):
    spec = DynamicsSpec(kind="rigid", encoder="joint", representation="occupancy", **TINY_SPEC)
    m = RigidMotion(spec).double()
    f, cache = m.encode_with_activations(grids)
    grad = m.encoder_input_grad(cache, torch.rand_like(f))
    assert grad.shape == grids.shape and not grad.any()


def test_the_float32_kernels_apply_the_slope(grids):
    """The float32 CPU path (our own kernels where built) against float64 autograd."""
    torch.manual_seed(4)
    spec = DynamicsSpec(kind="rigid", encoder="joint", representation="smooth_occupancy",
                        occupancy_sharpness=40.0, **TINY_SPEC)
    m64 = RigidMotion(spec).double()
    m32 = RigidMotion(spec)
    m32.load_state_dict({k: v.float() for k, v in m64.state_dict().items()})
    f, cache = m32.encode_with_activations(grids.float())
    g = torch.rand_like(f)
    grad = m32.encoder_input_grad(cache, g)
    xr = grids.clone().requires_grad_(True)
    (m64.encoder(xr) * g.double()).sum().backward()
    assert torch.allclose(grad.double(), xr.grad, rtol=1e-3, atol=1e-4 * xr.grad.abs().max())
