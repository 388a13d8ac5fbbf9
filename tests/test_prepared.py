"""contactqp.prepare: a scene prepared once, solved for other load values and gaps.

Every expected answer is a fresh contactqp.solve of the scene built anew with the same values
(not through Scene.with_values, the code under test), or the closed form of the default scene.
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp
from closed_forms import (
    DEFAULT_F,
    DEFAULT_GAP,
    DEFAULT_LENGTHS,
    EXAMPLES,
    INSTALLED_SOLVERS,
    SCENES,
    cantilever,
    default_areas,
    rebuilt,
    values,
)
from contactqp import Load, Wall
from contactqp.model.chain import layout_of

RUNS = [("lagrange", {}), ("penalty", {}), ("augmented", {}),
        ("qp", {"backend": "clarabel"}), ("qp", {"backend": "osqp"}),
        ("qp", {"backend": "cvxpy"})]
RUN_IDS = ["/".join([m, *o.values()]) for m, o in RUNS]


def assert_same(result: contactqp.Result, fresh: contactqp.Result) -> None:
    """The same answer to round-off: the same method on the same numbers."""
    scale = max(fresh.force_scale, float(np.abs(fresh.contact_force).max(initial=0.0)))
    np.testing.assert_allclose(result.contact_force, fresh.contact_force, rtol=0,
                               atol=1e-12 * scale)
    np.testing.assert_allclose(result.u, fresh.u, rtol=0,
                               atol=1e-12 * max(fresh.displacement_scale, np.abs(fresh.u).max()))
    assert result.verified == fresh.verified
    assert result.options == fresh.options


RESULT_ARRAYS = ("u", "contact_force", "reactions", "penetration", "element_force", "stress")


@pytest.mark.parametrize("method", ["lagrange", "penalty", "augmented", "lemke"])
def test_the_prepared_path_gives_the_fresh_result_bit_for_bit_on_random_scenes(method):
    # what a prepared scene shares between solves (the layout's topology, the model's
    # numbering and K) must not change a single bit of the answer or of its check
    from contactqp.random_scenes import random_scene

    rng = np.random.default_rng()  # fresh scenes each run; the seed is in the message
    seed = int(rng.integers(2**32))
    rng = np.random.default_rng(seed)
    for _ in range(15):
        scene = random_scene(rng)
        loads, gaps = values(scene)
        prepared = contactqp.prepare(scene, method)
        for _ in range(2):
            new_loads = loads * rng.uniform(0.2, 1.8, loads.size)
            new_gaps = gaps * rng.uniform(0.5, 2.0, gaps.size)
            try:
                fresh = contactqp.solve(rebuilt(scene, new_loads, new_gaps), method)
            except (contactqp.SolverError, contactqp.SceneError):
                continue  # new values that leave a bar unheld, or a singular answer
            found = prepared.solve(new_loads, new_gaps)
            for name in RESULT_ARRAYS:
                assert np.array_equal(getattr(found, name), getattr(fresh, name),
                                      equal_nan=True), f"{name}, seed {seed}"
            assert found.residuals == fresh.residuals, f"seed {seed}"
            assert (found.verified, found.force_error_bound, found.displacement_error_bound) \
                == (fresh.verified, fresh.force_error_bound, fresh.displacement_error_bound)


# a scene on a frictional bed is refused by prepare (tests/test_bed_scene.py)
SCENE_FILES = [pytest.param(path, id=path.stem) for path in EXAMPLES
               if "[[bed]]" not in path.read_text(encoding="utf-8")]


@pytest.mark.parametrize(("method", "options"), RUNS, ids=RUN_IDS)
@pytest.mark.parametrize("name", sorted(SCENES))
def test_a_prepared_solve_is_a_fresh_solve_of_the_scene_with_those_values(name, method,
                                                                         options):
    scene = SCENES[name]()
    prepared = contactqp.prepare(scene, method, **options)
    rng = np.random.default_rng(7)
    loads, gaps = values(scene)
    for _ in range(3):
        new_loads = loads * rng.uniform(0.2, 1.8, loads.size)
        new_gaps = gaps * rng.uniform(0.5, 2.0, gaps.size)
        fresh = contactqp.solve(rebuilt(scene, new_loads, new_gaps), method, **options)
        assert_same(prepared.solve(new_loads, new_gaps), fresh)
    assert_same(prepared.solve(), contactqp.solve(scene, method, **options))


@pytest.mark.parametrize("path", SCENE_FILES)
def test_every_example_scene_can_be_prepared(path):
    """Distributed loads, bar contacts, several bars, mm units: the values in scene order."""
    scene = contactqp.load_scene(path)
    prepared = contactqp.prepare(scene)
    loads, gaps = values(scene)
    new_loads, new_gaps = 1.3 * loads, 0.8 * gaps
    assert_same(prepared.solve(new_loads, new_gaps),
                contactqp.solve(rebuilt(scene, new_loads, new_gaps)))


@pytest.mark.parametrize("info", INSTALLED_SOLVERS,
                         ids=[f"{s.backend}-{s.solver}" for s in INSTALLED_SOLVERS])
def test_every_installed_qp_solver_re_solves_as_it_solves(info):
    scene = SCENES["several_walls"]()
    loads, gaps = values(scene)
    prepared = contactqp.prepare(scene, "qp", backend=info.backend, solver=info.solver)
    fresh = contactqp.solve(rebuilt(scene, 0.7 * loads, 1.2 * gaps), "qp",
                            backend=info.backend, solver=info.solver)
    assert_same(prepared.solve(0.7 * loads, 1.2 * gaps), fresh)


def test_a_batch_is_its_cases_and_each_case_its_own_active_set():
    """Loads from 0 to 2F on the default scene: the small ones leave the gap open, the large
    ones close it; every case's force is the closed form max(0, (F f₂ − g) / f₄)."""
    forces = np.linspace(0.0, 2.0 * DEFAULT_F, 9)
    gaps = np.linspace(0.5, 1.5, 9) * DEFAULT_GAP
    batch = contactqp.prepare().solve_many(forces[:, None], gaps[:, None])
    expected = [cantilever(DEFAULT_LENGTHS, default_areas("midpoint"), 210e9, [(2, f)],
                           (4, g, "+"))[1] for f, g in zip(forces, gaps)]
    assert len(batch) == 9 and batch.contact_force.shape == (9, 1)
    np.testing.assert_allclose(batch.contact_force[:, 0], expected, rtol=1e-12,
                               atol=1e-9 * DEFAULT_F)
    assert (batch.contact_force == 0.0).any() and (batch.contact_force > 0.0).any()
    assert batch.verified.all() and batch.u.shape == (9, 5) and batch.reactions.shape == (9, 1)
    assert batch.penetration.shape == (9, 1) and batch.residuals["force"].shape == (9,)
    assert batch[3].contact_force[0] == batch.contact_force[3, 0]


