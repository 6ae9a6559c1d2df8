"""Tab. 3's section of ``robotplan reproduce``'s report: the shipped H_hang by method beside
the paper's SDF rows, then H_hang trained alike on each representation beside the paper's
best row of it."""

from __future__ import annotations

from robotplan.base.intervals import share_interval
from robotplan.bench.paper import PAPER_TAB3_BASELINES
from robotplan.bench.report import Block
from robotplan.bench.reproduce_tables import interval_text
from robotplan.hanging.bench.bench import METHODS, PAPER_TAB3
from robotplan.hanging.bench.reproduce import COLLISION_ROWS, HANG_REPRESENTATIONS

__all__ = ["tab3_blocks"]


def _share(share: float, scenes: int) -> str:
    """A share in % with its 95 % interval (a bootstrap over the ``scenes`` it is of)."""
    interval = share_interval(round(share * scenes), scenes)
    percent = interval and (100 * interval[0], 100 * interval[1])
    return f"{100 * share:.1f}{interval_text(percent, 1)}"


def _cells(summary: dict, method: str) -> list[str]:
    """found and total are shares of the scenes, sim success of the scenes where a pose was
    found, collision free of those where it hung (the paper's Tab. 3)."""
    r, scenes = summary[method], summary["scenes"]
    found = round(r["found"] * scenes)
    hung = round(r["sim_success"] * found)
    return [_share(r["found"], scenes), _share(r["sim_success"], found),
            _share(r["collision_free"], hung), _share(r["total"], scenes)]


def tab3_blocks(results: dict, sizes) -> list[Block]:
    """Tab. 3's section of the report: the shipped H_hang by method beside the paper's SDF
    rows, then each representation's H_hang trained alike beside the paper's best row."""
    shipped = results["tab3"]["result"]
    rows = [[m, *_cells(shipped, m), " / ".join(f"{100 * v:.1f}" for v in PAPER_TAB3[m])]
            for m in METHODS if m in shipped]
    header = ["found", "sim success", "collision free", "total"]
    b: list[Block] = [
        ("h2", "Tab. 3: mug hanging (% of scenes: found / sim success / collision free / "
               "total, each [95 % interval])"),
        ("table", ["method", *header, "paper"], rows),
        ("p", f"The shipped H_hang (`learned/hang`) with the paper's protocol: uniform "
              f"random starts, one network (`--no-threading --check none`; robotplan's "
              f"default program keeps the hook's arm through the handle, `bench hang`). "
              f"Median seconds of optimisation + sampling per scene: "
              f"{shipped.get('median_seconds')}.")]
    reps = results.get("tab3_representations", {})
    if not reps:
        return b
    rep_rows, held_out = [], []
    for key, step in reps.items():
        label = HANG_REPRESENTATIONS[key][0]
        for name, suffix in (("bench", ""), *((f"bench_{c}", text)
                                              for c, text in COLLISION_ROWS.items())):
            if name not in step:
                continue
            summary = step[name]["result"]
            for i, m in enumerate(m for m in METHODS if m in summary):
                first = i == 0
                rep_rows.append([label + suffix if first else "", m, *_cells(summary, m),
                                 PAPER_TAB3_BASELINES[key] if first and not suffix else ""])
        v = step["train"]["result"]["validation"]
        held_out.append([label, f"{v['loss']:.3f}", *(
            " / ".join(f"{v[k][r]:.3f}" if v[k][r] is not None else "–"
                       for r in ("accuracy", "recall", "specificity")) for k in ("k1", "k2"))])
    n, scenes = sizes.hang_train_steps, sizes.hang_representation_scenes
    b += [("table", ["H_hang on", "method", *header, "paper (best row)"], rep_rows),
          ("p", f"Each H_hang of this table has the paper's network and loss (eq. 21), "
                f"trained alike: {n} steps of batch 32 on {sizes.hang_train_scenes} scenes "
                f"of seed 0, training seed 0; each planned with on {scenes} "
                f"scene{'s' if scenes != 1 else ''} of seed 2 within "
                f"{sizes.hang_evaluations:,} functional evaluations per method (the paper: "
                "20,000). ψ and ψ_s go through the same convolutions as φ; a cloud is the "
                "marching-cubes vertices of the grid (eq. 12) through a PointNet or "
                "PointNet++, one feature vector per object. H_coll is eq. (7) on ψ for "
                "the ψ models, as the paper's (`bench hang --collision model`), and on the "
                "shapes' SDFs for the others (the paper's point-cloud rows \"+ SDF "
                "collision\")."
                + (" A row \"no collision row\" plans and accepts poses on H_hang alone "
                   "(`--collision none`), as the paper's point-cloud rows \"no collision\"."
                   if any("bench_none" in r for r in reps.values()) else "")),
          ("table", ["H_hang on", "held-out loss (eq. 21)",
                     "κ1: accuracy / recall / specificity", "κ2: accuracy / recall / "
                     "specificity"], held_out),
          ("p", f"The same models on {sizes.hang_test_scenes} held-out scenes of seed 1 "
                "(`robotplan eval hang`): \"H < κ predicts success\" against the drop's label "
                "(recall over the poses that hang, specificity over the rest).")]
    return b
