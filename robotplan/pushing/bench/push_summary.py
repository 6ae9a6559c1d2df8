"""The summary of ``robotplan bench push``: quartiles per shape type, where the planning time
goes, each simulator's outcomes and how far they part, and the box plot of coverage."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robotplan.base.files import write_atomically

__all__ = ["MODEL_NAMES", "box_plot", "candidate_timings", "compare_simulators",
           "of_simulator", "quartiles", "summarize", "time_profile", "time_profile_line"]


def quartiles(values: list[float]) -> dict:
    """``n``, the quartiles ``q1``, ``median``, ``q3`` and the extremes ``min``, ``max``."""
    if not values:
        return {"n": 0}
    q = np.percentile(values, [25, 50, 75])
    return {"n": len(values), "q1": round(float(q[0]), 4), "median": round(float(q[1]), 4),
            "q3": round(float(q[2]), 4), "min": round(float(min(values)), 4),
            "max": round(float(max(values)), 4)}


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


def time_profile_line(profile: dict, top: int = 6) -> str | None:
    """One line of a :func:`time_profile`: its programs, their seconds and the ``top``
    timers' shares; None where no program was timed."""
    if not profile["candidate_seconds"]:
        return None
    shares = ", ".join(f"{k} {100 * v:.0f} %" for k, v in list(profile["share"].items())[:top])
    return (f"time: {profile['programs']} programs, {profile['candidate_seconds']:.0f} s in "
            f"their callbacks and solver" + (f": {shares}" if shares else ""))


def summarize(rows: list[dict]) -> dict:
    """Quartiles per shape type: coverage closed loop (``coverage``) and open loop, plan
    time (the rehearsal's included), the rehearsal's seconds, wall time of plan + execution
    each way (a closed loop needs no rehearsal: its seconds are left out), re-plans per
    scene, how many of them the loop went on with, and their seconds."""
    out: dict = {"scenes": len(rows), "coverage": {}, "open_loop_coverage": {},
                 "plan_seconds": {}, "rehearsal_seconds": {}, "closed_loop_seconds": {},
                 "open_loop_seconds": {},
                 "replans": {}, "replans_adopted": {}, "replan_seconds": {}, "below_0_9": {}}
    for kind in sorted({r["shape"] for r in rows}):
        sel = [r for r in rows if r["shape"] == kind]
        out["coverage"][kind] = quartiles([r["coverage"] for r in sel])
        out["open_loop_coverage"][kind] = quartiles([r.get("open_loop_coverage", 0.0)
                                                      for r in sel])
        out["below_0_9"][kind] = {
            "closed_loop": sum(r["coverage"] < 0.9 for r in sel),
            "open_loop": sum(r.get("open_loop_coverage", 0.0) < 0.9 for r in sel)}
        out["plan_seconds"][kind] = quartiles([r["plan_seconds"] for r in sel])
        out["rehearsal_seconds"][kind] = quartiles([r.get("rehearsal_seconds", 0.0)
                                                     for r in sel])
        out["closed_loop_seconds"][kind] = quartiles(
            [r["plan_seconds"] - r.get("rehearsal_seconds", 0.0) + r.get("execute_seconds", 0.0)
             for r in sel])
        out["open_loop_seconds"][kind] = quartiles(
            [r["plan_seconds"] + r.get("open_loop_seconds", 0.0) for r in sel])
        out["replans"][kind] = quartiles([len(r.get("replans", [])) for r in sel])
        every = [x for r in sel for x in r.get("replans", [])]
        out["replans_adopted"][kind] = {
            "adopted": sum(bool(x.get("adopted", x.get("solved"))) for x in every),
            "of": len(every)}
        out["replan_seconds"][kind] = quartiles([x["seconds"] for x in every])
    out["plan_seconds"]["all"] = quartiles([r["plan_seconds"] for r in rows])
    mixed = [r for r in rows if r["shape"] in ("ood", "pose")]
    if mixed:
        out["coverage_by_family"] = {
            fam: quartiles([r["coverage"] for r in mixed if r.get("family") == fam])
            for fam in sorted({r.get("family") for r in mixed})}
    poses = [r for r in rows if r["shape"] == "pose"]
    if poses:  # Push-T's success: coverage of the target footprint ≥ 0.95
        out["pose_success"] = {
            "closed_loop": round(sum(r["coverage"] >= 0.95 for r in poses) / len(poses), 3),
            "open_loop": round(sum(r.get("open_loop_coverage", 0) >= 0.95 for r in poses)
                               / len(poses), 3)}
    out["time_profile"] = time_profile(rows)
    return out


