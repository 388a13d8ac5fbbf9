"""The documentation: the README as a front page, the pages it links, and the numpy-style
docstrings the API reference is generated from (the docs build, `sphinx-build -W`, checks the
same with numpydoc; this test needs no Sphinx)."""

import dataclasses
import functools
import gzip
import inspect
import json
import math
import re
from collections import Counter
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
BUILT_BY_THE_LIBRARY = {"Result", "Batch", "Prepared", "Run", "LoadPath", "Model", "QPProblem"}
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
        # a reader of the repository opens the link as it is (the docs build points the links
        # to examples/ and docs/benchmark/ at the pages it makes of them: docs/conf.py)
        assert (page.parent / target).exists(), f"{page.name}: {target}"
        # benchmark_tables/ holds the build's wrappers, a raw {include} when read as they are
        if "benchmark_tables" not in page.parts:
            assert "benchmark_tables/" not in target, f"{page.name}: {target}"


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


def test_the_readme_says_why_nitsche_is_not_verified_on_two_bars():
    """The README explains the NO its example table shows for Nitsche on two_bars.toml; the
    closed form (two springs across a gap) gives the reactions 44000 N and 6000 N."""
    text = README.read_text(encoding="utf-8")
    claim = re.search(r"\((\d\.\d) µm at the default γ₀ = 100\), which moves the support "
                      r"reactions by (\d+) N and (\d+) N", text)
    assert claim, "the README no longer says why nitsche is NO on two_bars.toml"
    scene = contactqp.load_scene(ROOT / "examples" / "two_bars.toml")
    flagged = contactqp.solve(scene, method="nitsche")
    assert not flagged.verified
    assert f"{flagged.penetration.max() * 1e6:.1f}" == claim.group(1)
    shift = abs(flagged.reactions - [-44000.0, -6000.0])
    assert [f"{s:.0f}" for s in shift] == [claim.group(2), claim.group(3)]
    assert contactqp.solve(scene, method="nitsche", gamma0=1e6).verified


# The benchmark's pages quote its matrix run; the run's data is kept beside its tables
# (docs/benchmark/runs.json.gz, the runs.json that `python benchmarks/run.py` writes, gzipped),
# and every number the pages quote from it is read here from that data, not from a printout.
BENCHMARK = ROOT / "docs" / "benchmark"
BENCHMARKS_PAGE = ROOT / "docs" / "benchmarks.md"


@functools.cache
def matrix_run() -> dict:
    """The matrix run README.md and docs/benchmarks.md quote."""
    return json.loads(gzip.decompress((BENCHMARK / "runs.json.gz").read_bytes()))


def one_run(case: str, label: str) -> dict:
    found = [r for r in matrix_run()["runs"] if r["case"] == case and r["label"] == label]
    assert len(found) == 1, f"no single run {label!r} on {case!r}"
    return found[0]


def error(case: str, label: str) -> float:
    return one_run(case, label)["force_error"]


def percent(value: float) -> str:
    return f"{100 * value:.1f}"


def counted() -> dict[str, int]:
    """The run's outcomes, and why the skipped ones were skipped."""
    runs = matrix_run()["runs"]
    reasons = [r["skip_reason"] for r in runs if r["outcome"] == "skipped"]
    return {"runs": len(runs), "cases": len(matrix_run()["cases"]),
            **Counter(r["outcome"] for r in runs),
            "flagged, right": sum(r["outcome"] == "flagged"
                                  and r.get("force_error", math.inf) <= 1e-5 for r in runs),
            **{kind: sum(reason.startswith(start) for reason in reasons) for kind, start in (
                ("over budget", "over budget"), ("dense solver", "dense solver"),
                ("timed out", "timed out"), ("dense LCP", "the dense LCP"),
                ("refused", ("OptionError", "SceneError")))}}