def test_a_batch_of_equality_contact_has_no_complementarity_residual():
    batch = contactqp.prepare(contact="equality").solve_many(gaps=[[1e-4], [2e-3]])
    assert np.isnan(batch.residuals["complementarity"]).all()
    assert (batch.contact_force[1] < 0.0).all()  # the far wall pulls the tip out to it


def test_the_layout_shares_what_the_values_leave_alone():
    scene = contactqp.default_scene()
    layout = layout_of(scene)
    layout.rows, layout.element_stiffness, layout.nodal_loads  # noqa: B018 (made)
    other = scene.with_values([2.0e5], [3e-4])
    assert other.layout.element_stiffness is layout.element_stiffness
    assert other.layout.rows.node is layout.rows.node
    assert other.layout.rows.gap.tolist() == [3e-4]
    assert other.layout.nodal_loads.tolist() == [0.0, 0.0, 2.0e5, 0.0, 0.0]
    assert scene.walls[0].gap == DEFAULT_GAP and scene.loads[0].force == DEFAULT_F


def test_a_model_for_new_values_shares_what_k_and_the_supports_decide():
    # worked out once on the prepared model, not again for each solve's model; what depends
    # on the loads (P, and the model held for scales, which carries P) is its own
    prepared = contactqp.prepare()
    model = prepared.model.with_layout(prepared.scene.with_values([2.0e5], [3e-4]).layout)
    for name in ("determinate", "compliance_to_support", "floating"):
        assert getattr(model, name) is getattr(prepared.model, name)
    assert model.stiffest == prepared.model.band[0].max()
    assert model.held is model and model.P.tolist() == [0.0, 2.0e5, 0.0, 0.0]


