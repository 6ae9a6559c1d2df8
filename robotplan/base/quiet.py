"""pybullet without its banner ("pybullet build time …", printed by its C code on import and
connect); the banner would spoil the one-line output of the command line."""

from __future__ import annotations

import contextlib
import ctypes
import logging
import os
import sys
from collections.abc import Iterator
from types import ModuleType


@contextlib.contextmanager
def c_output_silenced() -> Iterator[None]:
    """Point file descriptors 1 and 2 at /dev/null (C code writes there directly)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
            yield
            ctypes.CDLL(None).fflush(None)  # flush C stdio while the fds still point to null
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in saved:
            os.close(fd)


def import_pybullet() -> ModuleType:
    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    with c_output_silenced():
        import pybullet
    return pybullet


def connect_direct() -> int:
    """A new pybullet DIRECT client, without the banner."""
    pb = import_pybullet()
    with c_output_silenced():
        return pb.connect(pb.DIRECT)


@contextlib.contextmanager
def drake_quiet(level: int = logging.ERROR) -> Iterator[None]:
    """Drake's log messages below ``level`` off (default ERROR: e.g. the parser's warning on
    the massless base link of pybullet's iiwa)."""
    logger = logging.getLogger("drake")
    saved = logger.level
    logger.setLevel(level)
    try:
        yield
    finally:
        logger.setLevel(saved)
