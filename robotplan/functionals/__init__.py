"""Functionals H(φ…) of signed-distance fields: zero when the scene is right (paper §5–6).

Analytic: :class:`Collision` (H_coll, eq. 7), :class:`GoalRegion` (H_g, eq. 8),
:class:`ContactPoint` (H_PoC, eq. 9). The learned pushing dynamics H_F (eq. 5) joins them.
"""

from robotplan.functionals.base import Functional, Quadrature
from robotplan.functionals.collision import Collision
from robotplan.functionals.contact import ContactPoint
from robotplan.functionals.goal import GoalRegion

__all__ = ["Collision", "ContactPoint", "Functional", "GoalRegion", "Quadrature"]
