"""The real training loop on tiny real data with a tiny model: learns, resumes exactly."""

import json
import math

import pytest
import torch

from robotplan.pushing.models.dynamics import load_model
from robotplan.pushing.training.evaluation import evaluate_push
from robotplan.pushing.training.model_card import record_heldout, write_model_card
from robotplan.pushing.training.rigid import train_rigid
from robotplan.pushing.training.train import TrainConfig, train
from tests.conftest import TINY_SPEC


def config(data, out, steps):
    return TrainConfig(data=str(data), out=str(out), steps=steps, batch=8, lr=3e-3,
                       warmup=5, points=64, val_every=20, val_samples=16, val_fraction=0.2,
                       spec=TINY_SPEC, seed=3)


def test_training_reduces_the_error(tiny_push_data, tmp_path):
    last = train(config(tiny_push_data, tmp_path / "m", 60), progress=False)
    history = json.loads((tmp_path / "m" / "training.json").read_text())["history"]
    assert history[0]["step"] == 0
    first = history[0]["val_rmse_mm"]["free"]
    assert last["step"] == 60
    # an untrained flow model predicts noise where nothing moves; training removes it
    assert last["val_rmse_mm"]["free"] < first
    for name in ("weights.pt", "spec.json", "checkpoint.pt", "training.json"):
        assert (tmp_path / "m" / name).is_file()


def test_resume_continues_exactly(tiny_push_data, tmp_path):
    torch.set_num_threads(1)
    train(config(tiny_push_data, tmp_path / "a", 30), progress=False)
    interrupted = config(tiny_push_data, tmp_path / "b", 30)
    interrupted.minutes = 0.0  # stops after its first step, as a time budget would
    assert train(interrupted, progress=False)["step"] == 1
    train(config(tiny_push_data, tmp_path / "b", 30), resume=True, progress=False)
    a, b = load_model(tmp_path / "a"), load_model(tmp_path / "b")
    for (k, va), vb in zip(a.state_dict().items(), b.state_dict().values(), strict=True):
        assert torch.allclose(va, vb, atol=1e-6), k


def test_evaluation_and_model_card(tiny_push_data, tmp_path):
    out = tmp_path / "m"
    train(config(tiny_push_data, out, 10), progress=False)
    result = evaluate_push(out, tiny_push_data, per_scene=3, progress=False)
    assert set(result["samples"]) == {"contact", "free"}
    assert result["baseline_rmse_mm"]["contact"] > 1.0
    assert result["baseline_rmse_mm"]["free"] < 2.0
    # batching (a GPU evaluates 128 samples at a time) does not change the numbers
    again = evaluate_push(out, tiny_push_data, per_scene=3, progress=False, chunk=64,
                          device="cpu")
    assert again["device"] == "cpu" and again["samples"] == result["samples"]
    for key in ("rmse_mm", "baseline_rmse_mm"):
        for split in ("contact", "free"):
            assert abs(again[key][split] - result[key][split]) <= 0.002
    write_model_card(out)
    record_heldout(out, result)
    card = (out / "MODEL_CARD.md").read_text()
    assert "held-out" in card and "Known failure modes" in card
    assert json.loads((out / "metrics.json").read_text())["heldout"] == result


def test_balanced_batches_run(tiny_push_data, tmp_path):
    cfg = config(tiny_push_data, tmp_path / "m", 5)
    cfg.contact_share = 0.5
    assert train(cfg, progress=False)["step"] == 5


def test_init_weights_starts_from_a_previous_run(tiny_push_data, tmp_path):
    train(config(tiny_push_data, tmp_path / "a", 10), progress=False)
    cfg = config(tiny_push_data, tmp_path / "b", 1)
    cfg.init_weights = str(tmp_path / "a" / "weights.pt")
    cfg.lr = 1e-12  # one step that changes nothing measurable
    train(cfg, progress=False)
    a, b = load_model(tmp_path / "a"), load_model(tmp_path / "b")
    for va, vb in zip(a.state_dict().values(), b.state_dict().values(), strict=True):
        assert torch.allclose(va, vb, atol=1e-6)


