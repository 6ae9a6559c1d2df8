"""The table of a push program's rows (``skeletons/rows.yaml``): which functional couples
which bodies in which steps, as which kind of row, at which scale, in which stage. One
builder (:class:`~robotplan.program.push_program.PushProgram`) reads it."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Literal

import yaml

from robotplan.base.resources import skeletons_dir
from robotplan.scene.reader import read

__all__ = ["RowSpec", "load_rows", "rows_for_stage"]


@dataclass(frozen=True)
class RowSpec:
    """One row of the table (the fields are explained in ``skeletons/rows.yaml``)."""

    row: str
    bodies: list[str]
    steps: Literal["all", "push", "reach", "free", "push_pairs", "final"]
    type: Literal["eq", "ineq", "cost"]
    scale: float
    bounds: str
    stage: Literal["kinematic", "learned", "both"]
    enabled: str | None = None


@dataclass(frozen=True)
class RowTable:
    rows: list[RowSpec]


@cache
def load_rows(path: Path | None = None) -> tuple[RowSpec, ...]:
    """The rows of the table in ``path`` (default ``skeletons/rows.yaml``), in order."""
    path = path or skeletons_dir() / "rows.yaml"
    table = read(RowTable, yaml.safe_load(path.read_text()))
    return tuple(table.rows)


def rows_for_stage(learned: bool, path: Path | None = None) -> list[RowSpec]:
    """The rows of the learned stage (with H_F) or of the kinematic one, in table order."""
    stage = "learned" if learned else "kinematic"
    return [r for r in load_rows(path) if r.stage in (stage, "both")]
