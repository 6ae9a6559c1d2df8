"""``robotplan bench push``: plan and execute random push scenes, as the paper's Fig. 3.

Scenes are drawn as in the paper (app. I): the object roughly in the middle of the table
(position noise 3 cm, any yaw), the pusher on a circle around it, the goal region at one of
8 positions around the object (every 45°, 0.35 m away) with Gaussian noise (2 cm) on its
centre. Boxes and L-shapes come from the ranges of the push data; the goal region is a
square large enough for the object in any orientation (at least 0.4 m). Each scene is
solved by the skeleton search and executed open loop in pybullet.

``DIR`` receives ``scenes/NNN.yaml`` (re-solvable with ``robotplan solve``), ``rows.jsonl``
(one line per finished scene, so an interrupted run continues where it stopped),
``results.csv``, ``coverage.png`` (box plot per shape type) and ``summary.json``.
"""

from __future__ import annotations

import csv
import io
import json
import math
import time
from pathlib import Path

import numpy as np
import yaml

from robotplan.base.files import write_atomically
from robotplan.scene import parse_scene
from robotplan.training.push_data import PushDataSpec, draw_shape

__all__ = ["OOD_FAMILIES", "candidate_timings", "draw_ood_shape", "draw_scene", "run_bench_push",
           "summarize", "time_profile"]

GOAL_DISTANCE = 0.35  # m from the object to the goal centre
GOAL_NOISE = 0.02  # m, standard deviation per axis
CENTER_NOISE = 0.03  # m


OOD_FAMILIES = ("triangle", "pentagon", "hexagon", "circle", "T", "cross", "U", "trapezoid")
"""Footprints never seen in training (``--shapes ood``, paper Figs. 2 and 7); T, cross and
U are concave. Scene ``i`` draws family ``i mod 8``, so 16 scenes hold each twice."""


def draw_ood_shape(rng: np.random.Generator, family: str):
    """A random footprint of ``family`` with bounding sides of 0.10–0.26 m (the push
    data's range), centred near its frame's origin."""
    from robotplan.sdf import Circle, Polygon

    u = rng.uniform
    if family == "circle":
        return Circle(round(float(u(0.05, 0.10)), 4))
    if family in ("pentagon", "hexagon"):
        n, r = (5 if family == "pentagon" else 6), u(0.07, 0.12)
        a = np.arange(n) * 2 * math.pi / n + math.pi / 2
        pts = r * np.stack((np.cos(a), np.sin(a)), 1)
    elif family == "triangle":
        b, h = u(0.14, 0.24), u(0.12, 0.22)
        pts = np.array([[-b / 2, -h / 3], [b / 2, -h / 3], [0.0, 2 * h / 3]])
    elif family == "trapezoid":
        b, h = u(0.16, 0.26), u(0.10, 0.18)
        top = b * u(0.4, 0.8)
        pts = np.array([[-b / 2, -h / 2], [b / 2, -h / 2], [top / 2, h / 2], [-top / 2, h / 2]])
    elif family == "T":
        w, h, t = u(0.16, 0.26), u(0.14, 0.24), u(0.05, 0.08)
        pts = np.array([[-t / 2, -h / 2], [t / 2, -h / 2], [t / 2, h / 2 - t], [w / 2, h / 2 - t],
                        [w / 2, h / 2], [-w / 2, h / 2], [-w / 2, h / 2 - t],
                        [-t / 2, h / 2 - t]])
    elif family == "cross":
        a, t = u(0.16, 0.26) / 2, u(0.05, 0.08) / 2
        pts = np.array([[t, -a], [t, -t], [a, -t], [a, t], [t, t], [t, a], [-t, a], [-t, t],
                        [-a, t], [-a, -t], [-t, -t], [-t, -a]])
    elif family == "U":
        w, h, t = u(0.16, 0.26), u(0.12, 0.20), u(0.04, 0.07)
        pts = np.array([[-w / 2, -h / 2], [w / 2, -h / 2], [w / 2, h / 2], [w / 2 - t, h / 2],
                        [w / 2 - t, -h / 2 + t], [-w / 2 + t, -h / 2 + t], [-w / 2 + t, h / 2],
                        [-w / 2, h / 2]])
    else:
        raise ValueError(f"unknown footprint family {family!r}")
    return Polygon(tuple((round(float(x), 4), round(float(y), 4)) for x, y in pts))


