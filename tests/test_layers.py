"""The layers of acdrive, read from the import statements of its sources (no import is executed).

The engine and the parts (``sim``, ``core``, ``plant``, ``machines``, ``control``) import only one
another and acdrive's top-level helper modules (``_cache``, ``_jit``, ``errors``, ...), at any
level: no drive, no export, nothing else above them. The C of the parts and the generators of a
system's C (``sim._ccode``) are the engine's: its native tier (``sim._native``) runs them, and the
plant's C integrates with its Runge-Kutta tableau (``sim._integrators``); the export
(``acdrive.export``) builds on them from above; every part kind's C, a drive's own controller
kinds' among them, is generated from its kernels on its first look-up, so the C registry names
no part kind. The drives build on the engine; scenarios, batches, sweeps, the analysis and the
commands reach a drive only through the registry (``acdrive.drives._registry``, whose ``BUILTIN`` table is the one place
that names a drive's package). Module-level imports must form no cycle, so every module can be
imported on its own.

Edges are resolved as Python resolves them: ``from acdrive.x import y`` is an edge to the module
``acdrive.x.y`` if there is one, else to the module a lazy namespace (``acdrive._lazy.namespace``
in ``acdrive/x/__init__.py``) maps ``y`` to, else to ``acdrive.x``. Imports under ``if
TYPE_CHECKING:`` are not run and are left out; imports inside a function are collected apart (they
run when the function is called, so they cannot make an import-time cycle).

``python tests/test_layers.py`` prints the module-level and the function-level cycles.
"""

from __future__ import annotations

import ast
import itertools
import sys
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[1] / "src"
PACKAGE = "acdrive"
#: the layers below the drives and the export (``sim`` with its C, ``sim._ccode``): they import
#: only one another and acdrive's top-level helper modules, and name no drive kind
ENGINE_LAYERS = ("sim", "core", "plant", "machines", "control")
#: the drive packages, which only acdrive.drives itself (and the registry's BUILTIN) may name
DRIVE_PACKAGES = ("acdrive.drives.dfim", "acdrive.drives.cage_im", "acdrive.drives.pm")
#: the drive kinds as a scenario names them
DRIVE_KINDS = ("dfim", "cage-im", "cage_im", "pm")


def module_files(root: Path = SOURCE) -> dict[str, Path]:
    """Dotted module name -> its file, for every module of the package under ``root``."""
    files = {}
    for path in sorted((root / PACKAGE).rglob("*.py")):
        parts = path.relative_to(root).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        files[".".join(parts)] = path
    return files


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.Module):
    """(import node, where) for every import: where is "module" (runs on import), "function"
    (runs when a function is called) or "typing" (under ``if TYPE_CHECKING``: never runs)."""

    def walk(node, where):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child.test):
                for stmt in child.body:
                    yield from walk_one(stmt, "typing")
                for stmt in child.orelse:
                    yield from walk_one(stmt, where)
                continue
            yield from walk_one(child, where)

    def walk_one(node, where):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node, where
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            yield from walk(node, "function" if where == "module" else where)
        else:
            yield from walk(node, where)

    yield from walk(tree, "module")


def _lazy_exports(module: str, tree: ast.Module) -> dict[str, str]:
    """A package's lazy names (``namespace(__name__, {name: ".module"})``) -> absolute module."""
    exports = {}
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Call)
            and getattr(node.func, "id", None) == "namespace"
            and len(node.args) == 2
            and isinstance(node.args[1], ast.Dict)
        ):
            for key, value in zip(node.args[1].keys, node.args[1].values):
                if isinstance(key, ast.Constant) and isinstance(value, ast.Constant):
                    exports[key.value] = _absolute(module, value.value, is_package=True)
    return exports


def _absolute(module: str, name: str, is_package: bool, level: int | None = None) -> str:
    """The absolute name of ``name`` imported relatively from ``module``."""
    if level is None:
        level = len(name) - len(name.lstrip("."))
        name = name[level:]
    if level == 0:
        return name
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([name] if name else []))


