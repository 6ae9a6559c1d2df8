"""Direct convolutions of our own for the SDF encoder (``encoder_kernels.c``, float32, CPU).

The encoder's layers have 3–5 channels: oneDNN reaches ~7 GMAC/s on the 3 → 3 first layer
of the joint encoder (140 × 140, 10 images) and ~14 on the strided ones, and a ReLU, a
channel max and a ReLU mask per layer are separate passes over memory. The kernels in
``encoder_kernels.c`` keep all output channels of a block of 16 pixels in registers, fuse
bias, ReLU and the channel sums into the forward pass and the ReLU mask into the backward
one, and skip the dead channels of the previous layer. On the AVX2-only EPYC of the
benchmark, forward and backward of the three layers for a 10-step phase take ~2.8 ms against
~8.9 ms through oneDNN (``robotplan bench functional`` reports the H_F phase).

The C file is compiled once per machine with the system's C compiler (``cc``, or ``$CC``)
into ``$XDG_CACHE_HOME/robotplan`` (default ``~/.cache/robotplan``), keyed by a hash of the
source and the flags, and loaded with :mod:`ctypes`. Where that fails (no compiler, a
read-only cache) or ``ROBOTPLAN_NATIVE=0``, :func:`kernels` returns None and the callers
use PyTorch's convolutions: same values up to float32 rounding.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import shutil
import subprocess
import tempfile
import warnings
from pathlib import Path

import torch
from torch import Tensor

__all__ = ["conv_relu_forward", "conv_relu_input_grad", "kernels"]

SOURCE = Path(__file__).with_name("encoder_kernels.c")
MAX_CHANNELS = 8  # per layer, as compiled (MAXC in the C file)


def _compile_flags() -> list[str]:
    flags = ["-O3", "-shared", "-fPIC", "-std=gnu11"]
    try:
        with open("/proc/cpuinfo") as f:
            cpu = f.read()
    except OSError:
        cpu = ""
    words = set(cpu.split())
    if {"avx2", "fma"} <= words:
        flags += ["-mavx2", "-mfma"]
    return flags


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "robotplan"


def _build() -> Path:
    """Compile the kernels (once; later calls find the library by its hash)."""
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not compiler:
        raise OSError("no C compiler (cc, gcc or $CC) found")
    flags = _compile_flags()
    source = SOURCE.read_bytes()
    key = hashlib.sha256(source + " ".join([compiler, *flags]).encode()).hexdigest()[:16]
    folder = _cache_dir()
    target = folder / f"encoder_kernels-{key}.so"
    if target.is_file():
        return target
    folder.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".so", dir=folder)
    os.close(fd)
    try:
        subprocess.run([compiler, *flags, "-o", tmp, str(SOURCE)], check=True,
                       capture_output=True, text=True)
        os.replace(tmp, target)  # whole or not at all; concurrent builds write the same bytes
    except subprocess.CalledProcessError as err:
        raise OSError(f"{compiler} failed on {SOURCE.name}: {err.stderr.strip()[:500]}") from err
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target


@functools.cache
def kernels() -> ctypes.CDLL | None:
    """The compiled kernels, or None where they cannot be used (see the module notes)."""
    if os.environ.get("ROBOTPLAN_NATIVE", "1") == "0":
        return None
    try:
        lib = ctypes.CDLL(str(_build()))
    except OSError as err:
        warnings.warn(f"robotplan: encoder kernels unavailable ({err}); using PyTorch's "
                      "convolutions (slower)", RuntimeWarning, stacklevel=2)
        return None
    p, i = ctypes.c_void_p, ctypes.c_int
    lib.rp_conv_forward.argtypes = [p, i, i, i, i, p, i, p, p, i, i, i, p, p]
    lib.rp_conv_forward.restype = i
    lib.rp_conv_backward.argtypes = [p, p, i, i, p, i, i, i, p, i, i, i, i, i, p]
    lib.rp_conv_backward.restype = i
    return lib


def _usable(*tensors: Tensor) -> bool:
    return all(t.dtype == torch.float32 and t.device.type == "cpu" for t in tensors)


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
