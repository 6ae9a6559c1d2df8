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


def assert_step_jacobians(H, X1, X2, J1, J2, h: float, tol: float,
                          scale_with_jacobian: bool = False) -> None:
    """Each state's column of H.evaluate's per-step Jacobians (``J[t, 0]``: state t−1 of
    step t, ``J[t, 1]``: state t) against central differences of its values, relative to
    the largest difference (or also the largest Jacobian entry)."""
    for X, J in ((X1, J1), (X2, J2)):
        for s in range(X.shape[0]):
            for k in range(X.shape[1]):
                plus, minus = X.clone(), X.clone()
                plus[s, k] += h
                minus[s, k] -= h
                args_p = (plus, X2) if X is X1 else (X1, plus)
                args_m = (minus, X2) if X is X1 else (X1, minus)
                fd = (H.evaluate(*args_p, jacobian=False)[0]
                      - H.evaluate(*args_m, jacobian=False)[0]) / (2 * h)
                # H_t depends on state s only for t = s (as "now") and t = s + 1 ("prev")
                expected = torch.zeros_like(fd)
                if s >= 1:
                    expected[s - 1] = J[s - 1, 1, k]
                if s + 1 <= X.shape[0] - 1:
                    expected[s] = J[s, 0, k]
                scale = (max(float(fd.abs().max()), float(J.abs().max())) if scale_with_jacobian
                         else fd.abs().max().clamp_min(1e-12))
                assert ((fd - expected).abs().max() / scale) < tol, (s, k)