def test_the_readme_figure_is_drawn_as_contactqp_curve_draws_it(tmp_path, capsys):
    """docs/load_path.png, the README's figure, is redrawn by every docs build (docs/conf.py,
    with docs/nitsche_sweep.png); one whose layout changed since (its size in pixels: the old
    one-panel chart was 840 × 552) is stale."""
    from PIL import Image

    from contactqp.cli import main

    assert main(["curve", "--steps", "3", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    with (Image.open(tmp_path / "load_path.png") as fresh,
          Image.open(ROOT / "docs" / "load_path.png") as committed):
        assert committed.size == fresh.size, "docs/load_path.png is stale: build the docs"


def said(page: Path, pattern: str) -> tuple[str, ...]:
    """What the page says where pattern matches (its groups), line breaks read as spaces."""
    found = re.search(pattern, " ".join(page.read_text(encoding="utf-8").split()))
    assert found, f"{page.name} no longer says {pattern!r}"
    return found.groups()


COMPARE = ROOT / "benchmarks" / "qpbenchmark" / "results" / "compare.md"
COLUMNS = ("problem", "solver", "settings", "qpbenchmark", "check", "error", "residuals")


def compared() -> list[dict[str, str]]:
    """The rows of the qpbenchmark comparison (compare.py's compare.md): every run whose
    qpbenchmark verdict and contact force disagree."""
    rows = [[c.strip() for c in line.strip().strip("|").split("|")]
            for line in COMPARE.read_text(encoding="utf-8").splitlines() if line.startswith("|")]
    return [dict(zip(COLUMNS, r)) for r in rows
            if len(r) == len(COLUMNS) and r[0] != "problem" and not r[0].startswith("---")]


def test_the_qpbenchmark_numbers_are_those_of_its_comparison():
    text = COMPARE.read_text(encoding="utf-8")
    summary = re.findall(r"^\| (success|failure) \| (right|wrong) \| (\d+) \|$", text, re.MULTILINE)
    page = BENCHMARKS_PAGE.read_text(encoding="utf-8")
    for verdict, force, runs in summary:
        assert re.search(rf"^\| (\*\*)?{verdict}(\*\*)? \| (\*\*)?{force}(\*\*)? \| "
                         rf"(\*\*)?{runs}(\*\*)? \|$", page, re.MULTILINE), (verdict, force, runs)
    # (the table prints two digits: one success there at 1.0e-05 is just above 1e-5)
    fooled = [r for r in compared()
              if r["qpbenchmark"] == "success" and float(r["error"]) >= 1e-5]
    by_setting = Counter(r["settings"] for r in fooled)
    assert said(BENCHMARKS_PAGE, r"(\d+) runs pass qpbenchmark's residual tests") == (
        str(len(fooled)),)
    assert said(BENCHMARKS_PAGE, r"\((\d+) at its low-accuracy setting, (\d+) at its default, "
                r"whose tolerances are 1, (\d+) at mid accuracy, none at high\)") == tuple(
        str(by_setting[s]) for s in ("low_accuracy", "default", "mid_accuracy"))
    assert by_setting["high_accuracy"] == 0
    listed = said(BENCHMARKS_PAGE, r"none at high\): ((?:[a-z]+ \d+, )+[a-z]+ \d+) \(")[0]
    assert dict(pair.split() for pair in listed.split(", ")) == {
        solver: str(n) for solver, n in Counter(r["solver"] for r in fooled).items()}

    def run(problem: str, solver: str, settings: str) -> dict[str, str]:
        return next(r for r in compared() if (r["problem"], r["solver"], r["settings"]) == (
            problem, solver, settings))

    highs, daqp = run("two_bars_SI", "highs", "default"), run("two_bars_SI", "daqp", "low_accuracy")
    gap, highs_off, residual, daqp_off = said(
        BENCHMARKS_PAGE, r"HiGHS at default settings has a duality gap of (\S+) and the force "
        r"(\d+) % off, DAQP at low accuracy a primal residual of (\S+) m and the force (\d+) % off")
    assert float(gap) == float(highs["residuals"].split(", ")[2])
    assert float(residual) == float(daqp["residuals"].split(", ")[0])
    assert (highs_off, daqp_off) == (f"{100 * float(highs['error']):.0f}",
                                     f"{100 * float(daqp['error']):.0f}")
    osqp_off, scs_off = said(
        BENCHMARKS_PAGE, r"OSQP at default settings passes with the force (\S+) of F off, and on "
        r"the scaled 10⁵-element bar SCS at default settings with the force (\S+) % off")
    assert float(osqp_off) == float(run("taper_10000_scaled", "osqp", "default")["error"])
    assert scs_off == percent(float(run("taper_100000_scaled", "scs", "default")["error"]))
    held = sum(r["problem"].startswith(("held_by_contact", "free_bar")) for r in fooled)
    assert said(BENCHMARKS_PAGE, r"\((\d+) of them on the bars held by contact, (\d+) on the "
                r"10⁵-element bar\)") == (
        str(held), str(sum(r["problem"].startswith("taper_100000_") for r in fooled)))
