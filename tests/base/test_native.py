"""Our own C kernels (robotplan/base/kernels.c): encoder convolutions and grid rendering against
PyTorch's, the fallback where they do not apply, and the pinned arithmetic (base/arith)."""

import os
import subprocess
import sys

import pytest
import torch
from torch import nn

from robotplan.base import native
from robotplan.pushing.functionals import dynamics as fd
from robotplan.pushing.functionals import grid_render
from robotplan.pushing.functionals.dynamics import render_on_grid
from robotplan.pushing.models import encoder_passes as passes
from robotplan.pushing.models.dynamics import DynamicsSpec, PushDynamics
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle, LShape, Polygon, Workspace

F32, F64 = torch.float32, torch.float64

needs_kernels = pytest.mark.skipif(native.kernels() is None,
                                   reason="C kernels not in use (not built, or ROBOTPLAN_NATIVE=0)")

# (images, channels in, H, W, channels out, kernel, stride): the shipped encoder's layers at
# T = 10, and odd sizes that end mid-vector, narrower than a block, one channel in
LAYERS = [(10, 3, 140, 140, 3, 3, 1), (10, 3, 138, 138, 5, 5, 2), (10, 5, 67, 67, 5, 5, 2),
          (2, 2, 31, 29, 4, 5, 2), (3, 1, 20, 23, 2, 3, 1), (1, 4, 12, 9, 8, 3, 2),
          (2, 3, 45, 70, 7, 4, 1), (2, 2, 30, 33, 3, 4, 2),
          # wider than one register block of 8 output channels: run in groups
          (3, 6, 69, 69, 12, 5, 2), (2, 12, 33, 33, 5, 5, 2), (2, 3, 20, 21, 11, 3, 1),
          (1, 17, 15, 18, 17, 3, 1)]


def _layer(case, seed=0):
    M, C, H, W, N, K, S = case
    g = torch.Generator().manual_seed(seed)
    x = torch.randn(M, C, H, W, dtype=F64, generator=g)
    w = torch.randn(N, C, K, K, dtype=F64, generator=g) / K
    b = torch.randn(N, dtype=F64, generator=g) * 0.3
    return x, w, b, S


@needs_kernels
@pytest.mark.parametrize("case", LAYERS, ids=str)
def test_forward_matches_relu_of_conv2d(case):
    x, w, b, S = _layer(case)
    expected = nn.functional.conv2d(x, w, b, S).clamp_min(0)  # float64 reference
    y, sums = native.conv_relu_forward(x.float(), w.float(), b.float(), S)
    assert y.shape == expected.shape and y.is_contiguous()
    assert (y.double() - expected).abs().max() < 2e-5 * expected.abs().max()
    assert torch.allclose(sums.double(), expected.sum((0, 2, 3)), rtol=1e-4)
    # only some input channels: the others are read as zeros
    C = x.shape[1]
    channels = torch.tensor([C - 1, 0][: max(1, C - 1)])
    zeroed = torch.zeros_like(x)
    zeroed[:, channels] = x[:, channels]
    expected = nn.functional.conv2d(zeroed, w, b, S).clamp_min(0)
    y, _ = native.conv_relu_forward(x.float(), w.float(), b.float(), S, channels)
    assert (y.double() - expected).abs().max() < 2e-5 * expected.abs().max()


@needs_kernels
@pytest.mark.parametrize("case", LAYERS, ids=str)
def test_input_grad_matches_autograd(case):
    x, w, b, S = _layer(case, seed=1)
    N, C = w.shape[:2]
    live = torch.arange(N) if N == 1 else torch.tensor([N - 1, 0])  # any order
    wanted = torch.arange(C) if C == 1 else torch.tensor([0, C - 1])
    x_ = x.clone().requires_grad_(True)
    y = nn.functional.conv2d(x_, w, b, S).clamp_min(0)
    grad = torch.randn(x.shape[0], len(live), *y.shape[2:], dtype=F64,
                       generator=torch.Generator().manual_seed(2))
    (expected,) = torch.autograd.grad((y[:, live] * grad).sum(), x_)
    expected = expected[:, wanted]
    out = native.conv_relu_input_grad(grad.float(), y.detach().float(), live,
                                      w[live][:, wanted].float(), S, tuple(x.shape[2:]))
    assert out.shape == expected.shape
    assert (out.double() - expected).abs().max() < 2e-5 * expected.abs().max()


