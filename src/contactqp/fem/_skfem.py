"""scikit-fem, imported when a model is built (it is an optional extra)."""

from __future__ import annotations

from types import ModuleType

INSTALL = 'pip install "contactqp[fem]"'


def require_skfem() -> ModuleType:
    """Import scikit-fem, or raise one line that says how to install it.

    Returns
    -------
    module
        The ``skfem`` package.

    Raises
    ------
    ImportError
        scikit-fem is not installed; the message gives the install command.
    """
    try:
        import skfem
    except ImportError as error:
        raise ImportError(
            f"contactqp.fem needs scikit-fem, which is not installed: {INSTALL}") from error
    return skfem
