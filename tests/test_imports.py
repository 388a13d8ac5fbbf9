"""The package's own imports form a tree: no module of src/contactqp imports, directly or
through others, a module that imports it back. Imports inside functions count (they run, just
later); imports under `if TYPE_CHECKING:` do not (they never run). The graph is read from the
source with `ast`, so the test needs no import to succeed and finds a circle Python's lazy
imports would hide. And the lower layers (the scene, its layout, its constraint graph) import
nothing of the model, the methods or what comes after them."""

import ast
from pathlib import Path

import pytest

SOURCE = Path(__file__).parent.parent / "src"
PACKAGE = "contactqp"


def module_files() -> dict[str, Path]:
    """Every module of the package by dotted name (a package by its own name)."""
    found = {}
    for path in sorted((SOURCE / PACKAGE).rglob("*.py")):
        parts = list(path.relative_to(SOURCE).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        found[".".join(parts)] = path
    return found


def is_type_checking(test: ast.expr) -> bool:
    """Whether an `if` tests TYPE_CHECKING (bare or as typing.TYPE_CHECKING)."""
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def runtime_imports(tree: ast.AST):
    """The Import and ImportFrom nodes that can run, at any depth, skipping TYPE_CHECKING."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        if isinstance(node, ast.If) and is_type_checking(node.test):
            for child in node.orelse:
                yield from runtime_imports(ast.Module(body=[child], type_ignores=[]))
            continue
        yield from runtime_imports(node)


def imported(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The package's modules that module `name` imports. `from a.b import c` names the module
    a.b.c if there is one (c is a submodule), else a.b itself; a relative import is resolved
    against the module's own package."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    targets = set()
    for node in runtime_imports(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            bases = [alias.name for alias in node.names]
            names: list[str] = []
        else:
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            bases, names = [base], [alias.name for alias in node.names]
        for base in bases:
            for alias in names or [None]:
                full = f"{base}.{alias}" if alias else base
                target = full if full in modules else base
                while target and target not in modules:  # `import a.b.c` binds a.b.c
                    target = target.rpartition(".")[0]
                if target and target != name:
                    targets.add(target)
    return targets


def import_graph() -> dict[str, set[str]]:
    modules = module_files()
    return {name: imported(name, path, modules) for name, path in modules.items()}


def find_circle(graph: dict[str, set[str]]) -> list[str] | None:
    """One circle of the graph as [a, b, ..., a], or None: a depth-first walk that meets a
    module still on its own path."""
    state: dict[str, str] = {}  # "open" while on the path, "done" once every import is walked
    path: list[str] = []

    def walk(module: str) -> list[str] | None:
        state[module] = "open"
        path.append(module)
        for target in sorted(graph.get(module, ())):
            if state.get(target) == "open":
                return path[path.index(target):] + [target]
            if target not in state and (circle := walk(target)):
                return circle
        path.pop()
        state[module] = "done"
        return None

    for module in sorted(graph):
        if module not in state and (circle := walk(module)):
            return circle
    return None


def test_the_package_imports_form_no_circle():
    graph, circles = import_graph(), []
    while (circle := find_circle(graph)) is not None:  # each found, then cut to find the next
        circles.append(" -> ".join(circle))
        graph[circle[-2]].discard(circle[-1])
    assert circles == [], "import circles: " + "; ".join(circles)


def reachable(graph: dict[str, set[str]], start: str) -> set[str]:
    """Every module ``start`` imports, directly or through others."""
    seen, todo = set(), [start]
    while todo:
        for target in graph.get(todo.pop(), ()):
            if target not in seen:
                seen.add(target)
                todo.append(target)
    return seen


# What each lower layer stands on (docs/architecture.md): a scene, its numbering and its
# constraint graph know nothing of the model, the methods or what comes after them.
LOWER_LAYERS = ("contactqp.scene", "contactqp.layout", "contactqp.feasibility")
HIGHER = ("contactqp.model", "contactqp.methods", "contactqp.solve", "contactqp.result",
          "contactqp.check", "contactqp.plot", "contactqp.cli")


@pytest.mark.parametrize("lower", LOWER_LAYERS)
def test_the_lower_layers_import_nothing_above_them(lower):
    above = sorted(module for module in reachable(import_graph(), lower)
                   if module.startswith(HIGHER))
    assert above == [], f"{lower} imports {above}"


def test_the_graph_sees_imports_inside_functions_and_skips_type_checking():
    """The walk itself: a circle through a function-local import is found, one through an
    import under TYPE_CHECKING is not (so the test above could fail)."""
    graph = import_graph()
    # cli imports plot only inside functions, to keep matplotlib out of a plain run
    assert "contactqp.plot" in graph["contactqp.cli"]
    # chain imports condense only for annotations; condense imports chain for real
    assert "contactqp.model.condense" not in graph["contactqp.model.chain"]
    assert "contactqp.model.chain" in graph["contactqp.model.condense"]
    assert find_circle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_circle({"a": {"b"}, "b": {"c"}, "c": set()}) is None


@pytest.mark.parametrize("source, expected", [
    ("from contactqp import linalg", {"contactqp.linalg"}),
    ("from contactqp import __version__", {"contactqp"}),
    ("from contactqp.model import Model", {"contactqp.model"}),
    ("from . import linalg", {"contactqp.linalg"}),
    ("from .chain import Model", {"contactqp.model.chain"}),
    ("import contactqp.model.chain", {"contactqp.model.chain"}),
    ("def f():\n    from contactqp import plot", {"contactqp.plot"}),
    ("if TYPE_CHECKING:\n    from contactqp import plot", set()),
])
def test_imports_are_resolved_to_modules(tmp_path, source, expected):
    path = tmp_path / "layout.py"
    path.write_text(source)
    modules = module_files()
    where = "contactqp.model.layout"
    if source.startswith("from . "):
        where = "contactqp.cli"  # a module of the top package
    assert imported(where, path, modules) == expected
