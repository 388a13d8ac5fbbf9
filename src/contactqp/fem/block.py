"""An elastic block pressed onto a wavy rigid foundation (plane strain): no closed form.

The block 0 ≤ x ≤ L, 0 ≤ y ≤ H (a structured triangle mesh); its top is bonded to a rigid
press that moves down by δ (u_x = 0, u_y = −δ); its bottom rests, frictionless, on the
foundation y_f(x) = −A (1 − cos(2π w x / L)), which touches it at its w + 1 crests (x = 0,
L/w, …, L) before loading. Every bottom node may not pass it: y + u_y ≥ y_f, the row
−u_y ≤ A (1 − cos(2π w x / L)). Pressed, the block touches in patches around the crests whose
widths no formula gives for a finite block: the case on which the methods are compared with
each other.
"""

from __future__ import annotations

import numpy as np

from contactqp._validate import one_line
from contactqp.fem._arguments import at_least_zero, count, nodes_within, poisson_ratio, positive
from contactqp.fem._skfem import require_skfem
from contactqp.fem.elasticity import dof_coordinates, plane_strain_stiffness, rows_above_flat
from contactqp.problem import Problem


def block_on_wavy_foundation(length: float = 20.0, height: float = 10.0,
                             young: float = 210e3, poisson: float = 0.3,
                             amplitude: float = 0.005, waves: int = 2,
                             approach: float = 0.004, elements: int = 40,
                             units: str = "N, mm") -> Problem:
    """The block of the module docstring as a :class:`~contactqp.Problem`.

    Parameters
    ----------
    length, height : float
        L and H (length).
    young, poisson : float
        E (stress) and ν.
    amplitude : float
        A, the foundation's depth below its crests (length).
    waves : int
        w, the foundation's wavelengths along the block.
    approach : float
        δ, how far the press moves down (length).
    elements : int
        Element rows along the block's length (the height gets ``elements · H / L``).
    units : str
        The label of the answer's units.

    Raises
    ------
    ProblemError
        An argument that is not valid, or a mesh past :data:`~contactqp.fem._arguments.
        MAX_NODES` nodes (one line naming it).
    """
    name = "block_on_wavy_foundation"
    length, height = positive(name, "length", length), positive(name, "height", height)
    young, poisson = positive(name, "young", young), poisson_ratio(name, poisson)
    amplitude = at_least_zero(name, "amplitude", amplitude)
    waves, elements = count(name, "waves", waves), count(name, "elements", elements)
    approach, units = at_least_zero(name, "approach", approach), one_line(f"{name}: units", units)
    rows_high = max(1, round(elements * height / length))
    nodes_within(name, (elements + 1.0) * (rows_high + 1.0), f"elements = {elements}")
    skfem = require_skfem()
    mesh = skfem.MeshTri.init_tensor(np.linspace(0.0, length, elements + 1),
                                     np.linspace(0.0, height, rows_high + 1))
    K, dofs = plane_strain_stiffness(mesh, young, poisson)
    x, y = mesh.p
    tol = 1e-12 * height
    top = np.flatnonzero(y > height - tol)
    bottom = np.flatnonzero(y < tol)
    bottom = bottom[np.argsort(x[bottom])]
    C = rows_above_flat(dofs, bottom)
    gap = amplitude * (1.0 - np.cos(2.0 * np.pi * waves * x[bottom] / length))
    return Problem(
        K, np.zeros(K.shape[0]), C, gap,
        prescribed=np.concatenate([dofs[0, top], dofs[1, top]]),
        prescribed_values=np.concatenate([np.zeros(top.size), np.full(top.size, -approach)]),
        names=[f"x={xi:.4g}" for xi in x[bottom]], coordinates=dof_coordinates(mesh, dofs),
        units=units, name=f"block on a wavy foundation, {K.shape[0]} dofs")
