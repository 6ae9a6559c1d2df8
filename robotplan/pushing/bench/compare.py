"""``robotplan bench push --dynamics flow,rigid,direct``: the same scenes planned with each
learned dynamics, side by side, open and closed loop.

Each model's run is an ordinary push benchmark in ``DIR/<kind>/`` (resumable on its own);
``DIR/compare.json`` holds, per model and shape type, the coverage quartiles closed and open
loop, the scenes below 0.9, the plan time quartiles and the searches without a solved plan,
and ``DIR/compare.png`` the box plot of all of them.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from robotplan.base.files import write_atomically
from robotplan.base.resources import DYNAMICS_FOLDERS, learned_dir
from robotplan.pushing.bench.push import run_bench_push
from robotplan.pushing.bench.push_scenes import scene_name
from robotplan.pushing.bench.push_summary import MODEL_NAMES, summarize

__all__ = ["compare_rows", "run_bench_compare"]


def compare_rows(rows_by_kind: dict[str, list[dict]]) -> dict:
    """Side-by-side figures from each model's benchmark rows (``rows.jsonl``)."""
    out: dict = {}
    for kind, rows in rows_by_kind.items():
        summary = summarize(rows)
        out[kind] = {shape: {
            "closed_loop": summary["coverage"][shape],
            "open_loop": summary["open_loop_coverage"][shape],
            "below_0_9": summary["below_0_9"][shape],
            "plan_seconds": summary["plan_seconds"][shape],
            "unsolved": sum(r["status"] != "solved" for r in rows if r["shape"] == shape),
        } for shape in summary["coverage"]}
    return out


def _plot(rows_by_kind: dict[str, list[dict]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kinds = list(rows_by_kind)
    shapes = sorted({r["shape"] for rows in rows_by_kind.values() for r in rows})
    colors = plt.get_cmap("tab10").colors
    width = 0.8 / (2 * len(kinds))
    fig, ax = plt.subplots(figsize=(2.2 + 1.8 * len(shapes) * len(kinds) / 2, 3.6), dpi=120)
    for m, kind in enumerate(kinds):
        for loop, (key, alpha) in enumerate((("open_loop_coverage", 0.35),
                                             ("coverage", 1.0))):
            offset = -0.4 + width * (2 * m + loop + 0.5)
            data = [[r.get(key, 0.0) for r in rows_by_kind[kind] if r["shape"] == s]
                    for s in shapes]
            box = ax.boxplot(data, positions=np.arange(1, len(shapes) + 1) + offset,
                             widths=0.9 * width, patch_artist=True)
            for patch in box["boxes"]:
                patch.set_facecolor(colors[m % len(colors)])
                patch.set_alpha(alpha)
        ax.plot([], [], color=colors[m % len(colors)], linewidth=8,
                label=MODEL_NAMES.get(DYNAMICS_FOLDERS.get(kind, kind), kind))
    ax.plot([], [], color="#cccccc", linewidth=8, label="pale: open loop")
    ax.set_xticks(range(1, len(shapes) + 1), shapes)
    ax.set_ylabel("coverage of the object inside the goal")
    ax.set_ylim(-0.02, 1.02)
    ax.legend(loc="lower left", fontsize=8)
    ax.set_title("learned dynamics side by side: open (pale) and closed loop")
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    write_atomically(path, lambda tmp: fig.savefig(tmp, format="png"))
    plt.close(fig)


def run_bench_compare(kinds: list[str], scenes: int, seed: int, out: Path, workers: int = 2,
                      shapes: tuple[str, ...] = ("box", "lshape"), exhaustive: bool = False,
                      time_budget: float | None = None, perturb: int | None = None,
                      loop: dict | None = None, ray: str | None = None,
                      program: dict | None = None, rehearse: bool = True) -> dict:
    """One push benchmark per dynamics kind (``flow``, ``rigid``, ``direct``) on the same
    scenes, in ``out/<kind>/``; returns (and writes) the comparison. ``loop``: closed-loop
    settings in place of each scene class's, ``program`` its program settings."""
    names = {scene_name(i, shape) for i in range(scenes) for shape in shapes}
    rows_by_kind = {}
    for kind in kinds:
        print(f"== {kind}", flush=True)
        run_bench_push(scenes, seed, out / kind, learned_dir(DYNAMICS_FOLDERS[kind]), workers,
                       shapes, exhaustive, time_budget, perturb, loop, ray, program,
                       rehearse=rehearse)
        lines = (out / kind / "rows.jsonl").read_text().splitlines()
        rows_by_kind[kind] = [row for row in map(json.loads, filter(str.strip, lines))
                              if row["scene"] in names]
    result = {"seed": seed, "scenes_per_shape": scenes, "time_budget_s": time_budget,
              "perturb": perturb, "loop_settings": loop or {},
              "models": compare_rows(rows_by_kind)}
    write_atomically(out / "compare.json",
                     lambda tmp: tmp.write_text(json.dumps(result, indent=1)))
    _plot(rows_by_kind, out / "compare.png")
    return result