MODEL_NAMES = {"push_flow": "F_flow", "push_rigid": "F_q", "push_direct": "F"}


def of_simulator(rows: list[dict], sim: str) -> list[dict]:
    """``rows`` with simulator ``sim``'s outcome at the top (rows of one simulator alone
    are as they are)."""
    return [{**r, **r["sims"][sim]} if "sims" in r else r for r in rows]


def compare_simulators(rows: list[dict], sims) -> dict:
    """Per simulator the quartiles of :func:`summarize` that an execution changes (coverage
    closed and open loop, re-plans; per shape type) and, for two or more, how far each
    scene's coverage in the others is from the first's: the largest gaps and their quartiles
    over the scenes, closed and open loop."""
    out: dict = {"names": list(sims), "by_simulator": {}}
    for sim in sims:
        part = summarize(of_simulator(rows, sim))
        out["by_simulator"][sim] = {k: part[k] for k in (
            "coverage", "open_loop_coverage", "below_0_9", "replans", "replans_adopted")}
    if len(sims) < 2:
        return out
    first = sims[0]
    out["disagreement"] = {}
    for sim in sims[1:]:
        gaps = {key: {r["scene"]: round(r["sims"][sim][key] - r["sims"][first][key], 4)
                      for r in rows} for key in ("coverage", "open_loop_coverage")}
        out["disagreement"][f"{sim}-{first}"] = {
            key: {"quartiles": quartiles(list(g.values())),
                  "abs_mean": round(float(np.mean(np.abs(list(g.values())))), 4),
                  "per_scene": g} for key, g in gaps.items()}
    return out


def box_plot(rows: list[dict], path: Path, model: str, sim: str = "pybullet") -> None:
    """Coverage per shape type, open and closed loop side by side, in simulator ``sim``;
    ``model`` names the learned dynamics in the title (``auto``: the models the rows
    used)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kinds = sorted({r["shape"] for r in rows})
    fig, ax = plt.subplots(figsize=(5.5, 3.9), dpi=120)
    jitter = np.random.default_rng(0)  # the dots' spread only: the same picture every run
    for offset, key, color, dots, label in (
            (-0.18, "open_loop_coverage", "#bbbbbb", "#555555", "open loop"),
            (0.18, "coverage", "#8fc0e6", "#1d5f93", "closed loop")):
        data = [[r.get(key, 0.0) for r in rows if r["shape"] == k] for k in kinds]
        positions = np.arange(1, len(kinds) + 1) + offset
        box = ax.boxplot(data, positions=positions, widths=0.3, showfliers=False,
                         patch_artist=True)
        for patch in box["boxes"]:
            patch.set_facecolor(color)
        # every scene as a dot: a box of all-equal values is a line, the dots still show n
        for x, values in zip(positions, data, strict=True):
            ax.scatter(x + jitter.uniform(-0.09, 0.09, len(values)), values, s=9,
                       color=dots, alpha=0.8, linewidths=0, zorder=3)
        ax.plot([], [], color=color, linewidth=8, label=label)

    def label(kind: str) -> str:
        sel = [r for r in rows if r["shape"] == kind]
        below = [sum(r.get(key, 0.0) < 0.9 for r in sel)
                 for key in ("open_loop_coverage", "coverage")]
        return f"{kind} (n={len(sel)})\nbelow 0.9: {below[0]} open, {below[1]} closed"

    ax.set_xticks(range(1, len(kinds) + 1), [label(k) for k in kinds], fontsize=8)
    ax.set_ylabel("coverage of the object inside the goal")
    ax.set_ylim(-0.02, 1.02)
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.08), ncol=2, fontsize=8,
              frameon=False)
    if model == "auto":
        used = sorted({r["model"] for r in rows if r.get("model")})
        model = ", ".join(MODEL_NAMES.get(m, m) for m in used) or "auto"
    else:
        model = MODEL_NAMES.get(Path(model).name, Path(model).name)
    ax.set_title(f"execution in {sim}: open vs closed loop ({model})")
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()

    def write(tmp: Path) -> None:
        fig.savefig(tmp, format="png")

    write_atomically(path, write)
    plt.close(fig)
