"""robotplan.base.memory: the allocator setting that keeps freed tensor memory for reuse."""

import os
import platform
import subprocess
import sys

import pytest

from robotplan.base.memory import keep_freed_memory


@pytest.mark.skipif(platform.system() != "Linux" or platform.libc_ver()[0] != "glibc",
                    reason="mallopt is glibc's")
def test_keep_freed_memory_applies_once_and_can_be_switched_off():
    assert keep_freed_memory() and keep_freed_memory()  # idempotent
    code = "from robotplan.base.memory import keep_freed_memory as k; print(k())"
    env = dict(os.environ, ROBOTPLAN_MALLOC="0")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.skipif(platform.system() != "Linux" or platform.libc_ver()[0] != "glibc",
                    reason="mallopt is glibc's")
def test_a_freed_large_tensor_is_reused_without_page_faults():
    code = """
import resource, torch
from robotplan.base.memory import keep_freed_memory
keep_freed_memory()
sizes = [5_000_000, 9_000_000, 7_000_000, 40_000_000 // 4]  # floats: 20-40 MB blocks
for n in sizes:
    torch.ones(n)
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(5):
    for n in sizes:
        torch.ones(n)
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""
    faults = {}
    for flag in ("1", "0"):
        env = dict(os.environ, ROBOTPLAN_MALLOC=flag)
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                             text=True, check=True)
        faults[flag] = int(out.stdout.strip())
    # 20 blocks of 20-40 MB: ~100,000 faults of fresh pages without the setting
    assert faults["1"] < 1000 < faults["0"], faults
