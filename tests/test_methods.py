"""The method registry (contactqp.methods): an unknown method, contact kind, formulation or
option, a formulation a method does not solve, and a bad option value are each refused with an
OptionError that names them.
"""

from __future__ import annotations

import math

import pytest

import contactqp
from contactqp import OptionError


@pytest.mark.parametrize("kwargs, names", [
    ({"method": "newton"}, "method"),
    ({"contact": "bilateral"}, "contact"),
    ({"method": "lagrange", "penalty": 1e14}, "penalty"),
])
def test_unknown_method_contact_or_option(kwargs, names):
    with pytest.raises(OptionError, match=names):
        contactqp.solve(None, **kwargs)


def test_unknown_formulation_names_the_value():
    with pytest.raises(contactqp.OptionError, match="'sparse'"):
        contactqp.solve(formulation="sparse")


@pytest.mark.parametrize("method", ["penalty", "augmented"])
def test_strain_with_a_penalty_method_is_refused(method):
    with pytest.raises(contactqp.OptionError, match="formulation='strain'.*lagrange, qp"):
        contactqp.solve(method=method, formulation="strain")


@pytest.mark.parametrize("bad", [0.0, -1e14, math.nan, math.inf, "stiff"])
def test_penalty_must_be_a_positive_finite_number(bad):
    with pytest.raises(OptionError, match="penalty"):
        contactqp.solve(None, "penalty", penalty=bad)
