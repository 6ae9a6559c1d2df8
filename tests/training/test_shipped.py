"""The shipped learned models: complete folders, safe loading, better than no motion."""

import json

import pytest

from robotplan.hanging.models.hang_model import HANG_THRESHOLDS, load_hang_model
from robotplan.pushing.models.dynamics import load_model
from robotplan.pushing.models.rigid import load_rigid
from robotplan.pushing.training.evaluation import evaluate_push
from robotplan.pushing.training.rigid_evaluation import evaluate_rigid
from tests.conftest import DATA, ROOT

LEARNED = ROOT / "learned"
SHIPPED = ["push_flow", "push_direct", "push_flow_object", "push_direct_object"]
# free-space RMSE bound (mm) per model: F_flow predicts a flow that vanishes away from the
# pusher; the direct F re-draws the whole SDF and is far less exact there (held-out 11 mm,
# paper 5.2 mm: a known weakness, see its model card)
FREE_BOUND_MM = {"push_flow": 5.0, "push_direct": 15.0, "push_flow_object": 5.0,
                 "push_direct_object": 15.0}
HANG_KAPPA2 = HANG_THRESHOLDS["k2"]
FOLDERS = sorted(p for p in LEARNED.iterdir() if p.is_dir())


@pytest.mark.parametrize("folder", FOLDERS, ids=lambda p: p.name)
def test_model_folder_is_complete(folder):
    for name in ("weights.pt", "spec.json", "metrics.json", "MODEL_CARD.md"):
        assert (folder / name).is_file(), f"{folder.name} lacks {name}"
    json.loads((folder / "metrics.json").read_text())
    kind = json.loads((folder / "spec.json").read_text())["kind"]
    loader = {"rigid": load_rigid, "hang": load_hang_model}.get(kind, load_model)
    loader(folder)  # weights_only=True inside


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_model_beats_the_no_motion_baseline(name):
    folder = LEARNED / name
    if not folder.is_dir():
        pytest.skip(f"learned/{name} is not trained yet")
    # a small fixed held-out sample: 6 scenes of seed 2, never used in training
    result = evaluate_push(folder, DATA / "push_sample", per_scene=4, progress=False)
    assert result["samples"]["contact"] >= 10
    assert result["rmse_mm"]["contact"] < result["baseline_rmse_mm"]["contact"]
    assert result["rmse_mm"]["free"] < FREE_BOUND_MM[name]


@pytest.mark.parametrize("name", ["push_rigid", "push_rigid_object"])
def test_shipped_rigid_model_predicts_the_motion_and_the_turn(name):
    """F_q (table or object frame) on the fixed held-out sample: far below the no-motion
    error, and it turns the object with the world (a positive least-squares gain on both
    shapes)."""
    folder = LEARNED / name
    if not folder.is_dir():
        pytest.skip(f"learned/{name} is not trained yet")
    result = evaluate_rigid(folder, DATA / "push_sample")
    err, base = result["delta_q_error"], result["baseline_delta_q_error"]
    assert result["samples"]["contact"] >= 100
    for key in ("x_mm", "y_mm"):
        assert err[key][0] < 0.5 * base[key][0]
    assert err["alpha_deg"][0] < base["alpha_deg"][0]
    assert result["turn_gain"]["box"] > 0.5 and result["turn_gain"]["lshape"] > 0.2


def test_shipped_hang_model_tells_hanging_poses_from_the_rest():
    """H_hang on a fixed held-out sample (20 scenes of the test seed, never trained on): at
    κ2 it accepts most poses that hang in place and rejects most that do not."""
    import numpy as np

    from robotplan.hanging.training.train import HangSamples, hang_metrics

    folder = LEARNED / "hang"
    if not folder.is_dir():
        pytest.skip("learned/hang is not trained yet")
    model = load_hang_model(folder)
    samples = HangSamples(DATA / "hang_sample", model.spec)
    result = hang_metrics(model, samples, np.arange(len(samples)))
    assert result["successes"] >= 20
    assert result["k2"]["recall"] > 0.7 and result["k2"]["specificity"] > 0.8
    assert result["h_median_success"] < HANG_KAPPA2 < result["h_median_failure"]
