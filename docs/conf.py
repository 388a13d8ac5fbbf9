"""Sphinx configuration of the contactqp documentation site.

Build with ``sphinx-build -W -b html docs docs/_build/html`` (warnings are errors). The
examples in ``examples/*.py`` are run by sphinx-gallery at build time, so every number and
chart on the tutorial and example pages is the library's own output of that build.
"""

import re
import sys
from pathlib import Path

import contactqp

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).parent / "_ext"))

project = "contactqp"
author = "the contactqp developers"
copyright = "2026, the contactqp developers"
release = version = contactqp.__version__

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "benchmark/*.md",  # shown through benchmark_tables/
                    "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.md5", "auto_examples/*.json"]
suppress_warnings = ["myst.header"]  # the benchmark reports start at level-2 headings

myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3

# The API reference: one page per public name, from its numpy-style docstring.
autosummary_generate = True
autodoc_typehints = "none"  # the docstrings' Parameters sections say the types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
# Checked at build time (-W makes them errors): every parameter documented and no unknown one,
# a Returns section on every function, for the public names (not their methods).
numpydoc_validation_checks = {"PR01", "PR02", "RT01"}
# The classes the library builds (a Result from solve(), a Batch from solve_many(), …) list
# their fields under Attributes: nobody constructs them, so they take no Parameters section.
BUILT_BY_THE_LIBRARY = ("Result", "Batch", "Prepared", "Run", "LoadPath", "Model", "QPProblem",
                        "ProblemResult")
numpydoc_validation_exclude = {r"^contactqp\.[^.]+\.", r"\.__init__$",
                               *(rf"^contactqp\.{name}$" for name in BUILT_BY_THE_LIBRARY)}

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r".*\.py$",  # run every example, not only plot_*.py
    "image_scrapers": ("figures.scrape_figures",),  # contactqp draws without pyplot
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "show_memory": False,
    "min_reported_time": 10**9,
}

html_theme = "pydata_sphinx_theme"
html_title = f"contactqp {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
}
html_static_path = ["_static"]
html_css_files = ["contactqp.css"]
# Pages with no section below them show no (empty) navigation column, nor does the benchmarks
# page (its text links its tables): their code blocks and charts get the width of the page.
html_sidebars = {page: [] for page in ("index", "getting_started", "architecture", "benchmarks",
                                       "auto_examples/course_problem")}


# The figures the README and the how-to pages show (docs/load_path.png, docs/nitsche_sweep.png)
# are drawn here at every build, by the command line as a user runs it (`contactqp curve`, and
# `contactqp`, the main job), so that a change to a chart or to the library shows up in them:
# the README reads the committed files, which the last build rewrote.
CLI_FIGURES = {"load_path.png": ["curve"], "nitsche_sweep.png": []}


def draw_cli_figures(app) -> None:
    """Run the commands that draw the pages' figures and copy those into docs/."""
    import contextlib
    import io
    import shutil
    import tempfile

    from contactqp.cli import main

    with tempfile.TemporaryDirectory() as folder:
        for name, command in CLI_FIGURES.items():
            with contextlib.redirect_stdout(io.StringIO()):
                status = main([*command, "--out", folder])
            if status != 0:
                raise RuntimeError(f"contactqp {' '.join(command)} exited {status}")
            shutil.copyfile(Path(folder) / name, Path(app.srcdir) / name)


# The Markdown pages link what a reader of the repository can open (examples/*.py, the
# examples/ folder, docs/benchmark/*.md); in the built site the same links go to the pages the
# build makes of those (the gallery, and benchmark_tables/, which show the tables).
BUILT_PAGES = (
    (r"\]\((?:\.\./)+examples/(\w+)\.py\)", r"]({up}auto_examples/\1)"),
    (r"\]\((?:\.\./)+examples/?\)", r"]({up}auto_examples/index)"),
    (r"\]\((?:\.\./)*benchmark/(\w+)\.md\)", r"]({up}benchmark_tables/\1.md)"),
)


def link_built_pages(app, docname: str, source: list[str]) -> None:
    """Point a page's links to examples and benchmark tables at their built pages."""
    up = "../" * docname.count("/")
    for pattern, target in BUILT_PAGES:
        source[0] = re.sub(pattern, target.replace("{up}", up), source[0])


def setup(app) -> None:
    app.connect("builder-inited", draw_cli_figures)
    app.connect("source-read", link_built_pages)
