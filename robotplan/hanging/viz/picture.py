"""A still picture of a hang (PNG, matplotlib): the hook, and the mug at the pose the
optimiser found and where the simulated drop left it, seen from two sides."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from robotplan.geometry.transforms import quaternion_to_matrix
from robotplan.hanging.viz.viewer import hang_meshes
from robotplan.sdf.mug_hook import Hook, Mug

__all__ = ["write_hang_picture"]

VIEWS = ((20.0, -60.0), (20.0, 30.0))  # (elevation, azimuth) in degrees
MUG_COLOURS = {"found": (0.2, 0.45, 0.85, 0.35), "after the drop": (0.2, 0.45, 0.85, 1.0)}


def _triangles(parts: list, X: np.ndarray) -> np.ndarray:
    """``(F, 3, 3)`` world triangles of mesh ``parts`` posed at ``X (7,)``."""
    R = quaternion_to_matrix(torch.as_tensor(X[3:], dtype=torch.float64)).numpy()
    t = np.asarray(X[:3], dtype=float)
    return np.concatenate([(np.asarray(p.vertices) @ R.T + t)[np.asarray(p.faces)]
                           for p in parts])


def write_hang_picture(mug: Mug, hook: Hook, X_HM_found: np.ndarray | None,
                       X_HM_end: np.ndarray, path: Path, title: str = "") -> None:
    """Two views of the hook (its own frame H) with the mug ghosted at ``X_HM_found`` (if
    given) and solid at ``X_HM_end`` (poses ``(7,)``); written whole or not at all."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from robotplan.base.files import write_atomically

    mug_parts, hook_parts = hang_meshes(mug, hook)
    identity = np.array([0.0, 0, 0, 1, 0, 0, 0])
    bodies = [(_triangles(hook_parts, identity), (0.4, 0.4, 0.4, 1.0))]
    bodies += [(_triangles(mug_parts, X), MUG_COLOURS[name])
               for name, X in (("found", X_HM_found), ("after the drop", X_HM_end))
               if X is not None]
    # framed on the mugs and the top of the hook: the post runs out of the picture downwards
    mugs = np.concatenate([b[0].reshape(-1, 3) for b in bodies[1:]])
    top = bodies[0][0].reshape(-1, 3)
    top = top[top[:, 2] > hook.post_height - 0.05]
    every = np.concatenate([mugs, top])
    centre = (every.min(0) + every.max(0)) / 2
    half = float((every.max(0) - every.min(0)).max()) / 2 + 0.01
    fig = plt.figure(figsize=(8, 4.2))
    for k, (elev, azim) in enumerate(VIEWS):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        for tris, colour in bodies:
            ax.add_collection3d(Poly3DCollection(tris, facecolors=colour, edgecolors=colour,
                                                 linewidths=0.0, shade=True))
        for axis, c in zip("xyz", centre, strict=True):
            getattr(ax, f"set_{axis}lim")(c - half, c + half)
        ax.set_box_aspect((1, 1, 1), zoom=1.25)
        ax.view_init(elev=elev, azim=azim)
        ax.set_axis_off()
    fig.suptitle(title or "mug: found pose (light) and after the drop in pybullet (solid)",
                 fontsize=10)
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.0, top=0.94, wspace=0.0)
    write_atomically(Path(path), lambda tmp: fig.savefig(tmp, format="png", dpi=110))
    plt.close(fig)
