"""The package's own imports follow the pipeline (docs/architecture.md): no module of
src/contactqp or benchmarks/ imports, directly or through others, a module that imports it
back; and every import goes to a layer at or below the importer's (LAYERS: the leaves, the
front ends, the model, the methods and the check, the Result, the pipeline, the studies, the
report, the charts, the command line). Imports inside functions count (they run, just later),
and so do imports under `if TYPE_CHECKING:` (a module that names another in its types knows
it). The graph is read from the source with `ast`, so the test needs no import to succeed and
finds a circle Python's lazy imports would hide."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).parent.parent
SOURCE = ROOT / "src"
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


def runtime_imports(tree: ast.AST, type_only: bool = True):
    """The Import and ImportFrom nodes at any depth: those that run (inside functions too)
    and, with ``type_only``, those under TYPE_CHECKING, for annotations only: a module that
    names another in its types knows it as much as one that calls it."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        if isinstance(node, ast.If) and is_type_checking(node.test) and not type_only:
            for child in node.orelse:
                yield from runtime_imports(ast.Module(body=[child], type_ignores=[]), type_only)
            continue
        yield from runtime_imports(node, type_only)


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


def benchmark_graph() -> dict[str, set[str]]:
    """benchmarks/'s own imports among its scripts (``benchmarks.<name>``; a script imports a
    sibling by its bare name)."""
    scripts = {f"benchmarks.{p.relative_to(ROOT / 'benchmarks').with_suffix('').as_posix().replace('/', '.')}": p
               for p in sorted((ROOT / "benchmarks").rglob("*.py"))}
    graph = {}
    for name, path in scripts.items():
        targets = set()
        for node in runtime_imports(ast.parse(path.read_text(), str(path))):
            bases = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] + [f"{node.module}.{a.name}" for a in node.names])
            for base in bases:
                for candidate in (f"benchmarks.{base}", base,
                                  f"{name.rpartition('.')[0]}.{base}"):
                    if candidate in scripts and candidate != name:
                        targets.add(candidate)
        graph[name] = targets
    return graph


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


@pytest.mark.parametrize("graph", [import_graph, benchmark_graph], ids=["src", "benchmarks"])
def test_the_imports_form_no_circle(graph):
    graph, circles = graph(), []
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


# The pipeline, bottom to top (docs/architecture.md): a module imports only what stands on its
# own layer or below. A package name covers its modules; the first layer that names a module
# (or its package) is its own.
LAYERS = (
    ("contactqp.errors", "contactqp.units"),
    ("contactqp._validate", "contactqp.linalg", "contactqp.progress", "contactqp.cli_input"),
    ("contactqp.feasibility",),
    ("contactqp.problem", "contactqp.scene"),
    ("contactqp.problem_files", "contactqp.builders", "contactqp.scene_io"),
    ("contactqp.model.base", "contactqp.model.saddle"),
    ("contactqp.model",),
    ("contactqp.random_scenes", "contactqp.reference", "contactqp.fem", "contactqp.friction"),
    ("contactqp.methods.base",),
    ("contactqp.check", "contactqp.methods"),
    ("contactqp.formatting",),
    ("contactqp.result",),
    ("contactqp.solve",),
    ("contactqp.many", "contactqp.curve", "contactqp.studies"),
    ("contactqp.report",),
    ("contactqp.plot",),
    ("contactqp",),
    ("contactqp.cli_commands",),
    ("contactqp.cli",),
    ("contactqp.__main__",),
)


def layer(module: str) -> int:
    """The layer of ``module``: the first whose names it is, or is inside of (the package
    itself, ``contactqp``, only by its own name)."""
    for index, names in enumerate(LAYERS):
        for name in names:
            if module == name or (name != "contactqp" and module.startswith(name + ".")):
                return index
    raise AssertionError(f"{module} is in no layer of LAYERS")


def test_every_import_goes_down_the_pipeline():
    upward = [f"{module} ({layer(module)}) -> {target} ({layer(target)})"
              for module, targets in sorted(import_graph().items()) for target in sorted(targets)
              if layer(target) > layer(module)]
    assert upward == [], "imports that run up the pipeline: " + "; ".join(upward)


# Within a layer, what must stay apart: the check reads the model and the answer, never a
# method; a method never sees the Result; the chain and the sparse model know only the
# protocol, not each other
APART = (("contactqp.check", "contactqp.methods"), ("contactqp.methods", "contactqp.result"),
         ("contactqp.model.chain", "contactqp.model.sparse"),
         ("contactqp.model.sparse", "contactqp.model.chain"),
         ("contactqp.scene", "contactqp.model"), ("contactqp.feasibility", "contactqp.scene"))


@pytest.mark.parametrize(("lower", "higher"), APART, ids=[f"{a} !-> {b}" for a, b in APART])
def test_what_stays_apart(lower, higher):
    graph = import_graph()
    reached = sorted(target for module in graph if module == lower or module.startswith(lower + ".")
                     for target in reachable(graph, module)
                     if target == higher or target.startswith(higher + "."))
    assert reached == [], f"{lower} reaches {sorted(set(reached))}"


def test_the_graph_sees_imports_inside_functions_and_under_type_checking():
    """The walk itself: an import inside a function is an edge, and so is one under
    TYPE_CHECKING (so the tests above could fail); a circle is found."""
    graph = import_graph()
    # the commands import plot only inside functions, to keep matplotlib out of a plain run
    assert "contactqp.plot" in graph["contactqp.cli_commands"]
    assert find_circle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_circle({"a": {"b"}, "b": {"c"}, "c": set()}) is None


@pytest.mark.parametrize("source, expected", [
    ("from contactqp import linalg", {"contactqp.linalg"}),
    ("from contactqp import __version__", {"contactqp"}),
    ("from contactqp.model import Model", {"contactqp.model"}),
    ("from . import linalg", {"contactqp.linalg"}),
    ("from .chain import Model", {"contactqp.model.chain"}),
    ("import contactqp.model.chain.model", {"contactqp.model.chain.model"}),
    ("def f():\n    from contactqp import plot", {"contactqp.plot"}),
    ("if TYPE_CHECKING:\n    from contactqp import plot", {"contactqp.plot"}),
])
def test_imports_are_resolved_to_modules(tmp_path, source, expected):
    path = tmp_path / "layout.py"
    path.write_text(source)
    modules = module_files()
    where = "contactqp.model.chain.layout_names"
    if source.startswith("from . "):
        where = "contactqp.cli"  # a module of the top package
    assert imported(where, path, modules) == expected
