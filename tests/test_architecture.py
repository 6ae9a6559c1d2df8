"""The package's layers: each imports only the layers below it, no import cycles (a lazy
import counts like any other), no private names across modules, no module over the limit.

Mug hanging and pushing are vertical slices, ``robotplan.hanging`` and ``robotplan.pushing``
(:data:`SLICES`), with the core's layers inside them: a module ``robotplan.<slice>.<layer>...``
ranks as that core layer and may import the core and its own slice at or below it, never the
other slice. The core reaches into a slice only from its top layers (:data:`ENTERS_SLICES`:
the facade and the commands dispatch to it), at or below their rank, and no module outside
the hanging slice is named after hanging.

A scene is classified once into its task (``robotplan.scene.task``): no condition outside the
scene file layer reads the kind of a scene from its raw fields. The search and the programs
take their inputs in a few objects (a task, a request): at most :data:`MAX_PARAMETERS` each.

Imports under ``if TYPE_CHECKING:`` are annotations, not dependencies, and are left out.
"""

import ast
import re
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
SLICES = ("hanging", "pushing")  # robotplan.<slice>.<layer>...: a family, layered as the core
HANGING = "hanging"
ENTERS_SLICES = ("api", "bench", "cli")  # the core layers that may import a slice


def _slice(module: str) -> str | None:
    """The slice a module lives in (None: the core)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in SLICES else None


def _in_slice(module: str) -> bool:
    return _slice(module) is not None


def _layer(module: str) -> int:
    """The rank of ``robotplan.<layer>...`` and of ``robotplan.<slice>.<layer>...`` (the
    package root, and each slice's own root, rank above everything)."""
    parts = module.split(".")
    if _in_slice(module):
        return LAYERS.index(parts[2]) if len(parts) > 2 else len(LAYERS)
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


def _layer_name(module: str) -> str | None:
    """The layer package a module lives in (None: a root, the package's or a slice's)."""
    parts = module.split(".")
    if _in_slice(module):
        return parts[2] if len(parts) > 2 else None
    return parts[1] if len(parts) > 1 else None


def test_every_module_belongs_to_a_layer():
    for module in MODULES:
        if module not in ("robotplan", *(f"robotplan.{s}" for s in SLICES)):
            assert _layer_name(module) in LAYERS, (
                f"{module}: add its package to LAYERS (under a slice: a layer's name)")


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


def _slice_entries(module: str, imports) -> list[str]:
    """The imports of a slice that the slices' rule forbids: by a core module outside the
    top layers (or above its rank), or by the other slice."""
    if module == "robotplan":
        return []
    own = _slice(module)
    if own is not None:
        return [f"{module}:{line} imports {target} (the {own} slice may not import the "
                f"{_slice(target)} slice)"
                for target, _names, line in imports if _slice(target) not in (None, own)]
    return [f"{module}:{line} imports {target} ({LAYERS[_layer(module)]} may not reach into "
            f"{_slice(target)}: only {', '.join(ENTERS_SLICES)} may, at or below their rank)"
            for target, _names, line in imports if _in_slice(target)
            and (_layer_name(module) not in ENTERS_SLICES or _layer(target) > _layer(module))]


def _named_after_hanging(module: str) -> bool:
    """A module outside the hanging slice whose own name speaks of hanging."""
    return _slice(module) != HANGING and any("hang" in p for p in module.split(".")[1:])


def test_each_family_lives_in_its_package():
    """Everything only mug hanging uses is under ``robotplan/hanging`` (no other module is
    named after it), and the core reaches into a slice only from its top layers."""
    named = sorted(m for m in MODULES if _named_after_hanging(m))
    assert not named, f"move into robotplan/{HANGING}/<layer>/ (or rename): {named}"
    bad = [entry for module, imports in GRAPH.items() for entry in _slice_entries(module, imports)]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("name", SLICES)
def test_each_slice_has_a_subpackage_per_layer(name):
    """A slice's structure is visible: each layer it uses is a package of its own."""
    root = PACKAGE / name
    assert (root / "__init__.py").is_file()
    subs = {p.name for p in root.iterdir() if p.is_dir() and p.name != "__pycache__"}
    assert subs <= set(LAYERS), f"not layers: {subs - set(LAYERS)}"
    assert all((root / s / "__init__.py").is_file() for s in subs)
    assert not [p.name for p in root.glob("*.py") if p.name != "__init__.py"], (
        "a slice's modules live in its layer packages")


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
    low.write_text("def f():\n    from robotplan.cli.app import main\n")
    high.write_text("import robotplan.sdf\n")
    imports = _imports("robotplan.sdf.low", low, set(MODULES))
    assert imports == [("robotplan.cli.app", ["main"], 2)]
    assert _layer(imports[0][0]) > _layer("robotplan.sdf.low")
    # a slice: ranked by its inner layer, above its rank is up, the core's low layers stay out
    assert _layer("robotplan.hanging.program.x") == _layer("robotplan.program.x")
    assert _layer("robotplan.pushing.program.x") == _layer("robotplan.program.x")
    assert _layer("robotplan.hanging.cli.x") > _layer("robotplan.hanging.search.x")
    assert _named_after_hanging("robotplan.geometry.hang_x")
    assert _named_after_hanging("robotplan.pushing.search.hang_x")
    assert not _named_after_hanging("robotplan.hanging.search.hang_x")
    for entry in ([("robotplan.hanging.search.optimise", [], 3)],
                  [("robotplan.pushing.search.x", [], 3)]):
        assert _slice_entries("robotplan.functionals.x", entry)
        assert not _slice_entries("robotplan.api", entry)
    assert _slice_entries("robotplan.api", [("robotplan.hanging.cli.commands", [], 3)])
    # a slice imports the core and itself, never the other slice
    assert not _slice_entries("robotplan.pushing.api.x", [("robotplan.pushing.search.x", [], 3),
                                                          ("robotplan.functionals.x", [], 4)])
    assert _slice_entries("robotplan.hanging.api.x", [("robotplan.pushing.search.x", [], 3)])


# a condition that tells a scene's kind from its raw fields: arms or pushers present, the
# goal's type or class, the count of objects, a plan's class (the family dispatch reads the
# task's ``family`` instead)
KIND_TEST = re.compile(r"\.(robots|pushers)\b|\bgoal\.type\b|\.goal\)|"
                       r"isinstance\([^)]*(Goal|Plan)\b|getattr\([^)]*\.goal\b|"
                       r"len\([^)]*\.objects\)|\b(chain_target|scene_classes)\(")
TASK_MODULES = ("robotplan.scene",)  # the task module and the scene file layer
MAX_PARAMETERS = 6  # besides self / cls, in the search and the programs
FEW_PARAMETERS = ("search", "program")


def _conditions(tree: ast.AST) -> list[ast.expr]:
    """Every expression that decides something: tests of if / while / assert, conditional
    expressions, comprehension filters, the operands of and / or, isinstance and bool."""
    out: list[ast.expr] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.If | ast.IfExp | ast.While | ast.Assert):
            out.append(node.test)
        elif isinstance(node, ast.comprehension):
            out += node.ifs
        elif isinstance(node, ast.BoolOp):
            out += node.values
        elif isinstance(node, ast.Call) and getattr(node.func, "id", "") in ("isinstance",
                                                                             "bool"):
            out.append(node)
    return out


