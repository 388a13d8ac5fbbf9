"""Progress of long runs, opt-in: the library prints nothing unless asked.

A run that takes ``progress=`` (:meth:`contactqp.Prepared.solve_many`,
:func:`contactqp.load_path`) calls it as ``progress(done, total)`` as its cases or steps are
solved, ``done`` from 0 to ``total``. ``progress=True`` is :class:`Report`: lines on stderr
once the run has taken a second, at most one a second, each with the time it will take yet,
so that a large request says what it costs early on; a run that ends within a second prints
nothing. The command line shows long runs this way.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import time
from collections.abc import Callable, Iterator
from typing import Any, TextIO

from contactqp.errors import OptionError

Progress = Callable[[int, int], None]
QUIET_SECONDS = 1.0  # a run shorter than this prints nothing; then at most a line a second


class Report:
    """``progress(done, total)`` as lines on ``stream`` (default stderr): "``label``: done of
    total, elapsed, about … left", the first once the run has taken ``quiet`` seconds (default
    :data:`QUIET_SECONDS`), then at most one a second, and the last when ``done`` reaches ``total`` (if any was
    printed)."""

    def __init__(self, label: str, stream: TextIO | None = None,
                 quiet: float = QUIET_SECONDS) -> None:
        self.label = label
        self.stream = stream
        self.quiet = quiet
        self.start = time.perf_counter()
        self.shown = None  # when the last line was printed

    def __call__(self, done: int, total: int) -> None:
        now = time.perf_counter()
        elapsed = now - self.start
        last = done >= total
        if elapsed < self.quiet or (not last and self.shown is not None
                                    and now - self.shown < QUIET_SECONDS):
            return
        if last and self.shown is None:
            return  # finished before anything was said: nothing to add
        left = "done" if last else (f"about {elapsed * (total - done) / done:.0f} s left"
                                    if done else "")
        print(f"{self.label}: {done} of {total}, {elapsed:.0f} s, {left}".rstrip(", "),
              file=self.stream or sys.stderr, flush=True)
        self.shown = now


def as_progress(value: Any, label: str) -> Progress | None:
    """``value`` as a progress callable: None or False: none; True: a :class:`Report` named
    ``label``; a callable: itself."""
    if value is None or value is False:
        return None
    if value is True:
        return Report(label)
    if callable(value):
        return value
    raise OptionError(f"progress must be True, False or a callable (done, total), got {value!r}")


def counter(progress: Progress | None, total: int) -> Callable[[], None]:
    """A function to call once per finished piece of ``total``: it tells ``progress``
    (nothing when None)."""
    done = 0

    def advance() -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done, total)

    return advance


class _Sink(io.TextIOBase):
    """A text stream that keeps nothing."""

    def write(self, text: str) -> int:
        return len(text)


_SINK = _Sink()


@contextlib.contextmanager
def silenced() -> Iterator[None]:
    """Nothing written to standard output or error gets out meanwhile: from Python (OSQP's
    "Polishing not needed") nor from C (HiGHS's banner and presolve notes), through file
    descriptors 1 and 2 (a few microseconds). The QP backends and the friction cone programs
    run their solvers inside it: the library prints nothing unless asked."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        with contextlib.redirect_stdout(_SINK), contextlib.redirect_stderr(_SINK):
            yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for handle in (*saved, null):
            os.close(handle)


__all__ = ["QUIET_SECONDS", "Progress", "Report", "as_progress", "counter", "silenced"]
