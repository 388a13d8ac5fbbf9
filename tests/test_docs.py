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
import statistics
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

import contactqp

ROOT = Path(__file__).parent.parent
README = ROOT / "README.md"
QUICK_START = (
    'python3 -m venv .venv && .venv/bin/pip install -q . && .venv/bin/contactqp',
    ('python3 -m venv .venv && .venv/bin/pip install -q -e ".[test,solvers,fem]" '
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
    fields = ([f.name for f in dataclasses.fields(cls) if f.init]
              if dataclasses.is_dataclass(cls) else list(inspect.signature(cls).parameters))
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
OUTCOMES = ("verified", "flagged", "claimed success, wrong", "verified, wrong", "skipped")


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
    outcomes = Counter(r["outcome"] for r in runs)
    return {"runs": len(runs), "cases": len(matrix_run()["cases"]),
            **{outcome: outcomes[outcome] for outcome in OUTCOMES},
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


def sci(value: float, digits: int = 1) -> str:
    """A number as the pages write it: 7.6e-2 (no zero-padded exponent)."""
    mantissa, exponent = f"{value:.{digits}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def condensed_at_a_million() -> tuple[str, ...]:
    """The fast path: the condensed formulation's verified runs of lagrange, augmented and
    the QP at 10⁶ elements, in floors (least, most, median)."""
    ratios = [r["ratio"] for r in matrix_run()["runs"] if r["case"] == "taper 1e6"
              and r["formulation"] == "condensed" and r["outcome"] == "verified"
              and r["method"] in ("lagrange", "augmented", "qp")]
    assert ratios, "no verified condensed run at 10⁶ elements"
    return tuple(f"{value:.1f}" for value in (min(ratios), max(ratios), statistics.median(ratios)))


def machine() -> tuple[str, ...]:
    found = matrix_run()["machine"]
    return found["date"], found["python"], found["numpy"], found["scipy"]


def skipped() -> tuple[str, ...]:
    c = counted()
    return tuple(str(c[k]) for k in ("claimed success, wrong", "verified, wrong", "skipped",
                                      "over budget", "dense solver", "timed out", "dense LCP",
                                      "refused"))


def penalty_on_the_default_scene() -> tuple[str, ...]:
    outcome = {e: one_run("default", f"penalty full ε=1e+{e}")["outcome"] for e in (20, 22)}
    assert outcome == {20: "flagged", 22: "claimed success, wrong"}
    return (sci(error("default", "penalty full ε=1e+18")),
            sci(error("default", "penalty full ε=1e+20")),
            sci(error("default", "penalty full ε=1e+22")), sci(error("default", "augmented full")))


def in_si_units() -> tuple[str, ...]:
    runs = {name: one_run("default", f"qp {name} full SI default") for name in (
        "qpsolvers/highs", "qpsolvers/qpalm", "cvxpy/ECOS", "cvxpy/CVXOPT")}
    assert all(r["outcome"] != "verified" for r in runs.values())
    assert one_run("default", "qp qpsolvers/quadprog full SI default")["force_error"] == math.inf
    return (*(sci(r["force_error"]) for r in runs.values()),
            sci(error("default", "qp qpsolvers/highs full scaled default")))


C = counted
# (page, what it says with the numbers as groups, the numbers from the run)
MATRIX_QUOTES = [
    (README, r"solves (\d+) cases", lambda: (str(C()["cases"]),)),
    (README, r"in every formulation and setting: (\d+) runs", lambda: (str(C()["runs"]),)),
    (README, (r"\*\*(\d+) runs were verified and wrong\.\*\* (\d+) runs whose solver claimed "
     r"success were wrong \(HiGHS (\S+) % off on the default scene in SI units, SCS (\S+) % "
     r"off on the scaled 10⁵-element bar"), lambda: (
         str(C()["verified, wrong"]), str(C()["claimed success, wrong"]),
         percent(error("default", "qp qpsolvers/highs full SI default")),
         percent(error("taper 1e5", "qp qpsolvers/scs full scaled default")))),
    (BENCHMARKS_PAGE, (r"of (\d+) runs of every method and every installed QP solver on (\d+) "
     r"cases, \*\*(\d+) were verified and wrong\*\*; (\d+) runs whose solver claimed success"),
     lambda: tuple(str(C()[k]) for k in ("runs", "cases", "verified, wrong",
                                         "claimed success, wrong"))),
    (BENCHMARKS_PAGE, r"solves (\d+) cases by every method", lambda: (str(C()["cases"]),)),
    (BENCHMARKS_PAGE, (r"Nitsche: (\d+) runs\. Measured on (\S+) on the development machine "
     r"\(2 cores, 24 GB, Linux x86-64, Python (\S+), numpy (\S+), scipy (\S+)\)"),
     lambda: (str(C()["runs"]), *machine())),
    (BENCHMARKS_PAGE, r"(\d+) runs: (\d+) verified, (\d+) flagged \((\d+) of them within 1e-5",
     lambda: tuple(str(C()[k]) for k in ("runs", "verified", "flagged", "flagged, right"))),
    (BENCHMARKS_PAGE, (r"(\d+) claimed success but wrong \(every one flagged by the check\), "
     r"\*\*(\d+) verified but wrong\*\*, and (\d+) skipped with the reason recorded \((\d+) over "
     r"the time budget, extrapolated as n\^1\.5 from the previous size; (\d+) dense solvers "
     r"above 5000 unknowns; (\d+) stopped after 20 s; (\d+) the dense LCP past 2000 rows; "
     r"(\d+) refused \(Nitsche"), skipped),
    (BENCHMARKS_PAGE, (r"down to (\S+) at ε = 1e18; at 1e20 round-off in K \+ εCᵀC takes over "
     r"\((\S+), flagged\) and at 1e22 it is (\S+) off\. .* The augmented method reaches (\S+) "
     r"on the same scene"), penalty_on_the_default_scene),
    (BENCHMARKS_PAGE, (r"HiGHS reports success (\S+) off, QPALM (\S+) off .*, quadprog finds no answer, ECOS and CVXOPT "
     r"through cvxpy stop (\S+) and (\S+) off .*; scaled, the same solvers are right \(HiGHS "
     r"(\S+)\)"), in_si_units),
    (BENCHMARKS_PAGE, (r"SCS through qpsolvers claims success (\S+) off on the scaled "
     r"10⁵-element bar \((\S+) in SI units"), lambda: tuple(
         sci(error("taper 1e5", f"qp qpsolvers/scs full {scaling} default"))
         for scaling in ("scaled", "SI"))),
    (BENCHMARKS_PAGE, r"the wall pulls the tip out to it with (\S+) % of the load",
     lambda: (percent(error("open", "lagrange (equality) full")),)),
    (BENCHMARKS_PAGE, r"interior-point solvers stop with λ ~ (\S+)·F \(Clarabel",
     lambda: (sci(error("touching", "qp clarabel full scaled default"), 0),)),
    (BENCHMARKS_PAGE, (r"QP solvers took (\S+)–(\S+)× the floor in this run, median "
     r"(\S+)×"), condensed_at_a_million),
]


@pytest.mark.parametrize("quote", range(len(MATRIX_QUOTES)))
def test_every_number_quoted_from_the_benchmark_is_its_runs(quote: int):
    page, pattern, numbers = MATRIX_QUOTES[quote]
    assert said(page, pattern) == numbers()


def test_the_best_runs_on_the_benchmark_page_are_its_table():
    table = (BENCHMARK / "best.md").read_text(encoding="utf-8").strip()
    assert table in BENCHMARKS_PAGE.read_text(encoding="utf-8")


def test_the_benchmark_tables_are_those_of_its_data():
    """failures.md lists every run of runs.json.gz that is not verified, with its outcome."""
    rows = [line.split(" | ") for line in
            (BENCHMARK / "failures.md").read_text(encoding="utf-8").splitlines()[2:]]
    listed = Counter((r[0].removeprefix("| "), r[1], r[2]) for r in rows)
    assert listed == Counter((r["case"], r["label"], r["outcome"]) for r in matrix_run()["runs"]
                             if r["outcome"] != "verified")


def python_blocks(page: Path) -> list[str]:
    """The ```python blocks of a Markdown page, in order."""
    return re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), re.DOTALL)


def test_the_own_model_page_runs_as_it_reads(capsys):
    """docs/howto/own_model.md: the arrays example gives the hand calculation (the tip moves
    4 free, the wall 0.5 beyond it takes 1 − 0.5/4 = 0.875), and the scikit-fem example is
    verified, the force through the floor balanced by the top's reactions."""
    blocks = python_blocks(ROOT / "docs" / "howto" / "own_model.md")
    arrays = {}
    exec(blocks[0], arrays)  # noqa: S102 - the page's own code
    assert arrays["result"].contact_force == pytest.approx([0.875], rel=1e-12)
    fem_block = next(block for block in blocks if "import skfem" in block)
    pytest.importorskip("skfem", reason='the page\'s scikit-fem example: pip install "contactqp[fem]"')
    fem = {}
    exec(fem_block, fem)  # noqa: S102
    result, problem = fem["result"], fem["problem"]
    assert result.verified, result.message
    top = fem["top"].nodal["u^2"]
    pushed = result.reactions[np.isin(problem.prescribed, top)].sum()
    assert abs(pushed) == pytest.approx(result.contact_force.sum(), rel=1e-9)
    capsys.readouterr()


# docs/benchmarks.md's issue-28 table: its "this round" column is the range over the speed
# runs kept in docs/benchmark/speed/ (the speed.json each `benchmarks/run.py --cases speed`
# writes), each cell read here from them
SPEED_RUNS = BENCHMARK / "speed"
SPEED_ROWS = {  # the table's measure -> the runs' rows it quotes ("/" between two)
    "`solve(scene)` defaults, 10⁶ elements, one wall": ["solve(scene), 1000000 elements"],
    "condensed Lagrange, 10⁶ elements": ["condensed lagrange, 1000000 elements"],
    "10⁵ walls, warm re-solve (channel / flat patch)": [
        "channel (100000 walls), warm re-solve", "flat patch (100000 walls), warm re-solve"],
    "... the same in a process of its own (channel / flat patch)": [
        "channel (100000 walls), warm re-solve (own process)",
        "flat patch (100000 walls), warm re-solve (own process)"],
    "10⁵ walls, first solve in the process (channel / patch)": [
        "channel (100000 walls), first solve (this process)",
        "flat patch (100000 walls), first solve (this process)"],
    "... the same in a fresh process (channel / patch)": [
        "channel (100000 walls), first solve (fresh process)",
        "flat patch (100000 walls), first solve (fresh process)"],
    "one verified solve of the default scene / seed script": ["solve(default scene)"],
    "`prepared.solve` / seed script": ["prepared.solve"],
    "`solve_many`, 10⁴ cases (load and gap) / vectorised numpy": [
        "solve_many, 10000 cases (load and gap)"],
}
CHECK_ROWS = {
    "the check's time / the method's, 10⁶ one wall": ["solve(scene), 1000000 elements"],
    "the check's time / the method's, 10⁵ walls (channel / patch)": [
        "channel (100000 walls), warm re-solve", "flat patch (100000 walls), warm re-solve"],
}


def spread_of(values: list[float], unit: str) -> str:
    low, high = f"{min(values):.1f}", f"{max(values):.1f}"
    return f"{low}{unit}" if low == high else f"{low}–{high}{unit}"


def test_the_speed_table_is_its_runs():
    runs = [json.loads(path.read_text(encoding="utf-8"))["rows"]
            for path in sorted(SPEED_RUNS.glob("*.json"))]
    assert len(runs) >= 3, "docs/benchmark/speed/ keeps the runs its table quotes"
    table = {line.split(" | ")[0].removeprefix("| "): line.split(" | ")
             for line in BENCHMARKS_PAGE.read_text(encoding="utf-8").splitlines()
             if line.startswith("| ")}
    for rows, key, unit in ((SPEED_ROWS, "ratio", "×"), (CHECK_ROWS, "check_over_method", "")):
        for measure, names in rows.items():
            cell = " / ".join(spread_of([next(r[key] for r in run if r["run"] == name)
                                         for run in runs], unit) for name in names)
            shown = table[measure][3].replace("**", "").strip()  # bold: a goal met
            assert shown == cell, (measure, table[measure][3], cell)
