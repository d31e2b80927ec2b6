"""The package's layers, read from its imports (issue 11): data flows one way, and nothing imports in a circle.

Every ``import`` in ``symkin/`` is read, at module level and inside functions, and resolved to the
symkin module it loads, including the parent packages whose ``__init__`` runs first; imports under
``if TYPE_CHECKING:`` count too (a type that must point up goes through a protocol of the lower layer, as
``symkin.ir.quantity.Deriving`` for the derivation graph), and so does an import of the root ``symkin`` facade
(the api layer; only as a parent package run first it does not count).  A module may import from its
own layer or from a lower one, never from a higher one; and no set of modules may import each
other in a circle, however indirectly.  The layers, lowest first, are LAYERS below, which
docs/architecture.md renders.  A part is a top-level module or package of symkin, or a pattern of dotted
names: a backend's folder holds its loader (``backends/*/loader*``), which belongs to the runtime layer, above
the emitter beside it; the backend names it by a string that the runtime imports.

``KNOWN_UPWARD`` and ``KNOWN_CYCLES`` list the exceptions that exist today (a ratchet): the test
fails on any new one, and on a listed one that has gone, so that each fix shortens the list.
"""

from __future__ import annotations

import ast
import fnmatch
from collections import defaultdict
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "symkin"

#: Lowest first.  Each entry: the layer's name and its top-level modules or packages of symkin.
LAYERS = (
    ("foundation", {"_version", "errors", "atomic", "cache_trust", "expression_dag", "symengine_bridge", "text_table", "lazy",
                    "reporting", "newton", "numerics"}),
    ("model", {"model", "geometry"}),
    ("structure", {"structure"}),
    ("ir", {"ir"}),
    ("derivation", {"derivation", "kinematics", "dynamics", "parallel"}),
    ("optimize", {"optimize"}),
    ("backends", {"backends", "manifest", "manifest_schema", "pipeline", "pipeline_cache"}),
    ("runtime", {"runtime", "backends.*.loader*"}),
    ("mechanism", {"mechanism"}),
    ("analyses", {"ik", "integration", "analysis", "rating", "design", "identification", "references", "simulation", "stability",
                  "viewer"}),
    ("api", {"api"}),
    ("cli", {"cli", "__main__"}),
)
RANK = {part: rank for rank, (_name, parts) in enumerate(LAYERS) for part in parts if "*" not in part}
#: The parts that are patterns of dotted names below symkin (a backend's loader), before the top-level parts.
PATTERNS = {part: rank for rank, (_name, parts) in enumerate(LAYERS) for part in parts if "*" in part}
#: What each layer holds, for the table docs/architecture.md renders from LAYERS (checked below).
ROLES = {
    "foundation": "errors, atomic writes, trust in the cache folder, the version, expression graphs, the SymEngine bridge, text tables, "
                  "packages imported lazily, progress reports of long work, the batched Newton solver of every closure, "
                  "numerics: sampling, Sobol points and the conditioning of Jacobians",
    "model": "the model format: reading, validating, the schema; geometry",
    "structure": "mobility and topology synthesis",
    "ir": "`FunctionSpec`, `OptimizedFunction`, inputs, op counts, `QuantityDef`",
    "derivation": "the derivation graph and its catalog; serial kinematics and dynamics; parallel mechanisms",
    "optimize": "expression optimization",
    "backends": "the emitters, the manifest and its schema, the pipeline and its derivation cache",
    "runtime": "each backend's loader, the bindings they share, the numerical kinematics of parallel mechanisms",
    "mechanism": "the run-time mechanism every analysis asks: coordinates, limits, kinds, the passive joints' closure, "
                 "reachability through inverse kinematics and by continuation",
    "analyses": "inverse kinematics, integration (GCI integrators), analyses (workspace, GCI), rating, design, identification, "
                "references (the cross-checks), simulation, numerical stability, the viewer",
    "api": "the public functions, and the `symkin` package facade",
    "cli": "the commands",
}
ARCHITECTURE = PACKAGE.parent / "docs" / "architecture.md"