def test_kernels_decline_what_they_do_not_handle():
    x = torch.randn(1, 2, 9, 9, dtype=F64)
    assert native.conv_relu_forward(x, torch.randn(2, 2, 3, 3, dtype=F64),
                                    torch.zeros(2, dtype=F64), 1) is None  # float64
    if native.kernels() is not None:  # more output channels than compiled for
        w = torch.randn(native.MAX_CHANNELS + 1, 2, 3, 3)
        assert native.conv_relu_forward(x.float(), w, torch.zeros(len(w)), 1) is None


def test_kernels_are_built_at_install_time_and_can_be_switched_off(monkeypatch):
    """The library comes from setup.py (fixed flags), never from a build at run time; with
    ROBOTPLAN_NATIVE=0 or without the library every caller takes its PyTorch path."""
    assert native.library_path() is not None, "setup.py built no kernels library"
    native.kernels.cache_clear()
    try:
        monkeypatch.setenv("ROBOTPLAN_NATIVE", "0")
        assert native.kernels() is None
        native.kernels.cache_clear()
        monkeypatch.delenv("ROBOTPLAN_NATIVE")
        monkeypatch.setattr(native, "library_path", lambda: None)
        with pytest.warns(RuntimeWarning, match="not built at install time"):
            assert native.kernels() is None
    finally:
        native.kernels.cache_clear()


@needs_kernels
def test_encoder_pass_equals_the_pytorch_path(monkeypatch):
    """encode_with_activations / encoder_input_grad of a float32 joint encoder: our kernels
    against PyTorch's convolutions (the fallback), including the dead-channel bookkeeping."""
    spec = DynamicsSpec(encoder="joint", grid=(40, 40), channels=(3, 5, 5), sdf_features=8,
                        point_features=8, hidden=(16, 16))
    torch.manual_seed(3)
    m = PushDynamics(spec).eval()
    with torch.no_grad():
        m.encoder.conv[0].bias[1] = -50.0  # a dead channel in the first layer
    grids = torch.rand(4, 3, 40, 40) - 0.3

    def run():
        f, acts = m.encode_with_activations(grids, linear=False)
        g = torch.randn(f.shape, generator=torch.Generator().manual_seed(4))
        return f, acts, m.encoder_input_grad(acts, g, linear=False)

    f, acts, G = run()
    assert acts.live[0].tolist() == [0, 2]
    monkeypatch.setattr(passes, "conv_relu_forward", lambda *a, **k: None)
    monkeypatch.setattr(passes, "conv_relu_input_grad", lambda *a, **k: None)
    f_ref, acts_ref, G_ref = run()
    assert [a.tolist() for a in acts.live] == [a.tolist() for a in acts_ref.live]
    assert (f - f_ref).abs().max() < 1e-5 * f_ref.abs().max()
    assert (G - G_ref).abs().max() < 1e-5 * G_ref.abs().max() and G_ref.abs().max() > 0


RENDER_SHAPES = [Box((0.28, 0.18)), LShape((0.3, 0.2), 0.08), LShape((0.12, 0.25), 0.05),
                 Circle(0.02)]


