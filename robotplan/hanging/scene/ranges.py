"""The ranges of the hanging task's procedural mugs and hooks (``robots/hang/shapes.yaml``):
the schema, and drawing shapes from it (paper app. H: radius, height and the handle's three
parameters of a mug, the lengths and angles of a hook's two or three parts, all uniform)."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

import numpy as np
import yaml

from robotplan.base.resources import robots_dir
from robotplan.scene.reader import read
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["GridSpec", "HangRanges", "HookRanges", "MugRanges", "load_hang_ranges"]

Range = tuple[float, float]


def _check_ranges(obj, names: tuple[str, ...]) -> tuple[str, str] | None:
    for name in names:
        lo, hi = getattr(obj, name)
        if not 0 <= hi - lo:
            return name, "must be [low, high] with low ≤ high"
    return None


@dataclass(frozen=True)
class MugRanges:
    radius: Range
    height: Range
    handle_height: Range
    handle_reach: Range
    handle_span: Range
    wall: float = field(default=0.006, metadata={"positive": True})
    handle_radius: float = field(default=0.005, metadata={"positive": True})

    def check(self) -> tuple[str, str] | None:
        return _check_ranges(self, ("radius", "height", "handle_height", "handle_reach",
                                    "handle_span"))

    def sample(self, rng: np.random.Generator) -> Mug:
        """A mug drawn uniformly; the handle's span is shortened to keep its tube on the
        cup's wall between the bottom and the rim."""
        draw = {name: float(rng.uniform(*getattr(self, name)))
                for name in ("radius", "height", "handle_height", "handle_reach", "handle_span")}
        zc = draw["handle_height"] * draw["height"]
        room = min(zc - self.wall, draw["height"] - zc) - self.handle_radius
        draw["handle_span"] = min(draw["handle_span"], room)
        return Mug(**draw, wall=self.wall, handle_radius=self.handle_radius)


@dataclass(frozen=True)
class HookRanges:
    post_height: Range
    parts: tuple[int, int]
    first_length: Range
    first_angle: Range
    end_length: Range
    end_angle: Range
    post_radius: float = field(default=0.012, metadata={"positive": True})
    rod_radius: float = field(default=0.005, metadata={"positive": True})

    def check(self) -> tuple[str, str] | None:
        if not 1 <= self.parts[0] <= self.parts[1] <= 3:
            return "parts", "must be [low, high] within 1 to 3"
        return _check_ranges(self, ("post_height", "first_length", "first_angle",
                                    "end_length", "end_angle"))

    def sample(self, rng: np.random.Generator) -> Hook:
        parts = int(rng.integers(self.parts[0], self.parts[1] + 1))
        lengths = [float(rng.uniform(*self.first_length))]
        angles = [float(rng.uniform(*self.first_angle))]
        for _ in range(parts - 1):
            lengths.append(float(rng.uniform(*self.end_length)))
            angles.append(float(rng.uniform(*self.end_angle)))
        return Hook(float(rng.uniform(*self.post_height)), tuple(lengths), tuple(angles),
                    post_radius=self.post_radius, rod_radius=self.rod_radius)


@dataclass(frozen=True)
class GridSpec:
    """The query grid X_h of H_hang (paper app. H: 40 × 40 × 40 cells of 1 cm)."""

    size: float = field(metadata={"positive": True})
    cells: int = field(metadata={"positive": True})
    below_arm: float = 0.25

    def centre(self, hook: Hook) -> np.ndarray:
        """The cube's centre in the hook frame: over the middle of the arm in x and y."""
        arm = hook.arm_points()
        lo = self.size / 2 - self.below_arm
        return np.array([(arm[:, 0].min() + arm[:, 0].max()) / 2, 0.0,
                         hook.post_height + lo])

    def points(self, hook: Hook) -> np.ndarray:
        """Cell centres ``(cells, cells, cells, 3)`` in the hook frame, indexed (x, y, z)."""
        h = self.size / self.cells
        axis = (np.arange(self.cells) + 0.5) * h - self.size / 2
        grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1)
        return grid + self.centre(hook)


@dataclass(frozen=True)
class HangRanges:
    """The schema of ``robots/hang/shapes.yaml``."""

    mug: MugRanges
    hook: HookRanges
    grid: GridSpec


@cache
def load_hang_ranges() -> HangRanges:
    path = robots_dir() / "hang" / "shapes.yaml"
    return read(HangRanges, yaml.safe_load(path.read_text()))
