"""Process-wide allocator settings that keep freed tensor memory for reuse.

glibc's malloc serves large blocks (above a threshold that adapts up to 32 MB) with fresh
``mmap`` pages and returns them on ``free``, and trims the heap top above 2x that; a fast
H_F evaluation allocates ~20 MB of short-lived (T, P, 300) tensors per call, so every
call would pay thousands of page faults of zeroed memory. Freed memory is kept in the heap
instead (measured: docs/experiments.md#memory).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os

__all__ = ["keep_freed_memory"]

_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD = -1, -2, -3
_done = False


def keep_freed_memory(mmap_threshold: int = 1 << 30, top_pad: int = 64 << 20) -> bool:
    """Serve blocks below ``mmap_threshold`` bytes from the heap, never trim it, and grow
    it ``top_pad`` bytes at a time. Idempotent; a no-op (False) where the C library is not
    glibc or ``ROBOTPLAN_MALLOC=0``. The process keeps its peak heap (see the module notes).
    """
    global _done
    if _done:
        return True
    if os.environ.get("ROBOTPLAN_MALLOC", "1") == "0":
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    ok = (mallopt(_M_MMAP_THRESHOLD, min(mmap_threshold, 2**31 - 1))
          and mallopt(_M_TRIM_THRESHOLD, 2**31 - 1) and mallopt(_M_TOP_PAD, top_pad))
    _done = bool(ok)
    return _done