class ImportGraph:
    """The import edges between acdrive's modules, module-level and function-level apart."""

    def __init__(self, root: Path = SOURCE):
        self.files = module_files(root)
        self.trees = {m: ast.parse(p.read_text(), str(p)) for m, p in self.files.items()}
        self.lazy = {m: _lazy_exports(m, t) for m, t in self.trees.items()}
        #: module -> {imported module: first line}, for imports that run when it is imported
        self.module_level: dict[str, dict[str, int]] = {m: {} for m in self.files}
        #: module -> {imported module: first line}, for imports inside its functions
        self.function_level: dict[str, dict[str, int]] = {m: {} for m in self.files}
        #: module -> {imported module: first line}, for imports only a type checker reads
        self.typing_only: dict[str, dict[str, int]] = {m: {} for m in self.files}
        kinds = {"module": self.module_level, "function": self.function_level}
        kinds["typing"] = self.typing_only
        for module, tree in self.trees.items():
            is_package = self.files[module].name == "__init__.py"
            for node, where in _imports(tree):
                edges = kinds[where]
                for target in self._targets(module, node, is_package):
                    if target != module:
                        edges[module].setdefault(target, node.lineno)

    def all_imports(self) -> dict[str, dict[str, int]]:
        """Module -> {imported module: line}, module-level, function-level and typing-only."""
        return {
            m: {**self.typing_only[m], **self.function_level[m], **self.module_level[m]}
            for m in self.files
        }

    def _resolve(self, name: str) -> str | None:
        """The acdrive module ``name`` is, or lies in (an attribute of a module), or None."""
        while name and name not in self.files:
            name = name.rpartition(".")[0]
        return name or None

    def _targets(self, module: str, node, is_package: bool) -> list[str]:
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names if alias.name.startswith(PACKAGE)]
            return [t for t in map(self._resolve, names) if t]
        base = _absolute(module, node.module or "", is_package, node.level)
        if base != PACKAGE and not base.startswith(PACKAGE + "."):
            return []
        targets = []
        for alias in node.names:
            full = f"{base}.{alias.name}"
            if full in self.files:
                targets.append(full)
            elif alias.name in self.lazy.get(base, {}):
                targets.append(self._resolve(self.lazy[base][alias.name]))
            else:
                targets.append(self._resolve(base))
        return [t for t in targets if t]

    def cycles(self, edges: dict[str, dict[str, int]]) -> list[list[str]]:
        """One cycle through each strongly connected set of more than one module, shortest
        first."""
        return sorted((self._one_cycle(edges, c) for c in self.components(edges)), key=len)

    @staticmethod
    def components(edges: dict[str, dict]) -> list[set[str]]:
        """Every strongly connected set of more than one node (Tarjan)."""
        index, low, stack, on_stack, found = {}, {}, [], set(), []
        counter = [0]

        def visit(v):
            index[v] = low[v] = counter[0]
            counter[0] += 1
            stack.append(v)
            on_stack.add(v)
            for w in edges.get(v, {}):
                if w not in index:
                    visit(w)
                    low[v] = min(low[v], low[w])
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
            if low[v] == index[v]:
                component = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    component.append(w)
                    if w == v:
                        break
                if len(component) > 1:
                    found.append(set(component))

        sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
        for v in sorted(edges):
            if v not in index:
                visit(v)
        return found

    @staticmethod
    def _one_cycle(edges, component: set[str]) -> list[str]:
        """A shortest cycle through the first (sorted) member of a strongly connected set."""
        start = min(component)
        paths, seen = {start: [start]}, {start}
        frontier = [start]
        while frontier:
            following = []
            for v in frontier:
                for w in sorted(edges.get(v, {})):
                    if w == start:
                        return paths[v] + [start]
                    if w in component and w not in seen:
                        seen.add(w)
                        paths[w] = paths[v] + [w]
                        following.append(w)
            frontier = following
        return [start]

    def describe(self, cycle: list[str], edges) -> str:
        """The cycle as ``a (line n) -> b (line m) -> ... -> a``."""
        steps = [f"{a} (line {edges[a][b]})" for a, b in itertools.pairwise(cycle)]
        return " -> ".join([*steps, cycle[-1]])


