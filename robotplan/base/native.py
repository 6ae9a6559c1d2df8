"""C kernels of our own (``kernels.c``, float32, CPU, one thread), loaded with :mod:`ctypes`.

Two hot spots of H_F (and of the analytic functionals) are many small passes over memory
in PyTorch:

* **the SDF encoder's convolutions**: 3–5 channels, where oneDNN runs far below the CPU's
  peak, and ReLU, channel sums and the ReLU mask are separate passes. The kernels keep
  all output channels of a block of pixels in registers, fuse bias, ReLU and the channel
  sums into the forward pass and the ReLU mask into the backward one, and skip the
  previous layer's dead channels;
* **closed-form SDFs** of circles, boxes and L-shapes with their gradients, on the grid
  (with the body-frame coordinates) and at given points: one vectorized pass instead of
  15–60 tensor operations.

Timings against PyTorch's operations: docs/experiments.md#native-kernels.

``kernels.c`` is compiled at install time by ``setup.py`` with fixed flags (``-O3``, AVX2,
FMA), the same on every machine: the kernels' arithmetic does not follow the CPU they were
built on. Where no library was built (no compiler at install time), the CPU lacks AVX2 or
FMA, or with ``ROBOTPLAN_NATIVE=0``, :func:`kernels` is None and every caller uses its
PyTorch path: the same values up to float32 rounding.
The kernels never see float64 tensors (the tests' models) or tensors autograd tracks.
"""

from __future__ import annotations

import ctypes
import functools
import importlib.machinery
import os
import warnings
from pathlib import Path

import torch
from torch import Tensor

__all__ = ["BOX", "CIRCLE", "LSHAPE", "KernelShape", "conv_relu_forward", "conv_relu_input_grad",
           "kernels", "render_planes", "shape_planes"]

MAX_CHANNELS = 64  # per layer, as compiled (MAXCH in the C file)
REQUIRED_CPU_FLAGS = ("avx2", "fma")  # what setup.py compiles the kernels for


def library_path() -> Path | None:
    """The kernels built at install time (``setup.py``), or None where none was built."""
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        path = Path(__file__).with_name(f"_kernels{suffix}")
        if path.is_file():
            return path
    return None


def _cpu_runs_them() -> bool:
    """Whether this CPU has the instructions the kernels were compiled with (every x86-64
    CPU these machines have; elsewhere the kernels would stop the process)."""
    try:
        with open("/proc/cpuinfo") as f:
            words = set(f.read().split())
    except OSError:
        return False
    return set(REQUIRED_CPU_FLAGS) <= words


@functools.cache
def kernels() -> ctypes.CDLL | None:
    """The compiled kernels, or None where they cannot be used (see the module notes)."""
    if os.environ.get("ROBOTPLAN_NATIVE", "1") == "0":
        return None
    path = library_path()
    if path is None or not _cpu_runs_them():
        why = ("not built at install time (no C compiler?)" if path is None
               else f"this CPU lacks {' or '.join(REQUIRED_CPU_FLAGS)}")
        warnings.warn(f"robotplan: C kernels unavailable ({why}); using PyTorch's "
                      "operations (slower, same values up to float32 rounding)",
                      RuntimeWarning, stacklevel=2)
        return None
    lib = ctypes.CDLL(str(path))
    p, i = ctypes.c_void_p, ctypes.c_int
    lib.rp_conv_forward.argtypes = [p, i, i, i, i, p, i, p, p, i, i, i, p, p]
    lib.rp_conv_forward.restype = i
    lib.rp_conv_backward.argtypes = [p, p, i, i, p, i, i, i, p, i, i, i, i, i, p]
    lib.rp_conv_backward.restype = i
    f = ctypes.c_float
    lib.rp_render.argtypes = [p, i, i, p, i, i, f, f, f, i, p, p, p, p, p, p]
    lib.rp_render.restype = i
    lib.rp_shape_planes.argtypes = [i, p, ctypes.c_long, p, p, p, p, p]
    lib.rp_shape_planes.restype = i
    return lib


def _usable(*tensors: Tensor) -> bool:
    """float32 CPU tensors that autograd does not track (the kernels record no graph)."""
    return all(t.dtype == torch.float32 and t.device.type == "cpu" and not t.requires_grad
               for t in tensors)


def _index(channels: Tensor) -> Tensor:
    return channels.to(torch.int32).contiguous()


