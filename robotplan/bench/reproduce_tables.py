"""The push tables of ``robotplan reproduce``'s report (the paper's Tabs. 2, 4, 5 and 6): our
numbers beside the paper's, each mean with its spread over samples and, where the
evaluation kept its per-scene sums, its 95 % interval by a bootstrap over scenes
(:mod:`robotplan.base.intervals`); a row of several training seeds pools them."""

from __future__ import annotations

from robotplan.base.intervals import pooled_sums, ratio_interval
from robotplan.bench.paper import REPRESENTATIONS

__all__ = ["SHAPE_NAMES", "interval_text", "mean_cell", "tab2_rows", "tab4_rows",
           "tab56_rows", "training_text"]

SHAPE_NAMES = {"box": "boxes", "lshape": "L-shapes", "ood": "unseen footprints",
               "other": "unseen footprints"}
DQ_COLUMNS = ("x_mm", "y_mm", "alpha_deg")


def interval_text(interval: tuple[float, float] | None, digits: int = 2) -> str:
    """``" [lo, hi]"``, or nothing without an interval."""
    if interval is None:
        return ""
    return f" [{interval[0]:.{digits}f}, {interval[1]:.{digits}f}]"


def ms(pair) -> str:
    """``(mean, std)`` → ``"m ± s"``."""
    return f"{pair[0]:.2f} ± {pair[1]:.2f}"


def mean_cell(mean: float, std: float, sums: dict | None = None, numerator: str = "",
              denominator: str = "") -> str:
    """``"m ± s [lo, hi]"``: a mean over samples, their spread, and the 95 % interval of the
    mean from the per-scene ``sums`` (``numerator`` / ``denominator`` columns)."""
    interval = (ratio_interval(sums[numerator], sums[denominator])
                if sums and numerator in sums else None)
    return ms((mean, std)) + interval_text(interval)


def _pooled(steps: list[dict]) -> dict | None:
    """The per-scene sums of evaluation steps (one per seed) pooled, or None where one of
    them kept none."""
    sums = [s["result"].get("by_scene") for s in steps]
    return pooled_sums(sums) if all(sums) else None


def _rmse_cells(steps: list[dict], ours: str, spread: str, prefix: str) -> list[str]:
    """Contact and free cells of an RMSE (``ours``, ``spread`` keys; ``prefix`` of its
    per-scene columns: ``rmse`` or ``baseline``) averaged over ``steps``' seeds."""
    sums = _pooled(steps)
    cells = []
    for part in ("contact", "free"):
        mean = sum(s["result"][ours][part] for s in steps) / len(steps)
        std = sum(s["result"][spread][part] for s in steps) / len(steps)
        cells.append(mean_cell(mean, std, sums, f"{prefix}_{part}", part))
    return cells


def tab2_rows(results: dict, set_name: str, paper: dict) -> list:
    """Tab. 2 on ``set_name``: F_flow, F (and their object-frame models), F_q's moved SDF
    and no motion, beside ``paper`` (the paper's Tab. 2)."""
    rows = []
    for label, kind in (("F_flow", "flow"), ("F", "direct")):
        for name, key in ((label, f"rmse_{kind}_{set_name}"),
                          (f"{label}, object frame", f"rmse_{kind}_object_{set_name}")):
            if key not in results:  # no object-frame model shipped
                continue
            rows.append([name, *_rmse_cells([results[key]], "rmse_mm", "rmse_std_mm", "rmse"),
                         ms(paper[label]["contact"]), ms(paper[label]["free"])])
    rigid = results[f"rigid_{set_name}"]
    if "rmse_mm" in rigid["result"]:  # F_q's φ1_t = T(Δq)[φ1_{t−1}]; no Tab. 2 row in the paper
        rows.append(["F_q, T(Δq)[φ1_{t−1}]",
                     *_rmse_cells([rigid], "rmse_mm", "rmse_std_mm", "rmse"), "–", "–"])
    rows.append(["no motion", *_rmse_cells([results[f"rmse_flow_{set_name}"]],
                                           "baseline_rmse_mm", "baseline_std_mm", "baseline"),
                 ms(paper["no motion"]["contact"]), ms(paper["no motion"]["free"])])
    return rows


