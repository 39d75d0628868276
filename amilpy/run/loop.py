"""The integration loop: segments between breakpoints, steps, events, restarts.

`Integrator.integrate` takes a state (TIME, states, modes, memory) to an end
time. A segment runs from a restart to the next breakpoint with the branches
frozen; after each accepted step the watch looks for crossings, locates the
first, cuts the step there and the segment ends with a restart in the new
branches (`restarts.py`). Output rows go to a `Recorder` when one is given; a
failure raises `Stop` with its outcome kind and data (`outcome.MESSAGES`).

The integrator's parts, one module each: the segment's start (`segment.py`),
the look at each accepted step (`stepwatch.py`), restarts and stops
(`restarts.py`), and the routes' fast paths (`fastpaths.py`).
"""

from __future__ import annotations

import math
import time as _clock
from bisect import bisect_right

import numpy as np

from .. import interrupts, ir
from ..codegen import ModelCode
from ..diagnostics import AmilError
from ..outcome import Failure
from ..progress import report
from ..result import Events
from ..steppers import Stepper, first_bad
from .cursor import Cursor, Observer, Paused, Stop
from .fastpaths import FastPaths
from .faults import Fault
from .plan import Options, Purpose, RunPlan, sliding_in, time_breakpoints
from .record import Recorder
from .restarts import Restarts
from .segment import SegmentStart
from .stepwatch import StepWatch
from .watch import SurfaceWatch

__all__ = ["Cursor", "Integrator", "Observer", "RunLoop", "Stop"]

MAX_WINDOW = 1e8  # output intervals of an integration outside the run (an analysis's)


class RunLoop:
    """What every run loop keeps across calls of its `integrate`: the run's events,
    warnings and counts, its last good point, what stopped it, and its deadline
    (`Integrator` locates the switching; `steppoint.StepPoint` reads it at the
    step points)."""

    def __init__(self, model: ir.Model, plan: RunPlan, c: ModelCode, watch: SurfaceWatch,
                 opts: Options, started: float | None = None) -> None:
        self.model, self.plan, self.c, self.watch, self.opts = model, plan, c, watch, opts
        self.started = _clock.perf_counter() if started is None else started
        self.deadline = self.started + opts.max_time if opts.max_time else None
        self.events = Events()
        self.warnings: list[str] = []
        if plan.route.uses_tolerances and plan.tol.floored is not None:
            self.warnings.append(f"RELERR {plan.tol.floored:g} is below what double "
                                 f"precision can hold: {plan.tol.floor:.3g} was used")
        self.nsteps = 0
        self.nfev = 0
        self.last_good: tuple[float, np.ndarray, list[float]] | None = None
        self.stop_reason: int | None = None  # the FINISH/TERMT surface that ended the run
        # the crossings that run code (SCHEDULE, EVENT): one may change branch at a
        # restart another surface made (1 - RSW(X > 1, 1, 0) reaches zero with X - 1)
        self.scheduling = tuple(k for k, w in enumerate(plan.watched)
                                if w.purpose is Purpose.SCHEDULE)
        # the TERMTs: one may turn true at a restart another surface made, or hold
        # where the run starts
        self.terminating = tuple(k for k, w in enumerate(plan.watched)
                                 if w.purpose is Purpose.TERMT)
        # those that crossed where the loop stopped: their code is the caller's to run
        self.fired: list[int] = []


