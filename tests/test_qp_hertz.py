"""The QP backends at contactqp's default settings on the Hertz models (issue 39: "qp defaults
that a user's model verifies with"): the 2D cylinder and the 3D sphere, each loaded by the
prescribed motion of its cut, solved by Clarabel, OSQP and PIQP at ``accuracy="default"``;
every answer verified and its contact forces within its bound of the exact method's (another
method, Lagrange multipliers on the same model).

Measured before Clarabel's relative gap was set to 1e-12 (methods/qp/settings.py): Clarabel
stopped 1.3e-2·F off on the cylinder and 9.6e-4·F off on the sphere, not verified.
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import contactqp

pytest.importorskip("skfem", reason='scikit-fem is not installed (pip install "contactqp[fem]")')

BACKENDS = [{"backend": "clarabel"}, {"backend": "osqp"},
            pytest.param({"backend": "qpsolvers", "solver": "piqp"},
                         marks=pytest.mark.skipif(importlib.util.find_spec("piqp") is None,
                                                  reason="piqp is not installed"))]


@pytest.fixture(scope="module", params=["cylinder", "sphere"])
def hertz(request):
    from contactqp.fem import cylinder_on_flat, sphere_on_flat

    problem = (cylinder_on_flat(fine=0.0125) if request.param == "cylinder"
               else sphere_on_flat()).problem
    return problem, contactqp.solve(problem, "lagrange")


@pytest.mark.parametrize("options", BACKENDS, ids=["clarabel", "osqp", "piqp"])
def test_qp_at_its_defaults_is_verified_on_hertz(hertz, options):
    problem, exact = hertz
    assert exact.verified, exact.message
    found = contactqp.solve(problem, "qp", **options)
    assert found.verified, found.message
    off = np.abs(found.contact_force - exact.contact_force).max()
    assert off <= found.force_error_bound + exact.force_error_bound
    assert off <= 1e-5 * found.force_scale
