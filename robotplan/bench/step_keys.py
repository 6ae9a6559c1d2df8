"""What a step of ``robotplan reproduce`` reads, hashed: the modules it runs (the import
closure of its entry modules within the package, imports inside functions and the
``"module:class"`` entries of registries included, ``if TYPE_CHECKING:`` ones left out) and
the files it reads (by content). A step's key is built from these, its parameters and the
keys of the steps whose outputs it uses, so a change elsewhere in the code leaves it
standing."""

from __future__ import annotations

import ast
import hashlib
from collections.abc import Iterable
from functools import cache
from pathlib import Path

__all__ = ["files_digest", "module_closure", "modules_digest", "package_modules"]

PACKAGE = Path(__file__).resolve().parents[1]


def package_modules() -> list[str]:
    """Every module of the package (sorted dotted names)."""
    return sorted(_module_files())


@cache
def _module_files() -> dict[str, Path]:
    """Every module of the package by its dotted name."""
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _imported(module: str) -> set[str]:
    """The package's modules that ``module`` imports by name (a package's ``__init__`` when
    it is imported from; not the packages above an imported module, whose re-exports for
    users do not change what the module computes)."""
    path = _module_files()[module]
    return _imports_of(module, path, _stamp(path))


def _stamp(path: Path) -> tuple[int, int]:
    """What tells a file's versions apart without reading it: its size and change time."""
    stat = path.stat()
    return stat.st_size, stat.st_mtime_ns


def _file_sha256(path: Path) -> bytes:
    return _sha256_of(path, _stamp(path))


@cache
def _sha256_of(path: Path, stamp: tuple[int, int]) -> bytes:
    """The file's SHA-256, read once per version (``stamp``)."""
    return hashlib.sha256(path.read_bytes()).digest()


@cache
def _imports_of(module: str, path: Path, stamp: tuple[int, int]) -> set[str]:
    files = _module_files()
    tree = ast.parse(path.read_text())
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for inner in node.body:
                skip.update(range(inner.lineno, (inner.end_lineno or inner.lineno) + 1))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    names: set[str] = set()
    for node in ast.walk(tree):
        if getattr(node, "lineno", None) in skip:
            continue
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                head = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(head + ([base] if base else []))
            names.add(base)
            names.update(f"{base}.{a.name}" for a in node.names)
        elif (isinstance(node, ast.Constant) and isinstance(node.value, str)
              and node.value.startswith("robotplan.") and ":" in node.value):
            names.add(node.value.split(":")[0])  # a registry's "module:class", imported by name
    return {name for name in names if name in files}


def module_closure(entries: Iterable[str]) -> list[str]:
    """The modules ``entries`` run: themselves and everything of the package they import,
    directly or not (sorted)."""
    files = _module_files()
    todo = [e for e in entries]
    for entry in todo:
        if entry not in files:
            raise ValueError(f"no module {entry!r} in the package")
    seen: set[str] = set()
    while todo:
        module = todo.pop()
        if module in seen:
            continue
        seen.add(module)
        todo.extend(_imported(module) - seen)
    return sorted(seen)


def modules_digest(entries: Iterable[str]) -> str:
    """SHA-256 of the source of :func:`module_closure` of ``entries`` (and of the C kernels,
    which every computation runs)."""
    h = hashlib.sha256()
    files = _module_files()
    for module in module_closure(entries):
        h.update(module.encode())
        h.update(_file_sha256(files[module]))
    for kernel in sorted(PACKAGE.rglob("*.c")):
        h.update(_file_sha256(kernel))
    return h.hexdigest()


def files_digest(paths: Iterable[Path]) -> str:
    """SHA-256 of the files at ``paths`` (a folder: every file in it, by relative path and
    content; a missing path counts as absent)."""
    h = hashlib.sha256()
    for root in sorted(Path(p) for p in paths):
        h.update(str(root.name).encode())
        files = sorted(p for p in root.rglob("*") if p.is_file()) if root.is_dir() else (
            [root] if root.is_file() else [])
        for p in files:
            if "__pycache__" in p.parts:
                continue
            h.update(str(p.relative_to(root) if root.is_dir() else p.name).encode())
            h.update(_file_sha256(p))
    return h.hexdigest()
