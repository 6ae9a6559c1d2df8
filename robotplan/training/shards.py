"""Data sets stored as shards: ``meta.json`` with the settings, then ``shard_NNNNN.npz`` files,
each a block of scenes written atomically by a worker process. A re-run on a partial folder
makes only the missing shards; a folder made with other settings is refused."""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Sequence
from multiprocessing import get_context
from pathlib import Path

import numpy as np

__all__ = ["make_shards", "prepare_folder", "save_shard", "shard_path"]


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
    """Write a shard whole or not at all (a temporary file renamed into place)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp.npz")
    np.savez_compressed(tmp, **arrays)
    os.replace(tmp, path)


def make_shards(out: Path, scenes: int, shard_size: int, make: Callable[[tuple], int],
                extra: Sequence = (), workers: int = 2, progress: bool = True,
                desc: str = "data") -> tuple[int, int, int]:
    """Run ``make((out, k, first, last, *extra))`` for every missing shard ``k`` (scenes
    ``first ≤ i < last``), in ``workers`` processes, with a progress bar in scenes.
    ``make`` returns how many samples it wrote. Returns (shards, made, samples)."""
    from tqdm import tqdm

    jobs = [(out, k, first, min(first + shard_size, scenes), *extra)
            for k, first in enumerate(range(0, scenes, shard_size))]
    todo = [j for j in jobs if not shard_path(out, j[1]).exists()]
    samples = 0
    done = sum(j[3] - j[2] for j in jobs if j not in todo)
    with tqdm(total=scenes, initial=done, unit="scene", disable=not progress,
              desc=desc) as bar:
        if workers <= 1:
            for j in todo:
                samples += make(j)
                bar.update(j[3] - j[2])
        else:
            with get_context("fork").Pool(workers) as pool:
                for n, j in zip(pool.imap(make, todo), todo, strict=True):
                    samples += n
                    bar.update(j[3] - j[2])
    return len(jobs), len(todo), samples
