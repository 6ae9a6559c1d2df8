"""Spatial poses of the hang facade, ``(x, y, z, qw, qx, qy, qz)``: a table pose lifted to
one, and their composition and inverse (through Drake's RigidTransform)."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["compose", "inverse_pose", "table_pose"]


def table_pose(x: float, y: float, yaw: float, z: float = 0.0) -> np.ndarray:
    """A planar table pose as a spatial one ``(7,)``."""
    return np.array([x, y, z, math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


def _rigid(X: np.ndarray):
    """A spatial pose ``(7,)`` as Drake's RigidTransform."""
    from pydrake.common.eigen_geometry import Quaternion
    from pydrake.math import RigidTransform

    q = np.asarray(X[3:], dtype=float)
    return RigidTransform(Quaternion(q / np.linalg.norm(q)), np.asarray(X[:3], dtype=float))


def _pose(T) -> np.ndarray:
    q = T.rotation().ToQuaternion()
    return np.array([*T.translation(), q.w(), q.x(), q.y(), q.z()])


def compose(X_AB: np.ndarray, X_BC: np.ndarray) -> np.ndarray:
    """X_AC = X_AB · X_BC for spatial poses ``(7,)``."""
    return _pose(_rigid(X_AB) @ _rigid(X_BC))


def inverse_pose(X: np.ndarray) -> np.ndarray:
    """X⁻¹ of a spatial pose ``(7,)``."""
    return _pose(_rigid(X).inverse())