def training_text(sizes, steps: int, training: tuple = ()) -> str:
    """How each representation model of ``sizes`` was trained (``steps`` steps, the
    TrainConfig pairs ``training``), in words."""
    cfg = dict(training)
    extra = "".join(f", {k} {v}" for k, v in cfg.items() if k != "batch")
    seeds = sizes.training_seeds
    return (f"{steps:,} steps of batch {cfg.get('batch', 32)}{extra} on "
            f"{sizes.representation_scenes:,} scenes of seed 4, training seed"
            f"{'s' if len(seeds) > 1 else ''} {', '.join(map(str, seeds))}")


def _seed_note(steps: list[dict]) -> str:
    return f", {len(steps)} seeds" if len(steps) > 1 else ""


def tab4_rows(results: dict, sizes, paper: dict) -> list:
    """Tab. 4: per representation, our F_flow (its seeds pooled) and no-motion rows beside
    ``paper`` (the paper's Tab. 4)."""
    rows = []
    for key, steps in results["tab4"].items():
        label = REPRESENTATIONS[key][0]
        for name, ours, spread, prefix in (
                (f"F_flow on {label}, {sizes.flow_steps} steps{_seed_note(steps)}", "rmse_mm",
                 "rmse_std_mm", "rmse"),
                (f"no motion, {label}", "baseline_rmse_mm", "baseline_std_mm", "baseline")):
            ref = paper[key]["F_flow" if prefix == "rmse" else "no motion"]
            rows.append([name, *_rmse_cells(steps, ours, spread, prefix), ms(ref[0]),
                         ms(ref[1])])
    return rows


def _dq_cells(steps: list[dict], field: str = "delta_q_error", prefix: str = "") -> list[str]:
    """x, y, α cells of Tab. 5 (``prefix`` ``baseline_``: no motion), seeds pooled."""
    sums = _pooled(steps)
    cells = []
    for k in DQ_COLUMNS:
        mean = sum(s["result"][field][k][0] for s in steps) / len(steps)
        std = sum(s["result"][field][k][1] for s in steps) / len(steps)
        cells.append(mean_cell(mean, std, sums, prefix + k, "contact"))
    return cells


def _gains(steps: list[dict]) -> str:
    """The turn gain per shape (seeds pooled) with its interval."""
    sums = _pooled(steps)
    parts = []
    for k in steps[0]["result"]["turn_gain"]:
        interval = None
        if sums and "shape" in sums:
            mine = [i for i, shape in enumerate(sums["shape"]) if shape == k]
            product = [sums["turn_product"][i] for i in mine]
            square = [sums["turn_square"][i] for i in mine]
            gain = sum(product) / max(sum(square), 1e-12)
            interval = ratio_interval(product, square) if mine else None
        else:
            gain = sum(s["result"]["turn_gain"][k] for s in steps) / len(steps)
        parts.append(f"{SHAPE_NAMES.get(k, k)} {gain:.2f}{interval_text(interval)}")
    return ", ".join(parts)


def tab56_rows(results: dict, set_name: str, paper: dict, sizes) -> list:
    """Tab. 5 (``set_name`` ``test``) or 6 (``ood``): the shipped F_q, each representation's
    F_q (seeds pooled), F_flow read through the pose fit, no motion, and the paper's rows."""
    shipped = [results[f"rigid_{set_name}"]]
    rows = [["F_q on SDFs (ours, shipped)", *_dq_cells(shipped), _gains(shipped),
             *map(str, paper["SDF"])]]
    trained = results.get(f"reps_{set_name}", {})
    for key, steps in trained.items():
        label = REPRESENTATIONS[key][0]
        rows.append([f"F_q on {label}, {sizes.representation_steps} steps{_seed_note(steps)}",
                     *_dq_cells(steps), _gains(steps),
                     *(map(str, paper[label]) if label in paper else ["", "", ""])])
    fit = results.get("pose_fit_flow", {}).get("result", {})
    if set_name == "test" and "delta_q_error" in fit:
        fit_gains = ", ".join(f"{SHAPE_NAMES.get(k, k)} {fit[k]['turn_gain']:.2f}"
                              for k in ("box", "lshape") if k in fit)
        rows.append([f"F_flow read through the pose fit ({fit['samples']} samples)",
                     *_dq_cells([results["pose_fit_flow"]]), fit_gains, "", "", ""])
    rows.append(["no motion (Δq = 0)",
                 *_dq_cells(shipped, "baseline_delta_q_error", "baseline_"), "", "", "", ""])
    ours = {REPRESENTATIONS[key][0] for key in trained}
    rows.extend([f"{name} (paper only)", "", "", "", "", *map(str, v)]
                for name, v in paper.items() if name != "SDF" and name not in ours)
    return rows
