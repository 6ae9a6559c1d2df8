"""The drop test of mug hanging, whatever simulates it: its constants, its result, and the
procedure (:class:`DropTest`) that a simulator's world runs on a few primitives of its own
(place the mug, step, measure).

A pose *hangs* when the mug is not in collision with the hook where it starts (deeper than
``start_penetration``) and, after the drop and the impulse, still touches the hook and keeps
clear of the ground; it hangs *in place* when, besides, it came to rest (before the impulse)
at most ``in_place_fall`` below where it was released. The mug falling to the ground (its
lowest point under ``ground_clearance``) ends a run early.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Self

import numpy as np

__all__ = ["HANG_PHYSICS", "RECORD_EVERY", "DropResult", "DropTest", "HangPhysics",
           "centre_height", "kick_velocity"]


@dataclass(frozen=True)
class HangPhysics:
    """Simulation constants of the drop test (SI units)."""

    timestep: float = 1.0 / 240.0
    gravity: float = 9.81
    mug_mass: float = 0.3
    friction: float = 0.5  # each body's: a contact's coefficient is the product of its two
    settle_s: float = 1.5  # fall and settle before the impulse
    # the impulse that checks stability: a velocity kick off the arm's end and upwards
    kick_speed: float = 0.3  # m/s along (+x_H + z) / √2
    after_kick_s: float = 1.5
    ground_clearance: float = 0.01  # m: the mug's lowest point above the ground
    start_penetration: float = 0.001  # m: deeper contact at the start counts as collision
    # a hang *in place*: the mug's centre comes down at most this far (m) before it rests, so
    # the pose was a placement, not a fall that caught the arm (docs/experiments.md#hang-labels)
    in_place_fall: float = 0.05
    wall_boxes: int = 16

    def as_dict(self) -> dict:
        return asdict(self)


HANG_PHYSICS = HangPhysics()
RECORD_EVERY = 8  # simulation steps between recorded poses (30 per second)


@dataclass(frozen=True)
class DropResult:
    """What one drop gave: ``hangs`` is the label y of the data set."""

    hangs: bool
    collision_at_start: bool
    on_hook: bool
    on_ground: bool
    X_WM_end: tuple[float, ...]  # (x, y, z, qw, qx, qy, qz) after the drop and the impulse
    fall_m: float = 0.0  # how far the mug's centre came down before the impulse

    def in_place(self, physics: HangPhysics = HANG_PHYSICS) -> bool:
        """Hangs, and came to rest near its release height (``physics.in_place_fall``)."""
        return bool(self.hangs and self.fall_m <= physics.in_place_fall)


def centre_height(X_WM, mug_height: float) -> float:
    """Height of the mug's centre (on its axis, half way up) at pose ``X_WM (7,)``."""
    _, x, y, _ = X_WM[3:7]
    n = math.sqrt(sum(v * v for v in X_WM[3:7]))
    zz = 1.0 - 2.0 * (x * x + y * y) / (n * n)  # z component of the mug's rotated z axis
    return float(X_WM[2]) + zz * mug_height / 2


def kick_velocity(physics: HangPhysics = HANG_PHYSICS) -> np.ndarray:
    """The impulse's velocity ``(3,)``: ``kick_speed`` along (+x + z) / √2 of the hook's
    frame (off the arm's end and upwards)."""
    v = physics.kick_speed / math.sqrt(2.0)
    return np.array([v, 0.0, v])


class DropTest:
    """The drop test on a simulator's world: a subclass sets ``physics`` and ``mug_height``
    and supplies the primitives (``_place``, ``_depth``, ``_step``, ``_set_velocity``,
    ``_lowest``, ``_touches``, ``pose``, ``close``)."""

    physics: HangPhysics
    mug_height: float
    _record: list | None = None

    def _place(self, X_WM: np.ndarray) -> None:
        """Put the mug's frame at ``X_WM (7,)``, at rest."""
        raise NotImplementedError

    def _depth(self) -> float:
        """How deep (m, ≥ 0) the mug where it is now reaches into the hook."""
        raise NotImplementedError

    def _step(self) -> None:
        """One time step of the simulation."""
        raise NotImplementedError

    def _set_velocity(self, linear: np.ndarray) -> None:
        """Give the mug's centre of mass the velocity ``linear (3,)`` and no rotation."""
        raise NotImplementedError

    def _lowest(self) -> float:
        """The mug's lowest point's height (its bounding boxes', m)."""
        raise NotImplementedError

    def _touches(self, body: str) -> bool:
        """Whether the mug touches ``body`` (``"hook"`` or ``"ground"``) now."""
        raise NotImplementedError

    def pose(self) -> tuple[float, ...]:
        """The mug frame's pose ``(x, y, z, qw, qx, qy, qz)``."""
        raise NotImplementedError

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _steps(self, seconds: float) -> int:
        return round(seconds / self.physics.timestep)

    def collides(self, X_WM) -> bool:
        """The mug placed at ``X_WM (7,)`` starts in collision with the hook (deeper than
        ``physics.start_penetration``): a drop from there is a failure without simulating."""
        self._place(np.asarray(X_WM, dtype=float))
        return self._depth() > self.physics.start_penetration

    def drop(self, X_WM, record: list | None = None) -> DropResult:
        """Place the mug at ``X_WM (7,)`` at rest, let it fall and settle, kick it, and
        decide whether it hangs. A fall to the ground ends the run early. ``record``, if
        given, receives ``(t, X_WM)`` every ``RECORD_EVERY`` steps (for a playback)."""
        self._record = record
        ph = self.physics
        X = np.asarray(X_WM, dtype=float)
        self._place(X)
        if record is not None:
            record.append((0.0, self.pose()))
        if self._depth() > ph.start_penetration:
            return DropResult(False, True, True, False, self.pose())
        fallen = self._run(self._steps(ph.settle_s))
        fall = centre_height(X, self.mug_height) - centre_height(self.pose(), self.mug_height)
        if not fallen:
            self._set_velocity(kick_velocity(ph))
            fallen = self._run(self._steps(ph.after_kick_s))
        on_ground = fallen or self._touches("ground")
        on_hook = self._touches("hook")
        return DropResult(on_hook and not on_ground, False, on_hook, on_ground, self.pose(),
                          fall)

    def _run(self, steps: int) -> bool:
        """Step the world; True as soon as the mug comes down to the ground."""
        record = self._record
        for k in range(steps):
            self._step()
            if record is not None and k % RECORD_EVERY == 0:
                t = (record[-1][0] if record else 0.0) + RECORD_EVERY * self.physics.timestep
                record.append((t, self.pose()))
            if self._lowest() < self.physics.ground_clearance:
                return True
        return False
