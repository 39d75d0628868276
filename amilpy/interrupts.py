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
read."""

from __future__ import annotations

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
