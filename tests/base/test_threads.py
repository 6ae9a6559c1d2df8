"""One arithmetic thread per worker process (robotplan.base.threads)."""

from __future__ import annotations

import sys

import numpy as np
import pytest
import torch

from robotplan.base.threads import blas_libraries, blas_threads, one_thread


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/maps")
def test_one_thread_sets_every_loaded_openblas_to_one() -> None:
    np.ones((4, 4)) @ np.ones((4, 4))  # numpy's OpenBLAS is loaded with numpy
    found = blas_libraries()
    assert any("openblas" in p.name for p in found)
    one_thread()
    threads = blas_threads()
    assert threads, "no OpenBLAS answered its thread count"
    assert set(threads.values()) == {1}
    assert torch.get_num_threads() == 1

