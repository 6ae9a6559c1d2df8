import numpy as np
import pytest
from scipy.optimize import least_squares

from robotplan.base.batch_least_squares import forward_jacobian, least_squares_batch


def rosenbrock(points: np.ndarray, problems: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Residuals ``(B, R, 3)`` of a Rosenbrock valley per problem, its minimum at
    ``(a_p, a_p²)``, plus a small pull of x towards 0 (so that a bound can hold it)."""
    x, y = points[..., 0], points[..., 1]
    ap = a[problems][:, None]
    return np.stack((ap - x, 10.0 * (y - x**2), 0.1 * x), -1)


@pytest.fixture
def problems():
    rng = np.random.default_rng(0)
    a = rng.uniform(-1.5, 1.5, 40)
    x0 = rng.uniform(-2.0, 2.0, (40, 2))
    return a, x0


def test_each_problem_reaches_the_minimum_scipy_finds(problems):
    a, x0 = problems
    lo, hi = np.array([-1.0, -3.0]), np.array([1.2, 3.0])
    fit = least_squares_batch(lambda pts, idx: rosenbrock(pts, idx, a), x0, lo, hi)
    for p in range(len(a)):
        ref = least_squares(lambda v, p=p: rosenbrock(v[None, None], np.array([p]), a)[0, 0],
                            np.clip(x0[p], lo, hi), bounds=(lo, hi), xtol=1e-12, ftol=1e-12)
        assert fit.cost[p] <= ref.cost + 1e-9, p
        assert np.all(fit.x[p] >= lo) and np.all(fit.x[p] <= hi)
    # where a_p lies past a bound, the bound holds x
    at_bound = (a > hi[0] + 0.05) | (a < lo[0] - 0.05)
    assert at_bound.any()
    assert np.allclose(np.abs(fit.x[at_bound, 0]), np.where(a[at_bound] > 0, hi[0], -lo[0]))


def test_the_jacobian_matches_the_analytic_one_in_float64(problems):
    a, x0 = problems
    idx = np.arange(len(a))
    r = rosenbrock(x0[:, None], idx, a)[:, 0]
    J = forward_jacobian(lambda pts, i: rosenbrock(pts, i, a), x0, r, np.full(2, 10.0), idx)
    x = x0[:, 0]
    analytic = np.zeros((len(a), 3, 2))
    analytic[:, 0, 0] = -1.0
    analytic[:, 1, 0], analytic[:, 1, 1] = -20.0 * x, 10.0
    analytic[:, 2, 0] = 0.1
    assert np.abs(J - analytic).max() < 1e-5


def test_a_step_at_the_upper_bound_is_taken_downwards():
    hi = np.array([1.0])
    seen = []

    def residuals(pts, idx):
        seen.append(pts.copy())
        return pts**2

    forward_jacobian(residuals, np.array([[1.0]]), np.array([[1.0]]), hi, np.array([0]))
    assert seen[0].max() <= 1.0