def _shape_doc(shape) -> dict:
    if shape.type == "circle":
        return {"type": "circle", "radius": float(shape.radius)}
    if shape.type == "polygon":
        return {"type": "polygon", "vertices": [list(v) for v in shape.vertices]}
    if shape.type == "box":
        return {"type": "box", "size": [round(float(v), 4) for v in shape.size]}
    return {"type": "lshape", "size": [round(float(v), 4) for v in shape.size],
            "thickness": round(float(shape.thickness), 4)}


def draw_scene(index: int, seed: int, kind: str) -> dict:
    """The scene document (the YAML schema) of benchmark scene ``index`` for ``seed``."""
    rng = np.random.default_rng([seed, index, {"box": 0, "lshape": 1}.get(kind, 2)])
    if kind == "ood":
        shape = draw_ood_shape(rng, family_of(index, kind))
    else:
        shape = draw_shape(rng, PushDataSpec(), kind)
    r_obj = shape.bound_radius
    center = rng.normal(0.0, CENTER_NOISE, 2)
    yaw = rng.uniform(-math.pi, math.pi)
    radius = rng.uniform(0.02, 0.05)
    ang = rng.uniform(0, 2 * math.pi)
    dist = r_obj + radius + rng.uniform(0.05, 0.15)
    pusher = center + dist * np.array([math.cos(ang), math.sin(ang)])
    g_ang = math.radians(45 * int(rng.integers(8)))
    goal = (center + GOAL_DISTANCE * np.array([math.cos(g_ang), math.sin(g_ang)])
            + rng.normal(0.0, GOAL_NOISE, 2))
    side = max(0.4, 2 * r_obj + 0.04)
    r = lambda v: round(float(v), 4)  # noqa: E731
    return {
        "version": 1, "name": f"bench_{kind}_{index:03d}",
        "workspace": {"center": [0.0, 0.0], "size": [1.4, 1.4], "resolution": 0.01},
        "objects": [{"name": "object", "shape": _shape_doc(shape),
                     "pose": [r(center[0]), r(center[1]), r(yaw)]}],
        "pushers": [{"name": "pusher", "radius": r(radius),
                     "position": [r(pusher[0]), r(pusher[1])]}],
        "goal": {"type": "region", "object": "object",
                 "region": {"shape": {"type": "box", "size": [r(side), r(side)]},
                            "pose": [r(goal[0]), r(goal[1]), 0.0]}},
    }


def family_of(index: int, kind: str) -> str:
    return OOD_FAMILIES[index % len(OOD_FAMILIES)] if kind == "ood" else kind


def _quartiles(values: list[float]) -> dict:
    if not values:
        return {"n": 0}
    q = np.percentile(values, [25, 50, 75])
    return {"n": len(values), "q1": round(float(q[0]), 4), "median": round(float(q[1]), 4),
            "q3": round(float(q[2]), 4), "min": round(float(min(values)), 4)}


def candidate_timings(candidates: list[dict]) -> dict[str, float]:
    """Seconds per timer summed over a search's ``candidates`` (``result.json``): each
    functional's callbacks, ``solver`` (SNOPT itself), ``warm_start``…, plus ``programs``
    (their count) and ``total`` (the candidates' own seconds; with parallel workers more
    than the wall-clock plan time)."""
    out: dict[str, float] = {"programs": float(len(candidates)), "total": 0.0}
    for cand in candidates:
        out["total"] += float(cand.get("seconds") or 0.0)
        for name, seconds in (cand.get("timings") or {}).items():
            out[name] = out.get(name, 0.0) + float(seconds)
    return {k: round(v, 3) for k, v in out.items()}


def time_profile(rows: list[dict]) -> dict:
    """Where the planning time goes over a benchmark: each timer's seconds summed over all
    scenes' candidates and its share of the candidates' total, largest first. Rows without
    ``timings`` (e.g. in a ``rows.jsonl`` written without them) are left out and counted."""
    timed = [r["timings"] for r in rows if r.get("timings")]
    total = sum(t["total"] for t in timed)
    names = {k for t in timed for k in t} - {"programs", "total"}
    sums = sorted(((sum(t.get(k, 0.0) for t in timed), k) for k in names), reverse=True)
    seconds = {k: round(v, 1) for v, k in sums}  # largest first
    return {"scenes": len(timed), "untimed_scenes": len(rows) - len(timed),
            "programs": int(sum(t["programs"] for t in timed)),
            "candidate_seconds": round(total, 1), "seconds": seconds,
            "share": {k: round(v / total, 3) if total else 0.0 for k, v in seconds.items()}}


