"""Import cycles and upward imports between the project's modules:
``python -m benchmarks.checks.import_cycles``.

Reads every module of the packages (default: auv_gym, controllers, benchmarks) with `ast`, without
importing them, and follows every import statement, also those inside functions (a deferred
import hides a cycle from the interpreter, not from a reader). ``from a import b`` is an edge to
``a.b`` when that is a module, else to ``a``; a module's implicit import of its parent packages is
not an edge. Imports under ``if TYPE_CHECKING:`` are skipped.

Prints each cycle (a strongly connected component of the graph) and each upward import: an import
against the one direction of `LAYERS` (auv_gym's rooms support → paths → vehicle, ocean → sim →
envs → the top of auv_gym; then controllers, then benchmarks; docs/architecture.md). Exits 1 if
there is either, 0 otherwise.
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

__all__ = ["LAYERS", "find_cycles", "import_graph", "layer_of", "main", "upward_imports"]

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("auv_gym", "controllers", "benchmarks")

_MODEL = ("auv_gym.support", "auv_gym.paths")
_CORE = (*_MODEL, "auv_gym.vehicle", "auv_gym.ocean", "auv_gym.sim")
_AUV_GYM = (*_CORE, "auv_gym.envs", "auv_gym")
# Layer → the layers its modules may import besides their own. A module belongs to the longest
# layer name it starts with: ``auv_gym.sim.config`` to auv_gym.sim, ``auv_gym.rollout`` to the top
# of auv_gym (registration and the evaluation API: ``__init__``, rollout, metrics). vehicle and
# ocean are peers: neither imports the other.
LAYERS: dict[str, tuple[str, ...]] = {
    "auv_gym.support": (),
    "auv_gym.paths": ("auv_gym.support",),
    "auv_gym.vehicle": _MODEL,
    "auv_gym.ocean": _MODEL,
    "auv_gym.sim": _CORE[:-1],
    "auv_gym.envs": _CORE,
    "auv_gym": _AUV_GYM[:-1],
    "controllers": _AUV_GYM,
    "benchmarks": (*_AUV_GYM, "controllers"),
}


def _modules(root: Path, packages: Sequence[str]) -> dict[str, Path]:
    """Dotted module name → file, for every .py file under the packages."""
    found: dict[str, Path] = {}
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            found[name] = path
    return found


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST, module: str, is_package: bool) -> set[tuple[str, ...]]:
    """What ``module`` imports, as candidates (most specific first): ``import a.b`` gives
    ("a.b",), ``from a import b`` gives ("a.b", "a"); relative imports resolved."""
    found: set[tuple[str, ...]] = set()
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and _is_type_checking(node):
            stack.extend(node.orelse)
            continue
        if isinstance(node, ast.Import):
            found.update((alias.name,) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = module.split(".")
                anchor = anchor[: len(anchor) - node.level + (1 if is_package else 0)]
                base = ".".join([*anchor, *([base] if base else [])])
            found.update((f"{base}.{alias.name}", base) for alias in node.names)
        stack.extend(ast.iter_child_nodes(node))
    return found


def import_graph(root: Path = ROOT, packages: Sequence[str] = PACKAGES) -> dict[str, set[str]]:
    """Module → the project modules it imports (`_imports`, each resolved to the most specific
    candidate that is a module of the packages)."""
    modules = _modules(root, packages)
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        targets = set()
        for candidates in _imports(tree, name, path.name == "__init__.py"):
            target = next((c for c in candidates if c in modules), None)
            if target is not None and target != name:
                targets.add(target)
        graph[name] = targets
    return graph


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module, each sorted (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    cycles: list[list[str]] = []
    counter = 0

    def visit(v: str) -> None:
        nonlocal counter
        index[v] = low[v] = counter
        counter += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
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
                cycles.append(sorted(component))

    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 10 * len(graph) + 100))
    try:
        for v in sorted(graph):
            if v not in index:
                visit(v)
    finally:
        sys.setrecursionlimit(limit)
    return sorted(cycles)


def layer_of(module: str, layers: Mapping[str, Sequence[str]] = LAYERS) -> str | None:
    """The layer of ``module``: the longest layer name it is or starts with (None: no layer)."""
    found = [name for name in layers if module == name or module.startswith(f"{name}.")]
    return max(found, key=len, default=None)


def upward_imports(
    graph: Mapping[str, set[str]], layers: Mapping[str, Sequence[str]] = LAYERS
) -> list[tuple[str, str]]:
    """(importer, imported) of every import of a layer its layer may not import, sorted."""
    found = []
    for module, targets in graph.items():
        own = layer_of(module, layers)
        if own is None:
            continue
        for target in targets:
            other = layer_of(target, layers)
            if other is not None and other != own and other not in layers[own]:
                found.append((module, target))
    return sorted(found)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.checks.import_cycles", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("packages", nargs="*", default=list(PACKAGES), help="top-level packages")
    args = parser.parse_args(argv)
    graph = import_graph(ROOT, args.packages)
    cycles = find_cycles(graph)
    upward = upward_imports(graph)
    for cycle in cycles:
        print("import cycle: " + " <-> ".join(cycle))
    for module, target in upward:
        allowed = ", ".join(LAYERS[layer_of(module)]) or "nothing else"
        print(f"upward import: {module} -> {target} ({layer_of(module)} imports {allowed})")
    print(
        f"{len(graph)} modules, {sum(map(len, graph.values()))} imports, "
        f"{len(upward)} upward imports, {len(cycles)} cycles"
    )
    return 1 if cycles or upward else 0


if __name__ == "__main__":
    sys.exit(main())
