import pytest
import torch

from robotplan.pushing.models.dynamics import DynamicsSpec, PushDynamics, load_model, save_model
from tests.conftest import TINY_SPEC


def test_paper_architecture_by_default():
    m = PushDynamics()
    convs = [c for c in m.encoder.conv if isinstance(c, torch.nn.Conv2d)]
    assert [c.out_channels for c in convs] == [3, 5, 5]
    assert [c.kernel_size[0] for c in convs] == [3, 5, 5]
    assert [c.stride[0] for c in convs] == [1, 2, 2]
    assert m.encoder.linear.out_features == 200 and m.point_encoder.out_features == 100
    assert m.first_sdf.in_features + m.first_point.in_features == 700
    assert [h.out_features for h in m.head if isinstance(h, torch.nn.Linear)] == [300, 1]


def test_split_first_layer_equals_the_concatenated_layer():
    m = PushDynamics(DynamicsSpec(**TINY_SPEC)).double()
    inputs = torch.rand(3, 3, 140, 140, dtype=torch.float64)
    pts = torch.rand(3, 7, 2, dtype=torch.float64) - 0.5
    out = m(inputs, pts)
    # the same with one Linear over [sdf features, point features]
    feats = m.encode(inputs.flatten(0, 1)).reshape(3, -1)
    pf = m.point_encoder((pts - m.center) / m.half_size)
    W = torch.cat([m.first_sdf.weight, m.first_point.weight], dim=1)
    cat = torch.cat([feats[:, None, :].expand(3, 7, -1), pf], dim=-1)
    h = torch.relu(cat @ W.T + m.first_sdf.bias)
    ref = m.head(h)[..., 0] * m.spec.out_scale
    assert out.shape == (3, 7)
    assert (out - ref).abs().max() < 1e-12


def test_gradients_reach_points_and_inputs():
    m = PushDynamics(DynamicsSpec(**TINY_SPEC)).double()
    inputs = torch.rand(2, 3, 140, 140, dtype=torch.float64, requires_grad=True)
    pts = (torch.rand(2, 5, 2, dtype=torch.float64) - 0.5).requires_grad_(True)
    assert torch.autograd.gradcheck(lambda p: m(inputs.detach(), p), (pts,))
    m(inputs, pts).sum().backward()
    assert inputs.grad.abs().sum() > 0


def test_save_and_load_round_trip(tmp_path):
    m = PushDynamics(DynamicsSpec(kind="direct", **TINY_SPEC))
    save_model(m, tmp_path / "model")
    loaded = load_model(tmp_path / "model")
    assert loaded.spec == m.spec
    x, p = torch.rand(1, 3, 140, 140), torch.rand(1, 4, 2)
    assert torch.equal(loaded(x, p), m.eval()(x, p))


def test_load_refuses_non_model_folders(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"spec\.json"):
        load_model(tmp_path)


def test_joint_encoder_variant():
    m = PushDynamics(DynamicsSpec(encoder="joint", **TINY_SPEC)).double()
    assert m.encoder.conv[0].in_channels == 3
    x, p = torch.rand(2, 3, 140, 140, dtype=torch.float64), torch.rand(2, 5, 2, dtype=torch.float64)
    assert m(x, p).shape == (2, 5)
    # reverse mode through the encoder equals autograd's input gradient
    f, acts = m.encode_with_activations(x)
    g = torch.rand_like(f)
    grad = m.encoder_input_grad(acts, g)
    xr = x.clone().requires_grad_(True)
    (m.encoder(xr) * g).sum().backward()
    with torch.no_grad():
        assert torch.allclose(f, m.encoder(x), atol=1e-12)
    assert torch.allclose(grad, xr.grad, rtol=1e-9, atol=1e-12)
    assert grad.abs().sum() > 0


