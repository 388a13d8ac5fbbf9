"""The frictional bed on the bar front end (contactqp.Bed): a bar lying on a bed that resists
sliding up to τ per unit length, pulled at one end, against the closed form; the scene file,
the units, the command line, and the refusals.

Glossary: EA axial stiffness (N), L length, N elements of h = L/N, τ the bed's friction limit
per length (N/m), F < τL the pull at node 0 (in −x). The closed form: the bar slips over
x_s = F/τ, the axial force falls as N(x) = F − τx there, and u(x) = −τ(x_s − x)²/(2EA) for
x < x_s, zero beyond. With a node at x_s the lumped bed (τ times each node's tributary
length) gives it exactly at the nodes (contactqp/friction/bed.py).
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

import contactqp
from contactqp.cli import main

EXAMPLE = Path(__file__).parent.parent / "examples" / "bar_on_bed.toml"
E, A, L, ELEMENTS = 2e11, 1e-4, 1.0, 40
TAU = 4e4


def closed_form(x: np.ndarray, force: float) -> np.ndarray:
    """u(x) = −τ(x_s − x)²/(2EA) for x < x_s = F/τ, zero beyond (written out here, apart from
    the library's own bed module)."""
    return -TAU * np.clip(force / TAU - x, 0.0, None) ** 2 / (2.0 * E * A)


def bed_scene(force: float, **extra) -> contactqp.Scene:
    bar = contactqp.Bar.uniform(A, E, length=L, elements=ELEMENTS)
    return contactqp.Scene(bar, (contactqp.Support(ELEMENTS),), (contactqp.Load(0, -force),),
                           beds=(contactqp.Bed(TAU),), name="bed", **extra)


@pytest.mark.parametrize("method", ["lagrange", "qp", "augmented", "penalty"])
@pytest.mark.parametrize("slips_over", [0.25, 0.6, 0.9])
def test_the_bar_on_its_bed_is_the_closed_form(method, slips_over):
    """x_s = 0.25, 0.6, 0.9 of L fall on nodes: u at every node, the slip zone (the nodes
    before x_s slip, the rest stick) and N = EA Δu/h = F − τx at each element's midpoint in
    the slip zone, against the closed form; the penalty within its stated bound."""
    force = slips_over * TAU * L
    result = contactqp.solve(bed_scene(force), method)
    x = np.linspace(0.0, L, ELEMENTS + 1)
    exact = closed_form(x, force)
    # within the check's bound of the exact discrete answer, which is the closed form at the
    # nodes (to round-off: 1e-12 of the pull-out)
    reach = result.displacement_error_bound * (1 + 1e-6) + 1e-12 * np.abs(exact).max()
    assert np.abs(result.u - exact).max() <= reach
    if method == "penalty":
        return
    assert result.verified, result.message
    slipping = result.state == "slip"
    np.testing.assert_array_equal(np.flatnonzero(slipping), np.flatnonzero(x < slips_over - 1e-9))
    middle = (x[:-1] + x[1:]) / 2.0
    axial = E * A * np.diff(result.u) / (L / ELEMENTS)
    inside = middle < slips_over
    np.testing.assert_allclose(axial[inside], (force - TAU * middle)[inside], rtol=0.0,
                               atol=2.0 * E * A / (L / ELEMENTS) * reach)
    # the Result carries the bar's quantities as a scene's does: its element forces are the
    # axial forces read here from u, its stresses those over the area
    np.testing.assert_allclose(result.element_force, axial, rtol=1e-12, atol=1e-9 * force)
    np.testing.assert_allclose(result.stress, result.element_force / A, rtol=1e-14)
    # the bed's friction on the slipping nodes is at its limit, τ times the tributary length
    tributary = np.full(ELEMENTS + 1, L / ELEMENTS)
    tributary[[0, -1]] /= 2.0
    np.testing.assert_allclose(np.abs(result.friction_force[slipping, 0]),
                               TAU * tributary[slipping], rtol=0.0,
                               atol=result.force_error_bound * (1 + 1e-6) + 1e-12 * force)


def test_the_example_file_units_and_round_trip():
    """examples/bar_on_bed.toml is the scene above (x_s = 0.6 m); written and read again it
    is the same, and in mm-N-MPa it is the same physical answer (u in mm, 1000× the m)."""
    scene = contactqp.load_scene(EXAMPLE)
    assert scene.beds == (contactqp.Bed(TAU, 0),)
    again = contactqp.scene_from_dict(tomllib.loads(contactqp.scene_to_toml(scene)))
    assert again.beds == scene.beds
    in_m = contactqp.solve(scene)
    in_mm = contactqp.solve(contactqp.convert_units(scene, "mm-N-MPa"))
    assert in_m.verified and in_mm.verified
    np.testing.assert_allclose(in_mm.u, 1e3 * in_m.u, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(in_m.u, closed_form(np.linspace(0.0, L, ELEMENTS + 1),
                                                   24000.0), atol=1e-9 * 3.6e-4)


def test_the_command_line_solves_a_bed(capsys):
    """`contactqp solve examples/bar_on_bed.toml --json` answers with the friction forces and
    a verified answer whose pull-out is the closed form's τx_s²/(2EA)."""
    code = main(["solve", str(EXAMPLE), "--json"])
    out = capsys.readouterr().out
    assert code == 0
    answer = json.loads(out)
    assert answer["verified"] is True
    assert answer["u"][0] == pytest.approx(-TAU * 0.6**2 / (2 * E * A), rel=1e-9)
    assert len(answer["friction_force"]) == ELEMENTS + 1


@pytest.mark.parametrize(("bed", "extra", "words"), [
    (contactqp.Bed(-1.0), {}, "bed[0].tau must be > 0"),
    (contactqp.Bed(0.0), {}, "bed[0].tau must be > 0"),
    (contactqp.Bed(float("nan")), {}, "bed[0].tau must be finite"),
    (contactqp.Bed("stiff"), {}, "bed[0].tau must be a number"),
    (contactqp.Bed(1.0, bar=2), {}, "bed[0].bar = 2: no such bar"),
    (contactqp.Bed(1.0), {"walls": (contactqp.Wall(3, 1e-3, "-"),)},
     "walls and bar contacts beside a frictional bed are not modelled"),
])
def test_bad_beds_are_refused_in_one_line(bed, extra, words):
    bar = contactqp.Bar.uniform(A, E, length=L, elements=4)
    with pytest.raises(contactqp.SceneError, match=words.replace("[", r"\[").replace("]", r"\]")
                       ) as raised:
        contactqp.Scene(bar, (contactqp.Support(4),), beds=(bed,), **extra)
    assert "\n" not in str(raised.value)


def test_what_takes_no_friction_refuses_a_bed_in_one_line():
    """Every entry point but solve and load_path (tests/test_friction_path.py) refuses the
    bed (never a frictionless answer in its place); the CLI's compare too."""
    scene = bed_scene(0.5 * TAU * L)
    for call in (lambda: contactqp.compare(scene), lambda: contactqp.prepare(scene),
                 lambda: contactqp.penalty_sweep(scene),
                 lambda: contactqp.first_contact_factor(scene),
                 lambda: contactqp.check(scene, np.zeros(ELEMENTS + 1), [])):
        with pytest.raises(contactqp.ContactqpError, match="frictional bed") as raised:
            call()
        assert "\n" not in str(raised.value)
    assert main(["compare", str(EXAMPLE)]) == 2


def test_the_traction_chart_and_the_table_show_the_friction():
    """plot_traction draws the friction force of every node at its position (the data is the
    Result's), shades the stick zone over x ≥ x_s = 0.6 m and nothing before it; the table
    gives the largest friction force τh = 1000 N and the nodes that stick and slip (17/24:
    the 24 nodes before x_s slip, by the closed form)."""
    from matplotlib.patches import Rectangle

    from contactqp import plot

    result = contactqp.solve(EXAMPLE)
    x = np.linspace(0.0, L, ELEMENTS + 1)
    ax = plot.plot_traction(result, position=x)
    line = next(line for line in ax.get_lines() if line.get_gid() == "friction force")
    np.testing.assert_array_equal(line.get_xdata(), x)
    np.testing.assert_array_equal(line.get_ydata(), result.friction_force[:, 0])
    bands = [p for p in ax.patches if p.get_gid() == "stick zone"]
    assert len(bands) == 1
    band = bands[0]
    left = (band.get_x() if isinstance(band, Rectangle)
            else float(np.min(band.get_xy()[:, 0])))
    assert 0.575 <= left <= 0.6 <= 0.6 + 1e-12 and x[24] == pytest.approx(0.6)
    text = contactqp.table([contactqp.Run(label="lagrange", contact="inequality",
                                          result=result)])
    row = next(line for line in text.splitlines() if line.startswith("lagrange"))
    assert "1000 (" in row and " 17/24 " in row
    with pytest.raises(contactqp.OptionError, match="one value per contact"):
        plot.plot_traction(result, position=x[:-1])
    with pytest.raises(contactqp.OptionError, match="with friction"):
        plot.plot_traction(contactqp.solve())
    with pytest.raises(contactqp.OptionError, match="use plot_traction") as raised:
        plot.plot_bar(result)  # a problem's Result: no bars to draw
    assert "\n" not in str(raised.value)
