"""Pictures of scenes: the SDFs of all bodies on X_h as a PNG (matplotlib, no display)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from robotplan.base.files import write_atomically
from robotplan.scene import Scene

__all__ = ["render_scene_sdf"]


def render_scene_sdf(scene: Scene, path: Path) -> None:
    """Plot min_i φ_i(X_h) over the scene's table bodies with the zero level sets, the robot
    tips (dotted) and the goal region (dashed), and write it to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    grid = scene.workspace.points(torch.float64)
    bodies = list(scene.bodies.values())
    with torch.no_grad():
        fields = torch.stack([b.sdf(grid.reshape(-1, 2)) for b in bodies]).reshape(
            len(bodies), *grid.shape[:2])
    phi = fields.amin(dim=0).numpy()
    x0, x1, y0, y1 = scene.workspace.bounds
    norm = matplotlib.colors.TwoSlopeNorm(0.0, vmin=min(float(phi.min()), -1e-3),
                                          vmax=max(float(phi.max()), 1e-3))

    fig, ax = plt.subplots(figsize=(6.4, 6.0), dpi=110)
    im = ax.imshow(phi, origin="lower", extent=(x0, x1, y0, y1), cmap="RdBu", norm=norm)
    xs, ys = grid[0, :, 0].numpy(), grid[:, 0, 1].numpy()
    ax.contour(xs, ys, phi, levels=np.arange(0.05, float(phi.max()), 0.05), colors="k",
               linewidths=0.3, alpha=0.4)
    colors = {"object": "tab:orange", "obstacle": "0.3", "pusher": "gold", "robot": "tab:purple"}
    for b in bodies:
        o = np.vstack([b.outline_world(), b.outline_world()[:1]])
        ax.plot(o[:, 0], o[:, 1], color=colors[b.role], lw=1.8,
                ls=":" if b.role == "robot" else "-")
        ax.annotate(b.name, b.pose[:2], ha="center", va="center", fontsize=8)
    if scene.goal_region is not None:
        g = scene.goal_region.outline_world()
        g = np.vstack([g, g[:1]])
        ax.plot(g[:, 0], g[:, 1], "g--", lw=1.5, label=f"goal for {scene.goal.object}")
        ax.legend(loc="upper right", fontsize=8)
    ax.set(title=f"{scene.name}: min φ over bodies on X_h {scene.workspace.shape}",
           xlabel="x [m]", ylabel="y [m]", xlim=(x0, x1), ylim=(y0, y1))
    fig.colorbar(im, ax=ax, label="signed distance φ [m]", shrink=0.85)
    fig.tight_layout()
    write_atomically(path, lambda tmp: fig.savefig(tmp, format="png"))
    plt.close(fig)
