"""Issue 28's figures from one command: each a ratio to a floor measured in the same run.

    solve 10⁶         solve(scene) with its defaults on the tapered bar of 10⁶ elements, one
                      wall; floor: one banded factor-and-solve of K (benchmarks/cases.floor)
    condensed 10⁶     the same scene by Lagrange, formulation="condensed"
    walls 10⁵ warm    solve(scene) again on a scene of 10⁵ walls (a two-sided channel, a
                      pressed flat patch; contactqp.builders) whose model is built once;
                      again in a process that solves that scene alone (a subprocess)
    walls 10⁵ first   building that scene and its first solve, timed in this process and, in
                      a fresh process (a subprocess), with the imports the first solve needs
    check / method    the check's time over the method's, from the Results' own timings
    default scene     one verified solve of contactqp.default_scene() against the seed's numpy
                      script (benchmarks/loop.py, hand_script; no slower than in a process
                      with one OpenBLAS thread); prepared.solve against the same; each timed
                      in turn with its floor, the ratio the median of the rounds' ratios
    solve_many 10⁴    10⁴ cases varying the load and the gap against a vectorised numpy version
                      (timed in turn with it, as the default scene)

Every row gives the method's, the check's and the build's time apart (Result.timings), and
the page faults per call of the warm rows. Warm rows keep each run's Result only until the
next run's is made, as a user's loop does: on this machine (a VM) the first touch of a page
the OS hands out costs ~2 µs (10⁵ doubles written for the first time: 0.35-0.46 ms and 196
faults, against 0.03 ms reused), so holding every Result of a 10⁶-element run made its solve
97 ms instead of 35-48 ms. How many pages a call meets afresh also depends on what the
process allocated before it (glibc returns the top of its heap to the OS past a threshold
that grows with the largest block freed), so the same call took 0-4 000 faults from one
process to the next; the fault count says how much of a row that is. The warm rows of this
process follow the 10⁶-element rows, whose 8 MB blocks raise that threshold; each walls row
is timed again in a process of its own, which meets its pages afresh. The first-solve rows
pay those pages, as a user's first solve does; the fresh process counts its page faults.
Writes speed.json.
"""

from __future__ import annotations

import json
import math
import os
import resource
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import contactqp
from cases import floor, machine, median_time, tapered_scene
from contactqp.builders import channel, flat_patch
from loop import FORCE, GAP, hand_script, hand_stiffness

FIRST_SOLVE = """
import resource, sys, time
start = time.perf_counter()
import contactqp
from contactqp.builders import {builder}
imported = time.perf_counter()
scene = {builder}({size})
built = time.perf_counter()
faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
result = contactqp.solve(scene)
done = time.perf_counter()
faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
assert result.verified, result.message
print(imported - start, built - imported, done - built, faults)
"""


WARM_SOLVE = """
import resource, statistics, time
import contactqp
from contactqp.builders import {builder}
scene = {builder}({size})
result = contactqp.solve(scene)  # untimed, as median_time's first call
times, faults = [], resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range({repeats}):
    start = time.perf_counter()
    result = contactqp.solve(scene)
    times.append(time.perf_counter() - start)
faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
assert result.verified, result.message
print(statistics.median(times), faults / {repeats})
"""


def _warm_alone(builder: str, size: int, repeats: int) -> tuple[float, float]:
    """(the median warm re-solve, its page faults per call) in a process that solves this
    scene alone: what a user's loop meets where nothing larger was freed before it."""
    seconds, faults = _numbers_of(WARM_SOLVE.format(builder=builder, size=size,
                                                    repeats=repeats))
    return seconds, faults


def _numbers_of(code: str) -> list[float]:
    """The numbers a script prints, run in a fresh Python process."""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    return [float(number) for number in out]


def _split(result: contactqp.Result | _Timed) -> dict[str, float]:
    return {name: result.timings.get(name, 0.0) for name in ("build", "solve", "check")}


def _row(name: str, seconds: float, base: float, against: str, goal: float,
         result: contactqp.Result | _Timed | None = None, **extra: object) -> dict:
    row = {"run": name, "seconds": seconds, "ratio": seconds / base, "against": against,
           "goal": goal, **extra}
    if result is not None:
        row.update(_split(result))
        row["check_over_method"] = row["check"] / row["solve"]
        if isinstance(result, _Timed) and not math.isnan(result.faults):
            row["faults_per_call"] = result.faults
    return row


