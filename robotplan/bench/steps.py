"""The steps of ``robotplan reproduce``: each item of the report is a step (data,
training, evaluation, benchmark) with its parameters; a step's result is kept in
``OUT/steps/<name>-<key>/result.json``, where the key hashes the step's name, its parameters
and the content of the code, skeleton tables, robot descriptions and learned models
(:func:`inputs_digest`), so a second run reuses every step whose inputs did not change and
reruns the rest."""

from __future__ import annotations

import hashlib
import json
import shutil
import time
from collections.abc import Callable
from pathlib import Path

from robotplan.base.files import write_atomically
from robotplan.base.resources import data_root, robots_dir, skeletons_dir

__all__ = ["REPORT_ONLY", "Steps", "inputs_digest"]

# how the report is written, not what its steps compute: left out of the steps' key
REPORT_ONLY = frozenset({"bench/paper.py", "bench/report.py", "bench/reproduce_report.py",
                         "hanging/bench/report.py"})


def inputs_digest() -> str:
    """SHA-256 of the package's code (but the report's formatting, ``REPORT_ONLY``) and of
    the skeleton tables, robot descriptions and learned models it reads: what every step's
    result depends on beside its parameters."""
    h = hashlib.sha256()
    package = Path(__file__).resolve().parents[1]
    roots = [(package, ("*.py", "*.c")), (skeletons_dir(), ("*",)), (robots_dir(), ("*",)),
             (data_root() / "learned", ("*",))]
    for root, patterns in roots:
        files = sorted({p for pat in patterns for p in root.rglob(pat) if p.is_file()
                        and "__pycache__" not in p.parts
                        and not (root == package
                                 and p.relative_to(root).as_posix() in REPORT_ONLY)})
        for p in files:
            h.update(str(p.relative_to(root)).encode())
            h.update(p.read_bytes())
    return h.hexdigest()


class Steps:
    """Runs steps, or reuses their kept results (see the module docstring)."""

    def __init__(self, out: Path, digest: str, progress: bool) -> None:
        self.out, self.digest, self.progress = out, digest, progress
        self.log: list[dict] = []

    def run(self, name: str, params: dict, fn: Callable[[Path], dict], command: str) -> dict:
        key = hashlib.sha256(json.dumps({"name": name, "params": params,
                                         "inputs": self.digest}, sort_keys=True,
                                        default=str).encode()).hexdigest()[:12]
        folder = self.out / "steps" / f"{name}-{key}"
        done = folder / "result.json"
        if done.is_file():
            result = json.loads(done.read_text())
            self._say(f"{name}: reused ({folder.relative_to(self.out)})")
        else:
            if folder.exists():  # an interrupted run of this step: start it over
                shutil.rmtree(folder)
            folder.mkdir(parents=True)
            self._say(f"{name}: running `{command}` …")
            t0 = time.time()
            result = {"result": fn(folder), "seconds": round(time.time() - t0, 1),
                      "command": command, "params": params}
            write_atomically(done, lambda tmp: tmp.write_text(json.dumps(result, indent=1,
                                                                          default=str)))
            self._say(f"{name}: {result['seconds']} s")
        result["folder"] = str(folder.relative_to(self.out))
        self.log.append({"name": name, "folder": result["folder"],
                         "seconds": result["seconds"], "command": result["command"]})
        return result

    def _say(self, text: str) -> None:
        if self.progress:
            print(text, flush=True)
