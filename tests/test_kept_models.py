"""What a solve keeps, and for how long: a Scene keeps its layout and model, a Problem its
model (so that a second solve reuses K's factorisation), and a Result holds the model; none of
them may hold the others in a cycle, or each solve's factorisations stay in memory until
Python's cyclic collector happens to run (420 MB a solve at 3.3·10⁵ dofs, 42 MB for a scene of
10⁵ elements, growing with every solve of a loop).

Every test runs with the cyclic collector off: what plain reference counting does not free is
what such a cycle keeps. The expected answers need no number: an object is gone or is not.
"""

from __future__ import annotations

import gc
import pickle
import weakref

import numpy as np
import pytest

import contactqp
from contactqp.builders import flat_patch
from contactqp.model import scene_model
from contactqp.model.sparse import problem_model
from contactqp.random_scenes import random_scene

METHODS = [m for m in contactqp.METHODS if m != "nitsche"]  # nitsche refuses both models here


@pytest.fixture
def no_cyclic_collector():
    gc.collect()
    gc.disable()
    try:
        yield
    finally:
        gc.enable()


def _problem() -> contactqp.Problem:
    """Three springs in series on a support, the last node against a wall 1e-3 away, loaded
    past it (one row in contact)."""
    K = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]) * 1e3
    return contactqp.Problem(K, [0.0, 0.0, 5.0], [[0.0, 0.0, 1.0]], [1e-3])


@pytest.mark.parametrize("method", METHODS)
def test_a_solved_problem_its_model_and_result_go_with_their_last_reference(
        method, no_cyclic_collector):
    problem = _problem()
    result = contactqp.solve(problem, method)
    assert result.problem is problem  # the user's object while they hold it
    assert problem_model(problem) is result.model  # kept: a second solve reuses it
    K = problem.K
    seen = [weakref.ref(problem), weakref.ref(result.model)]
    del problem
    assert seen[0]() is None  # the Result does not hold the problem past its user
    assert result.problem.K is K and result.problem.n == 3  # a copy of it, the same arrays
    del result
    assert [ref() for ref in seen] == [None, None]


@pytest.mark.parametrize("method", METHODS)
def test_a_solved_scene_its_layout_model_and_result_go_with_their_last_reference(
        method, no_cyclic_collector):
    scene = flat_patch(30)
    result = contactqp.solve(scene, method)
    assert result.scene is scene and scene_model(scene) is result.model
    bars = scene.bars
    seen = [weakref.ref(scene), weakref.ref(result.model), weakref.ref(result.layout)]
    del scene
    assert seen[0]() is None
    assert result.scene.bars is bars and result.summary()  # a copy of it, the same parts
    del result
    assert [ref() for ref in seen] == [None, None, None]


def test_a_scene_with_floating_bars_goes_with_its_last_reference(no_cyclic_collector):
    """A model of bars with no support makes a second model with them tied (its scales): that
    one must not keep the first either."""
    rng = np.random.default_rng(7)
    for _ in range(50):
        scene = random_scene(rng, floating=1.0)
        if scene_model(scene).floating:
            break
    else:
        pytest.fail("no scene with a floating bar drawn")
    result = contactqp.solve(scene, "lagrange")
    assert result.model.held is not result.model
    seen = [weakref.ref(scene), weakref.ref(result.model), weakref.ref(result.model.held)]
    del scene, result
    assert [ref() for ref in seen] == [None, None, None]


def test_values_prepared_and_batched_go_with_their_last_reference(no_cyclic_collector):
    """A problem and a scene with other values (which share their parent's factorisation or
    numbering), and a prepared problem's solves."""
    problem = _problem()
    contactqp.solve(problem)
    other = problem.with_values(f=[0.0, 0.0, 8.0])
    again = contactqp.solve(other)
    assert again.problem is other and again.verified
    scene = flat_patch(20)
    contactqp.solve(scene)
    moved = scene.with_values(gaps=np.asarray(scene.walls.gaps) * 2.0)
    shifted = contactqp.solve(moved)
    assert shifted.scene is moved
    prepared = contactqp.prepare(problem, "lagrange")
    cases = [prepared.solve(loads=[0.0, 0.0, load]) for load in (3.0, 6.0)]
    seen = [weakref.ref(item) for item in (problem, other, again.model, scene, moved,
                                            shifted.model, prepared, cases[1].model)]
    del problem, other, again, scene, moved, shifted, prepared, cases
    assert [ref() for ref in seen] == [None] * len(seen)


def test_a_scene_its_result_and_layout_pickle_as_before():
    """A weak reference does not pickle: a layout pickles as one of its scene's detached copy,
    and a pickled Result of a scene reads the same as the one it was made from."""
    scene = flat_patch(12)
    result = contactqp.solve(scene, "lagrange")
    again = pickle.loads(pickle.dumps(result))
    for name in ("u", "contact_force", "reactions", "element_force"):
        assert np.array_equal(getattr(again, name), getattr(result, name)), name
    assert again.verified == result.verified and again.summary() == result.summary()
    assert again.layout.n_nodes == result.layout.n_nodes
    scene_again = pickle.loads(pickle.dumps(scene))  # without the layout and model it keeps
    assert not {"layout", "_scene_model"} & set(scene_again.__dict__)
    assert np.array_equal(contactqp.solve(scene_again, "lagrange").u, result.u)


def test_a_solved_problem_pickles_without_its_factorisation():
    """A Problem keeps its model, whose CHOLMOD factor does not pickle: the Problem pickles
    without it (it raised a TypeError before), and the copy solves to the same answer."""
    problem = _problem()
    first = contactqp.solve(problem, "lagrange")
    again = pickle.loads(pickle.dumps(problem))
    assert not any(key.startswith("_sparse_model") for key in again.__dict__)
    assert np.array_equal(contactqp.solve(again, "lagrange").u, first.u)
