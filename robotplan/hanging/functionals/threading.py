"""H_thread, an analytic functional of mug hanging: how far inside the handle's opening the
hook's arm passes, a function of the mug's pose X_HM in the hook frame.

A mug hangs when the arm goes through its handle; a pose the learned H_hang accepts can sit
beside the arm, handle not around it, and fall (docs/experiments.md#hang-threading). Part
``k`` of the arm (the segment from arm point k to k + 1, in the mug frame ``M``) crosses the
handle's plane y_M = 0 at one point c; its margin is the least of

* how far c lies inside the opening's ellipse, (1 − ρ)·min(a, b) with ρ the point's scaled
  radius (a lower bound of its distance to the ellipse),
* how far c lies outside the cup's wall, x_c − radius,
* how far c lies from the part's ends along it, min(t, 1 − t)·length,

less the arm's radius: > 0 where the arm is through the opening, < 0 where it is not. A part
parallel to the plane gets :data:`NO_CROSSING`. Every term is smooth in the pose where the
part crosses the plane, so the margin is a row SNOPT can keep.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor

from robotplan.functionals.base import Functional
from robotplan.geometry.transforms import spatial_to_body
from robotplan.sdf.closed_form import safe_norm
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["NO_CROSSING", "HandleThreading"]

NO_CROSSING = -1.0  # m: the margin of an arm part parallel to the handle's plane
PARALLEL = 1e-9  # m: |Δy| of a part's ends below which it counts as parallel


class HandleThreading(Functional):
    """H_thread: ``residual(X_HM (T, 7)) → (T, 1)``, the margin (m) by which arm part
    ``part`` passes through the handle's opening, or with ``part=None`` the largest margin
    over the arm's parts (:meth:`margins`)."""

    def __init__(self, mug: Mug, hook: Hook, part: int | None = None) -> None:
        self.mug, self.hook, self.part = mug, hook, part
        self.arm = torch.from_numpy(hook.arm_points())  # (P + 1, 3), frame H
        self.parts = self.arm.shape[0] - 1
        self.lengths = (self.arm[1:] - self.arm[:-1]).norm(dim=-1)  # (P,), rigid
        if part is not None and not 0 <= part < self.parts:
            raise ValueError(f"arm part {part}: the hook's arm has {self.parts} parts")

    def margins(self, X_HM: Tensor) -> Tensor:
        """Each part's margin ``(T, P)`` (m) at poses ``X_HM (T, 7)``."""
        arm = spatial_to_body(self.arm.to(X_HM)[None], X_HM)  # (T, P + 1, 3), frame M
        p, q = arm[:, :-1], arm[:, 1:]
        dy = p[..., 1] - q[..., 1]
        crosses = dy.abs() > PARALLEL
        t = p[..., 1] / torch.where(crosses, dy, torch.ones_like(dy))
        c = p + t[..., None] * (q - p)
        x0, z0, a, b = self.mug.opening()
        rho = safe_norm(torch.stack(((c[..., 0] - x0) / a, (c[..., 2] - z0) / b), dim=-1))
        inside = torch.minimum((1.0 - rho) * min(a, b), c[..., 0] - self.mug.radius)
        along = torch.minimum(t, 1.0 - t) * self.lengths.to(t)
        margin = torch.minimum(inside, along) - self.hook.rod_radius
        return torch.where(crosses, margin, torch.full_like(margin, NO_CROSSING))

    def residual(self, X_HM: Tensor) -> Tensor:
        m = self.margins(X_HM)
        if self.part is None:
            return m.amax(dim=-1, keepdim=True)
        return m[:, self.part:self.part + 1]

    def values(self, X_HM: np.ndarray) -> np.ndarray:
        """The margin ``(n,)`` (m) at poses ``(n, 7)`` (numpy, no gradients)."""
        with torch.no_grad():
            return self(torch.from_numpy(np.atleast_2d(X_HM).astype(np.float64)))[:, 0].numpy()
