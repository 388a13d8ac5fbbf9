"""Small friction problems that show what each law and method does, and every answer of a
small problem by enumeration.

- :func:`nonunique_coulomb`: one node on a flat under Coulomb's law with three answers (open,
  sticking, slipping), each exact; the methods land on different ones.
- :func:`cycling_fixed_point`: one node where the fixed point on Tresca cycles between two
  bounds forever while the active set finds the one Coulomb answer.
- :func:`sliding_block`: a block on a spring pulled past μP: Coulomb slides on the flat; the
  convex relaxation (Anitescu–Tasora, MuJoCo) lifts it off by μ|slip| while it still pushes.

Each node has a tangential dof u_t and a normal one u_n; the flat is u_n ≥ 0 (the row
−u_n ≤ 0) and the tangential row reads u_t.
"""

from __future__ import annotations

import itertools

import numpy as np

from contactqp.errors import OptionError
from contactqp.friction.answer import force_scale
from contactqp.friction.law import Law
from contactqp.friction.model import FrictionModel, friction_model
from contactqp.friction.reduced import Sets, solve_on_set, violations

ON_FLAT = {"C": [[0.0, -1.0]], "g": [0.0], "T": [[1.0, 0.0]]}  # one node, (u_t, u_n)
MAX_ENUMERATED = 8  # contacts: 2·3^m sets (2D) to try


def nonunique_coulomb() -> tuple[FrictionModel, float]:
    """(model, μ) with three Coulomb answers.

    K = [[1, −½], [−½, 1]] couples the tangential and the normal dof (pulling the node along
    lifts it), f = (2.5, −1) pulls it along and presses it down, μ = 3:

    - open: λ = 0, u = K⁻¹f = (8/3, 1/3), u_n > 0;
    - stick: u = 0, λ_N = 1, λ_T = 2.5 ≤ μλ_N = 3;
    - slip: u = (1, 0), λ_N = ½, λ_T = 1.5 = μλ_N, along the slip.
    """
    K = np.array([[1.0, -0.5], [-0.5, 1.0]])
    return friction_model(K, [2.5, -1.0], **ON_FLAT), 3.0


def cycling_fixed_point() -> tuple[FrictionModel, float]:
    """(model, μ) where s ← μλ_N(s) cycles.

    K = [[1, ½], [½, 1]], f = (4, −1), μ = 3. Sliding under a bound s gives u_t = 4 − s and
    λ_N = 1 + u_t/2, so s ← μλ_N has slope −3/2 about its fixed point s* = 3.6 (u_t = 0.4,
    λ_N = 1.2, the one Coulomb answer): from the frictionless start s = 9 the node sticks
    (λ_N = 1, s = 3), then slips (λ_N = 1.5, s = 4.5), then sticks again: the cycle 3, 4.5.
    """
    K = np.array([[1.0, 0.5], [0.5, 1.0]])
    return friction_model(K, [4.0, -1.0], **ON_FLAT), 3.0


def sliding_block() -> tuple[FrictionModel, float]:
    """(model, μ): a block on springs k = 10 pressed by P = 2 and pulled by 5 > μP = 1.

    Coulomb: it slides on the flat, u = (0.4, 0), λ_N = 2, λ_T = 1. The relaxation instead
    keeps u_n = μ u_t: u = (0.32, 0.16), λ_N = 3.6: off the flat and pushing.
    """
    return friction_model(10.0 * np.eye(2), [5.0, -2.0], **ON_FLAT), 0.5


def all_answers(model: FrictionModel, law: Law, previous_u=None,
                accept: float = 1e-9) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every answer of a small 2D problem: the sets (open or closed; stick, slip forwards or
    backwards) whose equations have a solution meeting every inequality (to ``accept`` of F).

    Returns
    -------
    list of (u, forces)
        One per distinct answer (u of all dofs; forces λ = (λ_N, λ_T flat)).
    """
    if model.d != 1 or model.contacts > MAX_ENUMERATED:
        raise OptionError(f"all_answers: enumerates 2D problems of up to {MAX_ENUMERATED} "
                          f"contacts; this one has {model.contacts} in {model.d + 1}D")
    b = model.reduced_rhs(previous_u)
    W = model.flexibility
    normal = [True] if model.C is None else [True, False]
    found: list[tuple[np.ndarray, np.ndarray]] = []
    for choice in itertools.product(itertools.product(normal, (0, 1, -1)),
                                    repeat=model.contacts):
        closed = np.array([c for c, _ in choice])
        turn = np.array([t for _, t in choice], dtype=float)
        sets = Sets(closed, turn != 0.0, turn[:, None])
        forces, solved = solve_on_set(model, law, sets, b, np.zeros(b.size))
        if not solved:
            continue
        F = force_scale(model, law, forces)
        if violations(model, law, sets, forces, b - W @ forces).max(initial=0.0) > accept * F:
            continue
        u = model.full(model.displacement(forces))
        if not any(np.allclose(u, other, rtol=1e-9, atol=1e-12) for other, _ in found):
            found.append((u, forces))
    return found