@needs_kernels
@pytest.mark.parametrize("shape", RENDER_SHAPES, ids=lambda s: s.describe())
@pytest.mark.parametrize("dofs", [2, 3])
def test_grid_rendering_matches_the_shapes_closed_forms(shape, dofs, monkeypatch):
    """render_on_grid through our kernel against the PyTorch closed forms (float64), at
    random poses on a grid whose rows are not a multiple of the vector width."""
    ws = Workspace((0.05, -0.02), (0.9, 0.7), 0.01)  # 70 × 90 cells
    g = torch.Generator().manual_seed(6)
    X = (torch.rand(7, 3, dtype=F64, generator=g) - 0.5) * torch.tensor([0.6, 0.5, 6.0],
                                                                         dtype=F64)
    X = X[:, :dofs]
    body = Body("b", "object", shape, (0.0, 0.0, 0.0), 0.0, 0.06)
    phi, tangents = render_on_grid(body, X.float(), ws)
    phi_ref, ref = render_on_grid(body, X, ws)  # float64: the PyTorch path
    assert (phi.double() - phi_ref).abs().max() < 1e-5
    values_only, none = render_on_grid(body, X.float(), ws, tangents=False)  # still turned
    assert none is None and (values_only - phi).abs().max() < 1e-6
    dense, dense_ref = tangents.dense().double(), ref.dense()
    assert dense.shape == dense_ref.shape
    # the gradient jumps where the nearest face changes: rounding may pick the other side
    close = (dense - dense_ref).abs() < 1e-4
    assert close.float().mean() > 0.999, close.float().mean()
    monkeypatch.setattr(grid_render, "render_planes", lambda *a, **k: None)  # the fallback
    phi32, t32 = render_on_grid(body, X.float(), ws)
    assert (phi32 - phi).abs().max() < 1e-5
    assert ((t32.dense() - tangents.dense()).abs() < 1e-4).float().mean() > 0.999


def test_rendering_declines_other_shapes_and_dtypes():
    X = torch.zeros(2, 3)
    square = Polygon(((0.0, 0.0), (0.1, 0.0), (0.1, 0.1), (0.0, 0.1)))
    assert native.render_planes(square.kernel_shape, X, None, (0.0, 0.0), 0.01, (4, 4)) is None
    assert native.render_planes(Box((0.1, 0.1)).kernel_shape, X.double(), None, (0.0, 0.0), 0.01,
                                (4, 4)) is None


@needs_kernels
@pytest.mark.parametrize("shape", RENDER_SHAPES, ids=lambda s: s.describe())
def test_shape_planes_at_points_match_the_closed_forms(shape):
    """sdf_and_grad_planes in float32 (our kernel) against float64 (PyTorch), at scattered
    points in and around the shape, more of them than one chunk of the L-shape's rows."""
    g = torch.Generator().manual_seed(7)
    px, py = (torch.rand(2, 3, 700, dtype=F64, generator=g) - 0.5) * 0.5
    phi, gx, gy = shape.sdf_and_grad_planes(px.float(), py.float())
    assert phi.dtype == F32 and phi.shape == px.shape
    phi_ref, gx_ref, gy_ref = shape.sdf_and_grad_planes(px, py)
    assert (phi.double() - phi_ref).abs().max() < 1e-6
    for a, b in ((gx, gx_ref), (gy, gy_ref)):
        assert ((a.double() - b).abs() < 1e-4).float().mean() > 0.999
    # autograd-tracked inputs stay on the PyTorch path (the kernels record no graph)
    px_ = px.float().requires_grad_(True)
    assert native.shape_planes(shape.kernel_shape, px_, py.float()) is None


@needs_kernels
@pytest.mark.parametrize("shape", [Box((0.2, 0.12)), LShape((0.24, 0.18), 0.07)],
                         ids=["box", "lshape"])
