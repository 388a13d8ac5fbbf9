"""Test settings: under CI (CI=true) hypothesis runs derandomised, so a submission's CI run
tries the same examples as every other; locally it keeps exploring new ones. The report's
header names the Python and the release of every dependency the run used, so a release that
breaks a test is named in the log (CI once passed on older packages than a fresh install
gets)."""

import importlib.metadata
import os
import platform

from hypothesis import settings

settings.register_profile("ci", derandomize=True, deadline=None)
if os.environ.get("CI", "").lower() == "true":
    settings.load_profile("ci")

DEPENDENCIES = ("numpy", "scipy", "cvxpy", "osqp", "clarabel", "qpsolvers", "matplotlib",
                "hypothesis", "scikit-fem")


def installed_versions() -> list[str]:
    """'name version' of each of DEPENDENCIES that is installed."""
    found = []
    for name in DEPENDENCIES:
        try:
            found.append(f"{name} {importlib.metadata.version(name)}")
        except importlib.metadata.PackageNotFoundError:
            pass
    return found


def cpu_name() -> str:
    """The processor's model name (a LAPACK build can meet a singular matrix differently on
    another CPU: issue 25's Nitsche failure showed on an Intel Xeon and not on an AMD EPYC)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as info:
            for line in info:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def pytest_report_header(config) -> str:
    return (f"contactqp dependencies: Python {platform.python_version()} "
            f"({platform.machine()}, {cpu_name()}); " + ", ".join(installed_versions()))
