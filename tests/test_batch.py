"""contactqp.many.batch: many cases of a prepared scene, solved and checked together.

Every expected answer is the exact reference of the case's scene built anew from its parts
(contactqp.reference, itself tested against closed forms and exact arithmetic), a fresh
contactqp.solve of that scene, or the default scene's closed form; never the batch itself.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import contactqp
from closed_forms import (
    DEFAULT_F,
    DEFAULT_GAP,
    DEFAULT_LENGTHS,
    cantilever,
    default_areas,
    rebuilt,
    values,
)
from contactqp.many.batch import tiled_scene
from contactqp.random_scenes import random_scene
from contactqp.reference import reference

SCENES = Path(__file__).parent / "scenes"
# the reference is exact to ~1e-13 of F and U, and the bounds round at ~1e-14 (as in
# test_guarantee.py)
ROUND_OFF = 1e-12
BOUND_FACTOR = 2.0  # as test_guarantee.py: within the bounds where a row may change sides


def random_cases(rng: np.random.Generator, scene: contactqp.Scene,
                 cases: int) -> tuple[np.ndarray, np.ndarray]:
    """Loads scaled by −1.5..2 (signs flip: walls open, close and swap), gaps by 0..2 with one
    case in four at zero gap (touching everywhere); bar contacts' gaps stay >= 0."""
    loads, gaps = values(scene)
    load_cases = loads * rng.uniform(-1.5, 2.0, (cases, 1))
    gap_cases = gaps * rng.uniform(0.0, 2.0, (cases, 1))
    gap_cases[rng.random(cases) < 0.25] = 0.0
    return load_cases, gap_cases


def quietly(function, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return function(*args, **kwargs)


def assert_right(u, force, F, U, force_bound, displacement_bound, exact, context) -> None:
    """Within the guarantee, and within the bounds (BOUND_FACTOR)."""
    force_error = float(np.abs(force - exact.contact_force).max(initial=0.0))
    displacement_error = float(np.abs(u - exact.displacement).max())
    assert force_error <= contactqp.GUARANTEE[0] * F, context
    assert displacement_error <= contactqp.GUARANTEE[1] * U, context
    assert force_error <= BOUND_FACTOR * force_bound + ROUND_OFF * F, context
    assert displacement_error <= BOUND_FACTOR * displacement_bound + ROUND_OFF * U, context


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1), st.sampled_from(["lagrange", "penalty"]))
def test_every_case_verified_in_a_batch_is_right_and_verified_alone(seed, method):
    """Random scenes (several bars, walls on both sides, zero gaps, press fits, bar contacts)
    and random cases: a case the batch verifies is within its guarantee of the exact answer of
    its scene, and its own Result (``batch[i]``, checked alone) verifies it too, with
    residuals no larger than the batch's; the batch's scales are the case's own (U bit for bit,
    F to its last bits)."""
    rng = np.random.default_rng(seed)
    scene = random_scene(rng)
    loads, gaps = random_cases(rng, scene, 4)
    try:
        batch = quietly(contactqp.prepare(scene, method).solve_many, loads, gaps)
    except contactqp.SceneError:  # a case's gaps leave a node no position: refused
        return
    for case in range(len(batch)):
        alone = quietly(batch.__getitem__, case)
        context = f"seed {seed}, {method}, case {case}: {alone.residuals}"
        # the same numbers: each case's load terms come from its own running sum, bit for bit;
        # λ₀'s step (a press fit's force scale) is summed in another order over the tiled
        # rows, its last bits apart (seed 12532693: 11571911.458631499 against ...495)
        assert batch.force_scale[case] == pytest.approx(alone.force_scale, rel=1e-13), context
        assert batch.displacement_scale[case] == alone.displacement_scale, context
        np.testing.assert_array_equal(batch.contact_force[case], alone.contact_force)
        np.testing.assert_array_equal(batch.u[case], alone.u)
        if not batch.verified[case]:
            continue
        assert alone.verified, context
        for name, value in alone.residuals.items():  # the batch's are at least its own, but
            # for round-off (sums over other cases: contactqp.many.batch). Not the error
            # bounds: the certificate counts a row as pushing past COMPLEMENTARITY × F, and
            # the batch's F is the largest case's, so it may read a case through other held
            # rows and find a smaller (as sound) bound than the case alone (seeds 59252 and
            # 180364: 2.8e-8 F against 1.3e-8 F). Both must bound the error: assert_right.
            if value is not None and name not in ("force", "displacement"):
                assert value <= batch.residuals[name][case] + 1e-9, (name, context)
        exact = reference(rebuilt(scene, loads[case], gaps[case]))
        assert_right(batch.u[case], batch.contact_force[case], batch.force_scale[case],
                     batch.displacement_scale[case], batch.force_error_bound[case],
                     batch.displacement_error_bound[case], exact, context)
        assert_right(alone.u, alone.contact_force, alone.force_scale, alone.displacement_scale,
                     alone.force_error_bound, alone.displacement_error_bound, exact, context)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_lagrange_in_a_batch_is_verified_where_it_is_alone(seed):
    """Without the extra stiffness contrast Lagrange multipliers are exact to round-off
    (test_guarantee.py): every case of a batch is verified, and its forces agree with a fresh
    solve of the case's scene within the two answers' bounds."""
    rng = np.random.default_rng(seed)
    scene = random_scene(rng, max_bars=1, contrast=False)
    loads, gaps = random_cases(rng, scene, 5)
    try:
        batch = contactqp.prepare(scene).solve_many(loads, gaps)
    except contactqp.SceneError:
        return
    for case in range(len(batch)):
        fresh = contactqp.solve(rebuilt(scene, loads[case], gaps[case]))
        assert fresh.verified and batch.verified[case], (seed, case, fresh.message)
        bound = fresh.force_error_bound + batch.force_error_bound[case]
        assert np.abs(batch.contact_force[case] - fresh.contact_force).max(initial=0.0) <= (
            bound + ROUND_OFF * fresh.force_scale)