def _kind_tests(tree: ast.AST) -> list[tuple[int, str]]:
    """``(line, condition)`` of each condition that reads a scene's kind from raw fields."""
    found = {(c.lineno, ast.unparse(c)) for c in _conditions(tree)}
    return sorted((line, text) for line, text in found if KIND_TEST.search(text))


def test_the_task_is_made_once():
    """Outside the scene file layer (where the task module builds the task), no condition
    reads what kind of scene it is from the scene's fields: layers get the task."""
    bad = [f"{MODULES[m].relative_to(PACKAGE.parent)}:{line}: {text}"
           for m, path in MODULES.items() if not m.startswith(TASK_MODULES)
           for line, text in _kind_tests(ast.parse(path.read_text()))]
    assert not bad, "read the task instead (robotplan.scene.task):\n" + "\n".join(bad)


def _parameters(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    a = fn.args
    names = [x.arg for x in (*a.posonlyargs, *a.args, *a.kwonlyargs)]
    return (len([n for n in names if n not in ("self", "cls")]) + (a.vararg is not None)
            + (a.kwarg is not None))


def _long_signatures(tree: ast.AST) -> list[tuple[int, str, int]]:
    return [(fn.lineno, fn.name, n) for fn in ast.walk(tree)
            if isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef)
            and (n := _parameters(fn)) > MAX_PARAMETERS]


def test_search_and_programs_take_few_parameters():
    """A function of the search or the programs takes at most MAX_PARAMETERS besides
    ``self``: what a search needs travels in a frozen request, a program gets a task."""
    bad = [f"{MODULES[m].relative_to(PACKAGE.parent)}:{line} {name}: {n} parameters"
           for m, path in MODULES.items() if _layer_name(m) in FEW_PARAMETERS
           for line, name, n in _long_signatures(ast.parse(path.read_text()))]
    assert not bad, "\n".join(bad)


def test_the_task_and_parameter_checks_can_fail():
    tree = ast.parse("def f(scene, a, b, c, d, e, g):\n"
                     "    if scene.robots or scene.goal.type == 'pose':\n"
                     "        return [o for o in scene.objects\n"
                     "                if isinstance(scene.goal, PoseGoal)]\n"
                     "    return bool(task.arms)\n")
    assert [line for line, _ in _kind_tests(tree)] == [2, 2, 2, 4]
    assert _long_signatures(tree) == [(1, "f", 7)]
    assert not _kind_tests(ast.parse("for robot in scene.robots:\n    x = task.arms\n"))


MAX_PROGRAM_SETTINGS = 25  # what is per row lives in the row table, per tier in the tiers


def test_program_settings_stay_few():
    """``ProgramSettings`` holds the solver's options and the two-stage scheme; the rows'
    constants are the row table's (``skeletons/rows.yaml``)."""
    from dataclasses import fields

    from robotplan.pushing.program.settings import ProgramSettings

    names = [f.name for f in fields(ProgramSettings)]
    assert len(names) <= MAX_PROGRAM_SETTINGS, names
