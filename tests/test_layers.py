"""ndpack's modules import only downward: each module sits in a layer, and imports from its own
layer or the layers below it, never above, at module level or inside a function (issue 24).

The table is the layer map; a new module fails :func:`test_every_module_has_a_layer` until it is
placed in it. Packages are placed by prefix (``ndpack.kernels`` places every ``ndpack.kernels.*``).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "ndpack"

#: Bottom to top: a module may import from its own layer or any layer below it.
LAYERS = (
    # Errors, notices, machine-independent arithmetic, and geometry with no shape in it.
    ("base", ("ndpack.errors", "ndpack.log", "ndpack.reproducible", "ndpack.parallel", "ndpack.compile_ahead",
              "ndpack.geometry")),
    # The scalar-kernel language, programs, the tape, the library, compiling, compiled_program.
    ("kernels", ("ndpack.kernels",)),
    ("meshes", ("ndpack.meshes",)),
    ("shapes", ("ndpack.oracle", "ndpack.shapes")),
    ("backends", ("ndpack.backends",)),
    # The result and its checks.
    ("results", ("ndpack.packing", "ndpack.verify", "ndpack.consistency")),
    # Files (named shapes and shape sources among them), pictures and sample files.
    ("outside", ("ndpack.io", "ndpack.pictures", "ndpack.samples")),
    # The packing drivers: greedy, sizes, collision (coverings).
    ("drivers", ("ndpack.drivers",)),
    # Many parts, tiles, and where their tasks run.
    ("scale", ("ndpack.scale",)),
    ("top", ("ndpack.cli", "ndpack")),
)

#: Upward imports allowed inside a function only: none. A lower module that needs a higher one's
#: service holds a registry the higher one fills when imported (``Packing.save`` from ndpack.io,
#: ``Oracle.union`` from ndpack.shapes.csg), as trimesh's exchange and fogleman/sdf's operators do.
ALLOWED_UPWARD = {}

_PLACE = {prefix: number for number, (_, prefixes) in enumerate(LAYERS) for prefix in prefixes}


def _modules() -> dict[str, Path]:
    """Every module of the package by dotted name (a package by its own name)."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


MODULES = _modules()


def _prefix(module: str) -> str | None:
    """The table's entry that places ``module``: itself or its nearest package listed (the
    package ``ndpack`` places only itself)."""
    name = module
    while name:
        if name in _PLACE and (name != "ndpack" or module == "ndpack"):
            return name
        name = name.rpartition(".")[0]
    return None


def layer(module: str) -> int | None:
    prefix = _prefix(module)
    return None if prefix is None else _PLACE[prefix]


def _describe(module: str) -> str:
    number = layer(module)
    return f"{module} (layer {number}, {LAYERS[number][0]})"


def imports(module: str) -> list[tuple[str, int, bool]]:
    """The ndpack modules ``module`` imports: (module, line, inside a function), relative imports
    resolved; ``from package import name`` counts as the submodule where ``name`` is one."""
    path = MODULES[module]
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = []

    def visit(node, local):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.Import):
                found.extend((alias.name, child.lineno, local) for alias in child.names)
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = package.split(".")
                    base = base[: len(base) - (child.level - 1)]
                    source = ".".join(base + ([child.module] if child.module else []))
                else:
                    source = child.module or ""
                for alias in child.names:
                    target = f"{source}.{alias.name}"
                    found.append((target if target in MODULES else source, child.lineno, local))
            visit(child, local or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)))

    visit(ast.parse(path.read_text(), str(path)), False)
    return [(target, line, local) for target, line, local in found
            if target == "ndpack" or target.startswith("ndpack.")]


def _where(module: str, line: int) -> str:
    return f"{MODULES[module].relative_to(PACKAGE.parent)}:{line}"


def test_every_module_has_a_layer():
    unknown = [f"{_where(module, 1)}: {module}" for module in MODULES if layer(module) is None]
    unknown += [f"{_where(module, line)}: imports {target}, which is not in the table"
                for module in MODULES for target, line, _ in imports(module) if layer(target) is None]
    assert not unknown, "place these modules in tests/test_layers.py's LAYERS:\n" + "\n".join(unknown)


def test_imports_go_only_downward():
    upward = []
    for module in MODULES:
        if layer(module) is None:
            continue  # reported by test_every_module_has_a_layer
        for target, line, local in imports(module):
            if layer(target) is None or layer(target) <= layer(module):
                continue
            if local and (_prefix(module), _prefix(target)) in ALLOWED_UPWARD:
                continue
            upward.append(f"{_where(module, line)}: {_describe(module)} imports {_describe(target)}"
                          + ("" if local else " at module level"))
    assert not upward, "imports from a lower layer to a higher one:\n" + "\n".join(upward)


def test_no_two_modules_import_each_other_at_module_level():
    graph = {module: {} for module in MODULES}
    for module in MODULES:
        for target, line, local in imports(module):
            if not local and target != module and target in MODULES:
                graph[module].setdefault(target, line)
    mutual = sorted(f"{_where(a, graph[a][b])} imports {b}, and {_where(b, graph[b][a])} imports {a}"
                    for a in graph for b in graph[a] if a < b and a in graph[b])
    assert not mutual, "modules that import each other at module level:\n" + "\n".join(mutual)


@pytest.mark.parametrize("module, expected", [
    ("ndpack", "top"), ("ndpack.cli", "top"), ("ndpack.kernels", "kernels"), ("ndpack.kernels.tape", "kernels"),
    ("ndpack.shapes.csg", "shapes"), ("ndpack.oracle", "shapes"), ("ndpack.io.registry", "outside"),
])
def test_the_table_places_by_prefix(module, expected):
    assert LAYERS[layer(module)][0] == expected
    assert layer("ndpack.nothing_of_that_name") is None  # "ndpack" places the package alone


def test_the_walk_sees_local_and_relative_imports():
    found = {(target, local) for target, _, local in imports("ndpack.oracle")}
    assert ("ndpack.errors", False) in found  # from .errors import ...
    found = {(target, local) for target, _, local in imports("ndpack.cli")}
    assert ("ndpack.drivers.greedy.protosphere", True) in found  # inside a command's function


def _circles(graph: dict) -> list[list[str]]:
    """The strongly connected groups of more than one module in ``graph`` (module -> modules it
    imports): each a circle of imports (Tarjan's algorithm, iterative)."""
    index, low, stack, on_stack, found, counter = {}, {}, [], set(), [], 0
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, targets = work[-1]
            for target in targets:
                if target not in index:
                    index[target] = low[target] = counter
                    counter += 1
                    stack.append(target)
                    on_stack.add(target)
                    work.append((target, iter(sorted(graph[target]))))
                    break
                if target in on_stack:
                    low[node] = min(low[node], index[target])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    group = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        group.append(member)
                        if member == node:
                            break
                    if len(group) > 1:
                        found.append(sorted(group))
    return found


def test_no_circle_of_imports_anywhere_in_the_text():
    """No module imports one that imports it back, directly or around a circle, counting imports
    inside functions: a lower module that needs a higher one holds a registry (issue 46)."""
    graph = {module: {target for target, _, _ in imports(module) if target in MODULES and target != module}
             for module in MODULES}
    circles = _circles(graph)
    assert not circles, "modules in circles of imports:\n" + "\n".join(", ".join(group) for group in circles)
    # The check finds one: a circle made on purpose.
    assert _circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