class Integrator(RunLoop, SegmentStart, StepWatch, Restarts, FastPaths):
    """Integrates one run's model under its plan, switching instants located."""

    def __init__(self, model: ir.Model, plan: RunPlan, c: ModelCode, watch: SurfaceWatch,
                 opts: Options, started: float | None = None) -> None:
        super().__init__(model, plan, c, watch, opts, started)
        self.faults: list[Fault] = []  # arithmetic faults the integration has not passed
        self.stiff_from: float | None = None  # where an explicit pair became stiff
        self._recent: list[float] = []  # restart instants (chatter)
        self._last_step: float | None = None
        self._tiny = 0
        self._iterations = 0
        self.breakpoints, self.roots = plan.breakpoints, plan.roots
        self.check_times = plan.grid.times  # where AUTO looks at the surfaces
        self._kernel = None  # METHOD COMPILED: the model's generated module, on first use
        self._stop_at_event = False
        self._paused: Paused | None = None
        self._grazing: dict[int, float] = {}  # (`_grazing_bands`)
        self._exited: set[int] = set()  # the slides the last restart ended
        # a resumed stepper's steps and evaluations already counted in nsteps, nfev
        self._counted = self._counted_nfev = 0

    # ------------------------------------------------------------------ public
    def first_step(self, h: float) -> None:
        """The first step to try (a restart takes the length of the step before)."""
        self._last_step = h

    def window(self, t0: float, t1: float) -> None:
        """Breakpoints and check instants for an integration outside the run's own
        [t0, FINTIM] (check instants every output interval, as on the grid)."""
        plan = self.plan
        if t0 < plan.t0 or t1 > plan.fintim:
            self.roots, points = time_breakpoints(self.c, list(plan.watched), t0, t1)
            self.breakpoints = tuple(points)
            step = min(plan.timer["OUTDEL"], plan.timer["PRDEL"])
            span = (t1 - t0) / step
            if not span <= MAX_WINDOW:  # (NaN and infinities too)
                raise AmilError(
                    f"integrating from TIME = {t0:g} to {t1:g} spans {span:.3g} output "
                    f"intervals of {step:g} s, more than the {MAX_WINDOW:.0e} an analysis "
                    "looks at: ask for less time (--settle, --period, --at), or raise OUTDEL")
            k0, k1 = math.floor((t0 - plan.t0) / step), math.ceil((t1 - plan.t0) / step)
            self.check_times = plan.t0 + step * np.arange(k0, k1 + 1)

    def integrate(self, cur: Cursor, t_end: float, rec: Recorder | None = None,
                  stop_at_event: bool = False, observer: Observer | None = None,
                  pause: bool = False) -> Cursor:
        """Integrate from `cur` to `t_end`, a FINISH/TERMT, or (stop_at_event) the
        first event; rows go to `rec`. Raises Stop when the run cannot go on.

        `pause`: t_end is an instant where the caller runs code that may change
        nothing the derivatives read (an ACSL CINT instant or event): a chunked
        segment stops there without ending, and the next call goes on with it when
        the states, the branches and the memory the derivatives read are as they
        were (`_resume`); else it starts afresh, as at any restart."""
        bad = first_bad(cur.y)
        if bad is not None:
            raise Stop(Failure.INITIAL_NOT_FINITE, cur.t, name=self.c.state_names[bad],
                       value=cur.y[bad])
        n_events = len(self.events)
        self._stop_at_event = stop_at_event
        while cur.t < t_end and self.stop_reason is None:
            if stop_at_event and len(self.events) > n_events:
                break
            stop, pausing = self._next_stop(cur, t_end, pause, observer is not None)
            held = self._resume(cur, stop, rec, observer)
            if held is not None:
                stepper, f, seg_end, seg_start = held
            else:
                seg_end = self._segment_end(cur, stop, pausing)
                # (where it pauses, if it may start afresh there: the caller's code,
                # or a memory the integrator sees changing)
                stepper, f = self._start_segment(cur, seg_end, rec, observer is not None,
                                                 stop if pause or self.c.seen_times else None)
                seg_start = cur.t
            if seg_end > stop and not stepper.stop_at(stop):
                # (a chunk that cannot stop there: a segment ending at the stop)
                seg_end = self._segment_end(cur, stop)
                stepper, f = self._start_segment(cur, seg_end, rec, observer is not None)
                seg_start = cur.t
            try:
                self._segment(cur, stepper, f, seg_end, stop, rec, observer, stop_at_event,
                              seg_start)
            finally:
                self.nfev += stepper.nfev - self._counted_nfev
                self.nsteps += stepper.nstep - self._counted
                self._counted = self._counted_nfev = 0
                if self._paused is not None and self._paused.stepper is stepper:
                    self._counted, self._counted_nfev = stepper.nstep, stepper.nfev
        return cur

    def new_grid(self, times: np.ndarray) -> None:
        """The output instants from now on are `times` (the ACSL form's CINT assigned
        by its code): a segment paused on the old ones is not resumed (its chunk was
        integrated to the old instants, and rows between them were read off the
        interpolant across an old interval: 1.5e-4 off)."""
        self.check_times = times
        self._paused = None
        self._counted = self._counted_nfev = 0

    def _resume(self, cur: Cursor, t_end: float, rec, observer) -> tuple | None:
        """The paused segment, if nothing it reads has changed since it paused at the
        instant where `cur` stands: (stepper, f, its end, its start)."""
        p, self._paused = self._paused, None
        if p is None:
            return None
        if observer is not None or rec is not p.rec or cur is not p.cur or cur.t != p.t or \
                tuple(cur.m) != p.modes or not np.array_equal(cur.y, p.y) or \
                tuple(cur.z[k] for k in sorted(self.c.seen_memory)) != p.read or \
                self._segment_end(cur, t_end, True) < p.seg_end:
            self._counted = self._counted_nfev = 0
            return None
        return p.stepper, p.f, p.seg_end, p.seg_start

    # ---------------------------------------------------------------- segments
    def _pausing(self, cur: Cursor) -> bool:
        """Whether a segment from `cur` can stop at an instant and go on."""
        return self.plan.pauses and not sliding_in(cur.m) and len(cur.y) > 0

    def _next_stop(self, cur: Cursor, t_end: float, pause: bool, observed: bool
                   ) -> tuple[float, bool]:
        """Where the next segment stops, and whether it pauses there: t_end, or the
        first instant before it at which a memory may change (a draw due, a new day's
        weather, PULSE's end), where a chunked segment pauses. The memory's update
        there restarts the run only if it changes what the integrator sees (`_restart`):
        a draw only printed costs no restart."""
        if observed:
            return t_end, False  # (an observer wants every step of each segment)
        if self._pausing(cur):
            wakes = [e for e in self._pulse_ends(cur.z, cur.t) if e < t_end]
            if wakes:
                return min(wakes), True
        return t_end, pause

    def _segment_end(self, cur: Cursor, t_end: float, pause: bool = False) -> float:
        """Where a segment from `cur` ends: t_end (unless the segment may pause there:
        a chunked one, then the run's end), a breakpoint, a memory's instant (where a
        chunked segment pauses instead, `_next_stop`)."""
        k = bisect_right(self.breakpoints, cur.t * (1 + 1e-15) + 1e-300)
        chunked = pause and self._pausing(cur)
        seg_end = self.plan.fintim if chunked and t_end <= self.plan.fintim else t_end
        if k < len(self.breakpoints):
            seg_end = min(seg_end, self.breakpoints[k])
        if not chunked:
            for end in self._pulse_ends(cur.z, cur.t):
                seg_end = min(seg_end, end)
        return seg_end

    def _pulse_ends(self, z, t: float) -> list[float]:
        return [e for e in self.c.memory_times(z, t) if e < self.plan.fintim]

    def _segment(self, cur: Cursor, stepper: Stepper, f, seg_end: float, t_end: float,
                 rec: Recorder | None, observer: Observer | None, stop_at_event: bool,
                 seg_start: float) -> None:
        """Step until the segment ends: its bound, a restart, or a stop; or until it
        pauses at t_end, when it goes on past it (see `integrate`)."""
        c, plan = self.c, self.plan
        e_prev = self.watch.surfaces_here(cur.t, cur.y, cur.m, cur.z) if plan.watch_idx else []
        self._grazing = self._grazing_bands(cur, e_prev, self._exited)
        self._exited = set()
        take = self._fast_path(stepper, cur, rec)
        while True:
            if take is not None:
                e_prev, seg_start = take(stepper, cur, min(seg_end, t_end), rec, e_prev,
                                         seg_start)
            self._check_limits(cur.t, stepper)
            failure = stepper.step()
            if failure is not None:
                raise self._stop_for(failure, stepper)
            ta, step = stepper.t_old, self._accepted(stepper, cur, e_prev, seg_start)
            e_prev = step.e_b
            # (the memory the step began with: DELAY's store samples inside it, below,
            # and the observer follows those samples itself)
            z_step = list(cur.z) if observer is not None else None
            if rec is not None:
                taken = stepper.samples(step.tb)
                if taken is not None:
                    rec.samples(*taken, cur.m, cur.z)
                self._rows_inside(rec, stepper, f, ta, cur.y, step.tb, step.yb, cur,
                                  step.silent)
            self.sample_memory(stepper, cur, step.tb)
            if observer is not None:
                observer(ta, step.tb, stepper.interpolant(), list(cur.m), z_step)
            tb, yb = step.tb, step.yb
            at_output = rec is not None and rec.out_i < len(plan.grid.times) and \
                plan.grid.times[rec.out_i] <= tb * (1 + 4e-16)
            at_boundary = tb >= seg_end
            if at_boundary and tb < t_end:
                # a breakpoint: the surfaces on TIME that reach zero here decide anew
                step.triggered |= {k for k, root in self.roots.items() if root == tb}
            restart = step.triggered or step.departed or step.truncated or \
                (at_boundary and tb < t_end) or \
                any(e <= tb for e in self._pulse_ends(cur.z, cur.t))  # a memory's instant
            if restart:
                # a breakpoint a few ulps ahead decides here too: the next segment would
                # take it as passed (a switch located on it: X = 1 - TIME reaching 0.5
                # where STEP(0.5) does)
                step.triggered |= {k for k, root in self.roots.items()
                                   if tb <= root <= tb * (1 + 1e-15) + 1e-300}
            if rec is not None and not at_output and not restart:
                # every step's end is one of RANGE's samples (a restart's, in its new
                # branches, is kept by the restart)
                rec.sample(tb, yb, cur.m, cur.z)
            if restart:
                h = min(stepper.step_size, tb - ta) if tb > ta else stepper.step_size
                if self._restart(cur, step, h, at_output, at_boundary, rec, stop_at_event):
                    return
                at_output = False  # recorded by the restart, in the new branches
            elif c.z0:
                cur.z[:] = c.mem(tb, yb.tolist(), cur.m, cur.m, cur.z)
            if at_output:
                rec.grid_row(tb, yb, cur.m, cur.z)
            cur.t, cur.y = tb, yb
            if at_boundary:
                return
            if tb >= t_end:
                # paused at t_end: the caller's instant; the segment goes on from here
                self._paused = Paused(stepper, f, seg_end, seg_start, cur, tb, yb,
                                       tuple(cur.m), tuple(cur.z[k] for k in
                                                           sorted(c.seen_memory)), rec)
                return
            if self.opts.progress is not None and self._iterations % 200 == 0:
                self._report(cur.t, stepper)
            if any(cur.t < e < min(seg_end, t_end) for e in self._pulse_ends(cur.z, cur.t)):
                return

    def _report(self, t: float, stepper: Stepper) -> None:
        report(self.opts.progress, "run", t, self.plan.fintim, events=len(self.events),
               steps=self.nsteps + stepper.nstep - self._counted)

    def _check_limits(self, t: float, stepper: Stepper) -> None:
        interrupts.check()
        self._iterations += 1
        if self.nsteps + stepper.nstep - self._counted >= self.opts.max_steps:
            raise Stop(Failure.STEPS, t, limit=self.opts.max_steps)
        if self.deadline is not None and _clock.perf_counter() > self.deadline:
            raise Stop(Failure.TIME_LIMIT, t, limit=self.opts.max_time)