def summarize(rows: list[dict]) -> dict:
    out: dict = {"scenes": len(rows), "coverage": {}, "plan_seconds": {}}
    for kind in sorted({r["shape"] for r in rows}):
        sel = [r for r in rows if r["shape"] == kind]
        out["coverage"][kind] = _quartiles([r["coverage"] for r in sel])
        out["plan_seconds"][kind] = _quartiles([r["plan_seconds"] for r in sel])
    out["plan_seconds"]["all"] = _quartiles([r["plan_seconds"] for r in rows])
    ood = [r for r in rows if r["shape"] == "ood"]
    if ood:
        out["coverage_by_family"] = {
            fam: _quartiles([r["coverage"] for r in ood if r.get("family") == fam])
            for fam in sorted({r.get("family") for r in ood})}
    out["time_profile"] = time_profile(rows)
    return out


def _box_plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kinds = sorted({r["shape"] for r in rows})
    data = [[r["coverage"] for r in rows if r["shape"] == k] for k in kinds]
    fig, ax = plt.subplots(figsize=(4.5, 3.6), dpi=120)
    ax.boxplot(data, showfliers=True)
    ax.set_xticks(range(1, len(kinds) + 1), [f"{k}\n(n={len(d)})" for k, d in zip(kinds, data,
                                                                               strict=True)])
    ax.set_ylabel("coverage of the object inside the goal")
    ax.set_ylim(-0.02, 1.02)
    ax.set_title("open-loop execution in pybullet (F_flow)")
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()

    def write(tmp: Path) -> None:
        fig.savefig(tmp, format="png")

    write_atomically(path, write)
    plt.close(fig)


def run_bench_push(scenes: int, seed: int, out: Path, model_dir: Path, workers: int = 2,
                   shapes: tuple[str, ...] = ("box", "lshape"), exhaustive: bool = False,
                   time_budget: float | None = None) -> dict:
    """Solve and execute ``scenes`` scenes per shape type; returns the summary."""
    from robotplan.api import solve

    (out / "scenes").mkdir(parents=True, exist_ok=True)
    rows_path = out / "rows.jsonl"
    done = {}
    if rows_path.exists():
        for line in rows_path.read_text().splitlines():
            if line.strip():
                row = json.loads(line)
                done[row["scene"]] = row
    todo = [(i, kind) for i in range(scenes) for kind in shapes]
    for n, (i, kind) in enumerate(todo):
        doc = draw_scene(i, seed, kind)
        name = doc["name"]
        if name in done:
            continue
        scene_path = out / "scenes" / f"{name}.yaml"
        scene_path.write_text(yaml.safe_dump(doc, sort_keys=False, default_flow_style=None))
        scene = parse_scene(doc, scene_path)
        t0 = time.time()
        print(f"[{n + 1}/{len(todo)}] {name}: {scene.objects[0].shape.describe()}", flush=True)
        result = solve(scene, out / "solutions" / name, model_dir, workers=workers,
                       progress=False, exhaustive=exhaustive, quiet=True,
                       time_budget=time_budget)
        ex = result.get("execution") or {}
        row = {"scene": name, "shape": kind, "family": family_of(i, kind),
               "status": result["status"],
               "coverage": float(ex.get("coverage") or 0.0),
               "plan_seconds": result["plan_seconds"], "total_seconds": round(time.time() - t0, 1),
               "programs": result["programs_solved"],
               "skeleton": " ".join(f"{p['mode']}@{p['init']}" for p in result["skeleton"]),
               "violation": result["violation"],
               "dynamics_rms_mm": result.get("dynamics_rms_mm"),
               "timings": candidate_timings(result.get("candidates") or [])}
        done[name] = row
        with rows_path.open("a") as f:
            f.write(json.dumps(row) + "\n")
        print(f"    coverage {row['coverage']:.3f}, plan {row['plan_seconds']:.1f} s, "
              f"{row['programs']} programs, {row['skeleton']}", flush=True)
    rows = [done[draw_scene(i, seed, kind)["name"]] for i, kind in todo]
    summary = summarize(rows)
    summary.update({"seed": seed, "model": str(model_dir), "exhaustive": exhaustive,
                    "time_budget_s": time_budget})
    buf = io.StringIO()
    flat = [{k: v for k, v in r.items() if k != "timings"} for r in rows]
    fields = list(dict.fromkeys(k for r in flat for k in r))
    writer = csv.DictWriter(buf, fieldnames=fields)
    writer.writeheader()
    writer.writerows(flat)
    write_atomically(out / "results.csv", lambda tmp: tmp.write_text(buf.getvalue()))
    _box_plot(rows, out / "coverage.png")
    write_atomically(out / "summary.json",
                     lambda tmp: tmp.write_text(json.dumps(summary, indent=1)))
    return summary
