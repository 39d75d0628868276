"""What a run of an ensemble gives back (a `Member`: its grid rows, not the whole
run) and a set of them (`Batch`), shared by the routes that make them: one run
at a time (`montecarlo.run_sets`) or every run at once (`stacked`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..result import Run, Status


@dataclass(frozen=True)
class Member:
    """What one run gives back: its grid rows of the reported variables."""

    times: np.ndarray
    prdel: np.ndarray  # which of `times` are PRDEL instants
    values: np.ndarray  # (len(times), variables)
    final: tuple[float, ...]  # the variables' values at the run's end
    terminal: dict[str, float]
    status: str
    message: str
    extrema: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)


def member_of(names: tuple[str, ...], run: Run) -> Member:
    """The reduction a worker applies to its run (`farm.Task.reduce`)."""
    grid = run.outdel_mask | run.prdel_mask
    times = run.times[grid]
    values = np.empty((len(times), len(names)))
    for j, name in enumerate(names):
        values[:, j] = run.values[name][grid] if name in run.values else \
            run.constants.get(name, math.nan)
    final = tuple(float(run.final.get(n, values[-1, j] if len(times) else math.nan))
                  for j, n in enumerate(names))
    return Member(times, run.prdel_mask[grid], values, final, dict(run.terminal),
                  str(run.status), run.message, dict(run.extrema))


def shared_times(member: Member, other: Member | None) -> Member:
    """`member`, holding `other`'s output instants and masks where they are the same
    (most members of an ensemble: one array for all instead of one a member)."""
    if other is None or member.times is other.times or \
            not np.array_equal(member.times, other.times) or \
            not np.array_equal(member.prdel, other.prdel):
        return member
    return replace(member, times=other.times, prdel=other.prdel)


@dataclass
class Batch:
    """What `run_sets` gives: a Member per set (None: failed before it ran, the
    error in `errors`, or not run)."""

    members: list[Member | None]
    errors: dict[int, str]
    interrupted: bool = False
    timed_out: bool = False
    how: str = ""  # how the runs were made, when not as a plain run would be

    def status(self, k: int) -> str:
        """Run k's: finished, stopped, failed, or "" (not run)."""
        member = self.members[k]
        if member is not None:
            return member.status
        return str(Status.FAILED) if k in self.errors else ""

    def message(self, k: int) -> str:
        member = self.members[k]
        return member.message if member is not None else self.errors.get(k, "")