def layer_table() -> list[str]:
    """The rows of docs/architecture.md's layer table, rendered from LAYERS (packages as `name/`)."""
    def shown(part: str) -> str:
        if "*" in part:
            return f"`{part.replace('.', '/')}`"
        return f"`{part}/`" if (PACKAGE / part).is_dir() else f"`{part}`"
    rows = ["| layer | packages and modules | what it holds |", "|---|---|---|"]
    for name, parts in LAYERS:
        rows.append(f"| {name} | {', '.join(shown(p) for p in sorted(parts, key=lambda p: p.lstrip('_')))} | "
                    f"{ROLES[name]} |")
    return rows


def test_the_architecture_document_renders_the_layers_written_here():
    """The layer order is written once, in LAYERS above; docs/architecture.md's table is its rendering, and
    README.md points there instead of listing the layers again."""
    lines = ARCHITECTURE.read_text().splitlines()
    start = lines.index("| layer | packages and modules | what it holds |")
    rendered = layer_table()
    assert lines[start:start + len(rendered)] == rendered, "\n".join(["replace the table with:"] + rendered)
    readme = (PACKAGE.parent / "README.md").read_text()
    assert "docs/architecture.md" in readme
    assert "1. foundation:" not in readme
ROOT_PACKAGE = "symkin"

#: Imports against the layer order that exist today: (importer, imported).  Shrinks to empty.
KNOWN_UPWARD: set[tuple[str, str]] = set()

#: Import cycles that exist today, each as the set of its modules.  Shrinks to empty.
KNOWN_CYCLES: set[frozenset[str]] = set()


def modules(package: Path = PACKAGE) -> dict[str, Path]:
    """Every module of the package by dotted name (a package by its own name)."""
    found = {}
    for path in package.rglob("*.py"):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        found[".".join(parts)] = path
    return found


def _imported_names(module: str, path: Path, node: ast.Import | ast.ImportFrom, known: dict) -> list[str]:
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    base = node.module or ""
    if node.level:
        parts = package.split(".")
        base = ".".join(parts[:len(parts) - node.level + 1] + ([base] if base else []))
    # `from package import name` loads the submodule `name` when there is one
    return [f"{base}.{alias.name}" if f"{base}.{alias.name}" in known else base for alias in node.names]


def _annotation_only(tree: ast.Module) -> set[int]:
    """ids of the imports under ``if TYPE_CHECKING:``: names for annotations, never executed."""
    guarded = [n for n in ast.walk(tree) if isinstance(n, ast.If) and (
        (isinstance(n.test, ast.Name) and n.test.id == "TYPE_CHECKING")
        or (isinstance(n.test, ast.Attribute) and n.test.attr == "TYPE_CHECKING"))]
    return {id(i) for g in guarded for statement in g.body for i in ast.walk(statement)}


def import_graph(package: Path = PACKAGE, *, annotations: bool = True) -> dict[str, set[str]]:
    """module -> the symkin modules it imports (anywhere in it), with the packages they run first.

    With ``annotations`` (the layer order's count) the imports under ``if TYPE_CHECKING:`` count too (a type
    that must point up goes through a protocol of the lower layer), and so does an import of the root facade
    (``from symkin import load``: the api layer).  Without, the graph is what runs.
    """
    known = modules(package)
    graph: dict[str, set[str]] = defaultdict(set)
    for module, path in known.items():
        tree = ast.parse(path.read_text(), str(path))
        skipped = set() if annotations else _annotation_only(tree)
        for node in ast.walk(tree):
            if not isinstance(node, (ast.Import, ast.ImportFrom)) or id(node) in skipped:
                continue
            for name in _imported_names(module, path, node, known):
                if not name.startswith("symkin"):
                    continue
                while name not in known and "." in name:
                    name = name.rsplit(".", 1)[0]
                if annotations and name == ROOT_PACKAGE and module != ROOT_PACKAGE:
                    graph[module].add(ROOT_PACKAGE)  # the facade itself, not a parent package run first
                target = name
                while target.count("."):  # the module and its parent packages, the root facade excepted
                    if target in known and target != module and not module.startswith(target + "."):
                        graph[module].add(target)
                    target = target.rsplit(".", 1)[0]
    return graph


