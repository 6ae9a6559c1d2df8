"""Typed reading of plain data (parsed YAML/JSON) into dataclasses: the dataclass is the schema.

``read(cls, data, where)`` checks every field against the dataclass's type hints: unknown or
missing fields, wrong types, NaN/inf, numbers beyond ``MAX_MAGNITUDE``, non-positive values
where ``field(metadata={"positive": True})`` asks for them, tuple lengths, ``Literal``
choices, and unions of dataclasses told apart by their ``type`` tag. A dataclass may add its
own cross-field check as ``check() -> (field, message) | None``. Any failure raises
:class:`SchemaError` naming the field by its path, e.g. ``objects[0].shape.size``.
"""

from __future__ import annotations

import dataclasses
import math
import reprlib
import types
from typing import Any, Literal, Union, get_args, get_origin, get_type_hints

__all__ = ["MAX_MAGNITUDE", "SchemaError", "read", "show"]

# Every number of an input file is a length in metres or an angle in radians: beyond this it
# is a typo, and squares and products of such numbers stay far from float overflow.
MAX_MAGNITUDE = 1e6

_repr = reprlib.Repr()
_repr.maxlevel, _repr.maxlist, _repr.maxtuple, _repr.maxdict = 3, 6, 6, 4
_repr.maxstring, _repr.maxother, _repr.maxlong = 60, 60, 40


class SchemaError(ValueError):
    """A field of an input file is wrong. ``field`` is its path, ``message`` says why."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(f"{field}: {message}" if field else message)
        self.field = field
        self.message = message


def show(value: Any) -> str:
    """A short repr of an input value for a message: nested or huge data (a whole list, a
    YAML alias repeated) shows as its first few entries."""
    return _repr.repr(value)


def _join(where: str, name: str) -> str:
    return f"{where}.{name}" if where else name


def _type_name(tp: Any) -> str:
    if tp is float:
        return "a number"
    if tp is int:
        return "an integer"
    if tp is str:
        return "a string"
    if dataclasses.is_dataclass(tp):
        return "a mapping"
    return str(tp)


def _tagged_union_members(tp: Any) -> list[type] | None:
    args = [a for a in get_args(tp) if a is not type(None)]
    if args and all(dataclasses.is_dataclass(a) for a in args):
        return args
    return None


def _tag_of(cls: type) -> str | None:
    hints = get_type_hints(cls)
    tp = hints.get("type")
    if tp is not None and get_origin(tp) is Literal:
        return get_args(tp)[0]
    return None


def read(cls: Any, data: Any, where: str = "") -> Any:
    """Build ``cls`` (a dataclass or a union of tagged dataclasses) from ``data``."""
    members = _tagged_union_members(cls) if get_origin(cls) in (Union, types.UnionType) else None
    if members:
        if not isinstance(data, dict):
            raise SchemaError(where, "must be a mapping")
        tags = {_tag_of(m): m for m in members}
        tag = data.get("type")
        if tag is None:
            raise SchemaError(_join(where, "type"), f"missing; one of {sorted(tags)}")
        if not isinstance(tag, str) or tag not in tags:
            raise SchemaError(_join(where, "type"),
                              f"unknown type {show(tag)}; one of {sorted(tags)}")
        cls = tags[tag]
    if not isinstance(data, dict):
        raise SchemaError(where, "must be a mapping")
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    for key in data:
        if key not in fields:
            shown = key if isinstance(key, str) and len(key) <= 60 else show(key)
            raise SchemaError(_join(where, shown),
                              f"unknown field; expected one of {sorted(fields)}")
    kwargs: dict[str, Any] = {}
    for name, f in fields.items():
        path = _join(where, name)
        if name in data:
            kwargs[name] = _convert(hints[name], data[name], path, dict(f.metadata))
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise SchemaError(path, "missing required field")
    obj = cls(**kwargs)
    check = getattr(obj, "check", None)
    if callable(check):
        problem = check()
        if problem:
            raise SchemaError(_join(where, problem[0]), problem[1])
    return obj


def _convert(tp: Any, value: Any, where: str, meta: dict[str, Any]) -> Any:
    origin = get_origin(tp)
    if origin in (Union, types.UnionType):
        args = get_args(tp)
        if value is None and type(None) in args:
            return None
        if _tagged_union_members(tp):
            return read(tp, value, where)
        (inner,) = [a for a in args if a is not type(None)]
        return _convert(inner, value, where, meta)
    if origin is Literal:
        if value not in get_args(tp):
            raise SchemaError(where, f"must be one of {list(get_args(tp))}, got {show(value)}")
        return value
    if origin is tuple:
        args = get_args(tp)
        if not isinstance(value, list):
            raise SchemaError(where, "must be a list")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(args[0], v, f"{where}[{i}]", meta) for i, v in enumerate(value))
        if len(value) != len(args):
            raise SchemaError(where, f"must have {len(args)} entries, got {len(value)}")
        return tuple(_convert(a, v, f"{where}[{i}]", meta)
                     for i, (a, v) in enumerate(zip(args, value, strict=False)))
    if origin is list:
        (inner,) = get_args(tp)
        if not isinstance(value, list):
            raise SchemaError(where, "must be a list")
        return [_convert(inner, v, f"{where}[{i}]", meta) for i, v in enumerate(value)]
    if dataclasses.is_dataclass(tp):
        return read(tp, value, where)
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SchemaError(where, f"must be a number, got {show(value)}")
        try:
            value = float(value)
        except OverflowError:  # an integer of hundreds of digits
            raise SchemaError(where, f"must be at most {MAX_MAGNITUDE:g} in magnitude, got "
                              f"{show(value)}") from None
        if not math.isfinite(value):
            raise SchemaError(where, f"must be a finite number, got {value}")
        if abs(value) > MAX_MAGNITUDE:
            raise SchemaError(where, f"must be at most {MAX_MAGNITUDE:g} in magnitude (metres "
                              f"or radians), got {value:g}")
        if meta.get("positive") and value <= 0:
            raise SchemaError(where, f"must be positive, got {value:g}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise SchemaError(where, f"must be true or false, got {show(value)}")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise SchemaError(where, f"must be an integer, got {show(value)}")
        return value
    if tp is str:
        if not isinstance(value, str) or not value:
            raise SchemaError(where, f"must be a non-empty string, got {show(value)}")
        return value
    raise TypeError(f"schema type {tp!r} at {where} is not supported")  # programming error

