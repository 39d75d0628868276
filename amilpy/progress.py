"""Where a long computation stands: one report shape for every command.

Everything that takes long takes `progress`, a callable given a `Report` now and
then: a run (TIME reached), independent runs (how many have finished), a sweep
(points done; its runs report too), a periodic orbit's Newton steps and a
response curve's points. One callable may watch them all; the command line's
progress line (`console.Progress`) does. A callable that raises (KeyboardInterrupt,
say) stops the computation as an interrupt would.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

# the tasks that report, and what their `done` and `total` count
TASKS = {
    "run": "TIME reached, of FINTIM",
    "runs": "independent runs finished, of all of them",
    "sweep": "points run, of all of them",
    "periodic": "Newton steps taken (no total)",
    "response": "orbits found on the curve (no total)",
    "fit": "evaluations of the runs (no total)",
}


@dataclass(frozen=True)
class Report:
    """`task` (one of TASKS) has come to `done` of `total` (None: not known
    beforehand). `facts`: what the task adds, by name (a run: events, steps; a
    sweep: name, value; Newton: residual; a response: name, value, residual; runs:
    index, the run that finished; a fit: value, the values tried)."""

    task: str
    done: float
    total: float | None = None
    facts: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.task not in TASKS:
            raise ValueError(f"unknown progress task {self.task!r} (known: {', '.join(TASKS)})")


Progress = Callable[[Report], None]


def report(progress: Progress | None, task: str, done: float, total: float | None = None,
           **facts) -> None:
    """Tell `progress` (if any) where `task` stands."""
    if progress is not None:
        progress(Report(task, done, total, facts))
