"""The method registry (contactqp.methods): unknown methods, contact kinds and options named.
"""

from __future__ import annotations

import pytest

import contactqp
from contactqp import (
    OptionError,
)


@pytest.mark.parametrize("kwargs, names", [
    ({"method": "newton"}, "method"),
    ({"contact": "bilateral"}, "contact"),
    ({"method": "lagrange", "penalty": 1e14}, "penalty"),
])
def test_unknown_method_contact_or_option(kwargs, names):
    with pytest.raises(OptionError, match=names):
        contactqp.solve(None, **kwargs)