def _timed_solve(scene: contactqp.Scene, repeats: int, **options: object
                 ) -> tuple[float, _Timed]:
    """The median time of ``solve(scene)``, the Result of the median run and the page faults
    per call. Each run's Result is kept only until the next run's is made (its timings kept),
    as ``result = solve(...)`` in a user's loop keeps it: holding every Result of 10⁶ nodes
    made each run's arrays fresh pages from the OS, each ~2 µs on first touch on this
    machine, which doubled the 10⁶ figures (module docstring)."""
    runs: list[_Timed] = []
    last: list[contactqp.Result] = []

    def once() -> None:
        result = contactqp.solve(scene, **options)
        last[:] = [result]
        runs.append(_Timed(result.time, dict(result.timings), result.verified,
                           result.message))

    faults = _faults()
    seconds = median_time(once, repeats)
    faults = (_faults() - faults) / (repeats + 1)  # median_time calls once more to warm up
    if not last[0].verified:
        raise SystemExit(f"{scene.name}: not verified ({last[0].message})")
    # the split of the median run: the run whose total is the median
    middle = sorted(runs[1:], key=lambda r: r.time)[len(runs[1:]) // 2]
    return seconds, _Timed(middle.time, middle.timings, middle.verified, middle.message, faults)


def _faults() -> int:
    """The page faults this process has met so far (minor: a page handed out, first touched)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


@dataclass(frozen=True)
class _Timed:
    """What the table reads from one run's Result, without its arrays."""

    time: float
    timings: dict[str, float]
    verified: bool
    message: str
    faults: float = math.nan  # page faults per call, over the timed runs


def long_bar(quick: bool) -> list[dict]:
    n = 10**5 if quick else 10**6
    repeats = 3 if quick else 7
    scene = tapered_scene(n)
    base = floor(scene, repeats)
    rows = [_row(f"floor: pbsv on K, {n} elements", base, base, "", 1.0)]
    seconds, result = _timed_solve(scene, repeats)
    rows.append(_row(f"solve(scene), {n} elements", seconds, base, "floor", 3.0, result))
    seconds, result = _timed_solve(scene, repeats, formulation="condensed")
    rows.append(_row(f"condensed lagrange, {n} elements", seconds, base, "floor", 2.0, result))
    return rows


def _fresh_process(builder: str, size: int) -> dict[str, float]:
    imported, built, solved, faults = _numbers_of(FIRST_SOLVE.format(builder=builder, size=size))
    return {"import": imported, "scene": built, "first_solve": solved, "page_faults": faults}


def many_walls(quick: bool) -> list[dict]:
    size = 10**4 if quick else 10**5
    repeats = 3 if quick else 7
    rows = []
    for builder in (channel, flat_patch):
        scene = builder(size)
        base = floor(scene, repeats)
        rows.append(_row(f"floor: pbsv on K, {scene.name}", base, base, "", 1.0))
        seconds, result = _timed_solve(scene, repeats)
        rows.append(_row(f"{scene.name}, warm re-solve", seconds, base, "floor", 12.0, result))
        seconds, faults = _warm_alone(builder.__name__, size, repeats)
        rows.append(_row(f"{scene.name}, warm re-solve (own process)", seconds, base, "floor",
                         12.0, faults_per_call=faults))
        start = time.perf_counter()
        fresh = builder(size)
        made = time.perf_counter()
        result = contactqp.solve(fresh)
        seconds = time.perf_counter() - made
        rows.append(_row(f"{scene.name}, first solve (this process)", seconds, base, "floor",
                         20.0, result, scene_build=made - start))
        fresh = _fresh_process(builder.__name__, size)
        rows.append(_row(f"{scene.name}, first solve (fresh process)", fresh["first_solve"],
                         base, "floor", 20.0, None, **fresh))
    return rows


def default_loop(quick: bool) -> list[dict]:
    """The default scene against the seed script, and 10⁴ cases against a vectorised numpy
    version, each timed in turn with its floor, round after round (:func:`paired`): a busy
    moment of the machine slows both of a round, not one row's floor alone (measured: the
    seed script 34 µs, and 52-61 µs in two runs of the same minute). The seed script's floor
    in a round is also never slower than in a process with one OpenBLAS thread."""
    repeats, cases = (50, 1000) if quick else (300, 10_000)
    scene = contactqp.default_scene()
    result = contactqp.solve(scene)
    if not (result.verified and math.isclose(result.contact_force[0], hand_script()[1],
                                             rel_tol=1e-9)):
        raise SystemExit("default scene: the library and the seed script disagree")
    alone = _one_thread_script(repeats)
    solved: list[contactqp.Result] = []

    def solve_once() -> None:  # keeps the last Result only, as _timed_solve
        solved[:] = [contactqp.solve(scene)]

    script, solve_seconds, solve_ratio, solve_faults = paired(hand_script, solve_once,
                                                              repeats, alone)
    prepared = contactqp.prepare(scene)
    one = np.array([1.1 * FORCE])
    one_case = prepared.solve(one)
    _, prepared_seconds, prepared_ratio, prepared_faults = paired(
        hand_script, lambda: prepared.solve(one), repeats, alone)
    factors = np.linspace(0.5, 1.5, cases)
    loads, gaps = (FORCE * factors)[:, None], (GAP * factors[::-1])[:, None]
    exact = vectorised(loads[:, 0], gaps[:, 0])
    batch = prepared.solve_many(loads, gaps)
    if not (batch.verified.all() and np.allclose(batch.contact_force[:, 0], exact, rtol=1e-9,
                                                 atol=1e-9 * FORCE)):
        raise SystemExit("solve_many disagrees with the vectorised numpy version")
    numpy_time, many_seconds, many_ratio, many_faults = paired(
        lambda: vectorised(loads[:, 0], gaps[:, 0]), lambda: prepared.solve_many(loads, gaps),
        3 if quick else 10)
    rows = [_row("seed numpy script", script, script, "", 1.0, one_thread=alone),
            _row("solve(default scene)", solve_seconds, script, "seed script", 15.0,
                 solved[-1]),
            _row("prepared.solve", prepared_seconds, script, "seed script", 8.0, one_case),
            _row(f"vectorised numpy, {cases} cases", numpy_time, numpy_time, "", 1.0),
            _row(f"solve_many, {cases} cases (load and gap)", many_seconds, numpy_time,
                 "vectorised numpy", 10.0)]
    for row, ratio, faults in zip(rows[1:], (solve_ratio, prepared_ratio, None, many_ratio),
                                  (solve_faults, prepared_faults, None, many_faults)):
        if ratio is not None:
            row["ratio"] = ratio  # the median of the rounds' ratios
            row["faults_per_call"] = faults
    return rows


ROUNDS = 9  # rounds of paired(), each timing the floor and the job


def paired(floor_job: Callable[[], object], job: Callable[[], object], calls: int,
           floor_limit: float = math.inf) -> tuple[float, float, float, float]:
    """(the floor's median time, the job's median time, the median over ROUNDS rounds of the
    job's time over the floor's, the job's page faults per call), each round timing ``calls``
    calls of the floor, then of the job (both warmed first); a round's floor is at most
    ``floor_limit``."""
    floor_job(), job()
    floors, times, faults = [], [], 0
    for _ in range(ROUNDS):
        for target, into in ((floor_job, floors), (job, times)):
            before = _faults()
            start = time.perf_counter()
            for _ in range(calls):
                target()
            into.append((time.perf_counter() - start) / calls)
            if target is job:
                faults += _faults() - before
    floors = [min(f, floor_limit) for f in floors]
    ratios = [t / f for t, f in zip(times, floors)]
    return (statistics.median(floors), statistics.median(times), statistics.median(ratios),
            faults / (ROUNDS * calls))


SEED_SCRIPT = """
from cases import median_time
from loop import hand_script
print(median_time(hand_script, {repeats}))
"""


def _one_thread_script(repeats: int) -> float:
    """The seed script's median time in a process with one OpenBLAS thread. Its 5x5 solve
    took 34 µs there every time, and 34-80 µs from one process to the next with OpenBLAS's
    default threads (same numpy), so the floor is the faster of the two: the stricter one."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", SEED_SCRIPT.format(repeats=repeats)],
                         capture_output=True, text=True, check=True, env=env,
                         cwd=Path(__file__).parent).stdout
    return float(out)


def vectorised(forces: np.ndarray, gaps: np.ndarray) -> np.ndarray:
    """The tip wall's force of every case, as benchmarks/loop.py's hand_vectorised writes it:
    the free displacements of all cases by one solve with K and many right-hand sides, then
    the closed form of one wall, λ = max(0, (u_free,tip − g) / (K⁻¹)_tip,tip)."""
    K = hand_stiffness()
    P = np.zeros((4, forces.size))
    P[1] = forces  # the load at node 2
    u_free = np.linalg.solve(K, P)
    flexibility = np.linalg.solve(K, np.eye(4)[:, -1])[-1]
    return np.maximum(0.0, (u_free[-1] - gaps) / flexibility)


def main(quick: bool, out: Path) -> None:
    rows = long_bar(quick) + many_walls(quick) + default_loop(quick)
    print(f"{'run':48} {'ms':>9} {'ratio':>7} {'goal':>5} {'build':>7} {'method':>7} "
          f"{'check':>7} {'chk/mth':>7}")
    for r in rows:
        split = "".join(f" {1e3 * r[k]:7.2f}" if k in r else f" {'':7}"
                        for k in ("build", "solve", "check"))
        ratio = f" {r['check_over_method']:7.2f}" if "check_over_method" in r else ""
        goal = f"{r['goal']:5.0f}" if r["against"] else ""
        print(f"{r['run']:48} {1e3 * r['seconds']:9.3f} {r['ratio']:7.1f} {goal:>5}{split}{ratio}"
              + (f"  import {1e3 * r['import']:.0f} ms, {r['page_faults']:.0f} page faults"
                 if "import" in r else "")
              + (f"  (one OpenBLAS thread: {1e6 * r['one_thread']:.0f} µs)"
                 if "one_thread" in r else "")
              + (f"  {r['faults_per_call']:.0f} page faults a call"
                 if "faults_per_call" in r else ""))
    out.mkdir(parents=True, exist_ok=True)
    (out / "speed.json").write_text(json.dumps({"machine": machine(), "rows": rows}, indent=1))