@pytest.mark.parametrize("kind", ["flow", "rigid"])
def test_fine_tuned_model_keeps_the_recipe_of_its_parents(tiny_push_data, tmp_path, kind):
    run = train_rigid if kind == "rigid" else train
    for parent, child, steps in ((None, "a", 4), ("a", "b", 3), ("b", "c", 2)):
        cfg = config(tiny_push_data, tmp_path / child, steps)
        cfg.kind = kind
        cfg.init_weights = str(tmp_path / parent / "weights.pt") if parent else None
        cfg.command = f"train {child}"
        run(cfg, progress=False)
    record = json.loads((tmp_path / "c" / "training.json").read_text())
    assert [(s["command"], s["steps"]) for s in record["stages"]] == [("train a", 4),
                                                                      ("train b", 3)]
    if kind == "rigid":  # F_q's card is written by hand
        return
    write_model_card(tmp_path / "c")
    card = (tmp_path / "c" / "MODEL_CARD.md").read_text()
    assert "trained in 3 runs" in card
    assert card.index("`train a`") < card.index("`train b`") < card.index("`train c`")


def test_model_card_lists_the_pose_fit_by_shape_and_in_tab5_terms(tiny_push_data, tmp_path):
    out = tmp_path / "m"
    train(config(tiny_push_data, out, 2), progress=False)
    result = evaluate_push(out, tiny_push_data, per_scene=2, progress=False)
    row = {"samples": 3, "translation_error_mm": 2.5, "yaw_error_deg": 1.5,
           "true_turn_deg": 2.0, "turn_gain": 0.25}
    result["pose_fit"] = {"samples": 3, "box": row, "all": row, "seconds": 1.0,
                          "delta_q_error": {"x_mm": [2.4, 2.2], "y_mm": [2.3, 1.5],
                                            "alpha_deg": [1.8, 1.7]}}
    record_heldout(out, result)
    card = (out / "MODEL_CARD.md").read_text()
    assert "| box | 3 | 2.5 | 1.5 | 2.0 | 0.25 |" in card
    assert "x 2.4 ± 2.2 mm, y 2.3 ± 1.5 mm, α 1.8 ± 1.7°" in card


@pytest.mark.parametrize("representation", ["occupancy", "smooth_occupancy"])
def test_a_flow_on_an_occupancy_measure_predicts_it(tiny_push_data, tmp_path, representation):
    """Tab. 4: an F_flow on ψ learns and is scored in ψ (times 1000); its no-motion baseline
    is the RMSE of ψ1_t − ψ1_{t−1} over X_h, computed here from the samples themselves."""
    import numpy as np

    from robotplan.pushing.training.evaluation import pick_samples
    from robotplan.pushing.training.samples import PushSamples

    cfg = config(tiny_push_data, tmp_path / "m", 40)
    cfg.spec = {**TINY_SPEC, "representation": representation}
    last = train(cfg, progress=False)
    model = load_model(tmp_path / "m")
    assert model.spec.representation == representation and model.spec.out_scale == 1.0
    assert np.isfinite(last["val_rmse_mm"]["contact"])
    result = evaluate_push(tmp_path / "m", tiny_push_data, per_scene=3, progress=False)
    assert result["representation"] == representation
    samples = PushSamples(tiny_push_data)
    idx = pick_samples(samples, 3, 0)
    b = samples.batch(idx, dtype=torch.float64)
    grid = model.spec.workspace().points(torch.float64).reshape(1, -1, 2)
    psi = model.double().values_read
    base = (psi(b.phi1_now(grid)) - psi(b.phi1_prev(grid))).pow(2).mean(1).sqrt() * 1e3
    contact = samples.contact[idx]
    assert result["baseline_rmse_mm"]["contact"] == pytest.approx(
        float(base[torch.as_tensor(contact)].mean()), rel=1e-3)
    assert 0 < result["baseline_rmse_mm"]["contact"] <= 2000


