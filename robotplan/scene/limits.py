"""Size limits of a scene, so that checking any file takes seconds and solving it fits memory.

The checks cost: the YAML parser about a second per MB; a polygon's simplicity test and its
overlap tests grow with the square of its vertex count; the start-overlap test with the
square of the number of bodies. The workspace grid X_h is allocated per body and time step
when solving. The limits sit far above any real scene (the examples hold at most six
bodies, no polygon over a dozen vertices and a 140 × 140 grid).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from robotplan.scene.reader import SchemaError

if TYPE_CHECKING:
    from robotplan.sdf import Workspace

__all__ = [
    "MAX_BODIES",
    "MAX_FILE_BYTES",
    "MAX_GRID_CELLS",
    "MAX_POLYGON_VERTICES",
    "MAX_TOTAL_VERTICES",
    "check_counts",
    "check_grid",
]

MAX_FILE_BYTES = 1_000_000
MAX_BODIES = 100  # objects, obstacles, pushers and robots together
MAX_POLYGON_VERTICES = 128
MAX_TOTAL_VERTICES = 1024  # over every polygon of the scene, the goal region's included
MAX_GRID_SIDE = 4000
MAX_GRID_CELLS = MAX_GRID_SIDE * MAX_GRID_SIDE
_DEFAULT_RESOLUTION = 0.01  # m, Workspace's default

_BODY_GROUPS = ("objects", "obstacles", "pushers", "robots")


def _polygon_vertices(data: dict) -> list[tuple[str, int]]:
    """``(field, vertex count)`` of every polygon shape in raw scene data, where the data
    has the expected structure so far (the schema reader reports anything else)."""
    shapes: list[tuple[str, Any]] = []
    for group in ("objects", "obstacles"):
        items = data.get(group)
        if isinstance(items, list):
            shapes += [(f"{group}[{i}].shape", item.get("shape"))
                       for i, item in enumerate(items) if isinstance(item, dict)]
    goal = data.get("goal")
    region = goal.get("region") if isinstance(goal, dict) else None
    if isinstance(region, dict):
        shapes.append(("goal.region.shape", region.get("shape")))
    return [(f"{where}.vertices", len(shape["vertices"])) for where, shape in shapes
            if isinstance(shape, dict) and shape.get("type") == "polygon"
            and isinstance(shape.get("vertices"), list)]


def check_counts(data: dict) -> None:
    """Refuse too many bodies or polygon vertices in raw scene data, before the schema
    reader runs the checks whose cost grows with them. Raises SchemaError."""
    total = 0
    for group in _BODY_GROUPS:
        items = data.get(group)
        if isinstance(items, list):
            total += len(items)
            if total > MAX_BODIES:
                raise SchemaError(group, f"too many bodies: {total} or more objects, "
                                  f"obstacles, pushers and robots; at most {MAX_BODIES}")
    total = 0
    for where, count in _polygon_vertices(data):
        if count > MAX_POLYGON_VERTICES:
            raise SchemaError(where, f"a polygon of {count} vertices; at most "
                              f"{MAX_POLYGON_VERTICES} per polygon")
        total += count
        if total > MAX_TOTAL_VERTICES:
            raise SchemaError(where, f"too many polygon vertices: {total} or more in the "
                              f"scene; at most {MAX_TOTAL_VERTICES} in all")


def check_grid(workspace: Workspace) -> None:
    """Refuse a workspace whose grid X_h would have more than MAX_GRID_CELLS cells, naming
    the size when even the default resolution gives too many, else the resolution."""
    (w, h), r = workspace.size, workspace.resolution
    cols, rows = w / r, h / r  # floats: a huge count must not overflow on its way here
    cells = cols * rows
    if cells <= MAX_GRID_CELLS:
        return
    too_big = (w / _DEFAULT_RESOLUTION) * (h / _DEFAULT_RESOLUTION) > MAX_GRID_CELLS
    raise SchemaError(
        "workspace.size" if too_big else "workspace.resolution",
        f"a {w:g} × {h:g} m workspace at resolution {r:g} m is a grid of {cols:.4g} × "
        f"{rows:.4g} = {cells:.3g} cells; at most {MAX_GRID_CELLS:,} ({MAX_GRID_SIDE} × "
        f"{MAX_GRID_SIDE}): use a smaller workspace or a coarser resolution")
