"""One arithmetic thread per worker process: torch's, and every OpenBLAS loaded in it.

The search, data generation and benchmarks run one process per core. A second thread per
process only oversubscribes the cores: OpenBLAS threads (numpy's and scipy's bundled
libraries, used on the programs' small matrices) spin while they wait, so two programs on
two cores each ran 2-2.4x slower with OpenBLAS's default of one thread per core than with
one (docs/experiments.md#blas-threads), as torch's OpenMP threads did
(docs/experiments.md#torch-threads). One thread per process also makes the reductions'
order the same on every machine, whatever its core count.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import torch

__all__ = ["blas_cores", "blas_libraries", "blas_threads", "one_thread"]

# the setters OpenBLAS exports: plain builds, and the numpy / scipy wheels' prefixed ones
# (``64_``: the 64-bit integer interface numpy uses)
_SETTERS = ("openblas_set_num_threads", "openblas_set_num_threads64_",
            "scipy_openblas_set_num_threads", "scipy_openblas_set_num_threads64_")
_GETTERS = ("openblas_get_num_threads", "openblas_get_num_threads64_",
            "scipy_openblas_get_num_threads", "scipy_openblas_get_num_threads64_")
_CORE_NAMES = ("openblas_get_corename", "scipy_openblas_get_corename",
               "scipy_openblas_get_corename64_")


def blas_libraries() -> list[Path]:
    """The OpenBLAS libraries loaded in this process (from ``/proc/self/maps``; none where
    the system has no such file)."""
    try:
        lines = Path("/proc/self/maps").read_text().splitlines()
    except OSError:
        return []
    fields = (line.split(maxsplit=5) for line in lines)
    paths = {Path(f[5]) for f in fields if len(f) == 6}  # the mapped file, where there is one
    return sorted(p for p in paths if "openblas" in p.name.lower())


def _call_first(lib: ctypes.CDLL, names: tuple[str, ...], *args: int, restype=ctypes.c_int):
    """What the first of ``names`` that ``lib`` exports returns (None: it has none)."""
    for name in names:
        fn = getattr(lib, name, None)
        if fn is not None:
            fn.restype = restype
            return fn(*args)
    return None


def _per_library(names: tuple[str, ...], restype=ctypes.c_int) -> dict[str, object]:
    out = {}
    for path in blas_libraries():
        value = _call_first(ctypes.CDLL(str(path)), names, restype=restype)
        if value is not None:
            out[path.name] = value
    return out


def blas_threads() -> dict[str, int]:
    """Threads per loaded OpenBLAS library, by file name."""
    return _per_library(_GETTERS)


def blas_cores() -> dict[str, str]:
    """The kernel family (``Haswell``, ``SkylakeX``, …) per loaded OpenBLAS library, by file
    name (:data:`robotplan.base.arith.PINNED` pins it)."""
    return {k: v.decode() for k, v in _per_library(_CORE_NAMES, ctypes.c_char_p).items()}


def one_thread() -> None:
    """Run torch and every loaded OpenBLAS on one thread in this process (a worker's
    setup; libraries loaded later keep their own default)."""
    torch.set_num_threads(1)
    for path in blas_libraries():
        _call_first(ctypes.CDLL(str(path)), _SETTERS, 1)
