"""The package's layers import only downward: core <- surface <- simulate <- dataset <- surrogate <- engines <-
design / perception / objects <- cli, studio. Every import counts, at module level or inside a function (a lazy import
is still a dependency), except imports for type checkers only (``if TYPE_CHECKING:``)."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

from conftest import source_modules as modules

# lowest first; a module may import its own layer and those below it
LAYERS = [
    ("roughness.core", "roughness.models"),
    ("roughness.surface", "roughness.perceptual_scale"),
    ("roughness.simulate", "roughness.cluster"),
    ("roughness.dataset",),
    ("roughness.surrogate",),
    ("roughness.engines", "roughness.prediction", "roughness.maps", "roughness.classical", "roughness.compare",
     "roughness.report", "roughness.curvature_correction", "roughness.result_cache"),
    ("roughness.design", "roughness.perception", "roughness.objects", "roughness.fuzzy_feel", "roughness.fuzzy_tune",
     "roughness.fuzzy_palette"),
    ("roughness.cli", "roughness.studio"),  # the two front ends: the studio shows what the CLI prints, in its words
]
def layer_of(module: str) -> int | None:
    """The layer of a roughness module (None: the package's lazy front door, or not ours)."""
    for level, prefixes in enumerate(LAYERS):
        if any(module == p or module.startswith(p + ".") for p in prefixes):
            return level
    return None


def imports(module: str, path: Path) -> set[str]:
    """The absolute names a module imports, type-checking-only imports left out."""
    tree = ast.parse(path.read_text())
    typing_only = {id(n) for node in ast.walk(tree) if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(
        node.test) for n in ast.walk(node)}
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    names = set()
    for node in ast.walk(tree):
        if id(node) in typing_only:
            continue
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{parent}.{base}" if base else parent
            names |= {base} | {f"{base}.{a.name}" for a in node.names}
    return {n for n in names if n.startswith("roughness")}


def test_every_module_has_a_layer():
    assert [m for m in modules() if m != "roughness" and layer_of(m) is None] == []


@pytest.mark.parametrize("module, path", sorted(modules().items()), ids=lambda v: str(v).rpartition("/")[2])
def test_a_module_imports_only_its_own_layer_and_those_below(module, path):
    own = layer_of(module)
    if own is None:
        return  # src/roughness/__init__.py: names loaded on first use, from every layer
    upward = sorted(name for name in imports(module, path) if (layer_of(name) or 0) > own)
    assert upward == [], f"{module} (layer {own}) imports from above it: {upward}"


def import_graph() -> dict[str, set[str]]:
    """Each module and the modules it imports (a name imported from a module counts as that module)."""
    names = modules()
    graph = {}
    for module, path in names.items():
        targets = set()
        for name in imports(module, path):
            while name and name not in names:
                name = name.rpartition(".")[0]
            if name and name != module:
                targets.add(name)
        graph[module] = targets
    return graph


def test_no_module_imports_itself_through_others():
    """No import circle, lazy imports included: within a layer too, each module sits above what it imports."""
    graph, done, path = import_graph(), set(), []

    def visit(module: str) -> None:
        if module in path:
            raise AssertionError("import circle: " + " -> ".join(path[path.index(module):] + [module]))
        if module in done:
            return
        path.append(module)
        for target in sorted(graph[module]):
            visit(target)
        path.pop()
        done.add(module)

    for module in sorted(graph):
        visit(module)
