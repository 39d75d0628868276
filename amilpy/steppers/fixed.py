"""CSMP's fixed-step methods (RK4, Euler, Heun, Adams-Bashforth 2), and the clock
that stands in for a stepper when a model has no states."""

from __future__ import annotations

import math

import numpy as np

from ..outcome import Failure
from .base import Hermite, Rhs, StepFailure, Stepper, first_bad


class FixedStepper(Stepper):
    """A fixed-step method with step DELT on a grid anchored at TIME = 0.

    Steps end on the DELT grid (so output instants that are multiples of DELT are
    hit exactly); a step is shortened to end at the segment bound (a breakpoint)
    and, after an event, at the located instant. Dense output is the cubic
    Hermite through both ends, of the same order as RK4.

    `stability_limit` (from the route's row) is |h*lambda| where the method's
    stability region ends on the negative real axis.
    """

    UNSTABLE_STEPS = 3
    GROWTH = 1e3
    TEST_EVERY = 4  # steps between tests while none is past the limit

    def __init__(self, fun: Rhs, t0: float, y0: np.ndarray, t_bound: float, delt: float,
                 stability_limit: float) -> None:
        self.fun = fun
        self._nfev = 0
        self._steps = 0
        self.t = self.t_old = t0
        self.y = np.asarray(y0, dtype=float)
        self.t_bound = t_bound
        self.delt = delt
        self.stability_limit = stability_limit
        self.f = self._call(t0, self.y)
        self.y_old = self.y
        self.f_old = self.f
        self.steps_taken = 0  # in this segment (Adams starts with a one-step method)
        self._beyond = 0  # tests in a row past the stability limit
        self._dy_start = 0.0  # |y_new - y| when that streak began
        self._since = 0.0  # TIME it began

    @property
    def nfev(self) -> int:
        return self._nfev

    @property
    def nstep(self) -> int:
        return self._steps

    def _call(self, t: float, y: np.ndarray) -> np.ndarray:
        self._nfev += 1
        return np.asarray(self.fun(t, y), dtype=float)

    def next_time(self) -> float:
        k = math.floor(self.t / self.delt + 1e-9) + 1
        t_next = k * self.delt
        # a sliver left before the grid point after an event: merge into one step
        if t_next - self.t < 1e-6 * self.delt:
            t_next += self.delt
        return min(t_next, self.t_bound)

    def advance(self, t: float, y: np.ndarray, f: np.ndarray, h: float) -> np.ndarray:
        raise NotImplementedError  # pragma: no cover - each method's formula

    def step(self) -> StepFailure | None:
        if self.t >= self.t_bound:
            return StepFailure(Failure.SOLVER, self.t, "the segment is already finished")
        t_new = self.next_time()
        h = t_new - self.t
        y_new = self.advance(self.t, self.y, self.f, h)
        bad = first_bad(y_new)
        if bad is not None:
            return StepFailure(Failure.NOT_FINITE, self.t, "the state is no longer finite "
                               f"(step DELT = {self.delt:g} may be unstable)", index=bad)
        self.steps_taken += 1
        self._steps += 1
        self.t_old, self.y_old, self.f_old = self.t, self.y, self.f
        self.t, self.y = t_new, y_new
        self.f = self._call(t_new, y_new)
        if self._beyond or self._steps % self.TEST_EVERY == 0:
            return self._stability_test(h)
        return None

    def step_from(self, t: float, y: np.ndarray, f: np.ndarray, h: float
                  ) -> StepFailure | None:
        """One step of the method from (t, y) with rates f the caller took there, for
        step-point mode (memory and events change at each step point before its rates
        are taken; the stages call `fun` as `advance` does); the new state is `y`.
        Adams keeps its history as `step` keeps it. Each call continues from where the
        last one ended; the step that ended at t is tested for stability as `step`
        tests it (now that its end's rates are known)."""
        if self.steps_taken:
            self.y, self.f = y, f
            if self._beyond or self._steps % self.TEST_EVERY == 0:
                failure = self._stability_test(t - self.t_old)
                if failure is not None:
                    return failure
        self.t, self.y, self.f = t, y, f
        y_new = self.advance(t, y, f, h)
        self.steps_taken += 1
        self._steps += 1
        self.t_old, self.y_old, self.f_old = t, y, f
        self.t, self.y = t + h, y_new
        return None

    def _stability_test(self, h: float) -> StepFailure | None:
        """h*|lambda| along the last step, |f(y1) - f(y0)| / |y1 - y0|, with no extra
        evaluations. Past the method's limit on a decaying mode, the numerical
        solution grows by a factor each step. After UNSTABLE_STEPS such steps, once
        the step's change has grown GROWTH-fold, the run is stopped, long before
        the state overflows. AB2 at K = 1E5 in the stress suite used to print a
        finished table ending at 5.7E149."""
        dy = self.y - self.y_old
        den = float(dy @ dy)
        if not 0.0 < den < math.inf:
            self._beyond = 0
            return None
        df = self.f - self.f_old
        h_lambda = abs(h) * math.sqrt(float(df @ df) / den)
        # along a decaying mode (df.dy < 0) growth is the method's, not the model's:
        # a finite-time singularity grows with df.dy > 0 and is left to the non-finite
        # check, with its own message
        if not (h_lambda > self.stability_limit and float(df @ dy) < 0.0):
            self._beyond = 0
            return None
        if self._beyond == 0:
            self._dy_start = math.sqrt(den)
            self._since = self.t_old
        self._beyond += 1
        if self._beyond >= self.UNSTABLE_STEPS and math.sqrt(den) > self.GROWTH * \
                self._dy_start:
            # |lambda| from this step's own length (shorter than DELT after an event)
            return StepFailure(
                Failure.UNSTABLE, self.t,
                f"h*|lambda| = {h_lambda:.3g} is past the method's stability limit "
                f"{self.stability_limit:g}", index=int(np.argmax(np.abs(dy))),
                since=self._since, safe_delt=self.stability_limit * abs(h) / h_lambda)
        return None

    def interpolant(self):
        return Hermite(self.t_old, self.y_old, self.f_old, self.t, self.y, self.f)

    def truncate(self, t: float) -> None:
        """Redo the last step with the method itself, ending exactly at t."""
        h = t - self.t_old
        self.steps_taken -= 1
        self.t, self.y, self.f = self.t_old, self.y_old, self.f_old
        if h > 0:
            y_new = self.advance(self.t, self.y, self.f, h)
            self.steps_taken += 1
            self.t_old = self.t
            self.t, self.y = t, y_new
            self.f = self._call(t, y_new)


