"""The pose fit that reads a push model as the planner does (argmin of H_t)."""

import numpy as np
import pytest
import torch

from robotplan.functionals.base import Quadrature
from robotplan.pushing.functionals.dynamics import LearnedDynamics
from robotplan.pushing.models.dynamics import load_model
from robotplan.pushing.training.pose_fit import _local_quadrature, evaluate_pose_fit, fit_step
from robotplan.pushing.training.samples import PushSamples
from robotplan.scene.bodies import Body
from robotplan.sdf import Box, Circle, LShape
from tests.conftest import DATA, ROOT

FLOW = ROOT / "learned" / "push_flow"


def _h(model, obj, tool, q1p, q1, q2p, q2n, quad: Quadrature) -> float:
    dyn = LearnedDynamics(model, obj, tool, quad)
    X1 = torch.tensor(np.stack([q1p, q1]))
    X2 = torch.tensor(np.stack([q2p, q2n]))
    return float(dyn.evaluate(X1, X2, jacobian=False)[0][0])


def test_fit_is_a_minimum_of_h_t_near_the_true_step():
    """On held-out contact samples the fitted pose has a lower H_t than the start, the true
    next pose, and small moves (1 mm, 0.01 rad) around it; and it is within 3 cm of the
    simulator's step."""
    model = load_model(FLOW)
    data = PushSamples(DATA / "push_sample")
    d = data.data
    rng = np.random.default_rng(0)
    for i in rng.choice(np.flatnonzero(data.contact), 3, replace=False):
        s, now = data.scene[i], data.now[i]
        hw, hh, th = data.params[s]
        shape = LShape((2 * hw, 2 * hh), float(th)) if th < 2 * hh - 1e-9 else Box((2 * hw, 2 * hh))
        q1p, q1n = d["object_pose"][now - 1].astype(float), d["object_pose"][now].astype(float)
        q2p, q2n = d["pusher_xy"][now - 1].astype(float), d["pusher_xy"][now].astype(float)
        obj = Body("o", "object", shape, tuple(q1p), 0.0, 0.06)
        tool = Body("p", "pusher", Circle(float(d["pusher_radius"][s])), (*q2p, 0.0), 0.0, 0.06)
        fit = fit_step(model, obj, tool, q1p, q2p, q2n)
        quad = _local_quadrature(q1p, torch.float32)
        h_fit = _h(model, obj, tool, q1p, fit, q2p, q2n, quad)
        assert h_fit <= _h(model, obj, tool, q1p, q1p, q2p, q2n, quad)
        assert h_fit <= _h(model, obj, tool, q1p, q1n, q2p, q2n, quad)
        for k, eps in ((0, 1e-3), (1, 1e-3), (2, 1e-2)):
            for sign in (-1, 1):
                moved = fit.copy()
                moved[k] += sign * eps
                assert h_fit <= _h(model, obj, tool, q1p, moved, q2p, q2n, quad) * (1 + 1e-4)
        assert np.linalg.norm(fit[:2] - q1n[:2]) < 0.03


def test_evaluate_pose_fit_reports_both_shapes():
    out = evaluate_pose_fit(FLOW, DATA / "push_sample", samples=8, progress=False)
    assert out["samples"] == 8
    total = sum(out[k]["samples"] for k in ("box", "lshape") if k in out)
    assert total == out["all"]["samples"] == 8
    for k in ("box", "lshape", "all"):
        if k in out:
            assert 0 <= out[k]["translation_error_mm"] < 30
            assert np.isfinite(out[k]["turn_gain"])
    # the fitted steps read as F_q's Δq about the footprint's centroid (paper Tab. 5)
    table = out["delta_q_error"]
    assert set(table) == {"x_mm", "y_mm", "alpha_deg"}
    for mean, std in table.values():
        assert 0 <= mean < 30 and std >= 0
    sums = out["by_scene"]  # per-scene sums: a report's bootstrap gives back each mean
    assert sum(sums["contact"]) == 8 and len(sums["shape"]) == len(sums["scene"])
    for k, (mean, _std) in table.items():
        assert sum(sums[k]) / 8 == pytest.approx(mean, abs=2e-3)


def test_an_object_frame_model_is_fitted_through_its_own_h_f():
    """An object-frame F_flow is read as the planner reads it (H_F with the grid about the
    object): the fitted pose has a lower H_t than the start and than small moves around it."""
    from robotplan.models.spec import OBJECT_WINDOW
    from robotplan.pushing.functionals.framed_dynamics import FramedDynamics
    from robotplan.pushing.models.dynamics import DynamicsSpec, PushDynamics

    torch.manual_seed(2)
    spec = DynamicsSpec(kind="flow", frame="object", channels=(2, 3, 3), sdf_features=16,
                        point_features=8, hidden=(24, 24), **OBJECT_WINDOW)
    model = PushDynamics(spec).double()
    q1p, q2p, q2n = np.array([0.02, 0.01, 0.3]), np.array([-0.14, 0.02]), np.array([-0.12, 0.02])
    obj = Body("o", "object", LShape((0.2, 0.16), 0.07), tuple(q1p), 0.0, 0.06)
    tool = Body("p", "pusher", Circle(0.025), (*q2p, 0.0), 0.0, 0.06)
    fit = fit_step(model, obj, tool, q1p, q2p, q2n)
    H = FramedDynamics(model, obj, tool, _local_quadrature(q1p, torch.float64))
    X2 = torch.tensor(np.stack([q2p, q2n]))

    def h(q1) -> float:
        return float(H.evaluate(torch.tensor(np.stack([q1p, q1])), X2, jacobian=False)[0][0])

    assert np.linalg.norm(fit - q1p) > 1e-5 and h(fit) < h(q1p)
    for k, eps in ((0, 1e-3), (1, 1e-3), (2, 1e-2)):
        for sign in (-1, 1):
            moved = fit.copy()
            moved[k] += sign * eps
            assert h(fit) <= h(moved) * (1 + 1e-6)