def test_h_f_in_float32_equals_the_pytorch_path(shape, monkeypatch):
    """A float32 H_F phase (joint encoder with a dead channel, full grid) through the
    kernels against the same phase with every kernel declined."""
    spec = DynamicsSpec(encoder="joint", channels=(2, 3, 3), sdf_features=16,
                        point_features=8, hidden=(24, 24))
    torch.manual_seed(7)
    model = PushDynamics(spec).eval()
    with torch.no_grad():
        model.encoder.conv[0].bias[1] = -1e3  # dead everywhere
    obj = Body("obj", "object", shape, (0.0, 0.0, 0.0), 0.0, 0.06)
    pusher = Body("pusher", "pusher", Circle(0.03), (0.0, 0.0, 0.0), 0.0, 0.06)
    T = 4
    X1 = torch.zeros(T + 1, 3)
    X1[:, 0], X1[:, 2] = torch.linspace(0.0, 0.04, T + 1), torch.linspace(0.1, 0.25, T + 1)
    X2 = torch.stack((torch.linspace(-0.16, -0.11, T + 1), torch.full((T + 1,), 0.013)), 1)
    H = fd.LearnedDynamics(model, obj, pusher, fd.Quadrature.grid(Workspace()))
    h, j1, j2 = H.evaluate(X1, X2)
    for module, name in ((passes, "conv_relu_forward"), (passes, "conv_relu_input_grad"),
                         (grid_render, "render_planes"), (native, "shape_planes")):
        monkeypatch.setattr(module, name, lambda *a, **k: None)
    h_ref, j1_ref, j2_ref = H.evaluate(X1, X2)
    assert (h - h_ref).abs().max() < 1e-4 * h_ref.abs().max() and h_ref.abs().min() > 0
    for j, ref in ((j1, j1_ref), (j2, j2_ref)):
        assert (j - ref).abs().max() < 1e-3 * ref.abs().max() and ref.abs().max() > 0


def _capability(**env: str) -> str:
    """torch's kernel family in a fresh interpreter that imports robotplan first."""
    clean = {k: v for k, v in os.environ.items()
             if k not in ("ATEN_CPU_CAPABILITY", "MKL_CBWR", "ONEDNN_MAX_CPU_ISA",
                          "ROBOTPLAN_CPU_FEATURES")}
    res = subprocess.run([sys.executable, "-c", "import robotplan, torch, os; "
                          "print(torch.backends.cpu.get_cpu_capability(), os.environ['MKL_CBWR'] "
                          "if 'MKL_CBWR' in os.environ else '-')"],
                         env={**clean, **env}, capture_output=True, text=True, check=True)
    return res.stdout.strip()


def _blas_cores(**env: str) -> str:
    """The kernel family of every OpenBLAS numpy and scipy load, in a fresh interpreter that
    imports robotplan first."""
    clean = {k: v for k, v in os.environ.items()
             if k not in ("OPENBLAS_CORETYPE", "ROBOTPLAN_CPU_FEATURES")}
    code = ("import robotplan, numpy, scipy.linalg\n"
            "from robotplan.base.threads import blas_cores\n"
            "print(','.join(sorted(set(blas_cores().values()))))")
    res = subprocess.run([sys.executable, "-c", code], env={**clean, **env},
                         capture_output=True, text=True, check=True)
    return res.stdout.strip()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/maps")
def test_importing_robotplan_pins_openblas_to_its_avx2_kernels():
    assert _blas_cores() == "Haswell"
    assert _blas_cores(OPENBLAS_CORETYPE="Sandybridge") == "Sandybridge"  # the user's own


def test_importing_robotplan_pins_the_libraries_to_one_kernel_family():
    """The same arithmetic on every CPU: AVX2 kernels in PyTorch, MKL and oneDNN unless the
    user opts in to the CPU's own (ROBOTPLAN_CPU_FEATURES=native)."""
    assert _capability() == "AVX2 AVX2"
    assert _capability(ATEN_CPU_CAPABILITY="default") == "DEFAULT AVX2"  # the user's own
    assert _capability(ROBOTPLAN_CPU_FEATURES="native").endswith(" -")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/maps")
def test_the_test_session_itself_runs_on_the_pinned_kernels():
    """The suite's own arithmetic is the planner's default on every CPU: the conftest
    imports robotplan before numpy and torch load their kernels."""
    import torch

    from robotplan.base.threads import blas_cores

    assert set(blas_cores().values()) == {"Haswell"}
    assert torch.backends.cpu.get_cpu_capability() == "AVX2"
