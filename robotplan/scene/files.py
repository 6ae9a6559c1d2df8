"""A scene file's bytes to plain data (dicts, lists, numbers, strings): JSON or YAML.

``*.json`` files are JSON, ``*.yaml``/``*.yml`` files YAML; a file with any other name is
JSON when it parses as JSON, else YAML. YAML goes through the safe loader only (no Python
tags), with duplicate keys refused, exponent floats such as ``3e-06`` or ``1E5`` read
as numbers and only true/false read as booleans (``on``, ``yes`` stay strings), as JSON and
YAML 1.2 read them.
Every failure raises :class:`~robotplan.scene.reader.SchemaError` whose ``field`` is empty
or the line of the problem.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import yaml

from robotplan.scene.limits import MAX_FILE_BYTES
from robotplan.scene.reader import SchemaError, show

__all__ = ["read_data"]

_YAML_SUFFIXES = (".yaml", ".yml")
_MERGE_TAG = "tag:yaml.org,2002:merge"
# libyaml parses ~10x faster than the pure-Python parser (a 1 MB file in about a second)
_BaseLoader: type = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class _StrictSafeLoader(_BaseLoader):  # type: ignore[misc, valid-type]
    """The safe loader, refusing duplicate and unhashable keys instead of keeping the last
    silently or failing with a TypeError."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: set[Any] = set()
        for key_node, _ in node.value:
            if key_node.tag == _MERGE_TAG:
                continue  # '<<' merges another mapping; the safe constructor flattens it
            key = self.construct_object(key_node, deep=deep)
            mark = key_node.start_mark
            try:
                duplicate = key in seen
            except TypeError:
                raise yaml.constructor.ConstructorError(
                    None, None, f"a key must be a plain value, got {show(key)} "
                    f"(line {mark.line + 1})", mark) from None
            if duplicate:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r} (line {mark.line + 1})", mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


# YAML 1.2 / JSON floats with an exponent but no dot or no exponent sign: 1e-3, 3e-06, 1E5
_EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")
_StrictSafeLoader.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_FLOAT,
                                        list("-+0123456789."))
# YAML 1.2 / JSON booleans only: YAML 1.1 also reads yes/no/on/off as booleans, so that a
# hang goal's ``on: hook`` would become ``True: hook``
_BOOL = "tag:yaml.org,2002:bool"
_StrictSafeLoader.yaml_implicit_resolvers = {
    first: [(tag, rx) for tag, rx in resolvers if tag != _BOOL]
    for first, resolvers in _StrictSafeLoader.yaml_implicit_resolvers.items()}
_StrictSafeLoader.add_implicit_resolver(
    _BOOL, re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF"))


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise ValueError(f"duplicate key {k!r}")
        out[k] = v
    return out


def _parse_json(text: str) -> Any:
    try:
        return json.loads(text, object_pairs_hook=_no_duplicates)
    except RecursionError:
        raise SchemaError("", "invalid JSON: nested too deeply") from None
    except ValueError as err:  # JSONDecodeError, a duplicate key, an integer too long
        raise SchemaError("", f"invalid JSON: {_short(str(err))}") from None


def _parse_yaml(text: str) -> Any:
    try:
        return yaml.load(text, Loader=_StrictSafeLoader)
    except yaml.constructor.ConstructorError as err:
        mark = err.problem_mark
        where = f"line {mark.line + 1}" if mark else "YAML"
        problem = err.problem or str(err)
        if "could not determine a constructor" in problem:
            problem = (f"YAML tag {problem.split('tag')[-1].strip()} is not allowed: "
                       "scene files hold plain data only")
        raise SchemaError(where, _short(problem)) from None
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else "YAML"
        problem = getattr(err, "problem", None) or str(err)
        raise SchemaError(where, f"invalid YAML: {_short(problem)}") from None
    except RecursionError:
        raise SchemaError("YAML", "invalid YAML: nested too deeply") from None
    except Exception as err:
        # The safe constructor raises plain ValueError, TypeError, AttributeError... for a
        # malformed tagged or typed scalar (``!!int x``, ``2001-13-01``, a 5000-digit int).
        raise SchemaError("YAML", f"invalid YAML value: {_short(str(err))}") from None


def _short(text: str, limit: int = 200) -> str:
    """One line of at most ``limit`` characters: messages end as a single line."""
    line = " ".join(text.split())
    return line if len(line) <= limit else line[: limit - 3] + "..."


def read_data(path: Path) -> Any:
    """The parsed content of the scene file ``path`` (not yet checked against the schema)."""
    try:
        size = path.stat().st_size
        if path.is_file() and size > MAX_FILE_BYTES:
            raise SchemaError("", f"{size / 1e6:.1f} MB is too large for a scene file (at "
                              f"most {MAX_FILE_BYTES / 1e6:g} MB)")
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SchemaError("", "no such file") from None
    except IsADirectoryError:
        raise SchemaError("", "is a directory, not a scene file") from None
    except OSError as err:
        raise SchemaError("", f"cannot read: {err.strerror}") from None
    if len(raw) > MAX_FILE_BYTES:  # not a regular file (a pipe): its size is known once read
        raise SchemaError("", f"more than {MAX_FILE_BYTES / 1e6:g} MB is too large for a "
                          "scene file")
    try:
        text = raw.decode("utf-8-sig")  # a leading byte-order mark is not content
    except UnicodeDecodeError:
        raise SchemaError("", "not a UTF-8 text file") from None
    suffix = path.suffix.lower()
    if suffix == ".json":
        return _parse_json(text)
    if suffix not in _YAML_SUFFIXES and text.lstrip().startswith(("{", "[")):
        try:
            return _parse_json(text)
        except SchemaError:
            pass  # a YAML flow mapping or a bad file: YAML says which
    return _parse_yaml(text)