def conv_relu_forward(x: Tensor, weight: Tensor, bias: Tensor, stride: int,
                      in_channels: Tensor | None = None) -> tuple[Tensor, Tensor] | None:
    """``ReLU(conv2d(x, weight, bias, stride))`` and the sum of each output channel.

    ``x (M, C, H, W)``; ``weight (N, C, K, K)``; ``in_channels``: the channels of x that may
    be non-zero (default all; the others are skipped as zeros). Returns ``y (M, N, Ho, Wo)``
    (NCHW) and ``sums (N,)``, or None where the kernels do not apply (not float32 on the
    CPU, too many channels, or not compiled): the caller then uses PyTorch.
    """
    lib = kernels()
    N, _, K, _ = weight.shape
    if lib is None or not _usable(x, weight, bias) or N > MAX_CHANNELS:
        return None
    M, Cx, H, W = x.shape
    channels = torch.arange(Cx) if in_channels is None else in_channels
    if len(channels) == 0 or len(channels) > MAX_CHANNELS:
        return None
    x = x.contiguous()
    w = weight[:, channels].contiguous()
    b = bias.contiguous()
    index = _index(channels)
    y = x.new_empty(M, N, (H - K) // stride + 1, (W - K) // stride + 1)
    sums = x.new_zeros(N)
    status = lib.rp_conv_forward(x.data_ptr(), M, Cx, H, W, index.data_ptr(), len(index),
                                 w.data_ptr(), b.data_ptr(), N, K, stride, y.data_ptr(),
                                 sums.data_ptr())
    return (y, sums) if status == 0 else None


def conv_relu_input_grad(grad: Tensor, relu_output: Tensor, live: Tensor, weight: Tensor,
                         stride: int, size: tuple[int, int]) -> Tensor | None:
    """Reverse mode through ``ReLU(conv2d(x, ·, stride))`` to x, from the live channels only.

    ``grad (M, L, Ho, Wo)``: the gradient at the ReLU outputs of the ``live (L,)`` channels
    of ``relu_output (M, C, Ho, Wo)``; ``weight (L, N, K, K)``: the layer's weights from the
    N wanted input channels to the live outputs. Returns ``(M, N, *size)`` (NCHW), or None
    where the kernels do not apply.
    """
    lib = kernels()
    L, N, K, _ = weight.shape
    if (lib is None or not _usable(grad, relu_output, weight) or not 0 < L <= MAX_CHANNELS
            or N > MAX_CHANNELS):
        return None
    grad, relu_output = grad.contiguous(), relu_output.contiguous()
    M, C, Ho, Wo = relu_output.shape
    w = weight.flip(2, 3).transpose(0, 1) if stride == 1 else weight
    w = w.contiguous()
    index = _index(live)
    out = grad.new_empty(M, N, *size)
    status = lib.rp_conv_backward(grad.data_ptr(), relu_output.data_ptr(), M, C,
                                  index.data_ptr(), L, Ho, Wo, w.data_ptr(), N, K, stride,
                                  size[0], size[1], out.data_ptr())
    return out if status == 0 else None


KernelShape = tuple[int, Tensor]
"""A closed-form shape as the kernels know it: its code (:data:`CIRCLE`, :data:`BOX`,
:data:`LSHAPE`) and float32 parameters (``Shape2D.kernel_shape`` builds it)."""
CIRCLE, BOX, LSHAPE = 0, 1, 2


def render_planes(shape: KernelShape | None, X: Tensor, cos_sin: Tensor | None,
                  origin: tuple[float, float], resolution: float, size: tuple[int, int],
                  coordinates: bool = True
                  ) -> tuple[Tensor, Tensor, Tensor, Tensor | None, Tensor | None] | None:
    """φ, ∂φ/∂x, ∂φ/∂y (body frame) of a kernel shape (a circle, box or L-shape) at poses
    ``X (S, 2|3)`` on the grid of ``size = (H, W)`` cells from ``origin`` (its lower-left
    corner), each ``(S, H·W)``; ``cos_sin (S, 2)``: the cosine and sine of a turning body's
    yaw (None: yaw 0); with ``coordinates`` and a turning body also the body-frame
    coordinates px, py
    (else None). None where the kernels do not apply (another shape, not float32, not
    compiled)."""
    lib = kernels()
    code = shape if lib is not None else None
    if code is None or not _usable(X):
        return None
    kind, values = code
    X = X.contiguous()
    S, dofs = X.shape
    H, W = size
    phi, gx, gy = (X.new_empty(S, H * W) for _ in range(3))
    turning = cos_sin is not None
    wanted = turning and coordinates
    px, py = (X.new_empty(S, H * W), X.new_empty(S, H * W)) if wanted else (None, None)
    cs = cos_sin.to(torch.float32).contiguous() if turning else None
    status = lib.rp_render(X.data_ptr(), S, dofs, cs.data_ptr() if turning else None, H, W,
                           origin[0], origin[1], resolution, kind, values.data_ptr(),
                           phi.data_ptr(), gx.data_ptr(), gy.data_ptr(),
                           px.data_ptr() if wanted else None,
                           py.data_ptr() if wanted else None)
    return (phi, gx, gy, px, py) if status == 0 else None


def shape_planes(shape: KernelShape | None, px: Tensor, py: Tensor
                 ) -> tuple[Tensor, Tensor, Tensor] | None:
    """``Shape2D.sdf_and_grad_planes`` of a kernel shape (circle, box, L-shape) at body-frame
    coordinate planes ``px, py (...)`` (float32): φ, ∂φ/∂x, ∂φ/∂y, each ``(...)`` and
    contiguous; None where the kernels do not apply."""
    lib = kernels()
    code = shape if lib is not None else None
    if code is None or not _usable(px, py) or px.shape != py.shape:
        return None
    kind, values = code
    px, py = px.contiguous(), py.contiguous()
    phi, gx, gy = (torch.empty_like(px) for _ in range(3))
    status = lib.rp_shape_planes(kind, values.data_ptr(), px.numel(), px.data_ptr(),
                                 py.data_ptr(), phi.data_ptr(), gx.data_ptr(), gy.data_ptr())
    return (phi, gx, gy) if status == 0 else None
