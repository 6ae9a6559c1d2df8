"""Arms in the programs: forward kinematics functionals with exact Jacobians (float64 finite
differences), inverse kinematics of a tip path, and the arms' reach in robot.yaml."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from robotplan.functionals.kinematics import (
    ArmSeparation,
    CheckPointHeights,
    TipCoupling,
    TipHeight,
    arm_kinematics,
    track_tip_path,
)
from robotplan.scene.robots import available_models, load_robot_model
from robotplan.scene.schema import RobotSpec


def _spec(name: str, base) -> RobotSpec:
    return RobotSpec(name=name, model="iiwa", base=tuple(base), tip_radius=0.03)


@pytest.fixture(scope="module")
def left():
    return arm_kinematics(_spec("left", (-0.8, 0.0, 0.0, 0.0)))


@pytest.fixture(scope="module")
def right():
    return arm_kinematics(_spec("right", (0.8, 0.0, 0.0, np.pi)))


def _random_q(kin, rng, n: int) -> np.ndarray:
    lo, hi = np.array(kin.model.joint_lower), np.array(kin.model.joint_upper)
    return kin.q0 + rng.uniform(-0.5, 0.5, (n, kin.dof)).clip(lo - kin.q0, hi - kin.q0) * 0.8


def _check_jacobians(fn, inputs: list[np.ndarray], eps: float = 1e-6, tol: float = 1e-6):
    """Every block of ``fn.jacobians`` against central differences of ``fn``, per step."""
    tensors = [torch.tensor(x, dtype=torch.float64) for x in inputs]
    value, jacs = fn.jacobians(*tensors)
    assert torch.allclose(value, fn(*tensors))
    for i, x in enumerate(inputs):
        numeric = np.zeros(jacs[i].shape)
        for d in range(x.shape[1]):
            hi, lo = [t.clone() for t in tensors], [t.clone() for t in tensors]
            hi[i][:, d] += eps
            lo[i][:, d] -= eps
            numeric[:, :, d] = ((fn(*hi) - fn(*lo)) / (2 * eps)).numpy()
        err = np.abs(jacs[i].numpy() - numeric).max()
        assert err < tol, f"input {i}: Jacobian differs from finite differences by {err:.2e}"


def test_tip_coupling_height_and_link_jacobians(left, rng):
    q = _random_q(left, rng, 4)
    x = rng.normal(0.0, 0.3, (4, 2))
    _check_jacobians(TipCoupling(left), [q, x])
    _check_jacobians(TipHeight(left), [q])
    _check_jacobians(CheckPointHeights(left), [q])
    r = TipCoupling(left)(torch.tensor(q), torch.tensor(x)).numpy()
    tips = np.array([left.tip(qi)[:2] for qi in q])
    assert np.abs(r - (tips - x)).max() < 1e-12


def test_arm_separation_is_a_smooth_lower_bound(left, right, rng):
    qa, qb = _random_q(left, rng, 3), _random_q(right, rng, 3)
    sep = ArmSeparation(left, right)
    _check_jacobians(sep, [qa, qb], tol=1e-5)
    value = sep(torch.tensor(qa), torch.tensor(qb)).numpy()[:, 0]
    for k in range(3):
        pa, pb = left.fk(qa[k]).points, right.fk(qb[k]).points
        true_min = np.linalg.norm(pa[:, None] - pb[None], axis=-1).min()
        assert value[k] <= true_min + 1e-9
        assert value[k] > true_min - np.log(pa.shape[0] * pb.shape[0]) / sep.beta - 1e-9


def test_tip_path_follows_reachable_targets(left):
    """Sequential IK puts the tip on a straight push line at push height within 1 mm, and
    keeps the flange above its floor."""
    targets = np.stack([np.linspace(-0.45, -0.25, 5), np.full(5, -0.1), np.full(5, 0.03)], 1)
    Q = track_tip_path(left, targets, left.q0, flange_min=0.07, link_min=0.12)
    tips = np.array([left.tip(q) for q in Q])
    assert np.abs(tips - targets).max() < 1e-3
    assert min(left.fk(q).points[1, 2] for q in Q) > 0.07 - 1e-4
    assert all(left.model.within_limits(q) for q in Q)


@pytest.mark.parametrize("name", available_models())
def test_reach_in_robot_yaml_is_true(name):
    """Points at push height just inside ``reach`` are reachable with the flange up; one
    10 cm beyond it is not."""
    model = load_robot_model(name)
    lo, hi = model.reach
    assert 0.0 <= lo < hi < 2.0
    kin = arm_kinematics(_spec(name, (0.0, 0.0, 0.0, 0.0)))
    for r, reachable in ((lo + 0.02, True), (hi - 0.02, True), (hi + 0.10, False)):
        target = np.array([[r * np.cos(0.4), r * np.sin(0.4), 0.03]])
        q = track_tip_path(kin, target, kin.q0, flange_min=0.07, link_min=0.12)[0]
        miss = np.linalg.norm(kin.tip(q) - target[0])
        assert (miss < 2e-3) == reachable, f"{name} at {r:.2f} m: tip misses by {miss:.3f} m"
