"""The documentation: the README as a front page, the pages it links, and the numpy-style
docstrings the API reference is generated from (the docs build, `sphinx-build -W`, checks the
same with numpydoc; this test needs no Sphinx)."""

import dataclasses
import inspect
import re
from pathlib import Path

import pytest

import contactqp

ROOT = Path(__file__).parent.parent
README = ROOT / "README.md"
QUICK_START = (
    'python3 -m venv .venv && .venv/bin/pip install -q . && .venv/bin/contactqp',
    ('python3 -m venv .venv && .venv/bin/pip install -q -e ".[test,solvers]" '
     '&& .venv/bin/python -m pytest'),
)
# Classes contactqp builds and hands out (solve() a Result, prepare() a Prepared, …): nobody
# constructs them, so their fields are documented under Attributes, not Parameters.
BUILT_BY_THE_LIBRARY = {"Result", "Batch", "Prepared", "Run", "LoadPath", "Model", "QPProblem",
                        "ProblemResult"}
# Functions that raise nothing of their own, so they have no Raises section.
RAISE_NOTHING = {"table", "detail_table", "available_qp_solvers", "scene_to_toml", "minimal"}
PUBLIC = [getattr(contactqp, name) for name in contactqp.__all__]
FUNCTIONS = [f for f in PUBLIC if inspect.isfunction(f)]
CLASSES = [c for c in PUBLIC if inspect.isclass(c) and not issubclass(c, Exception)]


def sections(obj) -> dict[str, list[str]]:
    """The numpy-style sections of obj's docstring: title -> its lines."""
    found, title, lines = {}, None, inspect.getdoc(obj).split("\n")
    for i, line in enumerate(lines):
        if i + 1 < len(lines) and re.fullmatch(r"-{3,}", lines[i + 1]) and line.strip():
            title = line.strip()
            found[title] = []
        elif title is not None and not re.fullmatch(r"-{3,}", line):
            found[title].append(line)
    return found


def documented(lines: list[str]) -> list[str]:
    """The names a Parameters section lists (its unindented `name : type` lines)."""
    return [re.split(r"\s*:", line)[0].strip() for line in lines
            if line and not line.startswith(" ")]


def links(path: Path) -> list[str]:
    """The relative targets of path's Markdown links and images."""
    text = re.sub(r"```.*?```", "", path.read_text(encoding="utf-8"), flags=re.DOTALL)
    return [t for t in re.findall(r"\]\(([^)#]+)\)", text) if "://" not in t]


def test_the_readme_is_a_front_page():
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) < 200
    for command in QUICK_START:  # the two quick-start commands, word for word
        assert f"```bash\n{command}\n```" in text


def test_ci_runs_the_test_command_and_builds_the_docs_with_warnings_as_errors():
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert QUICK_START[1].removeprefix("python3 -m venv .venv && ") in ci
    assert re.search(r"sphinx-build -W .*-b html docs docs/_build/html", ci)


@pytest.mark.parametrize("page", [README, *sorted((ROOT / "docs").rglob("*.md"))],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_every_link_of_a_page_exists(page: Path):
    if "_build" in page.parts:
        pytest.skip("build output")
    for target in links(page):
        # the docs' links to the gallery and the API pages point at what the build generates
        if target.startswith(("auto_examples/", "../auto_examples/", "../api/")):
            continue
        assert (page.parent / target).exists(), f"{page.name}: {target}"


@pytest.mark.parametrize("function", FUNCTIONS, ids=lambda f: f.__name__)
def test_every_public_function_has_parameters_returns_and_raises(function):
    found = sections(function)
    parameters = [name.lstrip("*") for name in inspect.signature(function).parameters]
    if parameters:
        assert [n.lstrip("*") for n in documented(found.get("Parameters", []))] == parameters
    assert found.get("Returns"), "no Returns section"
    if function.__name__ not in RAISE_NOTHING:
        assert documented(found.get("Raises", [])), "no Raises section"
        for name in documented(found["Raises"]):
            assert name in dir(contactqp) or name in dir(__builtins__), name


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_every_public_class_documents_what_it_takes(cls):
    found = sections(cls)
    if cls.__name__ in BUILT_BY_THE_LIBRARY:
        assert found.get("Attributes"), "no Attributes section"
        return
    fields = [f.name for f in dataclasses.fields(cls) if f.init]
    assert documented(found.get("Parameters", [])) == fields


def test_the_readme_example_prints_what_the_readme_shows():
    """The README's example output is pasted in: it must be what the example prints today
    (the time on the method's line aside, which changes from run to run)."""
    text = README.read_text(encoding="utf-8")
    example = re.search(r"print\(result\.summary\(\)\)\n```\n\n```\n(.*?)```", text, re.DOTALL)
    assert example, "the README's example and its output are not where this test looks"
    assert untimed(example.group(1)) == untimed(contactqp.solve().summary())


def untimed(summary: str) -> str:
    """A summary with the time on its method line left out."""
    return re.sub(r", [0-9.]+ ms$", ", … ms", summary.strip(), flags=re.MULTILINE)