def layer_of(module: str) -> int:
    """The layer of a module; the root package (the public facade: load, derive) is the api's."""
    parts = module.split(".")
    inner = ".".join(parts[1:])
    for pattern, rank in PATTERNS.items():
        if fnmatch.fnmatchcase(inner, pattern):
            return rank
    return RANK[parts[1] if len(parts) > 1 else "api"]


def upward_imports(graph: dict[str, set[str]]) -> set[tuple[str, str]]:
    return {(a, b) for a, targets in graph.items() for b in targets if layer_of(a) < layer_of(b)}


def cycles(graph: dict[str, set[str]]) -> set[frozenset[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = set()
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.add(frozenset(component))
    return found


def test_every_module_belongs_to_a_layer():
    assert {m.split(".")[1] for m in modules() if "." in m} <= set(RANK), "add the new package to LAYERS"


def test_no_import_goes_against_the_layer_order():
    upward = upward_imports(import_graph())
    new = sorted(upward - KNOWN_UPWARD)
    assert not new, "imports from a higher layer (move the code down, or the import up):\n" + "\n".join(
        f"{a} ({LAYERS[layer_of(a)][0]}) -> {b} ({LAYERS[layer_of(b)][0]})" for a, b in new)
    gone = sorted(KNOWN_UPWARD - upward)
    assert not gone, f"fixed: remove from KNOWN_UPWARD: {gone}"


def test_no_import_cycles():
    found = cycles(import_graph())
    new = [sorted(c) for c in found - KNOWN_CYCLES]
    assert not new, f"import cycles: {new}"
    gone = [sorted(c) for c in KNOWN_CYCLES - found]
    assert not gone, f"fixed or changed: update KNOWN_CYCLES: {gone}"


def test_the_reader_sees_function_level_and_relative_imports_and_the_packages_they_run(tmp_path):
    package = tmp_path / "symkin"
    (package / "low").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "low" / "__init__.py").write_text("from symkin.low.base import thing\n")
    (package / "low" / "base.py").write_text("def thing():\n    from ..high import use\n    return use\n")
    (package / "low" / "other.py").write_text("from typing import TYPE_CHECKING\nfrom . import base\nimport numpy\n"
                                              "if TYPE_CHECKING:\n    from symkin.high import use\n")
    (package / "high.py").write_text("from symkin.low import other\nuse = 1\n")
    (package / "low" / "facade_user.py").write_text("def f():\n    from symkin import thing\n    return thing\n")
    running = import_graph(package, annotations=False)
    assert running["symkin.low.base"] == {"symkin.high"}  # inside a function, relative
    assert running["symkin.high"] == {"symkin.low.other", "symkin.low"}  # the package's __init__ runs first
    assert running["symkin.low.other"] == {"symkin.low.base"}
    assert "symkin.low.facade_user" not in running
    assert cycles(running) == {frozenset({"symkin.low", "symkin.low.base", "symkin.low.other", "symkin.high"})}
    counted = import_graph(package)  # the layer order's count: type-only imports and the facade too
    assert counted["symkin.low.other"] == {"symkin.low.base", "symkin.high"}
    assert counted["symkin.low.facade_user"] == {"symkin"}


#: A module longer than this says why in its docstring (a paragraph starting ``Length:``).
MODULE_LINES = 400


def test_long_modules_say_why_they_are_long():
    unexplained = []
    for module, path in sorted(modules().items()):
        text = path.read_text()
        lines = text.count("\n")
        docstring = ast.get_docstring(ast.parse(text)) or ""
        if lines > MODULE_LINES and "\nLength:" not in "\n" + docstring:
            unexplained.append(f"{module} ({lines} lines)")
    assert not unexplained, f"split these modules by job, or say why not ('Length: ...' in the docstring): {unexplained}"
