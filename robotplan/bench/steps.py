"""The steps of ``robotplan reproduce``: each item of the report is a step (data,
training, evaluation, benchmark) with its parameters.

A step's key hashes its name, its parameters, what it reads (:mod:`robotplan.bench.step_keys`:
the modules it runs, the files it reads by content, the skeleton tables and robot
descriptions) and the keys of the steps whose outputs it uses (``needs``). Its result is kept
in ``OUT/steps/<name>-<key>/result.json`` beside its outputs, and, with a ledger, as
``LEDGER/<name>.json`` (the result alone: small JSON, committed with the code). A step runs
only when neither has its key: a later run, on a new machine too, reuses every step whose
inputs did not change. A step reused from the ledger has no outputs on this machine; it runs
again only if a step that needs them has to run.

``dry=True`` runs nothing: each step is reported as ``done`` (its key in the folder or the
ledger), ``stale`` (the ledger holds an older key: something it reads changed) or ``missing``.
``allow(name)`` false leaves a step that would run ``skipped`` (a run in parts: some steps,
or as many as fit a time budget), and every step that needs it with it.

Several runs may share ``OUT`` (each on its own steps, ``reproduce --steps``): a step being
made holds ``OUT/steps/<name>-<key>.lock`` (its process id), and another run leaves that
step ``running`` (``skipped`` for what it would have run) instead of starting it over. A
lock whose process has ended is taken over.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

from robotplan.base.files import write_atomically
from robotplan.base.resources import robots_dir, skeletons_dir
from robotplan.bench.step_keys import files_digest, modules_digest, package_modules

__all__ = ["Steps", "ledger_json", "step_key"]

EVERYTHING = ("robotplan",)  # a step that does not say what it runs: the whole package
FINISHED = ("done", "ran")  # the states of a step whose result is in hand


def step_key(name: str, params: dict, runs: Iterable[str], reads: Iterable[Path],
             needs: Iterable[str]) -> str:
    """The key of a step (module docstring): 12 hex digits."""
    runs = tuple(runs)
    code = modules_digest(package_modules() if runs == EVERYTHING else runs)
    tables = files_digest([skeletons_dir(), robots_dir(), *reads])
    doc = {"name": name, "params": params, "code": code, "files": tables,
           "needs": sorted(needs)}
    return hashlib.sha256(json.dumps(doc, sort_keys=True, default=str).encode()
                          ).hexdigest()[:12]


@dataclass
class _Pending:
    """A step reused from the ledger whose outputs are not on this machine yet."""

    name: str
    fn: Callable[[Path], dict]
    needs: tuple[dict, ...]
    command: str
    params: dict = field(default_factory=dict)


def lock_owner(lock: Path) -> int | None:
    """The id of the live process (not this one) that holds ``lock``; None where there is no
    lock, it cannot be read, or its process has ended."""
    try:
        pid = int(lock.read_text())
    except (OSError, ValueError):
        return None
    if pid == os.getpid() or pid <= 0:
        return None
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return None
    except PermissionError:  # alive, another user's
        return pid
    return pid


def ledger_json(entry: dict) -> str:
    """``entry`` as indented JSON with each list of numbers or strings on one line (a
    ledger entry's per-scene sums stay a few lines, not one per number). Only structural
    line breaks are joined: JSON strings hold none."""
    text = json.dumps(entry, indent=1)
    return re.sub(r"\[\n([^\[\]{}]*?)\n *\]",
                  lambda m: "[" + re.sub(r"\n *", " ", m.group(1)).strip() + "]", text)


class Steps:
    """Runs steps, or reuses their kept results (see the module docstring)."""

    def __init__(self, out: Path, progress: bool = True, ledger: Path | None = None,
                 dry: bool = False, allow: Callable[[str], bool] | None = None,
                 device: str = "cpu") -> None:
        self.out, self.progress, self.ledger, self.dry = out, progress, ledger, dry
        self.allow = allow
        # where training steps put their networks; not in any key: what a step reads is the
        # same on either, so a model trained on an accelerator is reused on a CPU
        self.device = device
        if ledger is not None and not dry:
            ledger.mkdir(parents=True, exist_ok=True)
        self.log: list[dict] = []
        self._pending: dict[str, _Pending] = {}
        self._results: dict[str, dict] = {}  # each step's result by its folder
        self.params_log: list[dict] = []  # each logged step's parameters

    def run(self, name: str, params: dict, fn: Callable[[Path], dict], command: str, *,
            runs: Iterable[str] = EVERYTHING, reads: Iterable[Path] = (),
            needs: Iterable[dict] = ()) -> dict:
        """Run ``fn(folder)`` as step ``name`` or reuse its result. ``runs``: the entry
        modules it runs; ``reads``: files or folders it reads; ``needs``: the results (as
        returned here) of the steps whose outputs it uses."""
        needs = tuple(needs)
        key = step_key(name, params, runs, reads, [n["key"] for n in needs])
        folder = self.out / "steps" / f"{name}-{key}"
        rel = str(folder.relative_to(self.out))
        kept, entry = folder / "result.json", self._ledger_entry(name)
        owner = lock_owner(folder.with_suffix(".lock"))
        if kept.is_file():
            result, state = json.loads(kept.read_text()), "done"
            self._say(f"{name}: reused ({rel})")
        elif entry is not None and entry.get("key") == key:
            result, state = dict(entry), "done"
            self._pending[rel] = _Pending(name, fn, needs, command, params)
            self._say(f"{name}: reused from the ledger")
        elif self.dry or owner is not None or not self._may_run(name, needs):
            if self.dry:
                state = ("running" if owner is not None else "stale" if entry is not None
                         else "missing")
            else:
                state = "skipped"
                self._say(f"{name}: left for a later run" if owner is None else
                          f"{name}: being run by process {owner}; left for a later run")
            result = {"result": {}, "seconds": (entry or {}).get("seconds"),
                      "command": command, "params": params}
        else:
            result, state = self._execute(name, key, folder, fn, needs, command, params), "ran"
        result.update(folder=rel, key=key, state=state)
        self._results[rel] = result
        self.log.append({"name": name, "folder": rel, "key": key, "state": state,
                         "seconds": result.get("seconds"), "command": result["command"]})
        self.params_log.append(params)
        return result

    @property
    def complete(self) -> bool:
        """Whether every step so far is done or ran (none skipped)."""
        return all(step["state"] in FINISHED for step in self.log)

    def _may_run(self, name: str, needs: tuple[dict, ...]) -> bool:
        return (all(n["state"] in FINISHED for n in needs)
                and (self.allow is None or self.allow(name)))

    def uses(self, *paths: Path) -> dict:
        """``needs`` and ``reads`` of a step that reads ``paths``: a path inside a step's
        folder is that step's output (its key stands for its content), any other is read
        by content."""
        needs, reads = [], []
        for path in paths:
            parts = Path(path).resolve().relative_to(self.out.resolve()).parts if (
                Path(path).resolve().is_relative_to(self.out.resolve())) else ()
            step = (self._results.get(f"{parts[0]}/{parts[1]}")
                    if len(parts) > 1 and parts[0] == "steps" else None)
            if step is not None:
                needs.append(step)
            else:
                reads.append(Path(path))
        return {"needs": tuple(needs), "reads": tuple(reads)}

    def materialize(self, step: dict) -> None:
        """Make sure the outputs of ``step`` (a result of :meth:`run`) are on this machine:
        run it if it was reused from the ledger alone."""
        pending = self._pending.pop(step["folder"], None)
        if pending is None or (self.out / step["folder"] / "result.json").is_file():
            return
        self._execute(pending.name, step["key"], self.out / step["folder"], pending.fn,
                      pending.needs, pending.command, pending.params)

    def _execute(self, name: str, key: str, folder: Path, fn: Callable[[Path], dict],
                 needs: tuple[dict, ...], command: str, params: dict) -> dict:
        for step in needs:
            self.materialize(step)
        lock = folder.with_suffix(".lock")
        owner = lock_owner(lock)
        if owner is not None:
            raise RuntimeError(f"{name}: its outputs are being made by process {owner}; "
                               "run again when it ends")
        folder.parent.mkdir(parents=True, exist_ok=True)
        lock.write_text(str(os.getpid()))
        try:
            if folder.exists():  # an interrupted run of this step: start it over
                shutil.rmtree(folder)
            folder.mkdir(parents=True)
            self._say(f"{name}: running `{command}` …")
            t0 = time.time()
            result = {"result": fn(folder), "seconds": round(time.time() - t0, 1),
                      "command": command, "params": params}
        finally:
            lock.unlink(missing_ok=True)
        text = json.dumps(result, indent=1, default=str)
        write_atomically(folder / "result.json", lambda tmp: tmp.write_text(text))
        if self.ledger is not None:
            entry = ledger_json({"key": key, **json.loads(text)})
            write_atomically(self.ledger / f"{name}.json", lambda tmp: tmp.write_text(entry))
        self._say(f"{name}: {result['seconds']} s")
        return json.loads(text)

    def _ledger_entry(self, name: str) -> dict | None:
        if self.ledger is None or not (self.ledger / f"{name}.json").is_file():
            return None
        return json.loads((self.ledger / f"{name}.json").read_text())

    def _say(self, text: str) -> None:
        if self.progress:
            print(text, flush=True)