class Euler(FixedStepper):
    def advance(self, t, y, f, h):
        return y + h * f


class Heun(FixedStepper):
    """TRAPZ: Euler predictor, trapezoid corrector."""

    def advance(self, t, y, f, h):
        yp = y + h * f
        return y + 0.5 * h * (f + self._call(t + h, yp))


class RK4(FixedStepper):
    def advance(self, t, y, f, h):
        k1 = f
        k2 = self._call(t + 0.5 * h, y + 0.5 * h * k1)
        k3 = self._call(t + 0.5 * h, y + 0.5 * h * k2)
        k4 = self._call(t + h, y + h * k3)
        return y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


class AdamsBashforth2(FixedStepper):
    """ADAMS: two-step Adams-Bashforth; starts (and restarts) with a Heun step."""

    def advance(self, t, y, f, h):
        if self.t_old < t and self.steps_taken and self.t > self.t_old:
            h_prev = t - self.t_old
            f_prev = self.f_old
            # variable-step AB2 (steps after a shortened one keep second order)
            r = h / h_prev
            return y + h * ((1.0 + 0.5 * r) * f - 0.5 * r * f_prev)
        yp = y + h * f
        return y + 0.5 * h * (f + self._call(t + h, yp))


class Clock(Stepper):
    """A model with no states: time advances in steps of at most `max_step`
    (an output interval) so that switches on TIME are still watched."""

    def __init__(self, t0: float, t_bound: float, max_step: float) -> None:
        self.t = self.t_old = t0
        self.t_bound = t_bound
        self.h = max_step if math.isfinite(max_step) else (t_bound - t0) / 100.0
        self.y = np.zeros(0)
        self._steps = 0

    @property
    def nfev(self) -> int:
        return 0

    @property
    def nstep(self) -> int:
        return self._steps

    def step(self) -> StepFailure | None:
        self.t_old = self.t
        self.t = min(self.t + self.h, self.t_bound)
        self._steps += 1
        return None

    def interpolant(self):
        return lambda t: np.zeros(0)
