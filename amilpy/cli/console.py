"""The command line's dealings with the process: signals, stdout and progress.

- SIGTERM and SIGHUP are handled like Ctrl-C (SIGINT): during a run they become
  an interrupt, which the runner turns into a partial run (the rows so far kept);
  while output files are written they are held back until the files are
  complete, so a signal never leaves a file half-written or unwritten.
- A stdout that cannot encode a character (a cp1252 console, a redirect with
  PYTHONIOENCODING=ascii) gets "?" for it instead of a UnicodeEncodeError.
- A stdout closed by its reader (`amilpy run m.amil | head`) ends the printout
  quietly; the files were written before it and the exit code is the run's.
"""

from __future__ import annotations

import math
import os
import signal
import sys
import time
from contextlib import contextmanager
from typing import TextIO

from .. import interrupts
from ..interrupts import TimeLimit, time_limit  # noqa: F401 - (the command line's)
from ..output.files import to_devnull
from ..output.words import visible

HANDLED = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP")
                if hasattr(signal, name))


class Signals:
    """Turns SIGINT/SIGTERM/SIGHUP into KeyboardInterrupt, or holds them back."""

    def __init__(self) -> None:
        self.received: int | None = None  # the last signal, whenever it came
        self.held_back: int | None = None  # one that came while files were written
        self.holding = False
        self.previous: dict[int, object] = {}
        self.count = 0  # the signals that came outside the writing of files

    def _handler(self, signum: int, frame) -> None:
        self.received = signum
        if self.holding:
            self.held_back = signum
            return
        self.count += 1
        if self.count == 2:
            # A second Ctrl-C (a user pressing twice) came while the first was being
            # turned into a partial result: raised there, it lost the rows and the
            # files. It waits for the files instead; a third ends the command.
            self.held_back = signum
            return
        interrupts.arrived(signum)  # (raised again if a library swallows it)
        raise KeyboardInterrupt

    def install(self) -> None:
        for sig in HANDLED:
            try:
                self.previous[sig] = signal.signal(sig, self._handler)
            except (ValueError, OSError):  # not the main thread (e.g. a test runner)
                pass

    def restore(self) -> None:
        interrupts.handled()  # (nothing is left to end)
        for sig, handler in self.previous.items():
            signal.signal(sig, handler)
        self.previous.clear()

    @contextmanager
    def held(self):
        """Signals wait until the block is done (writing files)."""
        self.holding = True
        try:
            yield
        finally:
            self.holding = False

    @staticmethod
    def name(signum: int) -> str:
        return signal.Signals(signum).name





class Visible:
    """A text stream whose control characters are shown as "?" (everything else is
    the stream's own: its buffer, descriptor, encoding)."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        return self._stream.write(visible(text))

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


def tolerant_streams() -> None:
    """Characters the console cannot show become "?" instead of an error, and so do
    control characters from a listing (`Visible`); a standard stream that was closed
    when the command started writes nowhere (the files are still written)."""
    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if stream is None:
            setattr(sys, name, open(os.devnull, "w", encoding="utf-8"))  # noqa: SIM115
            continue
        try:
            stream.reconfigure(errors="replace")
        except (AttributeError, ValueError):  # not a TextIOWrapper, or closed
            pass
        if not isinstance(stream, Visible):
            setattr(sys, name, Visible(stream))


# why the printout could not be written (a full disk behind stdout), for the exit code
STDOUT_FAILED: list[str] = []


def write_out(text_writer, out: TextIO | None = None) -> bool:
    """Run `text_writer(stream)` on stdout; False if the reader went away (a closed
    pipe: quietly) or the stream failed (a full disk: said once, in STDOUT_FAILED),
    after which stdout is sent to /dev/null so the exit is quiet."""
    out = out or sys.stdout
    try:
        text_writer(out)
        out.flush()
    except OSError as exc:
        if not isinstance(exc, BrokenPipeError) and not STDOUT_FAILED:
            STDOUT_FAILED.append(exc.strerror or str(exc))
        to_devnull(out)
        return False
    return True


class Progress:
    """A progress line on stderr for computations longer than about a second (TTY
    only), from the `amilpy.progress` reports of every task: a run's TIME, the
    independent runs finished, a sweep's points (shown in front of its runs'
    TIME), a periodic orbit's Newton steps, a response curve's points."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled and sys.stderr.isatty()
        self.clock = time.perf_counter
        self.start = self.clock()
        self.last = 0.0
        self.shown = False
        self.prefix = ""

    def __call__(self, report) -> None:
        if not self.enabled:
            return
        task, done, total, facts = report.task, report.done, report.total, report.facts
        if task == "run":
            now = self.clock()
            if now - self.start < 1.0 or now - self.last < 0.2:
                return
            self.last = now
            rate = facts.get("steps", 0) / max(now - self.start, 1e-9)
            share = 100 * done / total if total else 0.0
            self.line(f"{self.prefix}TIME {done:.6g} / {total:g}  ({share:5.1f}%)  events "
                      f"{facts.get('events', 0)}  {rate:,.0f} steps/s")
        elif task == "runs":
            if total and total > 1:
                self.line(f"run {facts.get('index', 0) + 1} finished ({done:g} of {total:g})")
        elif task == "sweep":
            name, n = facts.get("name", ""), int(total or 0)
            self.prefix = f"{name} point {min(int(done) + 1, n)}/{n}  "
            self.line(f"{name} = {facts.get('value', math.nan):g} done ({done:g}/{n})")
        elif task == "periodic":
            self.line(f"periodic: Newton step {done:g}, residual "
                      f"{facts.get('residual', math.nan):.2e}")
        elif task == "response":
            self.line(f"response: {facts.get('name', '')} = {facts.get('value', math.nan):.7g}"
                      f"  point {done:g}  residual {facts.get('residual', math.nan):.1e}")
        elif task == "fit":
            self.line(f"fit: evaluation {done:g}  {facts.get('value', '')}")

    def line(self, text: str) -> None:
        if self.enabled:
            print(f"\r{text[:100]:<72}", end="", file=sys.stderr, flush=True)
            self.shown = True

    def done(self) -> None:
        if self.shown:
            print("\r" + " " * 100 + "\r", end="", file=sys.stderr, flush=True)
            self.shown = False
