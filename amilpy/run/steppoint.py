"""Step-point mode: the classic fixed-step translators' loop (CSMP III's RECT, ACSL's
ALGORITHM IALG = 3, FST's DRIVER = 'EUDRIV'), reproduced exactly.

    grid    t_k = t0 + k*DELT, k = 0 .. N, N = round((FINTIM - t0)/DELT) plus one when
            the rest exceeds 0.01*DELT (so the last point may pass FINTIM); DELT is
            used as given, and PRDEL and OUTDEL must be multiples of it
    at t_k  the events due (`due`: none yet), MODINT resets, the memory functions
            updated (HSTRSS, ZHOLD, DELAY, the random draws: read at t_k), a row if
            t_k is on the PRDEL or OUTDEL grid or last, FINISH and TERMT tested (true:
            the run stops with this row), stop if k = N, else the step:
            y += DELT*f(t_k) with EULER, the method's own stages with the others

Every switch is read where the code is evaluated: at t_k, and with RK4/TRAPZ/ADAMS
at each stage point too (CSMP III's RKSFX and ACSL's IALG = 5 evaluate the whole
derivative section at every stage); memory changes only at the step points (CSMP's
KEEP). Nothing is located and there are no breakpoints: STEP(2.5) with DELT = 1
switches at t = 3; FINISH X = V stops at the first step point where X has reached or
passed V; TERMT(C) at the first where C > 0 (t0 included); IMPULS is 1 at the first
step point at or after each of its instants. A branch change seen at a step point is
listed as an event at that point.

`StepPoint` has the members of `loop.Integrator` that `simulate` and `flow` read.
"""

from __future__ import annotations

import math
import time as _clock
from collections.abc import Callable

import numpy as np

from .. import interrupts, ir
from ..codegen import ModelCode
from ..diagnostics import AmilError, Diagnostic
from ..outcome import Failure
from ..progress import report
from ..result import Event, EventKind
from ..steppers import FIXED, first_bad
from .faults import Fault, fault_text
from .loop import Cursor, RunLoop, Stop
from .plan import Grid, Options, Purpose, RunPlan, same_instant
from .record import Recorder
from .watch import SurfaceWatch, literal_modes


def steps(length: float, delt: float) -> int:
    """N for a run of `length`: round(length/DELT), plus one when the rest exceeds
    0.01*DELT (the classic translators' rule)."""
    x = length / delt
    n = round(x)
    return n + 1 if x - n > 0.01 else n


def timer(model: ir.Model, spec: ir.RunSpec, timer: dict[str, float], method: str
          ) -> dict[str, float]:
    """The TIMER values of a step-point run: DELT as the listing gives it (not made to
    divide the output interval), PRDEL and OUTDEL multiples of it (else an error at
    the TIMER line that says what to write)."""
    t = dict(timer)
    delt = t["DELT"] = spec.timer.get("DELT", timer["DELT"])
    # an interval the listing gave must be a multiple; a default one is made one
    for name in sorted(("PRDEL", "OUTDEL"), key=lambda n: n not in spec.timer):
        r = t[name] / delt
        k = round(r)
        if k >= 1 and abs(r - k) <= 1e-9 * r:
            continue
        if name not in spec.timer:
            t[name] = max(1, k) * delt
            continue
        near = sorted({v for v in (math.floor(r) * delt, math.ceil(r) * delt) if v > 0})
        span = spec.timer_spans.get(name) or spec.timer_spans.get("DELT")
        raise AmilError([Diagnostic(
            f"{name} = {t[name]:g} is not a multiple of DELT = {delt:g}", span,
            f"in step-point mode (METHOD {method}) rows fall on the step points "
            f"t0 + k*DELT: write {name} = {' or '.join(f'{v:g}' for v in near)}, "
            f"or DELT = {t[name] / max(1, math.ceil(r)):g}")], model.path, model.source)
    return t


def grid(t0: float, timer: dict[str, float]) -> Grid:
    """The rows of a step-point run: every OUTDEL/DELT and PRDEL/DELT steps and the
    last point, at t0 + k*DELT exactly as the loop computes them."""
    delt = timer["DELT"]
    n = steps(timer["FINTIM"], delt)
    every_o, every_p = round(timer["OUTDEL"] / delt), round(timer["PRDEL"] / delt)
    out_k = np.union1d(np.arange(0, n + 1, every_o), [n])
    pr_k = np.union1d(np.arange(0, n + 1, every_p), [n])
    k = np.union1d(out_k, pr_k)
    return Grid(t0 + k * delt, np.isin(k, out_k), np.isin(k, pr_k))


