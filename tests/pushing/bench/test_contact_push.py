"""Fig. 5's push from contact: the scene, the still start, a model on ψ = sign(φ), which
passes the program no gradient through the pusher's grids, and a point-cloud F_q, which
the program takes too."""

import numpy as np
import pytest
import torch

from robotplan.pushing.bench.contact_push import (
    CONTACT_PUSH_SETTINGS,
    GAP,
    PUSHER_RADIUS,
    TRAVEL,
    contact_push_scene,
    plan_from_contact,
    plot_contact_pushes,
    still_guess,
)
from robotplan.pushing.models.dynamics import DynamicsSpec
from robotplan.pushing.models.rigid import RigidMotion, save_rigid
from tests.conftest import TINY_SPEC

SPEC = {k: v for k, v in TINY_SPEC.items() if k != "point_features"}


def test_the_pusher_starts_at_the_face_and_the_goal_lies_straight_ahead():
    scene = contact_push_scene()
    box, pusher = scene.bodies["box"], scene.bodies["pusher"]
    gap = float(box.shape.sdf(torch.tensor([pusher.pose[:2]], dtype=torch.float64))[0])
    assert gap - PUSHER_RADIUS == pytest.approx(GAP, abs=1e-9)
    assert scene.goal.pose[0] - box.pose[0] == pytest.approx(TRAVEL)
    assert scene.goal.pose[1] == box.pose[1] and scene.goal.pose[2] == box.pose[2]


def test_the_still_start_moves_nothing_and_touches_the_pusher_surface():
    scene = contact_push_scene()
    guess = still_guess(scene, 10)
    assert guess["q_obj"].shape == (11, 3) and guess["q_pusher"].shape == (11, 2)
    assert np.ptp(guess["q_obj"], axis=0).max() == 0
    assert np.ptp(guess["q_pusher"], axis=0).max() == 0
    gaps = np.linalg.norm(guess["p"] - guess["q_pusher"][0], axis=1)
    assert guess["p"].shape == (10, 2)
    np.testing.assert_allclose(gaps, PUSHER_RADIUS, atol=1e-12)
    assert (guess["p"][:, 0] > guess["q_pusher"][0, 0]).all()  # on the side facing the box


def test_the_program_holds_the_learned_row_and_the_goal_only():
    s = CONTACT_PUSH_SETTINGS
    assert not (s.warm_start or s.with_collision or s.with_contact or s.row("friction_cone").active
                or s.row("friction_cone").turn)
    assert s.row("lever").weight == 0 and s.row("H_F").weight > 0


@pytest.mark.slow
def test_a_model_on_sign_occupancy_leaves_the_pusher_where_it_starts(tmp_path):
    torch.manual_seed(0)
    model = RigidMotion(DynamicsSpec(kind="rigid", encoder="joint", representation="occupancy",
                                     **SPEC))
    save_rigid(model, tmp_path / "psi")
    result = plan_from_contact(tmp_path / "psi")
    assert result["planned_pusher_travel_m"] < 1e-6
    assert result["box_travel_m"] < 1e-3 and result["coverage"] < 0.05
    assert not result["success"]


@pytest.mark.parametrize("encoder", ["pointnet", "pointnet2"])
def test_a_point_cloud_f_q_moves_the_pusher_in_the_plan(tmp_path, encoder):
    """H_q differentiates a point-cloud F_q by autograd through its clouds' vertices: unlike
    ψ's, the pusher's grids pass the program a gradient, and that row is all that moves the
    pusher in the plan (an untrained F_q on a coarse grid: seconds)."""
    torch.manual_seed(0)
    model = RigidMotion(DynamicsSpec(
        kind="rigid", encoder="joint", representation="pointcloud", cloud_encoder=encoder,
        grid=(48, 48), cloud_points=32, cloud_widths=(8, 16), cloud_centroids=8,
        cloud_neighbours=6, cloud_local_widths=(8,), **SPEC))
    save_rigid(model, tmp_path / encoder)
    result = plan_from_contact(tmp_path / encoder)
    for key in ("violation", "dynamics_rms_mm", "box_travel_m", "coverage"):
        assert np.isfinite(result[key]) and result[key] >= 0, key
    assert result["planned_pusher_travel_m"] > 1e-3


def test_the_figure_draws_a_panel_per_model(tmp_path):
    from PIL import Image

    still = still_guess(contact_push_scene(), 10)
    moved = {**still, "q_obj": still["q_obj"] + [TRAVEL, 0.0, 0.0]}
    results = {key: {"q_obj": r["q_obj"].tolist(), "q_pusher": r["q_pusher"].tolist(),
                     "coverage": c} for key, r, c in (("a", still, 0.0), ("b", moved, 1.0))}
    plot_contact_pushes(results, {"a": "A", "b": "B"}, tmp_path / "fig5.png")
    one = tmp_path / "one.png"
    plot_contact_pushes({"a": results["a"]}, {"a": "A"}, one)
    wide, narrow = Image.open(tmp_path / "fig5.png"), Image.open(one)
    assert wide.size[0] > 1.8 * narrow.size[0] and wide.size[1] == narrow.size[1]
