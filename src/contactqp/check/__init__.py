"""The independent check of an answer: one entry (:func:`check`), one definition of the
residuals and of ``verified`` (:mod:`contactqp.check.residuals`), for every model alike. It
reads the model (its protocol, :mod:`contactqp.model.base`) and the answer, never a method.

The error bounds come from a certificate:

- every model: the exact answer on the answer's own contact set, solved with the model's set
  solve and measured (:mod:`contactqp.check.on_set`);
- a chain (a bar scene's model) first: its own certificate in O(n), the answer read as the
  exact answer of a nearby scene run by run (:mod:`contactqp.check.chain`). Where that does
  not verify an answer whose residuals pass, the general certificate is worked out too and
  the smaller of the two bounds kept: both bound the error, so the smaller does. A chain's
  verdict is therefore never looser than the general one, and is the same wherever its own
  certificate verifies what the general one verifies (tests/test_front_ends.py holds them
  equal on random scenes and every method). The chain's bounds hold to first order within the
  answer's own set of pushing contacts; an answer whose residuals fail gets the general
  certificate's bounds alone.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from contactqp.check.chain import chain_bounds, sized
from contactqp.check.on_set import on_set_bounds
from contactqp.check.residuals import (
    GUARANTEE,
    TOLERANCES,
    Check,
    Tolerances,
    natural_residual,
    not_finite,
    residuals,
    verdict,
)
from contactqp.errors import OptionError
from contactqp.model.base import ContactModel, natural_map
from contactqp.model.chain.model import Model
from contactqp.model.chain.to_problem import problem_from_scene
from contactqp.model.sparse import as_sparse_model, check_engine
from contactqp.problem import frictionless
from contactqp.scene import Scene

ChainBounds = Callable[[np.ndarray], tuple[float, float]]


def check_model(model: ContactModel, u_free: np.ndarray, lam: np.ndarray, contact: str,
                tolerances: Tolerances = TOLERANCES, *, chain: ChainBounds | None = None,
                natural: bool = True, imbalance: float | None = None) -> Check:
    """Check an answer (free-dof displacements, one force per row) against a model (module
    docstring); ``contact="equality"`` holds every row on its gap. ``chain``: the chain's
    own certificate, a function of the penetration C u − g (read here first) giving its
    (force, displacement) bounds. ``natural``: work out
    the natural-map residual (a batch reads it case by case). ``imbalance``:
    ‖K u − P + Cᵀλ‖∞ where the caller has it (else the model's :meth:`largest_imbalance`)."""
    equality = model.equality | (contact == "equality")
    u_free = np.asarray(u_free, dtype=float).reshape(-1)
    lam = np.asarray(lam, dtype=float).reshape(-1)
    if not (np.isfinite(u_free).all() and np.isfinite(lam).all()):
        return not_finite(model, equality, lam)
    F = model.force_scale
    found, pen = residuals(model, u_free, lam, equality, imbalance,
                           (tolerances.feasibility * F, tolerances.complementarity * F))
    found["natural_map"] = (natural_residual(model, lam, pen, equality) if natural
                            else None if equality.any() or model.singular else np.nan)
    passing = all(value is None or value <= getattr(tolerances, name)
                  for name, value in found.items() if name != "natural_map")
    force = displacement = np.inf
    why = ""
    # a bar that only contact holds: its rows see no stiffness with the supports held, and
    # the chain's certificate does not bound a force left on an open one (random scene
    # 223347597, floating=0.6: HiGHS put 13.3 N on a wall 8.4e-8 m open, and the chain's
    # bound said 0.17 N); there the general certificate's bound decides an answer that passes
    # The chain's bounds hold within the answer's own set of pushing contacts, to first order;
    # an answer whose residuals fail may be far from it (builders.flat_patch(20), the exact
    # answer with its largest force, 1e5 N, set to 0: the chain's bound said 51 316 N), so
    # there the general certificate's bound is the one given (the chain's own set solve: where
    # it finds no reference, no bound; the scene's problem is not built for an answer already
    # refused, which cost minutes and 10 GB on 3·10⁴ walls without CHOLMOD)
    if chain is not None and passing and not model.singular:
        force, displacement = chain(pen)
        if (force <= tolerances.force * model.force_scale
                and displacement <= tolerances.displacement * model.displacement_scale):
            return verdict(model, found, lam, equality, force, displacement, tolerances,
                           penetration=pen)
    general = on_set_bounds(model, u_free, lam, pen, equality)
    if chain is not None and passing and not np.isfinite(general[0]):
        # the chain's own set solve found no reference; the scene's problem (the same free
        # dofs and rows, a sparse factorisation) may: a scene is never judged looser than its
        # problem (tests/test_front_ends.py, seed 41339: a qp answer 7.5e-6 F within it)
        general = on_set_bounds(as_sparse_model(problem_from_scene(model.layout.scene)),
                                u_free, lam, pen, equality)
    force, displacement = min(force, general[0]), min(displacement, general[1])
    if not np.isfinite(force):
        why = general[2]
    return verdict(model, found, lam, equality, force, displacement, tolerances, why,
                   penetration=pen)


def check(model: Any, u: Any, contact_force: Any, reactions: Any = None,
          contact: str = "inequality", tolerances: Tolerances = TOLERANCES,
          engine: str = "direct") -> Check:
    """Check an answer, however it was found, against a scene or a user's problem: the one
    check every Result carries (module docstring).

    Parameters
    ----------
    model : Scene, Problem, or a model of either
        What the answer is checked against.
    u : array_like
        The displacement of every node (a scene) or dof (a problem).
    contact_force : array_like
        One force per contact row, positive when the row pushes.
    reactions : array_like, optional
        The force of every support (a scene) or prescribed dof (a problem); where given, what
        it differs from the reactions u implies counts as out of balance (equilibrium).
    contact : str
        ``"inequality"`` or ``"equality"`` (every row held on its gap).
    tolerances : Tolerances
        The residuals' tolerances (default :data:`TOLERANCES`).
    engine : str
        For a Problem: how its model solves with K, "direct" (factorised) or "amg" (conjugate
        gradients with pyamg's multigrid, :mod:`contactqp.model.iterative`), as
        :func:`contactqp.solve`'s ``engine``; a model is checked with its own engine (another
        named is an OptionError); a scene takes "direct" only.

    Returns
    -------
    Check
        ``verified``, ``physical``, the residuals, the error bounds and the message.

    Raises
    ------
    OptionError
        A bad contact kind, or an array of the wrong length for the model.
    SceneError
        A scene (or, as its subclass ProblemError, a problem) that is not valid.
    """
    if contact not in ("inequality", "equality"):
        raise OptionError(f"contact must be inequality or equality; got {contact!r}")
    if isinstance(model, (Scene, Model)):
        if not (isinstance(engine, str) and engine == "direct"):
            check_engine(engine)
            raise OptionError(f"engine={engine!r} applies to a Problem; a scene is checked "
                              "with engine='direct'")
        model, u, lam, reactions = sized(model, u, contact_force, reactions)
        if not np.isfinite(reactions).all():
            return not_finite(model, model.equality | (contact == "equality"), lam)
        found = check_model(
            model, model.free_part(u), lam, contact, tolerances,
            chain=lambda pen: chain_bounds(model, u, lam, reactions, contact, tolerances,
                                           penetration=pen))
        return found
    model = as_sparse_model(frictionless(model, "contactqp.check"), engine)
    u = _sized("u", u, model.problem.n)
    lam = _sized("contact_force", contact_force, model.n_contacts)
    found = check_model(model, model.free_part(u), lam, contact, tolerances)
    # what the answer holds at the prescribed dofs, and the reactions it says they give
    moved = float(np.abs(u[model.problem.prescribed] - model.problem.prescribed_values).max(
        initial=0.0))
    off = 0.0
    if reactions is not None:
        given = _sized("reactions", reactions, model.problem.prescribed.size)
        off = float(np.abs(given - model.reactions_of(u, lam)).max(initial=0.0))
    if moved == 0.0 and off == 0.0 or not np.isfinite(found.force_error_bound):
        return found
    residual = {k: v for k, v in found.residuals.items() if k not in ("force", "displacement")}
    residual["equilibrium"] = max(residual["equilibrium"] or 0.0, off / model.force_scale)
    return verdict(model, residual, lam, model.equality | (contact == "equality"),
                   found.force_error_bound + off, found.displacement_error_bound + moved,
                   tolerances, penetration=found.penetration)


def _sized(name: str, values: Any, size: int) -> np.ndarray:
    array = np.asarray(values, dtype=float).reshape(-1)
    if array.size != size:
        raise OptionError(f"{name} must have {size} values for this model, got {array.size}")
    return array


__all__ = ["GUARANTEE", "TOLERANCES", "Check", "Tolerances", "check", "check_model",
           "natural_map"]
