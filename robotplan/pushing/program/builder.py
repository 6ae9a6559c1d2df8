"""The one builder of push programs: it reads the row table (``skeletons/rows.yaml``) and
adds each row over the program's decision variables.

For every row of the program's stages (in table order, those whose ``enabled`` setting is
on and whose ``goals`` include the task's), the builder resolves the row's ``steps`` to
states (:class:`~robotplan.pushing.program.variables.StepSets`) and hands a :class:`RowContext` to
the row's functional (``ROWS``). The functional names its variables by the row's
``bodies`` and adds itself through the context, which adds it as the row's ``type`` says
(a constraint held to its ``bounds``, or a cost), multiplied by the row's ``scale``. Rows
over one arm's joints are added arm by arm."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from robotplan.program.bridge import bridge, stepwise, stepwise_sparsity
from robotplan.pushing.program.row_table import RowSpec, rows_for_stage
from robotplan.pushing.program.rows_arm import ARM_ROWS
from robotplan.pushing.program.rows_chain import CHAIN_ROWS
from robotplan.pushing.program.rows_goal import GOAL_ROWS
from robotplan.pushing.program.rows_push import PUSH_ROWS

if TYPE_CHECKING:
    from robotplan.pushing.program.push_program import PushProgram

__all__ = ["ROWS", "RowContext", "add_rows"]

ROWS: dict[str, Callable[[RowContext], None]] = {**PUSH_ROWS, **GOAL_ROWS, **CHAIN_ROWS,
                                                  **ARM_ROWS}


class RowContext:
    """One row of the table being added to ``program``: its ``spec``, the states ``steps``
    it holds at and, for a row over one arm's joints, the ``arm``."""

    def __init__(self, program: PushProgram, spec: RowSpec, steps: np.ndarray,
                 arm: str | None = None) -> None:
        self.program, self.spec, self.steps, self.arm = program, spec, steps, arm
        self.settings = program.settings

    @property
    def constants(self):
        """The row's constants (``skeletons/rows.yaml`` ``params``, as overlaid)."""
        return self.settings.row(self.spec.row)

    def body(self, name: str) -> np.ndarray:
        """The variables ``(N+1 | n, d)`` of one of the row's ``bodies``."""
        if name not in self.spec.bodies:
            raise KeyError(f"row {self.spec.row!r} does not name {name!r} in its bodies")
        return self.program.variables.body(name, self.arm)

    @property
    def name(self) -> str:
        """The row's name in reports and timings (per arm: ``ROW_ARM``)."""
        return self.spec.row if self.arm is None else f"{self.spec.row}_{self.arm}"

    # ------------------------------------------------------------ bounds
    def _value(self, term: float | str, quantities: dict) -> float | np.ndarray:
        if not isinstance(term, str):
            return float(term)
        sign, name = (-1.0, term[1:]) if term.startswith("-") else (1.0, term)
        if name == "inf":
            value = np.inf
        elif name in quantities:
            value = quantities[name]
        elif "." in name:
            value = self.settings.value(name)
        else:
            value = getattr(self.constants, name)
        return -np.asarray(value, dtype=float) if sign < 0 else value

    def bounds(self, key: str | None = None, **quantities: float | np.ndarray
               ) -> tuple[float | np.ndarray, float | np.ndarray]:
        """The row's ``bounds`` (the pair under ``key``) with its names resolved: the
        functional's ``quantities``, then the row's constants; not scaled."""
        lower, upper = self.spec.bounds[key]
        return self._value(lower, quantities), self._value(upper, quantities)

    def _scaled(self, key, quantities) -> tuple[np.ndarray, np.ndarray]:
        k = self.spec.scale
        return tuple(np.asarray(b, dtype=float) * k for b in self.bounds(key, **quantities))

    def _constraint(self) -> None:
        if self.spec.type == "cost":
            raise TypeError(f"row {self.spec.row!r} is a cost in the table, not a constraint")

    # ------------------------------------------------------------ rows
    def constrain(self, H, blocks: list[np.ndarray], m: int, *, key: str | None = None,
                  name: str | None = None, **quantities) -> None:
        """lower ≤ scale · H(row i of ``blocks``) ≤ upper, ``m`` residuals per row; bounds
        scalars, one per row ``(n,)`` or one per residual ``(1, m)``."""
        self._constraint()
        program, n = self.program, blocks[0].shape[0]
        fn, variables = stepwise(H, blocks, self.spec.scale)
        lb, ub = (np.broadcast_to(b[:, None] if b.ndim == 1 else b, (n, m)).ravel()
                  for b in self._scaled(key, quantities))
        name = name or self.name
        binding = program.prog.AddConstraint(bridge(fn, program.timings, name), lb, ub,
                                             variables, name)
        if self.settings.sparse_jacobians:
            binding.evaluator().SetGradientSparsityPattern(stepwise_sparsity(fn, m))

    def linear(self, A: np.ndarray, variables: np.ndarray, **quantities) -> None:
        """lower ≤ scale · A x ≤ upper on ``variables`` x (eq rows: = lower)."""
        self._constraint()
        lb, ub = self._scaled(None, quantities)
        A = A * self.spec.scale
        lb, ub = (np.broadcast_to(b, (A.shape[0],)) for b in (lb, ub))
        if self.spec.type == "eq":
            self.program.prog.AddLinearEqualityConstraint(A, lb, variables)
        else:
            self.program.prog.AddLinearConstraint(A, lb, ub, variables)

    def box(self, variables: np.ndarray, **quantities) -> None:
        """lower ≤ ``variables`` ≤ upper, elementwise (bounds broadcast to their shape)."""
        self._constraint()
        lb, ub = (np.broadcast_to(b, variables.shape).ravel()
                  for b in self._scaled(None, quantities))
        self.program.prog.AddBoundingBoxConstraint(lb, ub, variables.ravel())

    def _costing(self) -> None:
        if self.spec.type != "cost":
            raise TypeError(f"row {self.spec.row!r} is a {self.spec.type} row in the table, "
                            "not a cost")

    def cost(self, total, variables: np.ndarray, name: str | None = None) -> None:
        """A scalar cost ``total(x, jac) → ((1,), J (1, n) | None)`` on ``variables``."""
        self._costing()
        program, name = self.program, name or self.name
        bridged = bridge(total, program.timings, name)
        program.prog.AddCost(lambda x: bridged(x)[0], variables, description=name)

    def quadratic(self, Q: np.ndarray, variables: np.ndarray) -> None:
        """The convex cost ½ xᵀ (scale · Q) x on ``variables``."""
        self._costing()
        self.program.prog.AddQuadraticCost(Q * self.spec.scale, np.zeros(len(variables)),
                                           variables, is_convex=True)


def add_rows(program: PushProgram, stages: tuple[str, ...]) -> None:
    """Add the rows of ``stages`` to ``program``, in table order; a row over one arm's
    joints arm by arm, with the rows over joints that follow it."""
    settings, steps = program.settings, program.steps
    rows = [spec for spec in rows_for_stage(stages, goal=program.task.goal)
            if spec.enabled is None or settings.value(spec.enabled)]
    i = 0
    while i < len(rows):
        run = [rows[i]]
        while rows[i].per_arm and i + len(run) < len(rows) and rows[i + len(run)].per_arm:
            run.append(rows[i + len(run)])
        for arm in (program.variables.joints if rows[i].per_arm else [None]):
            for spec in run:
                states = steps.named(spec.steps, arm)
                if len(states):
                    ROWS[spec.row](RowContext(program, spec, states, arm))
        i += len(run)
