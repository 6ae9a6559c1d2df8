"""Settings overlays per scene class, as data: a YAML file maps a scene class to the fields
of a settings dataclass it changes (``skeletons/settings.yaml`` for the programs,
``skeletons/loop.yaml`` for the closed loop)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import fields, replace
from pathlib import Path
from typing import TypeVar

import yaml

__all__ = ["apply_overlays", "check_overlays", "parse_overrides", "read_overlays"]

S = TypeVar("S")


def _defaults(defaults: object) -> dict[str, object]:
    """Setting names → default values: a mapping as it is, a dataclass's fields."""
    if isinstance(defaults, Mapping):
        return dict(defaults)
    return {f.name: getattr(defaults, f.name) for f in fields(defaults)}


def read_overlays(path: Path, defaults: object, classes: tuple[str, ...],
                  what: str) -> dict[str, dict]:
    """The overlays of ``path`` (YAML, safe loader), each key a scene class of ``classes``
    and each setting one of ``defaults``' (a settings dataclass, or names → defaults) with
    a value of its type (an int where a float is expected is fine). Raises ValueError
    naming the file and the field; ``what`` says what the fields are (e.g. "program
    setting")."""
    return check_overlays(yaml.safe_load(path.read_text()) or {}, defaults, classes, what,
                          str(path))


def check_overlays(data: object, defaults: object, classes: tuple[str, ...] | None,
                   what: str, where: str) -> dict[str, dict]:
    """:func:`read_overlays` of data already read (``where`` names it in messages;
    ``classes`` None: any name)."""
    if not isinstance(data, dict):
        raise ValueError(f"{where}: must map scene classes to overlays")
    known = _defaults(defaults)
    for name, overlay in data.items():
        if classes is not None and name not in classes:
            raise ValueError(f"{where}: {name}: not a scene class; one of {classes}")
        if not isinstance(overlay, dict):
            raise ValueError(f"{where}: {name}: must map {what}s to values")
        for key, value in overlay.items():
            if key not in known:
                raise ValueError(f"{where}: {name}.{key}: not a {what}")
            default = known[key]
            if default is not None and type(value) is not type(default) and not (
                    isinstance(default, float) and type(value) is int):
                raise ValueError(f"{where}: {name}.{key}: must be a {type(default).__name__}")
    return data


def apply_overlays(base: S, overlays: dict[str, dict], classes: tuple[str, ...]) -> S:
    """``base`` with the overlays of ``classes`` applied in order."""
    out = base
    for name in classes:
        out = replace(out, **overlays.get(name, {}))
    return out


_TRUE, _FALSE = ("true", "on", "yes", "1"), ("false", "off", "no", "0")


def parse_overrides(defaults: object, items: Sequence[str], what: str) -> dict[str, object]:
    """``NAME=VALUE`` items (the CLI's ``--loop``, ``--program``) as settings of ``defaults``
    (a settings dataclass, or names → defaults) with values of their types: booleans as
    true/false (on/off, yes/no, 1/0), numbers as written and not negative, text as it is.
    Raises ValueError naming the item that is not a setting (``what`` names them, e.g.
    "closed-loop setting") or not of its type. Only settings of those kinds (or None by
    default) can be set so."""
    names = {k: v for k, v in _defaults(defaults).items()
             if isinstance(v, (bool, int, float, str, type(None)))}
    out: dict[str, object] = {}
    for item in items:
        name, sep, text = item.partition("=")
        name, text = name.strip(), text.strip()
        if not sep or not text:
            raise ValueError(f"{item!r}: expected NAME=VALUE")
        if name not in names:
            raise ValueError(f"{name}: not a {what}; one of {', '.join(sorted(names))}")
        default = names[name]
        try:
            if isinstance(default, bool):
                if text.lower() not in _TRUE + _FALSE:
                    raise ValueError
                value: object = text.lower() in _TRUE
            elif isinstance(default, str):
                value = text
            elif isinstance(default, int):
                value = int(text)
            else:  # floats, and optional limits whose default is None
                value = float(text)
                if not math.isfinite(value):
                    raise ValueError
        except ValueError:
            kind = "float" if default is None else type(default).__name__
            raise ValueError(f"{name}: {text!r} is not a {kind}") from None
        if isinstance(value, (int, float)) and not isinstance(value, bool) and value < 0:
            raise ValueError(f"{name}: must not be negative")
        out[name] = value
    return out
