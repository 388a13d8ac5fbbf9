"""The library's own exceptions: every error a user can cause is one of these."""

from __future__ import annotations


class ContactqpError(Exception):
    """Base class of every error contactqp raises on purpose."""


class SceneError(ContactqpError, ValueError):
    """A scene (or scene file) is invalid; the message names the field and the value."""


class ProblemError(SceneError):
    """A user's own model (:class:`contactqp.Problem`: K, f, C, g) is invalid; the message
    names the field and the value. A SceneError, so that every handler of bad input takes it."""


class OptionError(ContactqpError, ValueError):
    """An unknown method, contact kind or option, or an option with a bad value."""


class SolverError(ContactqpError, RuntimeError):
    """A method could not produce a solution (singular system, loop that does not terminate)."""


class SolverNotAvailable(ContactqpError, ImportError):
    """A QP backend or solver is not installed; the message says what would install it."""
