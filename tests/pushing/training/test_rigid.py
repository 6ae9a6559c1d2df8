"""F_q training and evaluation on tiny real pybullet data with a tiny model."""

import json
import math
import subprocess
import sys
from dataclasses import replace

import pytest
import torch

from robotplan.pushing.models.rigid import load_rigid
from robotplan.pushing.training.rigid import train_rigid
from robotplan.pushing.training.rigid_evaluation import evaluate_rigid
from robotplan.pushing.training.train import TrainConfig
from tests.conftest import TINY_SPEC


def config(data, out, steps):
    spec = {k: v for k, v in TINY_SPEC.items() if k != "point_features"}
    return TrainConfig(data=str(data), out=str(out), kind="rigid", steps=steps, batch=8,
                       lr=3e-3, warmup=5, val_every=20, val_samples=16, val_fraction=0.2,
                       spec=spec, seed=3)


def _free_error(row: dict) -> float:
    err = row["val_delta_q_error"]["free"]
    return err["x_mm"][0] + err["y_mm"][0] + err["alpha_deg"][0]


def test_training_lowers_the_delta_q_error(tiny_push_data, tmp_path):
    last = train_rigid(config(tiny_push_data, tmp_path / "fq", 80), progress=False)
    history = json.loads((tmp_path / "fq" / "training.json").read_text())["history"]
    assert history[0]["step"] == 0 and last["step"] == 80
    # an untrained model predicts motion where nothing moves; training removes it
    assert _free_error(last) < 0.7 * _free_error(history[0])
    assert load_rigid(tmp_path / "fq").spec.kind == "rigid"


@pytest.mark.parametrize("augment", ["none", "turns"])
def test_resume_continues_exactly(tiny_push_data, tmp_path, augment):
    torch.set_num_threads(1)

    def cfg(name):
        return replace(config(tiny_push_data, tmp_path / name, 20), augment=augment)

    train_rigid(cfg("a"), progress=False)
    interrupted = cfg("b")
    interrupted.minutes = 0.0
    assert train_rigid(interrupted, progress=False)["step"] == 1
    train_rigid(cfg("b"), resume=True, progress=False)
    a, b = load_rigid(tmp_path / "a"), load_rigid(tmp_path / "b")
    for (k, va), vb in zip(a.state_dict().items(), b.state_dict().values(), strict=True):
        assert torch.allclose(va, vb, atol=1e-6), k


