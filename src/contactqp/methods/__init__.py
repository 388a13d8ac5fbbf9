"""Every way of solving a contact problem, and their registry.

A method is a function ``(model, contact, **options) -> Solution``: ``model`` any model of the
protocol (:mod:`contactqp.model.base`: a bar scene's chain, its condensed chain, or a user's
sparse model; a method takes a chain's fast path where ``model.layout`` says it is one),
``contact`` "inequality" or "equality". :data:`METHODS`, the one registry, names each
method's options, with the validation each value must pass, the formulations it solves and the
models it accepts; :func:`checked_options` applies them, so that the methods themselves take
their options as given. The pipeline that builds the model and checks the answer is
:mod:`contactqp.solve`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from contactqp._validate import flag, positive_number, whole_number
from contactqp.errors import OptionError
from contactqp.methods.augmented import DEFAULT_MAX_ITERATIONS, DEFAULT_TOLERANCE, solve_augmented
from contactqp.methods.base import Solution
from contactqp.methods.complementarity import (
    NCP_FUNCTIONS,
    solve_lemke,
    solve_pgs,
    solve_semismooth_newton,
)
from contactqp.methods.lagrange import ACTIVE_SETS, solve_lagrange
from contactqp.methods.nitsche import THETAS, solve_nitsche
from contactqp.methods.penalty import solve_penalty
from contactqp.methods.qp import BACKENDS, solve_qp
from contactqp.methods.qp.settings import ACCURACIES

CONTACT_KINDS = ("inequality", "equality")  # the contact rows as C u <= g, or as C u = g
FORMULATIONS = ("full", "condensed", "strain")


def _or_none(validate: Callable[[Any], Any]) -> Callable[[Any], Any]:
    return lambda value: None if value is None else validate(value)


def _choice(name: str, choices: tuple[str, ...]) -> Callable[[Any], str]:
    def validate(value: Any) -> str:
        if not isinstance(value, str) or value not in choices:
            raise OptionError(f"{name} must be one of {', '.join(choices)}; got {value!r}")
        return value
    return validate


def _text(name: str) -> Callable[[Any], str]:
    def validate(value: Any) -> str:
        if not isinstance(value, str):
            raise OptionError(f"{name} must be a name (text), got {value!r}")
        return value
    return validate


# The most max_iterations may ask for, per kind of step, so that no request runs unbounded:
# a set solve (an active-set step, an update of the augmented Lagrangian, a Newton step) costs
# a factorisation or a solve with K; a pivot or a sweep a pass over the dense LCP, whose size
# and work each method bounds again when it knows the rows (methods.complementarity)
MOST_STEPS = 10**4
MOST_PASSES = 10**6


def _iterations(most: int, unit: str) -> Callable[[Any], int]:
    def validate(value: Any) -> int:
        count = whole_number("max_iterations", value, 1, error=OptionError)
        if count > most:
            raise OptionError(f"max_iterations must be at most {most} ({unit}), got {count}")
        return count
    return validate


ITERATIONS = _or_none(_iterations(MOST_STEPS, "set solves"))
PIVOTS = _or_none(_iterations(MOST_PASSES, "pivots"))
SWEEPS = _or_none(_iterations(MOST_PASSES, "sweeps"))
_steps = _iterations(MOST_STEPS, "steps")


def _residual(value: Any) -> float:
    return positive_number("tolerance", value, "natural-map residual, dimensionless",
                           OptionError)


def _theta(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value not in THETAS:
        raise OptionError(f"theta must be one of 1, 0, -1 (Nitsche's symmetric, incomplete "
                          f"and skew-symmetric forms); got {value!r}")
    return float(value)


def _relaxation(value: Any) -> float:
    value = positive_number("relaxation", value, "ω, 1 for Gauss–Seidel", OptionError)
    if not value < 2.0:
        raise OptionError(f"relaxation must be in (0, 2) (projected SOR diverges beyond); got "
                          f"{value!r}")
    return value
PENALTY = _or_none(lambda v: positive_number("penalty", v, "force per length, e.g. N/m",
                                             OptionError))


def _any_model(model: Any, contact: str, options: dict[str, Any]) -> str | None:
    """Every model: no reason to refuse."""
    return None


def _scenes_options(*names: str) -> Callable[[Any, str, dict[str, Any]], str | None]:
    """Options that only a chain (a bar scene's model) has a meaning for."""
    def accepts(model: Any, contact: str, options: dict[str, Any]) -> str | None:
        given = [name for name in names if name in options]
        if given and model.layout is None:
            return f"option {given[0]!r} applies to bar scenes only"
        return None
    return accepts


def _one_kind_of_row(method: str) -> Callable[[Any, str, dict[str, Any]], str | None]:
    def accepts(model: Any, contact: str, options: dict[str, Any]) -> str | None:
        equality = model.equality
        if contact != "equality" and equality.any() and not equality.all():
            return (f"{method} solves the LCP of inequality rows (or the linear system of "
                    "equality rows), and this problem mixes both: use lagrange")
        return None
    return accepts


NITSCHE_NEEDS = ("nitsche needs the traction σ(u)·n on the contact boundary, which a model of "
                 "matrices K, f, C, g does not carry; use lagrange, penalty, augmented or qp")


def _chains_only(model: Any, contact: str, options: dict[str, Any]) -> str | None:
    return NITSCHE_NEEDS if model.layout is None else None


@dataclass(frozen=True)
class Method:
    """A method: its name, its function, its options (name -> the validation its value must pass,
    returning the value to use), the formulations it solves, one line on what it does, and
    what models it accepts (``accepts(model, contact, options)``: None, or the one line that
    says why not)."""

    name: str
    solve: Callable[..., Solution]
    options: dict[str, Callable[[Any], Any]]
    formulations: tuple[str, ...]
    summary: str
    accepts: Callable[[Any, str, dict[str, Any]], str | None] = _any_model


METHODS: dict[str, Method] = {
    "lagrange": Method("lagrange", solve_lagrange,
                       {"max_iterations": ITERATIONS,
                        "active_set": _choice("active_set", ACTIVE_SETS)}, FORMULATIONS,
                       "the saddle-point system [[K, Cᵀ], [C, 0]], an active-set loop",
                       _scenes_options("active_set")),
    "penalty": Method("penalty", solve_penalty, {"penalty": PENALTY, "max_iterations": ITERATIONS},
                      ("full", "condensed"), "K + ε CᵀC, the penalty on the walls passed"),
    "augmented": Method(
        "augmented", solve_augmented,
        {"penalty": PENALTY,
         "tolerance": lambda v: positive_number("tolerance", v, "relative change of λ",
                                                OptionError),
         "max_iterations": _iterations(MOST_STEPS, "updates")},
        ("full", "condensed"), "the augmented Lagrangian (Uzawa) with a moderate penalty"),
    "qp": Method(
        "qp", solve_qp,
        {"backend": _choice("backend", tuple(BACKENDS)), "solver": _or_none(_text("solver")),
         "accuracy": _choice("accuracy", ACCURACIES),
         "scale": lambda v: flag("scale", v, OptionError),
         "verbose": lambda v: flag("verbose", v, OptionError)},
        FORMULATIONS, "a QP solver, whose dual values are the contact forces"),
    "lemke": Method("lemke", solve_lemke, {"max_iterations": PIVOTS}, ("full", "condensed"),
                    "the LCP in the contact forces by Lemke's pivoting (exact, finite)",
                    _one_kind_of_row("lemke")),
    "pgs": Method("pgs", solve_pgs,
                  {"relaxation": _relaxation, "tolerance": _residual, "max_iterations": SWEEPS,
                   "max_rows": lambda v: whole_number("max_rows", v, 1, error=OptionError)},
                  ("full", "condensed"),
                  "the LCP by projected Gauss–Seidel (PSOR with relaxation ω), iterative",
                  _one_kind_of_row("pgs")),
    "semismooth_newton": Method(
        "semismooth_newton", solve_semismooth_newton,
        {"ncp": _choice("ncp", NCP_FUNCTIONS), "tolerance": _residual,
         "max_iterations": _steps},
        ("full", "condensed"), "the LCP by Newton on an NCP function (min or Fischer–Burmeister)",
        _one_kind_of_row("semismooth_newton")),
    "nitsche": Method(
        "nitsche", solve_nitsche,
        {"gamma0": lambda v: positive_number("gamma0", v, "γ = γ₀·EA/h, dimensionless",
                                             OptionError),
         "theta": _theta, "max_iterations": _steps},
        ("full",), "Nitsche's method for walls at a bar's end (γ₀, θ), a semismooth system",
        _chains_only),
}


def checked_options(method: Any, contact: Any, formulation: Any,
                    options: dict[str, Any]) -> tuple[Method, dict[str, Any]]:
    """The method named ``method`` and its ``options`` checked, after checking ``contact``
    and ``formulation`` too (an OptionError names what is wrong)."""
    if not isinstance(method, str) or method not in METHODS:
        raise OptionError(f"method must be one of {', '.join(METHODS)}; got {method!r}")
    if not isinstance(contact, str) or contact not in CONTACT_KINDS:
        raise OptionError(f"contact must be one of {', '.join(CONTACT_KINDS)}; got {contact!r}")
    if not isinstance(formulation, str) or formulation not in ("auto", *FORMULATIONS):
        raise OptionError(f"formulation must be one of auto, {', '.join(FORMULATIONS)}; "
                          f"got {formulation!r}")
    spec = METHODS[method]
    if formulation != "auto" and formulation not in spec.formulations:
        takes = [name for name, m in METHODS.items() if formulation in m.formulations]
        raise OptionError(
            f"formulation={formulation!r} is solved by the methods {', '.join(takes)}, not "
            f"{method!r}: its tie rows must hold exactly, and {method!r} enforces rows by a "
            "penalty")
    checked = {}
    for name, value in options.items():
        if name not in spec.options:
            raise OptionError(f"method {method!r} has no option {name!r} (its options: "
                              f"{', '.join(spec.options)})")
        checked[name] = spec.options[name](value)
    return spec, checked


__all__ = ["CONTACT_KINDS", "DEFAULT_MAX_ITERATIONS", "DEFAULT_TOLERANCE", "FORMULATIONS",
           "METHODS", "Method", "checked_options"]