def test_an_object_frame_field_moves_with_the_scene(tiny_push_data):
    """An object-frame F_flow reads the same grids and the same query points when the whole
    scene and the points are moved and turned together, so its predicted field moves with
    the scene (exact, float64); a table-frame model's field does not."""
    from dataclasses import replace as with_fields

    import numpy as np

    from robotplan.models.spec import OBJECT_WINDOW
    from robotplan.pushing.models.dynamics import DynamicsSpec, PushDynamics
    from robotplan.pushing.training.samples import PushSamples
    from robotplan.pushing.training.train import framed, scored_workspace

    samples = PushSamples(tiny_push_data)
    batch = samples.batch(np.arange(0, len(samples), 9), dtype=torch.float64)
    angle, shift = 0.7, torch.tensor([-0.05, 0.09], dtype=torch.float64)
    c, s = math.cos(angle), math.sin(angle)

    def moved(p):
        xy = torch.stack((c * p[..., 0] - s * p[..., 1], s * p[..., 0] + c * p[..., 1]), -1)
        return torch.cat((xy + shift, p[..., 2:] + angle), -1) if p.shape[-1] == 3 else xy + shift

    other = with_fields(batch, object_prev=moved(batch.object_prev),
                        object_now=moved(batch.object_now),
                        pusher_prev=moved(batch.pusher_prev), pusher_now=moved(batch.pusher_now))
    fields = {}
    for frame, window in (("object", OBJECT_WINDOW), ("table", {})):
        torch.manual_seed(0)
        spec = DynamicsSpec(kind="flow", frame=frame, **window, **TINY_SPEC)
        model = PushDynamics(spec).double()
        grid = spec.workspace().points(torch.float64).reshape(-1, 2)
        pts = scored_workspace(spec).points(torch.float64)[::9, ::9].reshape(1, -1, 2)
        with torch.no_grad():
            fields[frame] = (model(*framed(spec, batch, grid, pts)),
                             model(*framed(spec, other, grid, moved(pts))))
    here, there = fields["object"]
    assert here.abs().max() > 0 and (there - here).abs().max() < 1e-9
    here, there = fields["table"]
    assert (there - here).abs().max() > 1e-4


def test_an_object_frame_flow_learns_and_is_scored_on_the_tables_grid(tiny_push_data,
                                                                       tmp_path):
    """Trained in the object's frame, F_flow is scored on the table's 140 × 140 X_h, as
    every other model is: the same samples give the same no-motion baseline as a
    table-frame model's evaluation, and its own error equals the training's full-grid
    RMSE; turns and views are refused."""
    from dataclasses import replace

    from robotplan.models.spec import OBJECT_WINDOW
    from robotplan.pushing.training.evaluation import pick_samples
    from robotplan.pushing.training.samples import PushSamples
    from robotplan.pushing.training.train import grid_rmse

    cfg = config(tiny_push_data, tmp_path / "obj", 60)
    cfg.spec = {**cfg.spec, "frame": "object", **OBJECT_WINDOW}
    last = train(cfg, progress=False)
    history = json.loads((tmp_path / "obj" / "training.json").read_text())["history"]
    # in contact, where the pushed object's SDF changes, it learns the change
    assert last["val_rmse_mm"]["contact"] < 0.95 * history[0]["val_rmse_mm"]["contact"]
    result = evaluate_push(tmp_path / "obj", tiny_push_data, per_scene=3, progress=False)
    assert result["frame"] == "object"
    train(config(tiny_push_data, tmp_path / "table", 1), progress=False)
    table = evaluate_push(tmp_path / "table", tiny_push_data, per_scene=3, progress=False)
    assert table["samples"] == result["samples"]
    assert table["baseline_rmse_mm"] == result["baseline_rmse_mm"]
    samples = PushSamples(tiny_push_data)
    idx = pick_samples(samples, 3, 0)
    err, _ = grid_rmse(load_model(tmp_path / "obj"), samples.batch(idx))
    c = samples.contact[idx]
    assert abs(1e3 * float(err[c].mean()) - result["rmse_mm"]["contact"]) < 2e-3
    with pytest.raises(ValueError, match="object-frame"):
        train(replace(cfg, out=str(tmp_path / "b"), augment="turns"), progress=False)
    with pytest.raises(ValueError, match="views"):
        evaluate_push(tmp_path / "obj", tiny_push_data, per_scene=1, progress=False, views=4)


def test_an_evaluation_on_unseen_footprints_is_recorded_beside_the_held_out_one(
        tiny_push_data, tiny_ood_push_data, tmp_path):
    """``eval push --record`` on a ``--shapes ood`` folder stores the result as ``unseen``
    and the card gets its row; the held-out result stays where it was."""
    out = tmp_path / "m"
    train(config(tiny_push_data, out, 2), progress=False)
    held = evaluate_push(out, tiny_push_data, per_scene=1, progress=False)
    unseen = evaluate_push(out, tiny_ood_push_data, per_scene=1, progress=False)
    record_heldout(out, held)
    record_heldout(out, unseen)
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["heldout"] == held and metrics["unseen"] == unseen
    card = (out / "MODEL_CARD.md").read_text()
    assert f"| held-out `{tiny_push_data}`" in card
    assert f"| unseen footprints `{tiny_ood_push_data}`" in card