def test_the_default_scene_batch_is_the_closed_form_and_solved_together():
    """10³ cases, loads from −F to 3F and gaps from 0 to 2g: every force is the closed form
    max(0, (F f₂ − g) / f₄), every case verified together (none solved alone)."""
    cases = 1000
    rng = np.random.default_rng(7)
    forces = rng.uniform(-1.0, 3.0, cases) * DEFAULT_F
    gaps = rng.uniform(0.0, 2.0, cases) * DEFAULT_GAP
    batch = contactqp.prepare().solve_many(forces[:, None], gaps[:, None])
    expected = [cantilever(DEFAULT_LENGTHS, default_areas("midpoint"), 210e9, [(2, f)],
                           (4, g, "+"))[1] for f, g in zip(forces, gaps)]
    np.testing.assert_allclose(batch.contact_force[:, 0], expected, rtol=1e-12,
                               atol=1e-12 * DEFAULT_F)
    assert batch.verified.all() and batch.physical.all() and not batch.alone
    assert set(batch.iterations.tolist()) <= {1, 2}  # open: one step; closed: two


def test_a_case_the_batch_cannot_settle_is_solved_alone():
    """A loop of walls and bar contacts with zero gaps (the textbook loop cycles on it, and
    Lagrange hands over to Lemke's method): its held rows are dependent, so the batch hands
    such cases to the single-case solve, and every case is right."""
    scene = contactqp.load_scene(SCENES / "cycle_zero_gap_loop.toml")
    loads, gaps = values(scene)
    load_cases = np.vstack([loads * f for f in (1.0, 0.5, -1.0)])
    batch = contactqp.prepare(scene).solve_many(load_cases, np.tile(gaps, (3, 1)))
    assert batch.alone and not batch.failures
    for case in range(3):
        exact = reference(rebuilt(scene, load_cases[case], gaps))
        assert batch.verified[case]
        assert_right(batch.u[case], batch.contact_force[case], batch.force_scale[case],
                     batch.displacement_scale[case], batch.force_error_bound[case],
                     batch.displacement_error_bound[case], exact, case)


@pytest.mark.parametrize("method", ["augmented", "qp"])
def test_other_methods_solve_a_batch_case_by_case(method):
    forces = np.array([[0.5], [1.0], [1.5]]) * DEFAULT_F
    batch = contactqp.prepare(method=method).solve_many(forces)
    assert sorted(batch.alone) == [0, 1, 2]
    for case in range(3):
        expected = cantilever(DEFAULT_LENGTHS, default_areas("midpoint"), 210e9,
                              [(2, forces[case, 0])], (4, DEFAULT_GAP, "+"))[1]
        assert batch.contact_force[case, 0] == pytest.approx(expected, rel=1e-5)
        assert batch[case].contact_force[0] == batch.contact_force[case, 0]


def test_a_case_with_gaps_that_leave_a_node_no_position_is_named():
    bar = contactqp.Bar.from_areas([1e-4, 1e-4], 2e11, length=2.0)
    scene = contactqp.Scene(bar, (contactqp.Support(0),), (contactqp.Load(1, 1e3),),
                            (contactqp.Wall(1, 1e-4, "+"), contactqp.Wall(1, 0.0, "-")))
    with pytest.raises(contactqp.SceneError, match=r"^case 1: wall\[0\]"):
        contactqp.prepare(scene).solve_many(gaps=[[2e-4, 0.0], [-2e-4, 1e-4]])


def test_a_tiled_scene_is_its_copies_side_by_side():
    """Two bars and a bar contact, three times: the copies' bars one after another, each
    copy's supports, loads, walls and contacts on its own bars."""
    scene = contactqp.load_scene(SCENES / "cycle_two_bar_contacts.toml")
    tiled = tiled_scene(scene, 3)
    n = len(scene.bars)
    assert len(tiled.bars) == 3 * n and tiled.n_contacts == 3 * scene.n_contacts
    assert [s.bar for s in tiled.supports] == [s.bar + k * n for k in range(3)
                                               for s in scene.supports]
    assert [(c.bar_a, c.bar_b) for c in tiled.contacts] == [
        (c.bar_a + k * n, c.bar_b + k * n) for k in range(3) for c in scene.contacts]


@pytest.mark.parametrize("method", ["lagrange", "pgs"])
def test_a_batch_tells_its_progress_when_asked(method):
    """Solved case by case (pgs), after each case; solved together (lagrange), at the end:
    the last call is always (cases, cases), and nothing counts down."""
    seen = []
    forces = np.linspace(0.5, 1.5, 4)[:, None] * DEFAULT_F
    contactqp.prepare(method=method).solve_many(forces,
                                                progress=lambda d, t: seen.append((d, t)))
    assert seen[-1] == (4, 4)
    assert [d for d, _ in seen] == sorted({d for d, _ in seen})
    if method == "pgs":
        assert seen == [(1, 4), (2, 4), (3, 4), (4, 4)]


def test_a_batch_larger_than_a_scene_may_be_is_refused_up_front():
    """The default scene has 4 elements: 10⁷ / 4 cases at most, said before any solve."""
    prepared = contactqp.prepare(method="pgs")
    with pytest.raises(contactqp.OptionError, match=r"2500001 cases of 4 elements; a batch "
                                                    r"takes at most 2500000"):
        prepared.solve_many(np.ones((2_500_001, 1)))
    with pytest.raises(contactqp.OptionError, match=r"progress must be True, False or a "
                                                    r"callable .* got 'yes'"):
        prepared.solve_many(progress="yes")
