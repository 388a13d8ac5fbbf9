"""Bad input from Python (contactqp._validate and every place a value enters): one ContactqpError
naming the field or option and the value, never a traceback, never a warning.
"""

from __future__ import annotations

import math
import warnings

import pytest

import contactqp
from closed_forms import (
    BAR,
    DEFAULT_SCENE,
)
from contactqp import (
    Bar,
    Load,
    Scene,
    Support,
)

BAD_CALLS = [  # (what, call, words the message must contain)
    ("E as text", lambda: Bar.from_areas([1e-4], "210e9", length=1.0),
     ["youngs_modulus", "'210e9'"]),
    ("area a boolean", lambda: Bar.from_areas([True], 2e11, length=1.0), ["bar.areas[0]", "True"]),
    ("area as text", lambda: Bar.from_areas([1e-4, "1e-4"], 2e11, length=1.0),
     ["bar.areas[1]", "'1e-4'"]),
    ("max_iterations text", lambda: contactqp.solve(DEFAULT_SCENE, max_iterations="abc"),
     ["max_iterations", "'abc'"]),
    ("max_iterations NaN", lambda: contactqp.solve(DEFAULT_SCENE, max_iterations=math.nan),
     ["max_iterations", "nan"]),
    ("max_iterations 2.5", lambda: contactqp.solve(DEFAULT_SCENE, "penalty", max_iterations=2.5),
     ["max_iterations", "2.5"]),
    ("max_iterations 0", lambda: contactqp.solve(DEFAULT_SCENE, max_iterations=0), ["max_iterations", "0"]),
    ("max_iterations -1", lambda: contactqp.solve(DEFAULT_SCENE, "augmented", max_iterations=-1),
     ["max_iterations", "-1"]),
    ("tolerance -1", lambda: contactqp.solve(DEFAULT_SCENE, "augmented", tolerance=-1),
     ["tolerance", "-1"]),
    ("tolerance NaN", lambda: contactqp.solve(DEFAULT_SCENE, "augmented", tolerance=math.nan),
     ["tolerance", "nan"]),
    ("tolerance text", lambda: contactqp.solve(DEFAULT_SCENE, "augmented", tolerance="x"),
     ["tolerance", "'x'"]),
    ("penalty True", lambda: contactqp.solve(DEFAULT_SCENE, "penalty", penalty=True), ["penalty", "True"]),
    ("method a list", lambda: contactqp.solve(DEFAULT_SCENE, ["lagrange"]), ["method", "['lagrange']"]),
    ("scene a number", lambda: contactqp.solve(3), ["scene", "int"]),
    ("verbose text", lambda: contactqp.solve(DEFAULT_SCENE, "qp", verbose="yes"), ["verbose", "'yes'"]),
    ("too many elements", lambda: Bar.tapered_circle(1.0, 10**12, 0.04, 0.02, 2e11),
     ["bar.elements", "1000000000000"]),
    ("E 1e300", lambda: Bar.from_areas([1e10], 1e300, length=1.0),
     ["youngs_modulus", "1e+300"]),
    ("load 1e308", lambda: DEFAULT_SCENE.with_loads((Load(2, 1e308),)), ["load[0].force", "1e+308"]),
    ("name a number", lambda: Scene(BAR, (Support(0),), name=3), ["name", "3"]),
    ("units unknown", lambda: Scene(BAR, (Support(0),), units="inch"), ["units", "'inch'"]),
    # options have a magnitude range, as a scene's numbers do: 1e300 overflowed what it
    # multiplies (a penalty ended "not verified", γ₀ leaked a RuntimeWarning)
    ("penalty 1e300", lambda: contactqp.solve(DEFAULT_SCENE, "penalty", penalty=1e300),
     ["penalty = 1e+300", "outside the range"]),
    ("gamma0 1e300", lambda: contactqp.solve(DEFAULT_SCENE, "nitsche", gamma0=1e300),
     ["gamma0 = 1e+300", "outside the range"]),
    ("tolerance 1e-300", lambda: contactqp.solve(DEFAULT_SCENE, "pgs", tolerance=1e-300),
     ["tolerance = 1e-300", "outside the range"]),
    ("sweep of text", lambda: contactqp.penalty_sweep(penalties=("x",)), ["penalties[0]", "'x'"]),
    ("sweep of -1", lambda: contactqp.penalty_sweep(penalties=(-1,)), ["penalties[0]", "-1"]),
    ("sweep of nothing", lambda: contactqp.penalty_sweep(penalties=()),
     ["penalties must hold at least one number", "()"]),
    ("sweep of a number", lambda: contactqp.penalty_sweep(penalties=1e6),
     ["penalties must be a sequence", "1000000.0"]),
    ("model of text", lambda: contactqp.build_model("x"), ["scene must be a contactqp.Scene", "'x'"]),
    ("check with a short u", lambda: contactqp.check(DEFAULT_SCENE, [0.0], [0.0], [0.0], "inequality"),
     ["u", "5"]),
]


@pytest.mark.parametrize(("what", "call", "words"), BAD_CALLS, ids=[c[0] for c in BAD_CALLS])
def test_bad_python_input_is_one_clear_error(what, call, words):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning on the way either
        with pytest.raises(contactqp.ContactqpError) as error:
            call()
    message = str(error.value)
    assert "\n" not in message
    for word in words:
        assert word in message, message
