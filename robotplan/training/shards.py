"""Data sets stored as shards: ``meta.json`` with the settings, then ``shard_NNNNN.npz`` files,
each a block of scenes computed by a worker (a local process or a Ray task) and written
atomically here. A re-run on a partial folder makes only the missing shards; a folder made
with other settings is refused; ``run.json`` says where and how long the last run ran."""

from __future__ import annotations

import io
import json
import os
import zipfile
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from robotplan.base.files import write_atomically
from robotplan.base.units import UnitsReport, run_units

__all__ = ["make_shards", "prepare_folder", "save_shard", "shard_path"]


ZIP_TIME = (1980, 1, 1, 0, 0, 0)  # the earliest a zip entry can carry


def shard_path(out: Path, k: int) -> Path:
    return out / f"shard_{k:05d}.npz"


def _jsonable(x: object) -> object:
    return json.loads(json.dumps(x))


def prepare_folder(out: Path, meta: dict, scenes: int,
                   legacy: Callable[[str, object], object] | None = None) -> dict:
    """Write ``out/meta.json`` (``meta`` plus ``scenes``, the most asked for so far), or check
    that the folder's settings are ``meta``'s. ``legacy(key, old_value)`` may fill in what an
    older folder's settings lack before they are compared. Raises ValueError naming the key."""
    out.mkdir(parents=True, exist_ok=True)
    meta_path = out / "meta.json"
    old = json.loads(meta_path.read_text()) if meta_path.exists() else None
    if old is not None:
        for key in meta:
            before = _jsonable(old.get(key))
            if legacy is not None:
                before = legacy(key, before)
            if before != _jsonable(meta[key]):
                raise ValueError(f"{meta_path}: {key}: the folder holds data made with other "
                                 f"settings ({old.get(key)!r}); use another --out")
    full = {**meta, "scenes": max(scenes, old.get("scenes", 0) if old else 0)}
    tmp = meta_path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(full, indent=1))
    os.replace(tmp, meta_path)
    return full


def save_shard(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """Write a shard whole or not at all: an ``.npz`` (deflated) whose bytes depend on the
    arrays alone (a fixed time stamp in every entry), so that a data set made again, with
    other workers or on Ray, is byte-identical."""

    def write(tmp: Path) -> None:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            for name, array in arrays.items():
                buf = io.BytesIO()
                np.lib.format.write_array(buf, np.asanyarray(array), allow_pickle=False)
                info = zipfile.ZipInfo(f"{name}.npy", date_time=ZIP_TIME)
                info.compress_type = zipfile.ZIP_DEFLATED
                zf.writestr(info, buf.getvalue())

    write_atomically(path, write)


def make_shards(out: Path, scenes: int, shard_size: int,
                make: Callable[[tuple], tuple[dict[str, np.ndarray], int]],
                extra: Sequence = (), workers: int = 2, progress: bool = True,
                desc: str = "data", ray: str | None = None) -> tuple[int, int, int]:
    """Make every missing shard ``k`` (scenes ``first ≤ i < last``): ``make((first, last,
    *extra))`` returns its arrays and how many samples they hold, and the shard is written
    here as each comes back, in order. The units run in ``workers`` local processes, or as
    Ray tasks (``ray``: :func:`robotplan.base.units.run_units`); where and how long they ran
    goes to ``out/run.json``, apart from the data. Returns (shards, made, samples)."""
    from tqdm import tqdm

    jobs = [(k, first, min(first + shard_size, scenes))
            for k, first in enumerate(range(0, scenes, shard_size))]
    todo = [j for j in jobs if not shard_path(out, j[0]).exists()]
    samples = 0
    done = sum(j[2] - j[1] for j in jobs if j not in todo)
    report = UnitsReport()
    units = run_units(make, [(first, last, *extra) for _, first, last in todo], workers, ray,
                      report)
    with tqdm(total=scenes, initial=done, unit="scene", disable=not progress,
              desc=desc) as bar:
        for (k, first, last), (arrays, n) in zip(todo, units, strict=True):
            save_shard(shard_path(out, k), arrays)
            samples += n
            bar.update(last - first)
    if todo:
        run = {**report.as_dict(), "shards": len(todo), "scenes": sum(j[2] - j[1] for j in todo)}
        write_atomically(out / "run.json",
                         lambda tmp: tmp.write_text(json.dumps(run, indent=1)))
    return len(jobs), len(todo), samples
