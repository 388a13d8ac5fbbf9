"""What the command line checks before it runs anything: numbers that start with '-', and the
folder the charts go to. Each gives one line naming the option and the value. And where a
run's chatter goes while JSON is being written (:func:`chatter_to_stderr`)."""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

from contactqp.errors import OptionError


def negative_numbers_joined(argv: list[str], options: tuple[str, ...]) -> list[str]:
    """``--tolerance -1e-3`` as ``--tolerance=-1e-3`` for each of ``options`` (those that
    take a number): argparse reads a token that starts with '-' and is not a plain decimal
    (-1e-3) as an option, and then says "expected one argument"; joined, the value reaches
    its check, which names it."""
    joined: list[str] = []
    for token in argv:
        if joined and joined[-1] in options and token.startswith("-"):
            try:
                float(token)
            except ValueError:
                pass
            else:
                joined[-1] = f"{joined[-1]}={token}"
                continue
        joined.append(token)
    return joined


def validate_out_folder(folder: Path) -> None:
    """An OptionError unless the charts can be written into ``folder`` (made with its missing
    parents if need be): a file of that name or on its way, or a place that cannot be
    written. The folders made to try are removed again, so that a run refused for bad input
    leaves nothing behind."""
    made = [p for p in (folder, *folder.parents) if not p.exists()]  # deepest first
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except (FileExistsError, NotADirectoryError):
        file = next(p for p in (folder, *folder.parents) if p.exists())
        raise OptionError(f"--out {str(folder)!r}: {str(file)!r} is a file, not a folder"
                          ) from None
    except OSError as error:
        raise OptionError(f"--out {str(folder)!r}: the charts cannot be written there "
                          f"({error.strerror})") from None
    finally:
        for path in made:
            try:
                path.rmdir()
            except OSError:
                pass


__all__ = ["chatter_to_stderr", "negative_numbers_joined", "validate_out_folder"]


@contextlib.contextmanager
def chatter_to_stderr(active: bool) -> Iterator[None]:
    """While ``active``, whatever is written to standard output goes to standard error
    instead, from Python and from a solver's C code alike (file descriptor 1 pointed at 2):
    with ``--json --verbose`` a solver's progress must not land inside the JSON."""
    if not active:
        yield
        return
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        os.dup2(2, 1)
        with contextlib.redirect_stdout(sys.stderr):
            yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)
