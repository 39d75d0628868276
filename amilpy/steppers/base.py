"""The stepper contract, a failure as a value, and the cubic Hermite.

A stepper integrates one smooth segment (the switches' branches frozen) from
`t0` towards `t_bound`, one accepted step at a time, in the manner of SciPy's
`OdeSolver`. The run loop reads these members and nothing else:

    step() -> StepFailure | None   advance one accepted step; a failure is a value
    t, t_old                       where the last accepted step ended and began
    y                              the state at `t` (an array the loop may keep)
    interpolant()                  callable t -> y on [t_old, t] (dense output)
    truncate(t)                    end the last step at t in [t_old, t] (an event)
    step_size                      the length of the method's own recent steps (the
                                   first step of the segment after a restart)
    nfev                           right-hand-side evaluations so far
    nstep                          accepted steps so far (internal ones included)
    stiff                          None, or a `Stiffness` once an explicit pair's
                                   steps are bound by stability, not accuracy

Optional capability, declared by subclassing `Chunked` (the AUTO route):

    pending() -> (T, Y)            check instants integrated ahead, not yet taken
    consume(n)                     take the next n of them at once
    samples(t) -> (S, SY)          the integrator's own step ends before t not handed
                                   out yet, between the instants (RANGE's samples)
    stop_at(t) -> bool             make t a check instant (the loop pauses there;
                                   SciPy's solvers have it too: the step over t is
                                   handed out in two, `ScipyStepper.stop_at`)
    first_wrong() -> int | None    the first pending instant where a surface is on
                                   the wrong side, as the stepper found (None: it
                                   does not look; the loop does)

Optional capability, declared by `refines = True` (AUTO's odeint chunks, whose dense
output is a cubic between two instants many LSODA steps apart):

    sharpen() -> bool              a quintic through a third instant, if close enough
    refine(t, surfaces)            integrate a narrow window around t again; the
                                   dense output with its exact ends
    resolved(t, surfaces) -> bool  whether the dense output around t is that narrow
    crossing_step(surfaces)        the integrator's own step, among those inside the
        -> (ta, tb) | None         present interval, that the first crossing of these
                                   surfaces is in (None: one step, or not known)

To add a route: subclass `Stepper` (the constructor takes what `make_stepper`
passes for its kind), then add a row to `routes.ROUTES` whose `stepper` names
the class in `steppers.STEPPERS`. Per-route constants (stability limits, local
tolerances) live in that row, not here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..outcome import Failure

Rhs = Callable[[float, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class StepFailure:
    """Why a step could not be taken, with what the message needs.

    `kind` is one of the outcome table's failures (SOLVER, NOT_FINITE, UNSTABLE,
    STEPS); `t` where the stepper stood; `detail` the solver's own words;
    `index` the state that went wrong; for UNSTABLE, `since` (TIME the growth
    began) and `safe_delt` (the largest DELT that is stable there).
    """

    kind: Failure
    t: float
    detail: str = ""
    index: int | None = None
    since: float | None = None
    safe_delt: float | None = None


@dataclass(frozen=True)
class Stiffness:
    """Where an explicit pair's steps became bound by stability, and h*|lambda| there."""

    t: float
    h_lambda: float


class Stepper:
    """Base of every route's stepper: see the module docstring for the contract."""

    t: float
    t_old: float
    y: np.ndarray
    stiff: Stiffness | None = None
    # What the run loop may do besides stepping one step at a time, declared here and
    # never guessed from the class (the loop's `run.fastpaths` reads it): None; "batch"
    # (a `Chunked` stepper: many accepted instants handed over at once); "ahead" (the
    # compiled kernel: steps, locates and switches on its own, `advance`/`done`).
    fast_path: str | None = None
    # Whether its dense output between two accepted instants may be too coarse to
    # locate a crossing on (AUTO's cubic over many of LSODA's steps): then it has
    # `sharpen()`, `refine(t, surfaces)` and `resolved(t, surfaces)`, which
    # `run.edges.locate_crossings` calls (every other route's dense output is its
    # method's own, as accurate as its steps)
    refines: bool = False

    @property
    def nfev(self) -> int:  # pragma: no cover - interface
        raise NotImplementedError

    @property
    def nstep(self) -> int:  # pragma: no cover - interface
        raise NotImplementedError

    def step(self) -> StepFailure | None:  # pragma: no cover - interface
        raise NotImplementedError

    def interpolant(self) -> Callable[[float], np.ndarray]:  # pragma: no cover
        raise NotImplementedError

    @property
    def step_size(self) -> float:
        """The length of the method's own recent steps (default: the last step's)."""
        return self.t - self.t_old

    def truncate(self, t: float) -> None:
        """End the last step at `t` (default: take the dense output there)."""
        self.y = np.asarray(self.interpolant()(t), dtype=float)
        self.t = t

    def stop_at(self, t: float) -> bool:
        """Make t an instant the segment can pause at and go on from; False if it
        cannot be (default: a stepper that goes one step at a time cannot)."""
        return False

    def samples(self, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Step ends strictly before t the stepper took on its own and not handed
        out yet, and their states (RANGE's samples); None: it hands out every step."""
        return None


class Chunked(Stepper):
    """A stepper that integrates many check instants per call (the capability the
    loop uses to record clean stretches at once)."""

    fast_path = "batch"

    def pending(self) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - interface
        """The check instants integrated and not yet taken, and their states."""
        raise NotImplementedError

    def consume(self, n: int) -> None:  # pragma: no cover - interface
        """Take the next `n` pending instants at once (the loop found them clean)."""
        raise NotImplementedError

    def samples(self, t: float) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
        """The step ends strictly before t not handed out yet, and their states."""
        raise NotImplementedError

    def stop_at(self, t: float) -> bool:  # pragma: no cover - interface
        """Make t a check instant; False if it cannot be."""
        raise NotImplementedError

    def first_wrong(self) -> int | None:  # pragma: no cover - interface
        """Index among the pending instants of the first one where a watched surface
        is on the wrong side (len(pending) if none); None if the stepper does not
        look at the surfaces itself."""
        raise NotImplementedError


class Hermite:
    """The cubic through both ends of a step with their derivatives: the dense
    output of the fixed-step methods, and of a step whose own interpolant is not
    to be trusted (stability-bound, or overflowing inside)."""

    def __init__(self, t0: float, y0: np.ndarray, f0: np.ndarray, t1: float, y1: np.ndarray,
                 f1: np.ndarray) -> None:
        self.t0, self.h = t0, t1 - t0
        self.y0, self.y1 = y0, y1
        self.f0, self.f1 = f0, f1

    def __call__(self, t: float) -> np.ndarray:
        if self.h == 0:
            return self.y1
        s = (t - self.t0) / self.h
        h00 = (1 + 2 * s) * (1 - s) ** 2
        h01 = s * s * (3 - 2 * s)
        h10 = s * (1 - s) ** 2
        h11 = s * s * (s - 1)
        with np.errstate(all="ignore"):
            return h00 * self.y0 + h01 * self.y1 + self.h * (h10 * self.f0 + h11 * self.f1)


def first_bad(v: np.ndarray) -> int | None:
    """The index of the first value that is not finite, or None."""
    finite = np.isfinite(v)
    if finite.all():  # the common case, without building an index array
        return None
    return int(np.argmin(finite))
