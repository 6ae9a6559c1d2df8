"""Random mutations of the example scenes: every one loads or is refused with SceneError in
one line (never another exception), and ``robotplan check`` exits 0 or 2 without a traceback.
"""

from __future__ import annotations

import copy
import json
import random
import subprocess
import sys
from collections.abc import Callable
from typing import Any

import pytest
import yaml

from robotplan import SceneError, load_scene
from robotplan.scene import parse_scene
from robotplan.scene.files import read_data
from tests.conftest import ROOT, TASKS

EXAMPLES = sorted(TASKS.glob("*.yaml"))
MUTATIONS_PER_SCENE = 50
ODD_VALUES: list[Any] = [None, {}, [], "a string", "", 1e308, -1e308, 10**30, -(10**400),
                         -3.0, 0, float("nan"), float("inf"), True, [[1, [2, [3]]], "x"],
                         {"type": {}}, [None], 2**64, 1e-300, 5e-324]


def paths(node: Any, prefix: tuple = ()) -> list[tuple]:
    """Every path (tuple of keys and indices) to a value inside ``node``."""
    out = [prefix] if prefix else []
    if isinstance(node, dict):
        for k, v in node.items():
            out += paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += paths(v, (*prefix, i))
    return out


def _parent(data: Any, path: tuple) -> Any:
    for key in path[:-1]:
        data = data[key]
    return data


def _scale(v: Any, rng: random.Random) -> Any:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or abs(v) > 1e300:
        return v
    return v * rng.choice([-1.0, 0.0, 1e-12, 1e-3, 0.5, 2.0, 1e3, 1e6, 1e9])


def mutate_once(data: Any, rng: random.Random) -> None:
    """One random change in place: delete, retype, duplicate, truncate or rescale."""
    path = rng.choice(paths(data))
    parent, key = _parent(data, path), path[-1]
    value = parent[key]
    ops: list[Callable[[], None]] = [
        lambda: parent.__delitem__(key),
        lambda: parent.__setitem__(key, copy.deepcopy(rng.choice(ODD_VALUES))),
        lambda: parent.__setitem__(key, _scale(value, rng)),
    ]
    if isinstance(value, list):
        ops += [lambda: parent.__setitem__(key, value * rng.choice([2, 3, 50])),
                lambda: parent.__setitem__(key, value[: rng.randrange(len(value) + 1)]),
                lambda: parent.__setitem__(key, [_scale(v, rng) for v in value])]
    if isinstance(value, dict):
        ops.append(lambda: value.__setitem__(rng.choice(["extra", "type", "name"]),
                                             rng.choice(ODD_VALUES)))
    rng.choice(ops)()


def mutants(rng: random.Random) -> list[tuple[str, Any]]:
    """``MUTATIONS_PER_SCENE`` mutants of each example, one to three changes each."""
    out = []
    for path in EXAMPLES:
        base = read_data(path)  # YAML 1.2 booleans, as robotplan reads scenes
        for i in range(MUTATIONS_PER_SCENE):
            data = copy.deepcopy(base)
            for _ in range(rng.choice([1, 1, 2, 3])):
                if not paths(data):
                    break
                mutate_once(data, rng)
            out.append((f"{path.stem}_{i}", data))
    return out


MUTANTS = mutants(random.Random(0))


def _one_line(err: SceneError) -> None:
    assert "\n" not in str(err) and len(str(err)) < 1000, str(err)


def test_mutated_scenes_load_or_are_refused_with_scene_error(tmp_path):
    outcomes = {"ok": 0, "refused": 0}
    for i, (name, data) in enumerate(MUTANTS):
        try:
            if i % 3 == 0:  # through a file too: YAML or JSON text
                f = tmp_path / f"{name}.{'json' if i % 2 else 'yaml'}"
                f.write_text(json.dumps(data) if i % 2 else yaml.safe_dump(data))
                load_scene(f)
            else:
                parse_scene(copy.deepcopy(data), name)
            outcomes["ok"] += 1
        except SceneError as err:
            _one_line(err)
            outcomes["refused"] += 1
        except Exception as err:
            pytest.fail(f"{name}: {type(err).__name__}: {err} for {json.dumps(data)[:2000]}")
    assert len(MUTANTS) >= 300
    assert outcomes["ok"] > 10 and outcomes["refused"] > 100, outcomes  # both kinds occur


def test_check_on_mutated_files_exits_0_or_2_without_traceback(tmp_path):
    rng = random.Random(0)
    files = []
    for name, data in rng.sample(MUTANTS, 8):
        f = tmp_path / f"{name}.yaml"
        f.write_text(yaml.safe_dump(data))
        files.append(str(f))
    res = subprocess.run([sys.executable, "-m", "robotplan.cli", "check", *files], cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert res.returncode in (0, 2), res.stderr
    assert "Traceback" not in res.stderr
    errors, oks = res.stderr.splitlines(), res.stdout.splitlines()
    assert len(errors) + len(oks) == len(files), res.stdout + res.stderr
    assert all(line.startswith("error: ") for line in errors)
    assert (res.returncode == 2) == bool(errors)
