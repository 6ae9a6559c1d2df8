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

__all__ = ["blas_libraries", "blas_threads", "one_thread"]

# the setters OpenBLAS exports: plain builds, and the numpy / scipy wheels' prefixed ones
# (``64_``: the 64-bit integer interface numpy uses)
_SETTERS = ("openblas_set_num_threads", "openblas_set_num_threads64_",
            "scipy_openblas_set_num_threads", "scipy_openblas_set_num_threads64_")
_GETTERS = ("openblas_get_num_threads", "openblas_get_num_threads64_",
            "scipy_openblas_get_num_threads", "scipy_openblas_get_num_threads64_")


def blas_libraries() -> list[Path]:
    """The OpenBLAS libraries loaded in this process (from ``/proc/self/maps``; none where
    the system has no such file)."""
    try:
        lines = Path("/proc/self/maps").read_text().splitlines()
    except OSError:
        return []
    paths = {line.split(maxsplit=5)[5] for line in lines if len(line.split(maxsplit=5)) == 6}
    return sorted(Path(p) for p in paths if "openblas" in Path(p).name.lower())


def _call_first(lib: ctypes.CDLL, names: tuple[str, ...], *args: int) -> int | None:
    for name in names:
        fn = getattr(lib, name, None)
        if fn is not None:
            return int(fn(*args) or 0)
    return None


def blas_threads() -> dict[str, int]:
    """Threads per loaded OpenBLAS library, by file name."""
    out = {}
    for path in blas_libraries():
        n = _call_first(ctypes.CDLL(str(path)), _GETTERS)
        if n is not None:
            out[path.name] = n
    return out


def one_thread() -> None:
    """Run torch and every loaded OpenBLAS on one thread in this process (a worker's
    setup; libraries loaded later keep their own default)."""
    torch.set_num_threads(1)
    for path in blas_libraries():
        _call_first(ctypes.CDLL(str(path)), _SETTERS, 1)
