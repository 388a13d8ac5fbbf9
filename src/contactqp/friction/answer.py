"""What a friction method answers: u, the normal and friction forces, the slip, the states."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from contactqp.friction.law import COULOMB, Law
from contactqp.friction.model import FrictionModel
from contactqp.friction.reduced import Sets, split

# a row is closed when it pushes, or touches, within this fraction of the force scale (the
# gap as the force its row stiffness gives it); a contact slips when its friction force is
# this close to its bound and its slip, as a force, is above it
HOLD = 1e-6
OPEN, STICK, SLIP = "open", "stick", "slip"


@dataclass(frozen=True, eq=False)
class FrictionAnswer:
    """One increment's answer.

    Attributes
    ----------
    u : array, n
        The displacement of every dof (length), prescribed ones at their values.
    normal_force : array, m, or None
        λ_N ≥ 0 per contact (force), acting on the dofs as −Cᵀλ_N; None with no normal rows.
    friction_force : array, m x d
        λ_T per contact (force), acting on the dofs as −Tᵀλ_T: along the slip, so the force
        on the body opposes it.
    slip : array, m x d
        T(u − u_prev): the slip of this increment (length).
    stick : bool array, m
        The contact does not slip in this increment.
    state : str array, m
        ``"open"`` (the normal row does not touch; under Tresca its friction still acts),
        ``"stick"`` or ``"slip"``.
    method : str
    status : str
        ``"solved"`` / ``"converged"``, or what stopped the method (``"not converged"``,
        ``"cycled"``, a backend's own word).
    iterations : int
        The method's iterations (active-set changes, interior-point steps, fixed-point
        iterations); −1 where a backend does not say.
    seconds : float
        Wall time of the solve, the model's factorisation included when it was made for it.
    history : tuple of float
        Per iteration of a fixed point: the change of what it iterates, relative to its scale.
    info : dict
        What else the method reports (formulation, sub-solves, Coulomb's warnings).
    """

    u: np.ndarray
    normal_force: np.ndarray | None
    friction_force: np.ndarray
    slip: np.ndarray
    stick: np.ndarray
    state: np.ndarray
    method: str
    status: str
    iterations: int
    seconds: float
    history: tuple[float, ...] = ()
    info: dict = field(default_factory=dict)

    @property
    def converged(self) -> bool:
        """Whether the method says it reached its answer (the check says whether it did)."""
        return self.status in ("solved", "converged")

    @property
    def forces(self) -> np.ndarray:
        """λ = (λ_N, λ_T flat): the forces over the rows G = [C; T]."""
        normal = () if self.normal_force is None else (self.normal_force,)
        return np.concatenate([*normal, self.friction_force.ravel()])


def force_scale(model: FrictionModel, law: Law, forces: np.ndarray) -> float:
    """F: the largest of the loads, the reactions of the prescribed dofs with no contact force
    (:attr:`FrictionModel.load_scale`: the rule of the frictionless check), the normal and
    friction forces and, under Coulomb, the bounds μλ_N (force). Every residual is a fraction
    of it. Tresca's slip bounds are inputs, not forces: one that no contact reaches (a bound
    of 1.8·10⁴ on a contact that sticks at 15) would set F a thousandfold above every force
    and let a slip of 4·10⁻⁴ read as none (fresh seed 1073741825 of the random tests); where
    a contact reaches its bound its friction force counts."""
    lam_N, _ = split(model, forces)
    bound = law.bound(lam_N) if law.kind == COULOMB else np.zeros(0)
    return max(model.load_scale, float(np.abs(forces).max(initial=0.0)),
               float(bound.max(initial=0.0)), 1e-300)


def read_sets(model: FrictionModel, law: Law, forces: np.ndarray, reads: np.ndarray) -> Sets:
    """The sets an answer shows (HOLD of the force scale): closed where the row pushes or
    touches; slipping where the friction force is at its bound and the slip is not zero."""
    F = force_scale(model, law, forces)
    kN, _ = split(model, model.row_stiffness)
    kT = model.tangential_stiffness
    lam_N, lam_T = split(model, forces)
    w_N, w_T = split(model, reads)
    closed = (np.ones(model.contacts, bool) if lam_N is None
              else (lam_N > HOLD * F) | (-w_N * kN < HOLD * F))
    size, length = np.linalg.norm(lam_T, axis=1), np.linalg.norm(w_T, axis=1)
    slip = (size >= law.bound(lam_N) - HOLD * F) & (length * kT > HOLD * F)
    if law.kind == COULOMB:
        slip &= closed
    slip &= law.frictional
    direction = np.where(slip[:, None], w_T / np.where(length > 0.0, length, 1.0)[:, None], 0.0)
    return Sets(closed, slip, direction)


def make_answer(model: FrictionModel, law: Law, u_free: np.ndarray, forces: np.ndarray,
                previous_u: np.ndarray | None, run: dict, sets: Sets | None = None
                ) -> FrictionAnswer:
    """The answer from the free dofs' displacement and the forces.

    Parameters
    ----------
    run : dict
        ``method``, ``status``, ``iterations``, ``seconds`` and optionally ``history`` and
        ``info``.
    sets : Sets, optional
        The method's own sets (an exact method knows them); read from the answer otherwise.
    """
    reads = model.rows @ u_free - model.targets(previous_u)
    if sets is None:
        sets = read_sets(model, law, forces, reads)
    lam_N, lam_T = split(model, forces)
    _, slip = split(model, reads)
    # a contact without friction slides freely: it slips wherever it moves at all
    moves = (np.linalg.norm(slip, axis=1) * model.tangential_stiffness
             > HOLD * force_scale(model, law, forces))
    slipping = np.where(law.frictional, sets.slip, moves)
    state = np.where(~sets.closed, OPEN, np.where(slipping, SLIP, STICK))
    return FrictionAnswer(
        u=model.full(u_free), normal_force=None if lam_N is None else lam_N.copy(),
        friction_force=lam_T.copy(), slip=slip.copy(), stick=~slipping, state=state,
        method=run["method"], status=run["status"], iterations=int(run["iterations"]),
        seconds=float(run["seconds"]), history=tuple(run.get("history", ())),
        info=dict(run.get("info", {})))


def friction_lines(law: str, state: np.ndarray, friction_force: np.ndarray, slip: np.ndarray,
                   force: str = "", length: str = "") -> list[str]:
    """A summary's lines on friction: the law, how many contacts are in each state, the
    largest friction force and slip (with the units' names ``force`` and ``length``)."""
    counts = ", ".join(f"{int(np.sum(state == s))} {s}" for s in (OPEN, STICK, SLIP))
    lines = [f"friction ({law}): {state.size} contacts, {counts}"]
    if state.size:
        size, moved = np.linalg.norm(friction_force, axis=1), np.linalg.norm(slip, axis=1)
        i, j = int(np.argmax(size)), int(np.argmax(moved))
        lines.append(f"largest friction force {_shown(size[i], '.6g')}{' ' + force if force else ''}"
                     f" at contact {i}; largest slip {_shown(moved[j], '.3g')}"
                     f"{' ' + length if length else ''} at contact {j}")
    return lines


def _shown(value: float, spec: str) -> str:
    return "0" if value == 0.0 else format(float(value), spec)
