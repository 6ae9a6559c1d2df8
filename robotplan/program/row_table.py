"""The table of a push program's rows (``skeletons/rows.yaml``): which functional couples
which bodies in which steps, as which kind of row, at which scale, in which stage, with
which constants. One builder (:class:`~robotplan.program.push_program.PushProgram`) reads
it; the arm and chain programs add their rows (stages ``arms``, ``chain…``) after these."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cache
from pathlib import Path
from typing import Literal

import yaml

from robotplan.base.resources import skeletons_dir
from robotplan.scene.reader import SchemaError, read, show

__all__ = ["RowSpec", "load_rows", "row_parameters", "row_spec", "rows_for_stage"]

Param = float | bool | None


@dataclass(frozen=True)
class RowSpec:
    """One row of the table (the fields are explained in ``skeletons/rows.yaml``)."""

    row: str
    bodies: list[str]
    steps: Literal["all", "push", "reach", "free", "push_pairs", "final"]
    type: Literal["eq", "ineq", "cost"]
    scale: float
    bounds: str
    stage: Literal["kinematic", "learned", "both", "arms", "chain", "chain_kinematic",
                   "chain_learned"]
    enabled: str | None = None
    goals: list[Literal["region", "pose", "touch"]] | None = None
    params: dict[str, Param] = field(default_factory=dict)


@dataclass(frozen=True)
class RowTable:
    rows: list[RowSpec]


def _check_params(row: int, params: object) -> dict[str, Param]:
    """A row's ``params``: names to numbers, booleans or null."""
    where = f"rows[{row}].params"
    if not isinstance(params, dict):
        raise SchemaError(where, f"must map names to values, got {show(params)}")
    for name, value in params.items():
        if not isinstance(name, str) or not name.isidentifier():
            raise SchemaError(where, f"{show(name)} is not a parameter name")
        if value is not None and not isinstance(value, bool | int | float):
            raise SchemaError(f"{where}.{name}", f"must be a number, true/false or null, got "
                              f"{show(value)}")
        if isinstance(value, float) and not math.isfinite(value):
            raise SchemaError(f"{where}.{name}", f"must be finite, got {value}")
    return params


@cache
def load_rows(path: Path | None = None) -> tuple[RowSpec, ...]:
    """The rows of the table in ``path`` (default ``skeletons/rows.yaml``), in order."""
    path = path or skeletons_dir() / "rows.yaml"
    data = yaml.safe_load(path.read_text())
    rows = (data or {}).get("rows") if isinstance(data, dict) else None
    params = [r.pop("params", {}) if isinstance(r, dict) else {} for r in rows or []]
    table = read(RowTable, data)
    out = tuple(replace(spec, params=_check_params(i, p))
                for i, (spec, p) in enumerate(zip(table.rows, params, strict=True)))
    seen: dict[str, dict] = {}
    for i, spec in enumerate(out):
        if spec.row in seen and spec.params != seen[spec.row]:
            raise SchemaError(f"rows[{i}].params", f"row {spec.row!r} has other parameters "
                              "where it appears before")
        seen[spec.row] = spec.params
    return out


def row_parameters(path: Path | None = None) -> dict[str, Param]:
    """Every row's constants as ``ROW.NAME`` → value, in table order."""
    return {f"{spec.row}.{name}": value for spec in load_rows(path)
            for name, value in spec.params.items()}


def row_spec(name: str) -> RowSpec:
    """The row ``name`` of ``skeletons/rows.yaml`` (its first entry)."""
    for spec in load_rows():
        if spec.row == name:
            return spec
    raise KeyError(f"skeletons/rows.yaml has no row {name!r}")


def rows_for_stage(learned: bool, goal: str | None = None,
                   path: Path | None = None) -> list[RowSpec]:
    """The rows of the learned stage (with H_F) or of the kinematic one, in table order;
    with ``goal``, those for that goal kind."""
    stage = "learned" if learned else "kinematic"
    return [r for r in load_rows(path) if r.stage in (stage, "both")
            and (goal is None or r.goals is None or goal in r.goals)]
