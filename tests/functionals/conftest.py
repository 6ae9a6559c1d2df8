import pytest
import torch

from robotplan.functionals import Quadrature
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle, LShape

F64 = torch.float64


@pytest.fixture
def box() -> Body:
    return Body("box", "object", Box((0.2, 0.12)), (0.0, 0.0, 0.0), 0.0, 0.06)


@pytest.fixture
def ell() -> Body:
    return Body("ell", "object", LShape((0.24, 0.18), 0.07), (0.0, 0.0, 0.0), 0.0, 0.06)


@pytest.fixture
def pusher() -> Body:
    return Body("pusher", "pusher", Circle(0.03), (-0.3, 0.0, 0.0), 0.0, 0.06)


@pytest.fixture
def region() -> Body:
    return Body("goal", "region", Box((0.4, 0.4)), (0.0, 0.0, 0.0), 0.0, 0.0)


@pytest.fixture
def coarse() -> Quadrature:
    """4 mm grid over ±0.35 m: cheap enough for gradcheck."""
    return Quadrature.box((0.0, 0.0), (0.7, 0.7), 0.004)


@pytest.fixture
def fine() -> Quadrature:
    """1 mm grid over ±0.35 m: resolves the a = 500 sigmoid edge (~2 mm)."""
    return Quadrature.box((0.0, 0.0), (0.7, 0.7), 0.001)


def central_difference_jacobian(fn, inputs, which, h=1e-6):
    """∂ fn(*inputs)[t] / ∂ inputs[which][t] by central differences, ``(T, m, d)``."""
    x = inputs[which]
    _T, d = x.shape
    cols = []
    for j in range(d):
        e = torch.zeros_like(x)
        e[:, j] = h
        plus = [*inputs[:which], x + e, *inputs[which + 1:]]
        minus = [*inputs[:which], x - e, *inputs[which + 1:]]
        cols.append((fn(*plus) - fn(*minus)) / (2 * h))
    return torch.stack(cols, dim=-1)
