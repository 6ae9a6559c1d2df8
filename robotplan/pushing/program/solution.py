"""What solving one skeleton's program gives: the plan, its violations and timings."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from robotplan.pushing.program.skeleton import Skeleton

__all__ = ["FEASIBLE", "SNOPT_MINOR_DEFAULT", "WARM_USABLE", "Solution", "rank"]


@dataclass
class Solution:
    skeleton: Skeleton
    success: bool
    status: str
    violation: float
    cost: float
    seconds: float
    q_obj: np.ndarray
    q_pusher: np.ndarray
    contact: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    dynamics_mm2: np.ndarray = field(default_factory=lambda: np.zeros(0))  # H_F per step
    timings: dict = field(default_factory=dict)  # seconds per functional; "solver": the rest
    violations: dict = field(default_factory=dict)  # worst violation per constraint name
    q_joints: dict = field(default_factory=dict)  # robot name → (N+1, dof) joint angles
    touch_point: np.ndarray | None = None  # (1, 2): the touch goal's contact point
    # a chained object's (N+1, 3) poses and its (·, 2) contact points (a chain)
    q_others: dict = field(default_factory=dict)
    contact_others: dict = field(default_factory=dict)
    # least distance (m) of the moved objects from the obstacles along the plan (the search
    # sets it: robotplan.functionals.clearance); inf without obstacles
    clearance: float = math.inf

    @property
    def dynamics_rms_mm(self) -> float:
        """RMS over steps of the model residual: √(mean_t H_F,t / |X|) in mm."""
        return float(np.sqrt(self.dynamics_mm2.mean())) if self.dynamics_mm2.size else 0.0


SNOPT_MINOR_DEFAULT = 10_000  # SNOPT's own "Iterations limit"
WARM_USABLE = 0.1  # largest violation of a kinematic solution worth starting from
FEASIBLE = 1e-2  # largest scaled constraint violation that counts as solved


def rank(violations: dict[str, float], cost: float, tie: float = FEASIBLE
          ) -> tuple[float, float]:
    """Order of plans: the least violation (all within ``tie`` tie), then the least cost."""
    return max(max(violations.values(), default=0.0), tie), cost
