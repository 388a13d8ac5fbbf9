"""Progress of long runs (contactqp.progress): opt-in, quiet for short runs, one line a second
with what is left."""

from __future__ import annotations

import io

import pytest

import contactqp
from contactqp.progress import Report, as_progress, counter


def test_a_run_within_its_quiet_time_prints_nothing():
    stream = io.StringIO()
    report = Report("batch", stream, quiet=3600.0)
    for done in range(1, 5):
        report(done, 4)
    assert stream.getvalue() == ""


def test_a_long_run_says_what_is_done_and_ends_with_done():
    stream = io.StringIO()
    report = Report("batch", stream, quiet=0.0)  # every call past its quiet time
    report(1, 4)
    report(4, 4)
    first, last = stream.getvalue().splitlines()
    assert first.startswith("batch: 1 of 4, ") and "left" in first
    assert last.startswith("batch: 4 of 4, ") and last.endswith("done")


def test_progress_is_opt_in_and_checked():
    assert as_progress(None, "x") is None and as_progress(False, "x") is None
    assert isinstance(as_progress(True, "x"), Report)
    with pytest.raises(contactqp.OptionError, match=r"progress must be .* got 3"):
        as_progress(3, "x")


def test_a_counter_tells_each_piece_done():
    seen = []
    advance = counter(lambda done, total: seen.append((done, total)), 3)
    for _ in range(3):
        advance()
    assert seen == [(1, 3), (2, 3), (3, 3)]
    counter(None, 3)()  # no progress asked for: nothing to call
