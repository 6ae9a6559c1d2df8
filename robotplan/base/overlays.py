"""Settings overlays per scene class, as data: a YAML file maps a scene class to the fields
of a settings dataclass it changes (``skeletons/settings.yaml`` for the programs,
``skeletons/loop.yaml`` for the closed loop)."""

from __future__ import annotations

from dataclasses import fields, replace
from pathlib import Path
from typing import TypeVar

import yaml

__all__ = ["apply_overlays", "read_overlays"]

S = TypeVar("S")


def read_overlays(path: Path, defaults: object, classes: tuple[str, ...],
                  what: str) -> dict[str, dict]:
    """The overlays of ``path`` (YAML, safe loader), each key a scene class of ``classes``
    and each field one of the dataclass ``defaults``' with a value of its type (an int
    where a float is expected is fine). Raises ValueError naming the file and the field;
    ``what`` says what the fields are (e.g. "program setting")."""
    data = yaml.safe_load(path.read_text()) or {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: must map scene classes to overlays")
    names = {f.name for f in fields(defaults)}
    for name, overlay in data.items():
        if name not in classes:
            raise ValueError(f"{path}: {name}: not a scene class; one of {classes}")
        if not isinstance(overlay, dict):
            raise ValueError(f"{path}: {name}: must map {what}s to values")
        for key, value in overlay.items():
            if key not in names:
                raise ValueError(f"{path}: {name}.{key}: not a {what}")
            default = getattr(defaults, key)
            if default is not None and type(value) is not type(default) and not (
                    isinstance(default, float) and type(value) is int):
                raise ValueError(f"{path}: {name}.{key}: must be a {type(default).__name__}")
    return data


def apply_overlays(base: S, overlays: dict[str, dict], classes: tuple[str, ...]) -> S:
    """``base`` with the overlays of ``classes`` applied in order."""
    out = base
    for name in classes:
        out = replace(out, **overlays.get(name, {}))
    return out
