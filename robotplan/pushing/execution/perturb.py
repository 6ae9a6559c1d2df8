"""A perturbed world for robustness checks: the physics the plans were not made for, and
a perception system that is not exact.

``Perturbation(seed)`` draws, once per seed, the objects' mass and the friction of
object–table and pusher–object contact each by a factor uniform in 1 ± ``physics_spread``
(±20 %); observed poses get Gaussian noise of ``position_noise`` (1 mm) and ``yaw_noise``
(0.5°) per axis, from a generator of the same seed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from robotplan.execution.physics import PHYSICS, Physics
from robotplan.execution.scene_world import Observation

__all__ = ["Perturbation"]


@dataclass(frozen=True)
class Perturbation:
    seed: int = 0
    physics_spread: float = 0.2
    position_noise: float = 0.001  # m, standard deviation per axis
    yaw_noise: float = math.radians(0.5)

    def physics(self, base: Physics = PHYSICS) -> Physics:
        """``base`` with mass and frictions scaled by this seed's factors."""
        rng = np.random.default_rng([self.seed, 0])
        low, high = 1.0 - self.physics_spread, 1.0 + self.physics_spread
        mass, obj_friction, pusher_friction = rng.uniform(low, high, 3)
        return replace(base, object_mass=base.object_mass * mass,
                       object_friction=base.object_friction * obj_friction,
                       pusher_friction=base.pusher_friction * pusher_friction)

    def observer(self) -> Callable[[Observation], Observation]:
        """A function that adds this seed's noise to the objects' observed poses (a fresh
        draw per call, reproducible per seed)."""
        rng = np.random.default_rng([self.seed, 1])
        scale = np.array([self.position_noise, self.position_noise, self.yaw_noise])

        def noisy(seen: Observation) -> Observation:
            poses = {name: pose + rng.normal(0.0, 1.0, 3) * scale
                     for name, pose in seen.poses.items()}
            return replace(seen, poses=poses)

        return noisy

    def describe(self) -> dict:
        ph = self.physics()
        return {"seed": self.seed, "object_mass": round(float(ph.object_mass), 4),
                "object_friction": round(float(ph.object_friction), 4),
                "pusher_friction": round(float(ph.pusher_friction), 4),
                "position_noise_m": self.position_noise,
                "yaw_noise_deg": round(math.degrees(self.yaw_noise), 3)}