@pytest.mark.parametrize(("arguments", "message"), [
    ({"loads": [1.0, 2.0]}, r"loads must have shape \(1,\) \(one per point load"),
    ({"loads": [float("nan")]}, r"loads\[0\] must be finite, got nan"),
    ({"gaps": ["near"]}, "gaps must be numbers"),
    ({"loads": ["400000"]}, "loads must be numbers"),  # text is not a number, as in a Scene
    ({"gaps": [True]}, "gaps must be numbers"),
    ({"gaps": [float("inf")]}, r"gaps\[0\] must be finite, got inf"),
])
def test_bad_values_are_one_clear_error_naming_the_argument(arguments, message):
    with pytest.raises(contactqp.OptionError, match=message):
        contactqp.prepare().solve(**arguments)


@pytest.mark.parametrize(("arguments", "message"), [
    ({"loads": np.zeros((0, 1))}, "at least one case"),
    ({"loads": [1.0, 2.0]}, r"loads must have shape \(cases, 1\)"),
    ({"loads": [[1.0], [float("nan")]]}, r"loads\[1, 0\] must be finite, got nan"),
    ({"loads": [[1.0], [2.0]], "gaps": [[1e-4]]}, "as many cases"),
])
def test_bad_batches_are_one_clear_error_naming_the_argument(arguments, message):
    with pytest.raises(contactqp.OptionError, match=message):
        contactqp.prepare().solve_many(**arguments)


def test_a_bar_contact_gap_may_be_a_press_fit():
    """Two bars of two elements (k = 2e7 N/m each), bar 0 held at node 0 and bar 1 at node 2,
    bar 0's tip against bar 1's head: a gap of 1e-4 m leaves them apart; an interference of
    1e-4 m pushes them apart with 1e-4 / (2/k + 2/k) = 500 N, the ends sharing the overlap."""
    bar = contactqp.Bar.from_areas([1e-4, 1e-4], 2e11, length=2.0)
    scene = contactqp.Scene((bar, bar), (contactqp.Support(0, 0), contactqp.Support(2, 1)),
                            (), (), contacts=(contactqp.BarContact(0, 2, 1, 0, 1e-4),))
    prepared = contactqp.prepare(scene)
    assert prepared.solve().contact_force[0] == 0.0
    pressed = prepared.solve(gaps=[-1e-4])
    assert pressed.verified and pressed.contact_force[0] == pytest.approx(500.0, rel=1e-12)
    assert pressed.u[2] == pytest.approx(-5e-5, rel=1e-12)  # each end takes half
    assert pressed.force_scale == pytest.approx(500.0, rel=1e-12)  # the press fit's force


def test_gaps_that_leave_a_node_no_position_are_refused():
    """Walls on both sides of a node, 0.1 mm apart, then overlapping: refused, not solved."""
    bar = contactqp.Bar.from_areas([1e-4, 1e-4], 2e11, length=2.0)
    scene = contactqp.Scene(bar, (contactqp.Support(0),), (Load(1, 1e3),),
                            (Wall(1, 1e-4, "+"), Wall(1, 0.0, "-")))
    prepared = contactqp.prepare(scene)
    assert prepared.solve(gaps=[2e-4, 0.0]).verified
    with pytest.raises(contactqp.SceneError):
        prepared.solve(gaps=[-2e-4, 1e-4])


def test_options_are_checked_once_when_prepared():
    with pytest.raises(contactqp.OptionError, match="penalty"):
        contactqp.prepare(method="penalty", penalty=-1.0)


@pytest.mark.parametrize(("gaps", "named"), [
    (np.array([1e-4 + 1e-5j]), "got complex values (dtype complex128)"),
    (np.array([None], dtype=object), "got None at gaps[0]"),
    (np.array([True]), "got True at gaps[0]"),
    (np.array(["near"]), "got 'near' at gaps[0]"),
])
def test_an_array_of_values_that_are_not_numbers_is_one_line_naming_the_entry(gaps, named):
    """An array's repr spans lines and holds every entry: the refusal names the first entry
    that is not a number (or the complex dtype) in one line, on a scene and a prepared one."""
    for call in (lambda: contactqp.default_scene().with_values(gaps=gaps),
                 lambda: contactqp.prepare().solve(gaps=gaps)):
        with pytest.raises(contactqp.ContactqpError) as refused:
            call()
        assert "\n" not in str(refused.value) and str(refused.value).startswith(
            "gaps must be numbers (") and str(refused.value).endswith(named)