def test_evaluation_reports_the_papers_columns(tiny_push_data, tmp_path):
    train_rigid(config(tiny_push_data, tmp_path / "fq", 10), progress=False)
    result = evaluate_rigid(tmp_path / "fq", tiny_push_data)
    for key in ("x_mm", "y_mm", "alpha_deg"):
        mean, std = result["delta_q_error"][key]
        assert mean >= 0 and std >= 0
    assert set(result["turn_gain"]) == {"box", "lshape"}
    base = result["baseline_delta_q_error"]
    assert base["x_mm"][0] + base["y_mm"][0] > 0  # objects in contact do move
    res = subprocess.run([sys.executable, "-m", "robotplan.cli", "eval", "push", "--model",
                          str(tmp_path / "fq"), "--data", str(tiny_push_data), "--json"],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    assert "delta_q_error" in json.loads(res.stdout)


def test_f_q_is_scored_in_tab_2_terms_beside_f_flow(tiny_push_data, tiny_ood_push_data,
                                                    tmp_path):
    """F_q's SDF error over the table's X_h: φ1_{t−1} moved by the true Δq is φ1_t, by no
    step the no-motion baseline; evaluate_rigid's baseline is evaluate_push's on the same
    samples, so the two models stand in one table."""
    from robotplan.models.spec import DynamicsSpec
    from robotplan.pushing.training.evaluation import evaluate_push
    from robotplan.pushing.training.rigid import rigid_targets
    from robotplan.pushing.training.rigid_evaluation import moved_sdf_rmse
    from robotplan.pushing.training.samples import PushSamples
    from robotplan.pushing.training.train import train

    ws = DynamicsSpec().workspace()
    table = ws.points(torch.float64).reshape(-1, 2)
    for folder in (tiny_push_data, tiny_ood_push_data):
        samples = PushSamples(folder)
        batch = samples.batch(list(range(0, len(samples), 7)), dtype=torch.float64)
        _, pivot, true = rigid_targets(batch, table, ws.shape)
        exact, base = moved_sdf_rmse(batch, true, pivot, table)
        assert exact.max() < 1e-9
        still, base_again = moved_sdf_rmse(batch, torch.zeros_like(true), pivot, table)
        assert torch.equal(still, base) and torch.equal(base_again, base)
        assert base[batch.contact].min() > 1e-4  # pushed objects do move
    train_rigid(config(tiny_push_data, tmp_path / "fq", 2), progress=False)
    rigid = evaluate_rigid(tmp_path / "fq", tiny_push_data, per_scene=3)
    flow_cfg = replace(config(tiny_push_data, tmp_path / "ff", 2), kind="flow",
                       spec=dict(TINY_SPEC))
    train(flow_cfg, progress=False)
    flow = evaluate_push(tmp_path / "ff", tiny_push_data, per_scene=3, progress=False)
    assert rigid["samples"] == flow["samples"]
    for side in ("contact", "free"):
        assert rigid["baseline_rmse_mm"][side] == pytest.approx(
            flow["baseline_rmse_mm"][side], abs=2e-3)
        assert rigid["rmse_mm"][side] >= 0
    assert rigid["views"] == 1
    # the per-scene sums give back every mean the evaluations report
    for result in (rigid, flow):
        sums = result["by_scene"]
        for side in ("contact", "free"):
            assert sum(sums[side]) == result["samples"][side]
            assert sum(sums[f"rmse_{side}"]) / sum(sums[side]) == pytest.approx(
                result["rmse_mm"][side], abs=2e-3)
            assert sum(sums[f"baseline_{side}"]) / sum(sums[side]) == pytest.approx(
                result["baseline_rmse_mm"][side], abs=2e-3)
    sums = rigid["by_scene"]
    for k in ("x_mm", "y_mm", "alpha_deg"):
        assert sum(sums[k]) / sum(sums["contact"]) == pytest.approx(
            rigid["delta_q_error"][k][0], abs=2e-3)
    for shape, gain in rigid["turn_gain"].items():
        mine = [i for i, s in enumerate(sums["shape"]) if s == shape]
        assert sum(sums["turn_product"][i] for i in mine) / sum(
            sums["turn_square"][i] for i in mine) == pytest.approx(gain, abs=2e-3)


def test_the_sdf_space_loss_has_the_gradient_of_its_finite_differences():
    """Eq. (5) through T(Δq), φ1_{t−1} read from a grid: float64 gradient in Δq against
    finite differences, and zero loss at the true Δq of an exactly rendered rigid motion."""
    from robotplan.pushing.models.rigid import moved_pivot_delta, sdf_pivot
    from robotplan.pushing.training.rigid import sdf_space_loss
    from robotplan.pushing.training.samples import object_sdf
    from robotplan.sdf import Workspace

    ws = Workspace((0.0, 0.0), (0.6, 0.6), 0.01)
    grid = ws.points(torch.float64)
    params = torch.tensor([[0.08, 0.05, 0.04]], dtype=torch.float64)  # an L-shape
    prev = torch.tensor([[0.02, -0.01, 0.3]], dtype=torch.float64)
    now = torch.tensor([[0.035, 0.0, 0.38]], dtype=torch.float64)
    phi_grid = object_sdf(params, prev, grid.reshape(1, -1, 2)).reshape(1, *ws.shape)
    pivot = sdf_pivot(phi_grid.flatten(1), grid.reshape(-1, 2))
    gen = torch.Generator().manual_seed(5)
    pts = (torch.rand(1, 200, 2, generator=gen, dtype=torch.float64) - 0.5) * 0.3
    phi_now = object_sdf(params, now, pts)
    true = moved_pivot_delta(pivot, prev, now)
    assert sdf_space_loss(true, phi_grid, pivot, phi_now, pts, ws.bounds) < 1e-6

    def loss(delta):
        return sdf_space_loss(delta, phi_grid, pivot, phi_now, pts, ws.bounds)

    delta = (true + torch.tensor([[0.004, -0.003, 0.05]], dtype=torch.float64)).requires_grad_()
    assert torch.autograd.gradcheck(loss, (delta,), eps=1e-7, atol=1e-6)


def test_training_on_sdfs_alone_lowers_the_delta_q_error(tiny_push_data, tmp_path):
    cfg = config(tiny_push_data, tmp_path / "fq", 80)
    cfg.rigid_loss, cfg.points = "sdf", 64
    last = train_rigid(cfg, progress=False)
    history = json.loads((tmp_path / "fq" / "training.json").read_text())["history"]

    def turn_error(row):  # the untrained model's random turns are what training removes first
        err = row["val_delta_q_error"]
        return err["contact"]["alpha_deg"][0] + err["free"]["alpha_deg"][0]

    assert turn_error(last) < 0.85 * turn_error(history[0])


def test_evaluation_breaks_the_errors_down_by_footprint(tmp_path, tiny_push_data,
                                                        tiny_ood_push_data):
    """``by_footprint``: every family's contact samples, their errors and turn gain, which
    together make up the whole set's."""
    cfg = TrainConfig(data=str(tiny_push_data), out=str(tmp_path / "fq"), kind="rigid",
                      steps=2, batch=8, val_every=2, spec=TINY_SPEC)
    train_rigid(cfg, progress=False)
    for folder, names in ((tiny_push_data, {"box", "lshape"}),
                          (tiny_ood_push_data, {"triangle", "pentagon", "hexagon", "circle",
                                                "T", "cross", "U", "trapezoid"})):
        result = evaluate_rigid(tmp_path / "fq", folder)
        parts = result["by_footprint"]
        assert set(parts) <= names and len(parts) >= len(names) - 1
        assert sum(p["samples"] for p in parts.values()) == result["samples"]["contact"]
        for key in ("x_mm", "alpha_deg"):
            mean = sum(p["samples"] * p["delta_q_error"][key][0] for p in parts.values())
            assert mean / result["samples"]["contact"] == pytest.approx(
                result["delta_q_error"][key][0], abs=2e-3)


def test_quarter_turns_turn_the_rendered_inputs_and_the_delta_q(tiny_push_data,
                                                                 tiny_ood_push_data):
    """Turning the scene by k × 90° about X_h's centre rotates the rendered grids by k
    quarter turns and the true Δq's shift by k × 90°, leaving its turn: the symmetry the
    ``turns`` augmentation relies on, for boxes, L-shapes and the unseen footprints."""
    from robotplan.models.spec import DynamicsSpec
    from robotplan.pushing.training.rigid import rigid_targets
    from robotplan.pushing.training.samples import PushSamples
    from robotplan.sdf import Workspace

    spec = DynamicsSpec(kind="rigid")
    ws = Workspace(spec.workspace_center, spec.workspace_size,
                   spec.workspace_size[0] / spec.grid[1])
    grid = ws.points(torch.float64).reshape(-1, 2)
    for folder in (tiny_push_data, tiny_ood_push_data):
        samples = PushSamples(folder)
        idx = torch.arange(0, len(samples), max(1, len(samples) // 12)).numpy()
        batch = samples.batch(idx, dtype=torch.float64)
        inputs, _, delta = rigid_targets(batch, grid, ws.shape)
        assert batch.contact.any()
        for k in (1, 2, 3):
            turned = batch.turned(torch.full((len(idx),), k), (0.0, 0.0))
            t_inputs, _, t_delta = rigid_targets(turned, grid, ws.shape)
            # rows run along y, columns along x: a counter-clockwise turn is rot90 of (y, x)
            expected = torch.rot90(inputs, k, dims=(3, 2))
            assert (t_inputs - expected).abs().max() < 1e-9
            c, s = round(math.cos(k * math.pi / 2)), round(math.sin(k * math.pi / 2))
            shift = torch.stack((c * delta[:, 0] - s * delta[:, 1],
                                 s * delta[:, 0] + c * delta[:, 1]), 1)
            assert (t_delta[:, :2] - shift).abs().max() < 1e-9
            assert (t_delta[:, 2] - delta[:, 2]).abs().max() < 1e-9


def test_object_frame_inputs_and_delta_q_do_not_change_with_the_scenes_place(tiny_push_data):
    """In the object's frame the rendered grids and the true Δq of a push are the same
    wherever the whole scene is moved and however it is turned (exact, float64); φ1_{t−1}
    there is the footprint's SDF about its centroid, and Δq turned back to the table is the
    table-frame Δq about that centroid."""
    from dataclasses import replace as with_fields

    from robotplan.models.spec import OBJECT_WINDOW, DynamicsSpec
    from robotplan.pushing.models.rigid import delta_in_frame, moved_pivot_delta, object_frame
    from robotplan.pushing.training.rigid import rigid_targets
    from robotplan.pushing.training.samples import PushSamples, object_sdf

    ws = DynamicsSpec(kind="rigid", frame="object", **OBJECT_WINDOW).workspace()
    grid = ws.points(torch.float64).reshape(-1, 2)
    samples = PushSamples(tiny_push_data)
    batch = samples.batch(torch.arange(0, len(samples), 7).numpy(), dtype=torch.float64)
    inputs, pivot, delta = rigid_targets(batch, grid, ws.shape, "object")
    assert batch.contact.any() and delta[batch.contact].abs().max() > 1e-4
    at_origin = torch.cat((-batch.centroid, torch.zeros_like(batch.radius)[:, None]), 1)
    phi1 = object_sdf(batch.params, at_origin, grid[None]).reshape(-1, *ws.shape)
    assert (inputs[:, 0] - phi1).abs().max() < 1e-12
    assert (pivot - object_frame(batch.object_prev, batch.centroid)[:, :2]).abs().max() == 0
    table = moved_pivot_delta(pivot, batch.object_prev, batch.object_now)
    assert (delta_in_frame(delta, batch.object_prev[:, 2]) - table).abs().max() < 1e-12
    angle, shift = 1.1, torch.tensor([0.07, -0.12], dtype=torch.float64)
    c, s = math.cos(angle), math.sin(angle)

    def moved(p):
        xy = torch.stack((c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]), 1) + shift
        return torch.cat((xy, p[:, 2:] + angle), 1) if p.shape[1] == 3 else xy

    other = with_fields(batch, object_prev=moved(batch.object_prev),
                        object_now=moved(batch.object_now),
                        pusher_prev=moved(batch.pusher_prev), pusher_now=moved(batch.pusher_now))
    o_inputs, _, o_delta = rigid_targets(other, grid, ws.shape, "object")
    assert (o_inputs - inputs).abs().max() < 1e-9
    assert (o_delta - delta).abs().max() < 1e-9


def test_an_object_frame_f_q_learns_and_reports_table_frame_errors(tiny_push_data, tmp_path):
    from robotplan.models.spec import OBJECT_WINDOW

    cfg = config(tiny_push_data, tmp_path / "fq", 80)
    cfg.spec = {**cfg.spec, "frame": "object", **OBJECT_WINDOW}
    last = train_rigid(cfg, progress=False)
    history = json.loads((tmp_path / "fq" / "training.json").read_text())["history"]

    def shift_error(row):  # in contact, where the pushed object moves
        err = row["val_delta_q_error"]["contact"]
        return err["x_mm"][0] + err["y_mm"][0]

    assert shift_error(last) < 0.8 * shift_error(history[0])
    result = evaluate_rigid(tmp_path / "fq", tiny_push_data)
    base = result["baseline_delta_q_error"]
    assert result["delta_q_error"]["x_mm"][0] < base["x_mm"][0] + base["y_mm"][0]
    with pytest.raises(ValueError, match="object-frame"):
        train_rigid(replace(cfg, out=str(tmp_path / "b"), augment="turns"), progress=False)


@pytest.mark.parametrize("offset", [(0.0, 0.0), (0.04, -0.05)])
def test_a_placed_object_frame_keeps_the_table_frame_delta_q(tiny_push_data, offset):
    """``augment headings`` / ``placements``: the window placed at X_OF = (x, y, u) in the
    object frame shows the footprint at X_OF⁻¹ X_OB, and Δq given in the window's axes about
    its origin is the same step on the table as the simulator's poses give about that
    point."""
    from robotplan.geometry.transforms import planar_to_body, planar_to_world
    from robotplan.models.spec import OBJECT_WINDOW, DynamicsSpec
    from robotplan.pushing.models.rigid import delta_in_frame, moved_pivot_delta, object_frame
    from robotplan.pushing.training.rigid import rigid_targets
    from robotplan.pushing.training.samples import PushSamples, object_sdf

    ws = DynamicsSpec(kind="rigid", frame="object", **OBJECT_WINDOW).workspace()
    grid = ws.points(torch.float64).reshape(-1, 2)
    samples = PushSamples(tiny_push_data)
    batch = samples.batch(torch.arange(0, len(samples), 11).numpy(), dtype=torch.float64)
    n = len(batch.radius)
    heading = torch.linspace(-3.0, 3.0, n, dtype=torch.float64)
    placement = torch.cat((torch.tensor(offset, dtype=torch.float64).expand(n, 2),
                           heading[:, None]), 1)
    inputs, pivot, delta = rigid_targets(batch, grid, ws.shape, "object", placement)
    X_WO = object_frame(batch.object_prev, batch.centroid)
    origin = planar_to_world(placement[:, None, :2], X_WO)[:, 0]
    torch.testing.assert_close(pivot, origin, rtol=0, atol=1e-12)
    yaw_F = batch.object_prev[:, 2] + heading
    true = moved_pivot_delta(origin, batch.object_prev, batch.object_now)
    torch.testing.assert_close(delta_in_frame(delta, yaw_F), true, rtol=0, atol=1e-12)
    # the body's origin seen from the placed window, and its heading there
    body_O = -batch.centroid - placement[:, :2]
    c, s = heading.cos(), heading.sin()
    X_FB = torch.stack((c * body_O[:, 0] + s * body_O[:, 1],
                        -s * body_O[:, 0] + c * body_O[:, 1], -heading), 1)
    phi1 = object_sdf(batch.params, X_FB, grid[None]).reshape(-1, *ws.shape)
    assert (inputs[:, 0] - phi1).abs().max() < 1e-12
    # the pusher's SDF is read at the same table points
    g_W = planar_to_world(grid[None], torch.cat((origin, yaw_F[:, None]), 1))
    r = planar_to_body(g_W, torch.cat((batch.pusher_prev, 0 * heading[:, None]), 1))
    phi2 = (r.norm(dim=-1) - batch.radius[:, None]).reshape(-1, *ws.shape)
    assert (inputs[:, 1] - phi2).abs().max() < 1e-12


def test_window_placements_are_drawn_per_step_within_reach():
    """Headings move no origin; placements stay within PLACEMENT_REACH, cover it, and are
    the same for a step whenever it is drawn (a resumed run sees the same ones)."""
    from robotplan.pushing.training.rigid import PLACEMENT_REACH, window_placements
    from robotplan.pushing.training.train import TrainConfig

    cfg = TrainConfig(data="d", out="o", kind="rigid", augment="headings")
    headings = window_placements(cfg, 7, 4000)
    assert (headings[:, :2] == 0).all()
    assert headings[:, 2].abs().max() <= math.pi and headings[:, 2].std() > 1.5
    placed = window_placements(replace(cfg, augment="placements"), 7, 4000)
    torch.testing.assert_close(placed[:, 2], headings[:, 2])
    reach = placed[:, :2].norm(dim=1)
    assert reach.max() <= PLACEMENT_REACH + 1e-6 and reach.max() > 0.95 * PLACEMENT_REACH
    assert (reach < PLACEMENT_REACH / 2).float().mean().item() == pytest.approx(0.25, abs=0.03)
    torch.testing.assert_close(window_placements(replace(cfg, augment="placements"), 7, 4000),
                               placed, rtol=0, atol=0)
    assert not torch.equal(window_placements(replace(cfg, augment="placements"), 8, 4000),
                           placed)
    wide = window_placements(replace(cfg, augment="placements", placement_reach=0.12), 7, 4000)
    assert wide[:, :2].norm(dim=1).max() <= 0.12 + 1e-6
    torch.testing.assert_close(wide[:, :2], placed[:, :2] * (0.12 / PLACEMENT_REACH))
