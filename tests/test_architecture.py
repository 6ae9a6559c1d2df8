"""The package's layers: each imports only the layers below it, no import cycles (a lazy
import counts like any other), no private names across modules, no module over the limit.

Imports under ``if TYPE_CHECKING:`` are annotations, not dependencies, and are left out.
"""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "robotplan"

LAYERS = [
    "base",         # files, kernels, pinned arithmetic, data folders, quiet imports
    "geometry",     # planar transforms and polygons
    "sdf",          # shapes and their signed distances
    "scene",        # the scene file: schema, reading, bodies, robot models
    "models",       # learned networks (F_flow, F)
    "functionals",  # H_coll, H_g, H_PoC, H_F, arm kinematics
    "program",      # skeletons, Drake programs and their solutions
    "search",       # the skeleton search
    "execution",    # pybullet
    "viz",          # MeshCat pages, PNG pictures
    "training",     # push data, training, evaluation
    "api",          # the facade: plan, execute, write_playback, solve
    "bench",        # benchmarks
    "cli",          # the command line
]
MAX_LINES = 300


def _layer(module: str) -> int:
    """The rank of ``robotplan.<layer>...`` (the package root ranks above everything)."""
    parts = module.split(".")
    return LAYERS.index(parts[1]) if len(parts) > 1 else len(LAYERS)


def _modules() -> dict[str, Path]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        rel = path.relative_to(PACKAGE.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _type_checking_lines(tree: ast.Module) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for inner in node.body:
                lines.update(range(inner.lineno, (inner.end_lineno or inner.lineno) + 1))
    return lines


def _imports(module: str, path: Path, known: set[str]) -> list[tuple[str, list[str], int]]:
    """``(imported module, names, line)`` for every robotplan import of a module, module level
    or inside functions."""
    tree = ast.parse(path.read_text())
    skip = _type_checking_lines(tree)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out = []
    for node in ast.walk(tree):
        if getattr(node, "lineno", None) in skip:
            continue
        if isinstance(node, ast.Import):
            out += [(a.name, [], node.lineno) for a in node.names if a.name.startswith("robotplan")]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[:len(package.split(".")) - node.level + 1]
                                + ([base] if base else []))
            if not base.startswith("robotplan"):
                continue
            names = [a.name for a in node.names]
            submodules = [n for n in names if f"{base}.{n}" in known]
            out += [(f"{base}.{n}", [], node.lineno) for n in submodules]
            rest = [n for n in names if n not in submodules]
            if rest:
                out.append((base, rest, node.lineno))
    return out


MODULES = _modules()
GRAPH = {m: _imports(m, p, set(MODULES)) for m, p in MODULES.items()}


def test_every_module_belongs_to_a_layer():
    for module in MODULES:
        if module != "robotplan":
            assert module.split(".")[1] in LAYERS, f"{module}: add its package to LAYERS"


def test_imports_go_down_the_layers():
    bad = []
    for module, imports in GRAPH.items():
        for target, _names, line in imports:
            if module == "robotplan":
                continue  # the package root re-exports the facade
            if _layer(target) > _layer(module):
                bad.append(f"{MODULES[module].relative_to(PACKAGE.parent)}:{line} imports "
                           f"{target} (layer {LAYERS[_layer(target)]} is above "
                           f"{LAYERS[_layer(module)]})")
    assert not bad, "\n".join(bad)


def test_no_import_cycles():
    edges = {m: {t for t, _n, _l in imps if t in MODULES and t != m} for m, imps in GRAPH.items()}
    # a package's __init__ re-exports its modules: importing a module runs it first
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for t in sorted(edges[m]):
            if state.get(t) == 1:
                cycle = [*stack[stack.index(t):], t]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if t not in state:
                visit(t)
        stack.pop()
        state[m] = 2

    for m in sorted(edges):
        if m not in state:
            visit(m)


def test_no_private_names_across_modules():
    bad = [f"{module} imports {target}.{name}"
           for module, imports in GRAPH.items() for target, names, _l in imports
           for name in names if name.startswith("_") and target != module]
    bad += [f"{module} imports {target}" for module, imports in GRAPH.items()
            for target, _n, _l in imports if any(p.startswith("_") and p != "__main__"
                                                 for p in target.split("."))]
    assert not bad, "\n".join(bad)


def test_modules_stay_small():
    long = {str(p.relative_to(PACKAGE.parent)): n for p in MODULES.values()
            if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not long, f"over {MAX_LINES} lines: {long}"


def test_the_checks_see_a_wrong_import(tmp_path):
    """The rules above can fail: an import up a layer and a cycle are found."""
    low, high = tmp_path / "low.py", tmp_path / "high.py"
    low.write_text("def f():\n    from robotplan.cli.main import main\n")
    high.write_text("import robotplan.sdf\n")
    imports = _imports("robotplan.sdf.low", low, set(MODULES))
    assert imports == [("robotplan.cli.main", ["main"], 2)]
    assert _layer(imports[0][0]) > _layer("robotplan.sdf.low")
