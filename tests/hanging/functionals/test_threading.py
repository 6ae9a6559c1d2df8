"""H_thread, the arm through the handle's opening: its sign on hand-placed poses, and its
Jacobian in float64 against central differences."""

import math

import numpy as np
import pytest
import torch

from robotplan.hanging.functionals.threading import NO_CROSSING, HandleThreading
from robotplan.sdf.mug_hook import Hook, Mug

HOOK = Hook(post_height=0.3, lengths=(0.12, 0.04), angles=(math.radians(10), math.radians(60)))
MUG = Mug(radius=0.04, height=0.1, handle_height=0.6, handle_reach=0.03, handle_span=0.03)
ALONG_ARM = 0.08  # m from the post


def threaded(dx: float = 0.0, dy: float = 0.0, dz: float = 0.0, yaw: float = math.pi / 2
             ) -> torch.Tensor:
    """Upright, turned ``yaw`` about z (90°: the handle's plane across the arm), the arm
    through the middle of the opening, then shifted; ``(1, 7)``."""
    arm_z = HOOK.post_height + ALONG_ARM * math.tan(HOOK.angles[0])
    mid = MUG.radius + (MUG.handle_reach - MUG.handle_radius) / 2
    x, y = ALONG_ARM - mid * math.cos(yaw), -mid * math.sin(yaw)
    z = arm_z - MUG.handle_height * MUG.height
    q = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
    return torch.tensor([[x + dx, y + dy, z + dz, *q]], dtype=torch.float64)


def test_the_arm_through_the_opening_is_threaded_and_beside_it_is_not():
    h = HandleThreading(MUG, HOOK)
    margin = float(h(threaded())[0, 0])
    x0, _, a, b = MUG.opening()
    # the arm's crossing is mid-opening: its margin is at most the gap to the nearer side
    # (a lower bound of the distance to the ellipse), less the arm's radius
    assert 0 < margin <= (x0 + a - MUG.radius) / 2 - HOOK.rod_radius + 1e-12
    assert float(h(threaded(dz=0.1))[0, 0]) < 0, "the opening far below the arm"
    assert float(h(threaded(dy=0.06))[0, 0]) < 0, "the cup across the arm, not the handle"
    # the mug lowered: the arm's crossing rises towards the opening's top, then above it
    rising = [float(h(threaded(dz=-dz))[0, 0]) for dz in (0.0, b / 3, 2 * b / 3, b + 0.002)]
    assert rising == sorted(rising, reverse=True) and rising[-1] < 0

def test_each_part_has_its_own_margin_and_a_parallel_part_none():
    X = threaded()
    parts = HandleThreading(MUG, HOOK).margins(X)
    assert parts.shape == (1, 2) and parts[0, 0] > 0 > parts[0, 1]
    assert float(HandleThreading(MUG, HOOK, part=1)(X)[0, 0]) == float(parts[0, 1])
    # turned so the handle's plane holds the arm's first part: it never crosses y_M = 0
    level = Hook(post_height=0.3, lengths=(0.12, 0.04), angles=(0.0, math.radians(60)))
    along = threaded(yaw=0.0)
    along[0, 1] = 0.0
    assert float(HandleThreading(MUG, level).margins(along)[0, 0]) == NO_CROSSING
    with pytest.raises(ValueError, match="2 parts"):
        HandleThreading(MUG, HOOK, part=2)


def test_the_jacobian_is_the_central_difference_in_float64():
    h = HandleThreading(MUG, HOOK, part=0)
    rng = np.random.default_rng(0)
    X = threaded(dx=0.003, dz=-0.004, yaw=math.pi / 2 + 0.2).repeat(3, 1)
    X[:, :3] += torch.from_numpy(rng.normal(0.0, 0.002, (3, 3)))
    X[:, 3:] += torch.from_numpy(rng.normal(0.0, 0.05, (3, 4)))
    _, (J,) = h.jacobians(X)
    eps = 1e-6
    for i in range(7):
        d = torch.zeros(7, dtype=torch.float64)
        d[i] = eps
        fd = (h(X + d) - h(X - d)) / (2 * eps)
        assert torch.allclose(J[:, :, i], fd, atol=1e-6, rtol=1e-5), i