class StepPoint(RunLoop):
    """Runs a step-point plan: switches read at the step points, nothing located."""

    def __init__(self, model: ir.Model, plan: RunPlan, c: ModelCode, watch: SurfaceWatch,
                 opts: Options, started: float | None = None) -> None:
        super().__init__(model, plan, c, watch, opts, started)
        self.extrema: dict[str, list[float]] = {}  # RANGE over every step point
        self._purposes = [(w, w.purpose) for w in plan.watched]
        self._stepper = None
        self._own = 0  # rates evaluated here (the stepper counts its own stages)
        self._points = 0  # step points processed (the first one has no events)
        # the run's code for crossings (SCHEDULE's DISCRETE, an EVENT's NEWVALUEs):
        # called with the cursor at the point and the surfaces that crossed there
        # (it returns the FINISH or TERMT surface the new values reach, if any)
        self.crossed: Callable[[Cursor, list[int]], int | None] | None = None

    # the members of loop.Integrator that callers use ------------------------------
    def window(self, t0: float, t1: float) -> None:
        """No breakpoints to compute: the grid is all there is."""

    def fault_or(self, stop: Stop) -> Stop:
        return stop

    def range_values(self) -> dict[str, tuple[float, float, float, float]]:
        """name -> (min, time, max, time) over every step point (RANGE)."""
        return {n: tuple(v) for n, v in self.extrema.items()}

    def integrate(self, cur: Cursor, t_end: float, rec: Recorder | None = None,
                  stop_at_event: bool = False, observer=None, pause: bool = False) -> Cursor:
        """The step points from cur.t (processed too) to t_end, on the grid cur.t +
        k*DELT; rows go to `rec`. Raises Stop when the run cannot go on. (`observer`,
        for the located loop's dense output, has nothing to observe here; nor has
        `pause`, since nothing here starts afresh at an instant.)"""
        bad = first_bad(cur.y)
        if bad is not None:
            raise Stop(Failure.INITIAL_NOT_FINITE, cur.t, name=self.c.state_names[bad],
                       value=cur.y[bad])
        delt = self.plan.timer["DELT"]
        t0, n = cur.t, steps(t_end - cur.t, delt)
        n_events = len(self.events)
        times = self.plan.grid.times
        for k in range(n + 1):
            t = t0 + k * delt
            if k == n and t != t_end and same_instant(t, t_end) and rec is not None and \
                    rec.out_i < len(times) and times[rec.out_i] == t_end:
                # (a call that starts between the grid's instants, after an ACSL
                # DYNAMIC block's restart, ends on the grid's instant, not a float off:
                # 0.09 + 10*0.001 is not 0.1)
                t = t_end
            if self._point(t, cur, rec, k == n):
                break
            if k == n or (stop_at_event and len(self.events) > n_events):
                break
            self._step(cur, delt)  # DELT itself, as the classic loop adds it
        return cur

    # one step point -------------------------------------------------------------------
    def due(self, t: float, cur: Cursor) -> None:
        """The events due at t, before anything else there (FST's time events: the run
        sets this hook when it has some)."""

    def _point(self, t: float, cur: Cursor, rec: Recorder | None, last: bool) -> bool:
        """Everything at step point t; True if FINISH or TERMT stops the run here."""
        c, plan = self.c, self.plan
        self.due(t, cur)
        y = cur.y
        yl = y.tolist()
        if plan.resets or c.settle is not None:
            y = self.watch.apply_resets(y, c.modes_literal(t, yl, cur.m, cur.z), t, cur.z)
            yl = y.tolist()
        if c.z0:
            cur.z[:] = c.mem(t, yl, cur.m, cur.m, cur.z)
        stop, m = False, cur.m
        if plan.watched:
            m = literal_modes(c, plan, t, yl, cur.m, cur.z)
            stop = self._changes(t, cur.m, m)
            cur.m[:] = m
        cur.t, cur.y = t, y
        if self.fired:
            # (the code runs before the point's row, and the step from it takes the
            # rates of the new values; a FINISH or TERMT they reach stops the run here)
            fired, self.fired = self.fired, []
            if self.crossed is not None:
                reached = self.crossed(cur, fired)
                y, m = cur.y, list(cur.m)
                if reached is not None and not stop:
                    stop, self.stop_reason = True, reached
                    w = self.plan.watched[reached]
                    self.events.append(w.event(t, 0.0, 1.0, EventKind(w.purpose.value)))
        self.last_good = (t, y, m)  # m is not changed in place later
        self._points += 1
        if rec is not None:
            times = plan.grid.times
            held = rec.hold == t  # (the ACSL form's caller takes this row)
            if rec.out_i < len(times) and times[rec.out_i] == t and not (stop and held):
                rec.grid_row(t, y, cur.m, cur.z)
            elif stop or last:  # (a stop at a held instant: no caller takes its row)
                rec.row(t, y, cur.m, cur.z)
            if rec.extrema.names:
                self._range(t, y, cur, rec)
        return stop

    def _changes(self, t: float, old: list[float], new: list[float]) -> bool:
        """Events for the branches that changed since the last step point; True if a
        TERMT condition holds (t0 included) or a FINISH was reached or passed."""
        first = self._points == 0
        if new == old and not first:
            return False  # nothing changed (a TERMT true here would have stopped before)
        stop = None
        for k, (w, purpose) in enumerate(self._purposes):
            was, now = old[k], new[k]
            if purpose is Purpose.TERMT:
                # T >= TSTOP holds at zero: a step point exactly there stops the run
                hit = w.stops(was, now)
            elif purpose is Purpose.FINISH:
                hit = not first and w.stops(was, now)
            else:
                fires = purpose is Purpose.SCHEDULE and w.fires(was, now)
                if not first and now != was and (fires or purpose is not Purpose.SCHEDULE):
                    # (a crossing that runs code is an event where it runs it)
                    self._event(w.event(t, was, now))
                    if fires:
                        self.fired.append(k)
                continue
            if hit and stop is None:
                stop = k
                self.events.append(w.event(t, was, now, EventKind(purpose.value)))
        self.stop_reason = stop
        return stop is not None

    def record_changes(self, t: float, y, m, new_m, z, at_zero: set[int],
                       quiet: set[int] = frozenset()) -> None:
        """Events for the branches that code changed at an instant (ACSL's DISCRETE,
        FST's NEWVALUEs; `quiet`: changes that are no event)."""
        for k, (w, purpose) in enumerate(self._purposes):
            if new_m[k] != m[k] and purpose not in (Purpose.TERMT, Purpose.FINISH) and \
                    k not in quiet:
                self._event(w.event(t, m[k], new_m[k]))

    def _event(self, event: Event) -> None:
        """A branch change; past the event limit they are counted, not kept (a
        chattering switch changes at every step point, as it did in the classic
        translators, and that is no failure)."""
        if len(self.events) < self.opts.max_events:
            self.events.append(event)
        elif len(self.events) == self.opts.max_events:
            self.events.append(event)
            self.warnings.append(f"more than {self.opts.max_events} branch changes: only "
                                 "the first are listed")

    def _range(self, t: float, y: np.ndarray, cur: Cursor, rec: Recorder) -> None:
        values = rec.outputs(t, y, cur.m, cur.z)
        for name, col in zip(rec.extrema.names, rec.extrema.columns, strict=True):
            v = values[col]
            lo = self.extrema.setdefault(name, [v, t, v, t])
            if v < lo[0]:
                lo[0], lo[1] = v, t
            if v > lo[2]:
                lo[2], lo[3] = v, t

    # the step to the next point ----------------------------------------------------------
    def _rates(self, t: float, y: np.ndarray, cur: Cursor) -> np.ndarray:
        try:
            return np.array(self.c.rhs(t, y.tolist(), cur.m, cur.z), dtype=float)
        except (ArithmeticError, ValueError) as exc:
            raise Stop(Failure.FAULT, t, detail=fault_text(
                self.model, self.c, Fault(exc, t, y.tolist(), list(cur.m), list(cur.z)))
            ) from None

    def _step(self, cur: Cursor, h: float) -> None:
        """From the step point cur.t to the next, h later."""
        if self.nsteps % 256 == 0 or self.nsteps >= self.opts.max_steps - 1:
            self._check_limits(cur.t)
        self.nsteps += 1
        if not len(cur.y):
            return
        if self._stepper is None:
            route = self.plan.route
            self._stepper = FIXED[route.stepper](
                lambda t, y: self._rates(t, y, cur), cur.t, cur.y, math.inf, h,
                route.stability_limit)  # its first call: the rates at this point
            f = self._stepper.f
        else:
            f = self._rates(cur.t, cur.y, cur)
            self._own += 1
        failure = self._stepper.step_from(cur.t, cur.y, f, h)
        self.nfev = self._stepper.nfev + self._own  # the stepper counts its stages
        if failure is not None:  # growing without bound: stopped before it overflows
            raise Stop(Failure.UNSTABLE, failure.t, name=self.c.state_names[failure.index],
                       since=failure.since, method=self.plan.method, delt=h,
                       detail=failure.detail, safe=failure.safe_delt)
        y = self._stepper.y
        bad = first_bad(y)
        if bad is not None:
            raise Stop(Failure.NOT_FINITE, cur.t, name=self.c.state_names[bad],
                       detail=f": the step DELT = {h:g} from TIME = {cur.t:g} overflowed")
        cur.y = y

    def _check_limits(self, t: float) -> None:
        """Every 256 steps (and at the step limit): limits, deadline, progress."""
        interrupts.check()
        if self.nsteps >= self.opts.max_steps:
            raise Stop(Failure.STEPS, t, limit=self.opts.max_steps)
        if self.deadline is not None and _clock.perf_counter() > self.deadline:
            raise Stop(Failure.TIME_LIMIT, t, limit=self.opts.max_time)
        if self.opts.progress is not None and self.nsteps % 2048 == 0:
            report(self.opts.progress, "run", t, self.plan.fintim, events=len(self.events),
                   steps=self.nsteps)
