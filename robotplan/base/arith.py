"""One arithmetic on every x86-64 CPU the planner runs on.

Plans move with the last bit of the SDF values (SNOPT's path through a non-convex program
branches on them), so the default arithmetic must not follow the CPU. PyTorch, MKL,
oneDNN and OpenBLAS pick their kernels by CPU features at first use: AVX-512 reductions sum
in another order than AVX2 ones, and oneDNN multiplies in bfloat16 or AMX where the CPU has
them. Importing robotplan pins all four to the AVX2 kernels, which every x86-64 CPU of these
machines has (:data:`PINNED`), unless the variables are already set.

Opt-ins, for a user who trades reproducibility across machines for speed:

* ``ROBOTPLAN_CPU_FEATURES=native``: leave the libraries' own choice per CPU;
* ``ROBOTPLAN_HEAD_BFLOAT16=1``: H_F's head multiplies in bfloat16 (float32 accumulation)
  where the CPU multiplies bfloat16 natively (AVX512-BF16, AMX; emulated it is slower).

Why: docs/design.md#cpu-arithmetic; measured: docs/experiments.md#bfloat16-head.
"""

from __future__ import annotations

import functools
import os

__all__ = ["BFLOAT16_CPU_FLAGS", "PINNED", "bfloat16_head", "cpu_flags", "pin_arithmetic"]

PINNED = {"ATEN_CPU_CAPABILITY": "avx2", "MKL_CBWR": "AVX2", "ONEDNN_MAX_CPU_ISA": "AVX2",
          "OPENBLAS_CORETYPE": "Haswell"}
"""Environment read by PyTorch (its vectorised kernels), MKL (conditional numerical
reproducibility), oneDNN (the highest instruction set it dispatches to) and the OpenBLAS
that numpy and scipy bring (its kernels: Haswell's are AVX2; it picks SkylakeX's AVX-512
ones where the CPU has them)."""

BFLOAT16_CPU_FLAGS = ("avx512_bf16", "amx_bf16")
"""CPU features (``/proc/cpuinfo`` flags) with native bfloat16 dot products."""


def pin_arithmetic() -> None:
    """Pin the libraries' kernels to :data:`PINNED` unless ``ROBOTPLAN_CPU_FEATURES=native``
    (a variable the user set stays as set). Runs when robotplan is imported, before any of
    its modules imports torch."""
    if os.environ.get("ROBOTPLAN_CPU_FEATURES", "") == "native":
        return
    for key, value in PINNED.items():
        os.environ.setdefault(key, value)


def cpu_flags(cpuinfo: str | None = None) -> frozenset[str]:
    """The ``flags`` of ``/proc/cpuinfo`` (or of the given text; empty where it is missing)."""
    if cpuinfo is None:
        return _this_cpu_flags()
    flags: set[str] = set()
    for line in cpuinfo.splitlines():
        key, _, value = line.partition(":")
        if key.strip() == "flags":
            flags.update(value.split())
    return frozenset(flags)


@functools.cache
def _this_cpu_flags() -> frozenset[str]:
    try:
        with open("/proc/cpuinfo") as f:
            return cpu_flags(f.read())
    except OSError:
        return frozenset()


def bfloat16_head(cpuinfo: str | None = None) -> bool:
    """Whether H_F's head multiplies in bfloat16: only where the user opted in
    (``ROBOTPLAN_HEAD_BFLOAT16=1``) and the CPU multiplies bfloat16 natively."""
    if os.environ.get("ROBOTPLAN_HEAD_BFLOAT16", "") != "1":
        return False
    return any(flag in cpu_flags(cpuinfo) for flag in BFLOAT16_CPU_FLAGS)
