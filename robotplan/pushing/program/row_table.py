"""The table of a push program's rows (``skeletons/rows.yaml``): which functional couples
which bodies in which steps, as which kind of row, at which scale, held to which bounds, in
which stage, with which constants. One builder (:mod:`robotplan.pushing.program.builder`) reads
every field."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cache
from pathlib import Path
from typing import Literal

import yaml

from robotplan.base.resources import skeletons_dir
from robotplan.scene.reader import SchemaError, read, show

__all__ = ["BODIES", "STAGES", "STEPS", "Bound", "RowSpec", "load_rows", "row_parameters",
           "row_spec", "rows_for_stage"]

Param = float | bool | None
Bound = float | str  # a number, or a name (a constant or a quantity), optionally "-name"

# the decision variables a row may couple (one arm's joints: ``joints``) and the fixed
# bodies it may read
BODIES = ("object", "actor", "contact", "touch", "chained", "chain_contact", "joints", "arms",
          "goal", "obstacles", "region")
STEPS = ("start", "every", "all", "push", "reach", "free", "push_pairs", "final",
         "chain_push", "chain_pairs", "unchained", "acting", "arm_push", "arm_reach", "idle",
         "tip_steps")
STAGES = ("kinematic", "learned", "both", "chain", "chain_kinematic", "chain_learned", "arms")


@dataclass(frozen=True)
class RowSpec:
    """One row of the table (the fields are explained in ``skeletons/rows.yaml``);
    ``bounds`` maps a key (None: the row's one pair) to ``(lower, upper)``."""

    row: str
    bodies: list[str]
    steps: str
    type: Literal["eq", "ineq", "cost"]
    scale: float
    stage: str
    enabled: str | None = None
    goals: list[Literal["region", "pose", "touch"]] | None = None
    params: dict[str, Param] = field(default_factory=dict)
    bounds: dict[str | None, tuple[Bound, Bound]] = field(default_factory=dict)

    @property
    def per_arm(self) -> bool:
        """Whether the row is over one arm's joints (added arm by arm)."""
        return "joints" in self.bodies


@dataclass(frozen=True)
class RowTable:
    rows: list[RowSpec]


def _check_params(where: str, params: object) -> dict[str, Param]:
    """A row's ``params``: names to numbers, booleans or null."""
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


def _check_pair(where: str, pair: object) -> tuple[Bound, Bound]:
    """``[lower, upper]``: numbers, ``inf``/``-inf`` or (negated) names."""
    if not isinstance(pair, list) or len(pair) != 2:
        raise SchemaError(where, f"must be [lower, upper], got {show(pair)}")
    for end in pair:
        if isinstance(end, bool) or not isinstance(end, int | float | str):
            raise SchemaError(where, f"{show(end)} is not a number or a name")
        if isinstance(end, str) and not all(p.isidentifier()
                                            for p in end.removeprefix("-").split(".")):
            raise SchemaError(where, f"{show(end)} is not a name or -name")
    return pair[0], pair[1]


def _check_bounds(where: str, spec: RowSpec, bounds: object
                  ) -> dict[str | None, tuple[Bound, Bound]]:
    """A row's ``bounds``: none for costs, ``[lower, upper]`` or ``{KEY: [lower, upper]}``
    for constraints (an eq row without them is held at 0; its ends are equal)."""
    if spec.type == "cost":
        if bounds is not None:
            raise SchemaError(where, "a cost has no bounds")
        return {}
    if bounds is None:
        if spec.type == "ineq":
            raise SchemaError(where, "an ineq row needs [lower, upper]")
        return {None: (0.0, 0.0)}
    pairs = ({key: _check_pair(f"{where}.{key}", pair) for key, pair in bounds.items()}
             if isinstance(bounds, dict) else {None: _check_pair(where, bounds)})
    for key, (lower, upper) in pairs.items():
        if spec.type == "eq" and lower != upper:
            raise SchemaError(where if key is None else f"{where}.{key}",
                              f"an eq row's ends are equal, got [{lower}, {upper}]")
    return pairs


def _check_spec(i: int, spec: RowSpec) -> None:
    where = f"rows[{i}]"
    for body in spec.bodies:
        if body not in BODIES:
            raise SchemaError(f"{where}.bodies", f"{show(body)} is none of {', '.join(BODIES)}")
    for name, known in (("steps", STEPS), ("stage", STAGES)):
        if getattr(spec, name) not in known:
            raise SchemaError(f"{where}.{name}", f"{show(getattr(spec, name))} is none of "
                              f"{', '.join(known)}")


@cache
def load_rows(path: Path | None = None) -> tuple[RowSpec, ...]:
    """The rows of the table in ``path`` (default ``skeletons/rows.yaml``), in order."""
    path = path or skeletons_dir() / "rows.yaml"
    data = yaml.safe_load(path.read_text())
    rows = (data or {}).get("rows") if isinstance(data, dict) else None
    extra = [(r.pop("params", {}), r.pop("bounds", None)) if isinstance(r, dict) else ({}, None)
             for r in rows or []]
    table = read(RowTable, data)
    out = []
    for i, (spec, (params, bounds)) in enumerate(zip(table.rows, extra, strict=True)):
        _check_spec(i, spec)
        out.append(replace(spec, params=_check_params(f"rows[{i}].params", params),
                           bounds=_check_bounds(f"rows[{i}].bounds", spec, bounds)))
    seen: dict[str, dict] = {}
    for i, spec in enumerate(out):
        if spec.row in seen and spec.params != seen[spec.row]:
            raise SchemaError(f"rows[{i}].params", f"row {spec.row!r} has other parameters "
                              "where it appears before")
        seen[spec.row] = spec.params
    return tuple(out)


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


def rows_for_stage(stages: tuple[str, ...], goal: str | None = None,
                   path: Path | None = None) -> list[RowSpec]:
    """The rows of the ``stages`` in table order; with ``goal``, those for that goal kind."""
    return [r for r in load_rows(path) if r.stage in stages
            and (goal is None or r.goals is None or goal in r.goals)]
