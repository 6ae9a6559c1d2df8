import numpy as np
import pytest
from pydrake.autodiffutils import ExtractGradient, ExtractValue, InitializeAutoDiff
from pydrake.solvers import MathematicalProgram, Solve

from robotplan.program.bridge import bridge


def quadratic(x: np.ndarray, jac: bool):
    """r = (x0² + x1, x1·x2): values and exact Jacobian ``(2, 3)``."""
    r = np.array([x[0] ** 2 + x[1], x[1] * x[2]])
    J = np.array([[2 * x[0], 1.0, 0.0], [0.0, x[2], x[1]]]) if jac else None
    return r, J


@pytest.mark.parametrize("seed", ["identity", "dense", "permutation", "scaled"])
def test_the_derivatives_are_the_chain_rule_through_any_seed(seed):
    rng = np.random.default_rng(0)
    x = np.array([0.3, -1.2, 2.0])
    G = {"identity": np.eye(3), "dense": rng.normal(size=(3, 4)),
         "permutation": np.eye(3)[[1, 0, 2]], "scaled": np.diag([1.0, 2.0, 1.0])}[seed]
    out = bridge(quadratic)(InitializeAutoDiff(x.reshape(-1, 1), G).ravel())
    r, J = quadratic(x, True)
    assert np.array_equal(ExtractValue(out).ravel(), r)
    assert np.abs(ExtractGradient(out) - J @ G).max() < 1e-14


def test_a_program_with_a_bridged_constraint_solves():
    prog = MathematicalProgram()
    x = prog.NewContinuousVariables(3)
    prog.AddConstraint(bridge(lambda v, jac: quadratic(v, jac)), [1.0, 0.5], [1.0, 0.5], x)
    prog.AddQuadraticCost(np.eye(3), np.zeros(3), x)
    result = Solve(prog, np.array([1.0, 0.5, 1.0]))
    assert result.is_success()
    r, _ = quadratic(result.GetSolution(x), False)
    assert np.abs(r - [1.0, 0.5]).max() < 1e-6
