"""An interrupt that must not be lost: the one place that knows a Ctrl-C (or
SIGTERM/SIGHUP) arrived and has not yet ended the work it was meant to end.

The command line's handler raises KeyboardInterrupt wherever Python happens to
be. Inside a compiled module's initialization that becomes an ImportError, and a
library that imports an optional module under `except ImportError` (SciPy,
NumPy, numba do) swallows it: the run would go on as if nothing had come. So the
handler also notes the signal here (`arrived`), whoever turns an interrupt into a
partial result says so (`handled`), and the loops that run for long look
(`check`) between their chunks, runs and results: an interrupt that was swallowed
is raised again at the next of them, where the rows so far are kept.

Outside the command line nothing calls `arrived`, and `check` costs one global
read.

A wall-clock limit is the other thing that ends work from outside it: `time_limit`
raises TimeLimit in a block that runs past it (SIGALRM), for code with no place to
look at a clock (reading a listing; a PROCEDURAL loop or one long step in a run)."""

from __future__ import annotations

import signal
import sys
from contextlib import contextmanager

_pending: int | None = None


def arrived(signum: int) -> None:
    """A signal came that should end the work under way."""
    global _pending
    _pending = signum


def handled() -> None:
    """The interrupt has ended the work it was meant to end (a partial run, the
    finished runs of a farm kept)."""
    global _pending
    _pending = None


def pending() -> bool:
    """An interrupt arrived that nothing has handled."""
    return _pending is not None


def check() -> None:
    """Raise KeyboardInterrupt if an interrupt arrived and nothing has handled it
    yet (it was swallowed on the way)."""
    if _pending is not None:
        raise KeyboardInterrupt


class TimeLimit(BaseException):
    """A block ran past its wall-clock limit (`time_limit`). Like KeyboardInterrupt
    it is no Exception, so no `except Exception` on the way can swallow it."""


@contextmanager
def time_limit(seconds: float | None):
    """Interrupt the block with TimeLimit after `seconds` of wall clock. Reading,
    checking and compiling a listing is one long call into lark and the code
    generator with no place to look at a clock, so SIGALRM does it; where there
    is none (Windows, a thread other than the main one) the block is not bounded."""
    # a limit of over a year is no limit (and past time_t, setitimer overflows)
    if not seconds or seconds > 3e7 or not hasattr(signal, "setitimer"):
        yield
        return

    def expired(signum: int, frame) -> None:
        # The handler may run inside a weakref callback or a __del__, where Python
        # prints an exception and drops it: ring again shortly until one lands.
        signal.setitimer(signal.ITIMER_REAL, RETRY)
        raise TimeLimit

    try:
        previous = signal.signal(signal.SIGALRM, expired)
    except ValueError:  # not the main thread
        yield
        return
    hook = sys.unraisablehook

    def quiet(unraisable) -> None:  # a dropped ring is not worth a message
        if not isinstance(unraisable.exc_value, TimeLimit):
            hook(unraisable)

    sys.unraisablehook = quiet
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
        sys.unraisablehook = hook


RETRY = 0.02  # seconds between two rings of an expired time_limit


def silence_alarm() -> None:
    """A TimeLimit was caught and its work ended: no more rings (an expired
    `time_limit` rings again every RETRY seconds until one lands)."""
    if hasattr(signal, "setitimer"):
        signal.setitimer(signal.ITIMER_REAL, 0)
