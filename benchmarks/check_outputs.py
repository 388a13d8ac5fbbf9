"""Check that a benchmarks/run.py output folder is complete and parses (CI's smoke test).

    python benchmarks/check_outputs.py DIR
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

CHARTS = ("speed_accuracy.png", "time_vs_elements.png", "penalty.png", "stability_map.png")
PNG = b"\x89PNG\r\n\x1a\n"
OUTCOMES = {"verified", "flagged", "claimed success, wrong", "verified, wrong", "skipped"}


def check(out: Path) -> list[str]:
    """Problems found in ``out`` (empty when it is complete)."""
    problems = []
    document = json.loads((out / "runs.json").read_text())
    runs = document["runs"]
    with open(out / "runs.csv", newline="") as handle:
        table = list(csv.DictReader(handle))
    if not runs or len(table) != len(runs):
        problems.append(f"runs.json has {len(runs)} runs, runs.csv {len(table)}")
    cases = {c["case"] for c in document["cases"]}
    if {r["case"] for r in runs} != cases:
        problems.append("runs and cases name different cases")
    for r in runs:
        if r["outcome"] not in OUTCOMES:
            problems.append(f"unknown outcome {r['outcome']!r} in {r['case']}: {r['label']}")
        elif r["outcome"] == "skipped" and not r.get("skip_reason"):
            problems.append(f"skipped without a reason: {r['case']}: {r['label']}")
        elif "seconds" in r and not (r["seconds"] > 0 and r["ratio"] > 0):
            problems.append(f"no time: {r['case']}: {r['label']}")
    if not any(r["outcome"] == "verified" for r in runs):
        problems.append("no verified run")
    for name in CHARTS:
        path = out / name
        if not path.is_file() or path.read_bytes()[:8] != PNG or path.stat().st_size < 5000:
            problems.append(f"{name} is missing or not a PNG chart")
    if "| case |" not in (out / "best.md").read_text():
        problems.append("best.md has no table")
    return problems


def main() -> None:
    out = Path(sys.argv[1])
    problems = check(out)
    for problem in problems:
        print(f"benchmark output: {problem}", file=sys.stderr)
    if problems:
        sys.exit(1)
    print(f"benchmark output in {out}: complete")


if __name__ == "__main__":
    main()