@pytest.mark.parametrize("linear", [True, False], ids=["features", "last-convolution"])
def test_encoder_skips_dead_channels_exactly(linear):
    """Channels that are zero on the whole batch drop out of the later layers and of reverse
    mode; features and input gradients stay those of autograd on the whole encoder."""
    torch.manual_seed(3)
    m = PushDynamics(DynamicsSpec(encoder="joint", **TINY_SPEC)).double()
    convs = [mod for mod in m.encoder.conv if isinstance(mod, torch.nn.Conv2d)]
    with torch.no_grad():
        convs[0].bias[0] = convs[-1].bias[1] = -1e3
    x = torch.rand(2, 3, 140, 140, dtype=torch.float64)
    f, cache = m.encode_with_activations(x, linear=linear)
    assert 0 not in cache.live[0].tolist() and 1 not in cache.live[-1].tolist()
    assert len(cache.live[0]) == convs[0].out_channels - 1
    g = torch.rand_like(f)
    grad = m.encoder_input_grad(cache, g, linear=linear)
    xr = x.clone().requires_grad_(True)
    out = m.encoder(xr) if linear else m.encoder.conv(xr * m.encoder.scale)
    if not linear:  # the live channels of the last convolution, flattened
        out = out[:, cache.live[-1]].flatten(1)
    (out * g).sum().backward()
    assert torch.allclose(f, out.detach(), atol=1e-12)
    assert torch.allclose(grad, xr.grad, rtol=1e-9, atol=1e-12)
    assert grad.abs().sum() > 0


def test_encoder_with_a_dead_layer_passes_no_gradient():
    m = PushDynamics(DynamicsSpec(encoder="joint", **TINY_SPEC)).double()
    with torch.no_grad():
        m.encoder.conv[2].bias.fill_(-1e3)  # every channel of the second convolution dead
    x = torch.rand(2, 3, 140, 140, dtype=torch.float64)
    f, cache = m.encode_with_activations(x, linear=False)
    assert len(cache.live[1]) == 0 and f.shape == (2, 0)
    grad = m.encoder_input_grad(cache, torch.rand_like(f), linear=False)
    assert grad.shape == x.shape and not grad.any()


def test_shared_encoder_input_grad_with_repeated_rows():
    m = PushDynamics(DynamicsSpec(**TINY_SPEC)).double()
    x = torch.rand(3, 1, 140, 140, dtype=torch.float64)
    f, acts = m.encode_with_activations(x)
    index = torch.tensor([2, 0, 2])
    g = torch.rand(3, f.shape[1], dtype=torch.float64)
    grad = m.encoder_input_grad(acts, g, index)
    for row, i in enumerate(index.tolist()):
        xr = x[i:i + 1].clone().requires_grad_(True)
        (m.encoder(xr) * g[row]).sum().backward()
        assert torch.allclose(grad[row:row + 1], xr.grad, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("hidden", [(16, 12), (16,)], ids=["two-layer", "one-layer"])
def test_head_reverse_mode_skips_dead_units_exactly(hidden):
    spec = dict(TINY_SPEC, hidden=hidden)
    m = PushDynamics(DynamicsSpec(**spec)).double()
    g = torch.Generator().manual_seed(3)
    S = torch.randn(4, hidden[0], dtype=torch.float64, generator=g)
    P = torch.randn(1, 9, hidden[0], dtype=torch.float64, generator=g)
    S[:, :5] -= 10.0  # units 0-4 dead at every (b, p); the head must drop them exactly
    out, (units, acts) = m.head_with_activations(S, P)
    assert len(units) <= hidden[0] - 5 and not (units < 5).any()
    assert (out - m.from_terms(S, P)).abs().max() < 1e-12
    c = torch.randn(4, 9, dtype=torch.float64, generator=g)
    S_ = S.clone().requires_grad_(True)
    (expected,) = torch.autograd.grad((m.from_terms(S_, P) * c).sum(), S_)
    grad = m.head_input_grad((units, acts), c)
    assert (grad - expected).abs().max() < 1e-12 * max(1.0, expected.abs().max().item())
    assert (grad[:, :5] == 0).all() and grad.abs().sum() > 0