def _strings(tree: ast.Module):
    """(string constant, line) for every string in the code that is not a docstring."""
    docstrings = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                docstrings.add(id(body[0].value))
    for node in ast.walk(tree):
        is_string = isinstance(node, ast.Constant) and isinstance(node.value, str)
        if is_string and id(node) not in docstrings:
            yield node.value, node.lineno


def _in(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


GRAPH = ImportGraph()


def test_the_graph_sees_the_drives_and_the_registry():
    """The reader itself: it finds the registry importing nothing of a drive at module level and
    the PM plug-in importing the registry, so an empty list below means something."""
    assert "acdrive.drives._registry" in GRAPH.files
    pm_edges = GRAPH.module_level["acdrive.drives.pm._plugin"]
    assert "acdrive.drives._registry" in pm_edges
    assert not any(
        _in(t, p) for t in GRAPH.module_level["acdrive.drives._registry"] for p in DRIVE_PACKAGES
    )


def test_the_graph_sees_the_engines_c_from_both_sides():
    """The reader finds the engine's native tier importing the engine's C inside a function and
    the export importing it from above, so an empty list of upward imports means something."""
    assert "acdrive.sim._ccode._c_source" in GRAPH.function_level["acdrive.sim._native"]
    assert "acdrive.sim._ccode._c_source" in GRAPH.module_level["acdrive.export._fmu"]


def test_the_c_registry_names_no_part_kind():
    """Every kind's C is generated from its kernels on its first look-up: the registry and the
    translator import no module of the parts (``control``, ``plant``, ``machines``) nor of a
    drive, at any level."""
    registry = [m for m in GRAPH.files if _in(m, f"{PACKAGE}.sim._ccode")]
    assert f"{PACKAGE}.sim._ccode._kinds" in registry
    parts = [f"{PACKAGE}.{p}" for p in ("control", "plant", "machines", "drives")]
    named = sorted(f"{m} -> {t}" for m in registry
                   for t in [*GRAPH.module_level[m], *GRAPH.function_level[m]]
                   if any(_in(t, p) for p in parts))  # fmt: skip
    assert not named, named


def test_no_module_level_import_cycle():
    cycles = GRAPH.cycles(GRAPH.module_level)
    assert not cycles, "module-level import cycles:\n" + "\n".join(
        GRAPH.describe(c, GRAPH.module_level) for c in cycles
    )


def test_no_import_cycle_even_inside_functions():
    """Nor do imports inside functions or for a type checker close a cycle: each such cycle was a
    shared thing living in the wrong module (they were moved where they belong)."""
    every = GRAPH.all_imports()
    cycles = GRAPH.cycles(every)
    assert not cycles, "import cycles:\n" + "\n".join(GRAPH.describe(c, every) for c in cycles)


def _in_engine(module: str) -> bool:
    return any(_in(module, f"{PACKAGE}.{layer}") for layer in ENGINE_LAYERS)


def _is_top_level_helper(graph: ImportGraph, module: str) -> bool:
    """A single-file module directly under acdrive/ (``acdrive._cache``, ``acdrive.errors``)."""
    return module.count(".") == 1 and graph.files[module].name != "__init__.py"


def engine_imports_above(graph: ImportGraph) -> list[str]:
    """Every import of an engine module (at module or function level, or for a type checker)
    of a module that is neither in the engine layers nor a top-level helper module: acdrive.export,
    acdrive.drives, or anything else above the engine."""
    bad = []
    for module, targets in graph.all_imports().items():
        if not _in_engine(module):
            continue
        for target, line in targets.items():
            if not (_in_engine(target) or _is_top_level_helper(graph, target)):
                bad.append(f"{module} line {line} imports {target}")
    return bad


def test_engine_layers_import_only_downward():
    """sim (with its C, sim._ccode), core, plant, machines and control import nothing of
    acdrive.export or acdrive.drives, nor of any other layer above them, at any level: only one
    another and the top-level helper modules."""
    bad = engine_imports_above(GRAPH)
    assert not bad, "\n".join(bad)


def test_engine_layers_know_no_drive():
    """sim, core, plant, machines and control name no drive kind in a string of their code (their
    imports: the test above)."""
    bad = []
    for module in GRAPH.files:
        if not _in_engine(module):
            continue
        for text, line in _strings(GRAPH.trees[module]):
            if text in DRIVE_KINDS or any(_in(text, p) for p in DRIVE_PACKAGES):
                bad.append(f"{module} line {line} names the drive {text!r}")
    assert not bad, "\n".join(bad)


#: The modules outside acdrive/drives that are about one paper's drive and still import its
#: package: the reproductions of Bodson's DFIM experiments and of the cage-IM paper's, and the
#: whole-drive linearisation of Bodson's DFIM drive with its command. Each is one drive's by its
#: subject, not by dispatch; they would move into their drive's folder (and the linearisation
#: behind a ``Drive`` method) to leave this list. The list only shrinks: a module that no longer
#: imports a drive must leave it (test below), a new one cannot join without an edit here.
ONE_DRIVE_MODULES = {
    "acdrive._report.bodson.discussion": "Bodson reproduction",
    "acdrive._report.bodson.experiments": "Bodson reproduction",
    "acdrive._report.bodson.verdicts": "Bodson reproduction",
    "acdrive._report.bodson.numbers": "Bodson reproduction",
    "acdrive._report.bodson.run_figures": "Bodson reproduction",
    "acdrive._report.limit_cycle_summary": "Bodson reproduction",
    "acdrive._report.speed_overshoot": "Bodson reproduction",
    "acdrive._report.im.figures": "cage-IM paper reproduction",
    "acdrive._report.im.numbers": "cage-IM paper reproduction",
    "acdrive._report.im.sections": "cage-IM paper reproduction",
}


def drive_package_uses() -> dict[str, list[str]]:
    """Module -> where it imports (at any level) or names (as a dotted module path in a string of
    its code) a drive package that is not its own. Inside acdrive/drives that is one drive
    reaching into another; the registry's ``BUILTIN`` table is the one place allowed to name
    them."""
    uses: dict[str, list[str]] = {}
    for module in GRAPH.files:
        own = next((p for p in DRIVE_PACKAGES if _in(module, p)), None)
        for edges in (GRAPH.module_level, GRAPH.function_level):
            for target, line in edges[module].items():
                for package in DRIVE_PACKAGES:
                    if _in(target, package) and package != own:
                        uses.setdefault(module, []).append(f"line {line} imports {target}")
        if own is not None:
            continue
        builtin_lines = _builtin_table_lines(module)
        for text, line in _strings(GRAPH.trees[module]):
            if any(_in(text, p) for p in DRIVE_PACKAGES) and line not in builtin_lines:
                uses.setdefault(module, []).append(f"line {line} names {text!r}")
    return uses


def test_only_the_drives_import_a_drive_package():
    """Outside acdrive/drives, no module imports or names a specific drive's package (but the
    one-drive modules listed, each for its subject); no drive reaches into another."""
    uses = drive_package_uses()
    bad = [f"{m} {where}" for m in sorted(uses) if m not in ONE_DRIVE_MODULES for where in uses[m]]
    assert not bad, "\n".join(bad)


def test_the_one_drive_list_only_shrinks():
    """Every listed module still imports its drive: one that stopped leaves the list."""
    uses = drive_package_uses()
    gone = sorted(m for m in ONE_DRIVE_MODULES if m not in uses)
    assert not gone, f"no longer import a drive package, remove from ONE_DRIVE_MODULES: {gone}"


def _builtin_table_lines(module: str) -> set[int]:
    """The lines of the registry's ``BUILTIN = {...}`` assignment (empty for other modules)."""
    if module != "acdrive.drives._registry":
        return set()
    for node in GRAPH.trees[module].body:
        targets = getattr(node, "targets", None) or [getattr(node, "target", None)]
        if any(getattr(t, "id", None) == "BUILTIN" for t in targets):
            return set(range(node.lineno, node.end_lineno + 1))
    return set()


def test_a_planted_cycle_and_a_planted_drive_import_are_seen(tmp_path):
    """The checks can fail: a copy of two modules importing each other, an engine module
    importing a drive, and one importing the export inside a function, are found by the same
    reader; an import of a top-level helper module is not."""
    package = tmp_path / PACKAGE
    (package / "sim").mkdir(parents=True)
    (package / "drives" / "pm").mkdir(parents=True)
    (package / "export").mkdir(parents=True)
    for folder in (package, package / "sim", package / "drives", package / "drives" / "pm",
                   package / "export"):  # fmt: skip
        (folder / "__init__.py").write_text("")
    (package / "sim" / "a.py").write_text("from acdrive.sim import b\n")
    (package / "sim" / "b.py").write_text(
        "from . import a\nfrom acdrive.drives.pm import _plugin\n"
    )
    (package / "sim" / "c.py").write_text(
        "from acdrive import _cache\n\ndef native():\n    from acdrive.export import _native\n"
    )
    (package / "_cache.py").write_text("")
    (package / "export" / "_native.py").write_text("")
    (package / "drives" / "pm" / "_plugin.py").write_text("import acdrive.sim.a\n")
    graph = ImportGraph(tmp_path)
    cycles = graph.cycles(graph.module_level)
    assert [set(c) for c in cycles] == [
        {"acdrive.sim.a", "acdrive.sim.b", "acdrive.drives.pm._plugin"}
    ]
    assert "acdrive.drives.pm._plugin" in graph.module_level["acdrive.sim.b"]
    assert engine_imports_above(graph) == [
        "acdrive.sim.b line 2 imports acdrive.drives.pm._plugin",
        "acdrive.sim.c line 4 imports acdrive.export._native",
    ]


def _package(module: str) -> str:
    """The layer a module belongs to: its subpackage (a drive's own package for a drive)."""
    parts = module.split(".")
    if len(parts) > 3 and parts[1] == "drives":
        return ".".join(parts[:3])
    return ".".join(parts[:2])


def main() -> None:
    """Print the imports of the engine layers from above them, the cycles among modules
    (module-level imports; then all imports, function-level and typing-only included) and among
    subpackages (all imports)."""
    upward = engine_imports_above(GRAPH)
    print(f"{len(upward)} import(s) of the engine layers from above them, all imports")
    for line in upward:
        print("  " + line)
    every = GRAPH.all_imports()
    for label, edges in (("module-level", GRAPH.module_level), ("all", every)):
        cycles = GRAPH.cycles(edges)
        print(f"{len(cycles)} module cycle(s), {label} imports")
        for cycle in cycles:
            print("  " + GRAPH.describe(cycle, edges))
    packages: dict[str, dict[str, str]] = {}
    for module, targets in every.items():
        for target in targets:
            a, b = _package(module), _package(target)
            if a != b:
                packages.setdefault(a, {}).setdefault(b, f"{module} -> {target}")
    for component in GRAPH.components(packages):
        print("subpackages importing each other, all imports: " + ", ".join(sorted(component)))
        for a in sorted(component):
            for b in sorted(set(packages[a]) & component):
                print(f"  {a} -> {b}: {packages[a][b]}")


if __name__ == "__main__":
    main()
