"""The integration loop: segments between breakpoints, steps, events, restarts.

`Integrator.integrate` takes a state (TIME, states, modes, memory) to an end
time. A segment runs from a restart to the next breakpoint with the branches
frozen; after each accepted step the watch looks for crossings, locates the
first, cuts the step there and the segment ends with a restart in the new
branches (`_restart`). Output rows go to a `Recorder` when one is given; a
failure raises `Stop` with its outcome kind and data (`outcome.MESSAGES`).
"""

from __future__ import annotations

import math
import time as _clock
from bisect import bisect_left, bisect_right
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from .. import interrupts, ir
from ..codegen import Compiled
from ..codegen.jacobian import for_compiled as jacobian_for
from ..codegen.rolled import for_compiled as rolled_rhs
from ..compiled.layout import LOOP, PLAIN, QUIET
from ..diagnostics import AmilError
from ..outcome import Failure
from ..progress import report
from ..result import Event
from ..steppers import (
    LOG_BUDGET,
    Chunked,
    Evaluations,
    Hermite,
    StepFailure,
    Stepper,
    first_bad,
    make_stepper,
)
from ..steppers.compiled import KernelStepper
from ..steppers.jacobian import SegmentJacobian
from .edges import expected_event, locate_crossings
from .faults import Fault, fault_text
from .plan import (
    SLIDE,
    Options,
    Purpose,
    RunPlan,
    SurfaceKind,
    time_breakpoints,
    train_instants,
)
from .record import Recorder
from .slide import MAX_SLIDING
from .watch import SurfaceWatch, TooManySlides, crossings

_EPS = float(np.finfo(float).eps)
CHUNK_SHARE = 0.02  # of --max-time, the most one odeint chunk may take
MAX_WINDOW = 1e8  # output intervals of an integration outside the run (an analysis's)

# (ta, tb, dense output, modes, memory) of every accepted step, for analyses
Observer = Callable[[float, float, Callable, list, list], None]


class Stop(Exception):
    """The run ends here, for `kind`, with the data its message needs."""

    def __init__(self, kind: Failure, t: float, **fields: object) -> None:
        super().__init__(kind.value)
        self.kind = kind
        self.t = t
        self.fields = fields


@dataclass
class Cursor:
    """Where the integration stands. `m` is shared with the segment's vector field
    (a silent switch changes it in place)."""

    t: float
    y: np.ndarray
    m: list[float]
    z: list[float]


@dataclass
class _Paused:
    """A chunked segment stopped at an instant that may change nothing it reads (an
    ACSL CINT instant or event): what is needed to go on with it (`_resume`)."""

    stepper: Stepper
    f: Callable
    seg_end: float
    seg_start: float
    cur: Cursor
    t: float
    y: np.ndarray
    modes: tuple
    read: tuple  # the memory slots the derivatives read, as they were
    rec: object


@dataclass
class _Step:
    """What the watch found in one accepted step."""

    tb: float
    yb: np.ndarray
    triggered: set[int]  # located at zero at tb
    departed: set[int]  # left a zero it sat on
    exits: dict[int, float]  # sliding surfaces leaving, to which side
    truncated: bool
    e_b: list[float]  # the watched surfaces at tb
    # hits whose branch changes no derivative (cut only for a surface that reads them)
    quiet: set[int] = field(default_factory=set)
    # surfaces that crossed silently in the step (their mode follows the sign, no
    # event): the rows inside the step take each one's sign where the row is
    silent: list[int] = field(default_factory=list)


class RunLoop:
    """What every run loop keeps across calls of its `integrate`: the run's events,
    warnings and counts, its last good point, what stopped it, and its deadline
    (`Integrator` locates the switching; `steppoint.StepPoint` reads it at the
    step points)."""

    def __init__(self, model: ir.Model, plan: RunPlan, c: Compiled, watch: SurfaceWatch,
                 opts: Options, started: float | None = None) -> None:
        self.model, self.plan, self.c, self.watch, self.opts = model, plan, c, watch, opts
        self.started = _clock.perf_counter() if started is None else started
        self.deadline = self.started + opts.max_time if opts.max_time else None
        self.events: list[Event] = []
        self.warnings: list[str] = []
        if plan.route.uses_tolerances and plan.tol.floored is not None:
            self.warnings.append(f"RELERR {plan.tol.floored:g} is below what double "
                                 f"precision can hold: {plan.tol.floor:.3g} was used")
        self.nsteps = 0
        self.nfev = 0
        self.last_good: tuple[float, np.ndarray, list[float]] | None = None
        self.stop_reason: int | None = None  # the FINISH/TERMT surface that ended the run


class Integrator(RunLoop):
    """Integrates one run's model under its plan, switching instants located."""

    def __init__(self, model: ir.Model, plan: RunPlan, c: Compiled, watch: SurfaceWatch,
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
        self._kernel = None  # METHOD COMPILED: the model's compiled module, on first use
        self._stop_at_event = False
        self._paused: _Paused | None = None
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
            if seg_end > stop and not (isinstance(stepper, Chunked) and
                                       stepper.stop_at(stop)):
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
        """Whether a segment from `cur` can stop at an instant and go on (chunked)."""
        return self.plan.chunked and SLIDE not in cur.m and len(cur.y) > 0

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

    def vector_field(self, cur: Cursor, log: Evaluations | None = None
                     ) -> Callable[[float, np.ndarray], list]:
        """The segment's vector field for the steppers. An arithmetic fault gives
        NaN (the solver shortens its step) and is kept for the message. A point
        exactly on a surface (the segment's start, say) may be where the branch in
        force has no value (X/P at P = 0 in X/FCNSW(P, P, 1., P)): there the
        function's own branch at zero is taken, as it is defined. `log`: where the
        evaluations are kept while it is on (AUTO's chunks: `OdeintStepper`)."""
        m, z, faults, n = cur.m, cur.z, self.faults, len(cur.y)
        deadline, calls = self.deadline, [0]
        rhs, sliding, field = self.c.rhs, SLIDE in m, self.watch.field
        rolled = rolled_rhs(self.c)  # a large model's repeated equations on arrays

        def f(t, y):
            if deadline is not None:
                calls[0] += 1
                if calls[0] % 256 == 0 and _clock.perf_counter() > deadline:
                    raise Stop(Failure.TIME_LIMIT, t, limit=self.opts.max_time)
            try:
                # no surface slides: the compiled derivatives themselves (the hot path)
                if sliding:
                    return field(t, y, m, z)
                if rolled:
                    return rolled(t, y, m, z)
                return rhs(t, y.tolist(), m, z)
            except (ArithmeticError, ValueError) as exc:
                try:
                    on = self.watch.at_zero(t, y, m, z)
                    if on != m:
                        return field(t, y, on, z)
                except (ArithmeticError, ValueError):
                    pass
                faults.append(Fault(exc, t, y.tolist(), list(m), list(z)))
                return [math.nan] * n
            except TooManySlides as exc:
                raise Stop(Failure.SLIDES, t, count=exc.count, limit=MAX_SLIDING) from None
        if log is not None:
            log.fun = self._logged(f, log, rhs if not (sliding or rolled or deadline) else None,
                                   m, z)
        return f

    @staticmethod
    def _logged(f: Callable, log: Evaluations, rhs: Callable | None, m, z) -> Callable:
        """f, keeping every evaluation in `log` (a chunk's own odeint call uses it);
        given `rhs`, the compiled derivatives straight (f for a fault only)."""
        log_t, log_y, logged = log.t.append, log.y.append, log.t
        if rhs is None:
            def slow(t, y):
                log_t(t)
                log_y(y.copy())
                if len(logged) > log.limit:
                    log.compact()
                return f(t, y)
            return slow

        def fast(t, y):
            yl = y.tolist()
            log_t(t)
            log_y(yl)
            if len(logged) > log.limit:
                log.compact()
            try:
                return rhs(t, yl, m, z)
            except (ArithmeticError, ValueError):
                return f(t, y)
        return fast

    def _start_segment(self, cur: Cursor, seg_end: float, rec: Recorder | None,
                       dense: bool = False, t_end: float | None = None
                       ) -> tuple[Stepper, Callable]:
        """The segment's stepper. `dense`: an observer wants every step's dense
        output, which AUTO's LSODA class gives as it steps (odeint's chunks would
        integrate every interval again for it)."""
        plan = self.plan
        chunked = plan.chunked and SLIDE not in cur.m and not dense
        # AUTO's chunks watch every step LSODA takes through the evaluations it makes
        # (and sample them for RANGE): a log when there is something to watch or find
        log = Evaluations(max(4096, LOG_BUDGET // max(len(cur.y), 1))) \
            if chunked and len(cur.y) and \
            (plan.watch_idx or (rec is not None and rec.extrema.names)) else None
        f = self.vector_field(cur, log)
        if len(cur.y):
            # a derivative that is not finite where a segment starts can never give
            # an accepted step: say so instead of shrinking the step forever
            f0 = np.asarray(f(cur.t, cur.y), dtype=float)
            bad = first_bad(f0)
            if bad is not None:
                raise self.fault_or(Stop(Failure.DERIVATIVE_NOT_FINITE, cur.t,
                                          name=self.c.state_names[bad], value=f0[bad]))
        checks = None
        # while a surface slides, step by step (LSODA's class): its exit is seen at
        # the step it happens, with no chunk integrated past it
        if chunked:
            # the AUTO route steps from output instant to output instant
            times = self.check_times
            lo = bisect_right(times, cur.t, rec.out_i if rec else 0)
            checks = times[lo:bisect_left(times, seg_end, lo)]
            if self.c.memory_trains:
                # (the instants it pauses at, known now: inserted later, each would cost
                # an integration of its own)
                checks = np.union1d(checks, train_instants(self.c.memory_trains, cur.t,
                                                           seg_end))
        # with nothing to watch nothing is thrown away after a chunk: long chunks (a
        # FINISH would throw away the rest of the run), unless it may pause and start
        # afresh (the caller's code, a memory the integrator sees); never the whole
        # segment in one call, whose output and counts would take 200 bytes a row of
        # a long run; nor under a time limit, until the chunks' time is known
        pausing = t_end is not None and seg_end > t_end
        chunk = 16 if plan.watch_idx or pausing or self.opts.max_time else 4096
        stepper = make_stepper(
            plan.route.name, f, cur.t, cur.y, seg_end, rtol=plan.tol.rtol, atol=plan.tol.atol,
            delt=plan.timer["DELT"], max_step=plan.max_step, first_step=self._last_step,
            checks=checks, chunk=chunk, max_steps=self.opts.max_steps - self.nsteps,
            expect=expected_event(self._recent, cur.t), jac=self._jacobian(cur, f),
            kernel=self._kernel_arguments(cur, dense, rec), log=log,
            watch=(self._wrong_at(cur), cur.m, cur.z) if plan.watch_idx else None,
            # (a chunk the time limit ends inside is lost: none may take long)
            chunk_seconds=CHUNK_SHARE * self.opts.max_time if self.opts.max_time else None)
        return stepper, f

    def _wrong_at(self, cur: Cursor) -> Callable[..., tuple[int, int]]:
        """`wrong_at(T, Y, only=None) -> (first, loud)`: the index of the first of the
        instants T (states Y, as rows) at which a watched surface (of `only`, if given)
        is on the wrong side of the branches in force, and of the first at which one
        that matters is (len(T) if none). One matters unless its branch is silent
        (where it is first and last on the wrong side there): the loop follows its sign
        without a restart, and an output instant shows where it stays crossed."""
        c, plan, watch, m, z = self.c, self.plan, self.watch, cur.m, cur.z

        def wrong_at(T: np.ndarray, Y: np.ndarray, only=None) -> tuple[int, int]:
            if not len(T):
                return 0, 0
            with np.errstate(all="ignore"):
                E = [column(v, len(T)) for v in c.surf_v(T, list(Y.T), m, z)]
            found = crossings(plan, E, m)
            if only is not None:
                found = {k: mask for k, mask in found.items() if k in only}
            if not found:
                return len(T), len(T)
            # (the surfaces in the order they cross: the first loud one is the answer,
            # and a crossing is mostly an event, so one look at silence is enough)
            first = sorted((int(np.argmax(mask)), k) for k, mask in found.items())
            for i, k in first:
                last = int(len(T) - 1 - np.argmax(found[k][::-1]))
                if not (watch.silent(k, float(T[i]), Y[i], m, z) and
                        watch.silent(k, float(T[last]), Y[last], m, z)):
                    return first[0][0], i
            return first[0][0], len(T)
        return wrong_at

    def _kernel_arguments(self, cur: Cursor, dense: bool, rec: Recorder | None = None
                          ) -> dict | None:
        """METHOD COMPILED: what its stepper needs (None: run on SciPy's DOP853, while
        a surface slides, for an observer that wants every step, or when the model
        has no compiled form -- said once)."""
        plan, c = self.plan, self.c
        if plan.route.stepper != "compiled" or SLIDE in cur.m or dense or not len(cur.y):
            return None
        if self._kernel is None:
            from ..compiled import kernel_for

            self._kernel = kernel_for(c)
            if not isinstance(self._kernel, str) and c.memory_every_step:
                self._kernel = "its memory (HSTRSS, BCKLSH, RST, DERIV, DELAY) is kept " \
                    "step by step in Python"
            if isinstance(self._kernel, str):
                self.warnings.append(f"METHOD {plan.method}: {self._kernel}; it ran as DOP853")
        if isinstance(self._kernel, str):
            return None
        plain = not (c.z0 or plan.resets or c.settle is not None or self._stop_at_event)
        arguments = kernel_arguments(self._kernel, c, plan, cur.m, cur.z, plain)
        arguments["sampling"] = rec is not None and bool(rec.extrema.names)
        return arguments

    def _jacobian(self, cur: Cursor, f) -> SegmentJacobian | None:
        """The segment's Jacobian from the model's equations, for the routes that use
        one (built the first time a stepper asks for it); none while surfaces slide."""
        route = self.plan.route
        if route.fixed or route.explicit or SLIDE in cur.m or not len(cur.y):
            return None
        c = self.c
        return SegmentJacobian(len(cur.y), lambda: jacobian_for(c), cur.m, cur.z, f)

    def _segment(self, cur: Cursor, stepper: Stepper, f, seg_end: float, t_end: float,
                 rec: Recorder | None, observer: Observer | None, stop_at_event: bool,
                 seg_start: float) -> None:
        """Step until the segment ends: its bound, a restart, or a stop; or until it
        pauses at t_end, when it goes on past it (see `integrate`)."""
        c, plan = self.c, self.plan
        e_prev = c.surf(cur.t, cur.y.tolist(), cur.m, cur.z) if plan.watch_idx else []
        self._grazing = self._grazing_bands(cur, e_prev, self._exited)
        self._exited = set()
        chunked = isinstance(stepper, Chunked)
        bulk = chunked and SLIDE not in cur.m and rec is not None
        compiled = isinstance(stepper, KernelStepper)
        while True:
            if bulk:
                e_prev = self._take_clean(stepper, cur, min(seg_end, t_end), rec, e_prev)
            elif compiled and not stepper.done:
                e_prev, seg_start = self._take_compiled(stepper, cur, rec, e_prev, seg_start)
            self._check_limits(cur.t, stepper)
            failure = stepper.step()
            if failure is not None:
                raise self._stop_for(failure, stepper)
            ta, step = stepper.t_old, self._accepted(stepper, cur, e_prev, seg_start)
            e_prev = step.e_b
            if rec is not None:
                if chunked:
                    rec.samples(*stepper.samples(step.tb), cur.m, cur.z)
                self._rows_inside(rec, stepper, f, ta, cur.y, step.tb, step.yb, cur,
                                  step.silent)
            self.sample_memory(stepper, cur, step.tb)
            if observer is not None:
                observer(ta, step.tb, stepper.interpolant(), list(cur.m), list(cur.z))
            tb, yb = step.tb, step.yb
            at_output = rec is not None and rec.out_i < len(plan.grid.times) and \
                plan.grid.times[rec.out_i] <= tb * (1 + 4e-16)
            at_boundary = tb >= seg_end
            if at_boundary and tb < t_end:
                # a breakpoint: the surfaces on TIME that reach zero here decide anew
                step.triggered |= {k for k, root in self.roots.items() if root == tb}
            restart = step.triggered or step.departed or (at_boundary and tb < t_end) or \
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
                self._paused = _Paused(stepper, f, seg_end, seg_start, cur, tb, yb,
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

    # ------------------------------------------------------------------- steps
    def _accepted(self, stepper: Stepper, cur: Cursor, e_prev, seg_start: float):
        """Checks of an accepted step, then the watch: crossings located, the step
        cut at the first."""
        ta, tb, yb = stepper.t_old, stepper.t, stepper.y
        self.last_good = (tb, yb, list(cur.m))
        self._note_stiff(stepper)
        if tb - ta < self.plan.h_floor:
            self._tiny += 1
            if self._tiny >= 100:
                big = int(np.argmax(np.abs(yb)))
                raise Stop(Failure.STEP_UNDERFLOW, tb, floor=self.plan.h_floor,
                           origin=self.plan.floor_origin, name=self.c.state_names[big],
                           value=yb[big])
        else:
            self._tiny = 0
        bad = first_bad(yb)
        if bad is not None:
            raise self.fault_or(Stop(Failure.NOT_FINITE, ta, name=self.c.state_names[bad],
                                      detail=""))
        self._passed(tb)
        return self._watch_step(stepper, cur, ta, tb, yb, e_prev, seg_start)

    def _note_stiff(self, stepper: Stepper) -> None:
        if stepper.stiff is not None and self.stiff_from is None:
            self.stiff_from = stepper.stiff.t
            self.warnings.append(
                f"stiff from TIME = {stepper.stiff.t:.6g}: the steps of METHOD "
                f"{self.plan.method} are limited by stability, not accuracy (h*|lambda| = "
                f"{stepper.stiff.h_lambda:.3g}): METHOD AUTO or STIFF needs far fewer steps")

    def _grazing_bands(self, cur: Cursor, e0, exited: set[int]) -> dict[int, float]:
        """The surfaces a segment starts on having just left a slide on them (a slide
        keeps its surface at zero to within the integration's error), and how far to
        their wrong side its first steps' errors may put them: a slide ends where the
        motion's rate off the surface is zero (a stuck mass breaking away as the
        spring force reaches the friction limit), so the surface moves off
        quadratically and the first steps' errors can show it a few tolerance units
        on the wrong side, which is no crossing."""
        plan = self.plan
        if not exited or not plan.route.uses_tolerances:
            return {}
        scale = plan.tol.atol + plan.tol.rtol * np.abs(cur.y)
        near = [k for k in exited if cur.m[k] != SLIDE and
                abs(e0[k]) <= 1e3 * float(np.max(scale, initial=0.0))]
        out = {}
        for k in near:
            g = plan.watched[k].gradient
            if g is None:
                g = self._surface_gradient(cur, e0, k)
            if g is not None:
                band = 10.0 * float(np.abs(g) @ scale)
                if abs(e0[k]) <= band:
                    out[k] = band
        return out

    def _surface_gradient(self, cur: Cursor, e0, k: int) -> np.ndarray | None:
        """d e_k/d y by differences (a surface not written linearly in the states: a
        variable defined as one), for a small model."""
        n = len(cur.y)
        if n > 64:
            return None
        g = np.empty(n)
        for i in range(n):
            d = 1e-7 * max(abs(cur.y[i]), 1.0)
            y = cur.y.copy()
            y[i] += d
            try:
                g[i] = (self.c.surf(cur.t, y.tolist(), cur.m, cur.z)[k] - e0[k]) / d
            except (ArithmeticError, ValueError):
                return None
        return g if np.isfinite(g).all() else None

    def _watch_step(self, stepper: Stepper, cur: Cursor, ta: float, tb: float,
                    yb: np.ndarray, e_prev, seg_start: float) -> _Step:
        c, watch, m, z = self.c, self.watch, cur.m, cur.z
        step = _Step(tb, yb, set(), set(), {}, False, e_prev)
        if not self.plan.watch_idx:
            return step
        e_b = c.surf(tb, yb.tolist(), m, z)
        hits, silent = [], []
        for k in self.plan.watch_idx:
            if m[k] != SLIDE and watch.crossed(k, m[k], e_b[k]):
                band = self._grazing.get(k)
                if band is not None and abs(e_b[k]) <= band:
                    continue  # a tangential departure's first steps: within their error
                # a branch that feeds nothing the states see now (a switch inside an
                # unused branch): follow its sign, no need to stop and restart
                if watch.silent(k, tb, yb, m, z):
                    silent.append(k)
                    continue
                hits.append(k)
                if watch.quiet(k, tb, yb, m, z):
                    step.quiet.add(k)  # cut for another surface that reads it: no event
            elif k in self._grazing and abs(e_b[k]) > self._grazing[k]:
                del self._grazing[k]  # (clear of the surface: any crossing counts)
        slide_exit = watch.slide_exits(m, tb, yb, z)
        if hits or slide_exit:
            # departed: no crossing to bracket, sign at tb
            roots, step.departed = locate_crossings(watch, stepper, hits, m, z, ta, tb,
                                                    seg_start, (e_prev, e_b))
            interp = stepper.interpolant()
            for k, side in slide_exit:
                roots[k] = watch.locate_slide_exit(k, side, m, z, interp, ta, tb)
            t_star = min(roots.values(), default=tb)
            # a crossing a few ulps before a breakpoint is at the breakpoint: both decide
            # there, exactly where the row of that instant shows them
            t_star = next((r for r in sorted(self.roots.values())
                           if t_star <= r <= min(tb, t_star * (1 + 1e-15) + 1e-300)), t_star)
            if t_star < tb:
                # the solver has moved past t_star: it must restart
                stepper.truncate(t_star)
                step.tb, step.yb, step.truncated = stepper.t, stepper.y, True
            e_b = c.surf(step.tb, step.yb.tolist(), m, z)
            close = 8 * _EPS * max(abs(step.tb), 1e-300)
            step.triggered = {k for k, tk in roots.items() if tk - t_star <= close}
            # leaving a sliding motion: the side it leaves to is known
            step.exits = {k: side for k, side in slide_exit if k in step.triggered}
        if silent and not step.truncated:
            lit = c.modes_literal(step.tb, step.yb.tolist(), m, z)
            step.silent = silent
            for k in silent:
                m[k] = lit[k]
            e_b = c.surf(step.tb, step.yb.tolist(), m, z)
        # a surface sitting at zero (mode 0) that has moved off it
        for k in self.plan.watch_idx:
            if m[k] == 0.0 and self.plan.watched[k].kind is SurfaceKind.SIGN and \
                    abs(e_b[k]) > 1e-12 * (1 + abs(e_prev[k])) and e_b[k] != 0:
                step.departed.add(k)
        step.e_b = e_b
        return step

    def _rows_inside(self, rec: Recorder, stepper: Stepper, f, ta: float, ya: np.ndarray,
                     tb: float, yb: np.ndarray, cur: Cursor, silent: list[int] = ()
                     ) -> None:
        """Rows at the grid instants inside (ta, tb); the one at tb waits for the
        new modes. A surface that crossed silently in the step (`silent`: its mode
        is already the one at tb) shows at each row the sign it has there."""
        times = self.plan.grid.times
        while rec.out_i < len(times) and times[rec.out_i] < tb * (1 - 4e-16):
            to = float(times[rec.out_i])
            yo = np.asarray(stepper.interpolant()(to), dtype=float)
            if not np.isfinite(yo).all():
                if first_bad(yb) is None:
                    # the dense output overflowed inside (DOP853's does near 1E300)
                    # while both ends are finite: a cubic through them
                    yo = Hermite(ta, ya, np.asarray(f(ta, ya), float), tb, yb,
                                 np.asarray(f(tb, yb), float))(to)
                bad = first_bad(yo)
                if bad is not None:
                    raise Stop(Failure.NOT_FINITE, ta, name=self.c.state_names[bad],
                               detail="")
            self.sample_memory(stepper, cur, to)
            m = cur.m
            if silent:
                lit = self.c.modes_literal(to, yo.tolist(), cur.m, cur.z)
                m = list(cur.m)
                for k in silent:
                    m[k] = lit[k]
            rec.grid_row(to, yo, m, cur.z)

    def sample_memory(self, stepper: Stepper, cur: Cursor, upto: float) -> None:
        """Memory that samples the trajectory (DELAY's store) gets every instant it asks
        for inside the last accepted step, before `upto`, at the state the dense
        output gives there: X at (g, y(g)), not a straight line between the step's
        ends. Called before each row inside the step (the row reads that past) and
        once the step is taken, before the memory update at its end."""
        c = self.c
        if c.next_sample is None:
            return
        g = c.next_sample(cur.z)
        if not g < upto:
            return
        dense = stepper.interpolant()
        while g < upto:
            y = np.asarray(dense(g), dtype=float)
            cur.z[:] = c.sample(g, y.tolist(), cur.m, cur.z)
            after = c.next_sample(cur.z)
            if not after > g:
                break
            g = after

    # ----------------------------------------------------------------- restarts
    def _restart(self, cur: Cursor, step: _Step, h: float, at_output: bool,
                 at_boundary: bool, rec: Recorder | None, stop_at_event: bool) -> bool:
        """New branches at step.tb, their events, memory and resets. True if the
        segment ends here (a restart, or the run stops); `h`: the step to try first
        after it."""
        c, watch, m, z = self.c, self.watch, cur.m, cur.z
        tb, yb = step.tb, step.yb
        new_m = watch.choose_modes(tb, yb, z, m, step.triggered, forced=step.exits)
        self._exited = set(step.exits)
        z_before = list(z)
        if c.z0:
            memory = c.mem(tb, yb.tolist(), m, new_m, z)
            new_m = watch.after_memory(tb, yb, new_m, z, memory)
            z[:] = memory
        for k in step.triggered:
            w = self.plan.watched[k]
            if (w.purpose is Purpose.TERMT and new_m[k] > 0) or \
                    (w.purpose is Purpose.FINISH and new_m[k] != m[k]) or \
                    (w.purpose is Purpose.SCHEDULE and w.fires(m[k], new_m[k])):
                self.stop_reason = k  # a SCHEDULE: the caller runs its DISCRETE, goes on
        n_events = len(self.events)
        self.record_changes(tb, yb, m, new_m, z, step.triggered, step.quiet)
        changed = new_m != m
        if rec is not None and changed:
            rec.sample(tb, yb, m, z_before)  # (RANGE reads both sides of a jump)
        m[:] = new_m
        y = watch.apply_resets(yb, m, tb, z)
        cur.t, cur.y = tb, y
        if rec is not None:
            rec.restarted(tb, y, m, z)
            if changed or not np.array_equal(y, yb):
                rec.sample(tb, y, m, z)
        if at_output:
            rec.grid_row(tb, y, m, z, shown=rec.shown_modes(tb, y, m, z))
        if self.stop_reason is not None:
            if rec is not None and rec.last_t != tb:
                rec.row(tb, y, m, z)
            return True
        if stop_at_event and len(self.events) > n_events:
            return True
        seen = any(z_before[k] != z[k] for k in c.seen_memory)  # (a draw, a new day)
        if changed or seen or at_boundary or step.truncated or not np.array_equal(y, yb):
            self._recent.append(tb)
            if len(self.events) > self.opts.max_events:
                raise Stop(Failure.EVENTS, tb, limit=self.opts.max_events)
            self._check_chatter()
            self._last_step = max(h, 1e-12 * max(abs(tb), 1.0))
            return True
        return False

    def record_changes(self, t: float, y: np.ndarray, m, new_m, z, at_zero: set[int],
                       quiet: set[int] = frozenset()) -> None:
        """An event for every watched surface whose branch changes at t (`quiet`:
        located, but changing no derivative: not an event)."""
        for k in range(len(self.plan.watched)):
            if new_m[k] == m[k] or k in quiet:
                continue
            if k not in at_zero and self.watch.silent(k, t, y, new_m, z):
                continue  # a branch nothing uses now: not an event
            if m[k] == 0.0 and k not in at_zero and self.watch.quiet(k, t, y, new_m, z):
                # leaving an exact zero (ABS(Y) from Y(0) = 0) that no derivative
                # feels: seen at whatever step end comes first, so not an event (the
                # event list would otherwise depend on the output grid)
                continue
            self._event(t, k, m[k], new_m[k])

    def _event(self, t: float, k: int, old: float, new: float) -> None:
        """Surface k's branch changes from old to new at t (a located crossing)."""
        w = self.plan.watched[k]
        last = next((e for e in reversed(self.events) if e.surface == w.surface), None)
        if last is not None and last.old == new and \
                abs(last.time - t) <= 1e-12 * max(abs(t), 1e-300):
            # switched and switched back at one instant (noise at a tangential
            # crossing): nothing happened
            self.events.remove(last)
            return
        self.events.append(Event(t, w.description, w.surface, old, new, w.event_kind(new),
                                 w.text))

    def _check_chatter(self) -> None:
        recent = self._recent
        if len(recent) < 200:
            return
        window = recent[-200:]
        span = window[-1] - window[0]
        if span <= 1e-9 * max(self.plan.fintim, abs(window[-1])):
            what = f"{self.events[-1].switch} chatters" if self.events else \
                "the run makes no progress"
            raise Stop(Failure.CHATTER, window[-1], what=what, span=span)
        del recent[:-200]

    # ------------------------------------------------------------- the AUTO path
    def _take_clean(self, stepper: Chunked, cur: Cursor, seg_end: float, rec: Recorder,
                    e_prev):
        """Record at once the pending odeint instants before the first one that needs
        a look (a surface crossed, a non-finite state, the segment's end), using the
        surface and output functions over NumPy columns. Returns the surfaces at the
        last instant taken (or e_prev)."""
        T, Y = stepper.pending()
        # the segment's end (a breakpoint, a pause) is the step-by-step path's
        n = int(np.searchsorted(T, seg_end, side="left"))
        if n == 0:
            return e_prev
        T, Y = T[:n], Y[:n]
        finite = np.isfinite(Y).all(axis=1)
        if not finite.all():
            n = int(np.argmin(finite))
        m, z = cur.m, cur.z
        if n and self.plan.watch_idx:
            wrong = stepper.first_wrong()  # the stepper's own look at the surfaces
            if wrong is None:
                wrong = self._wrong_at(cur)(T[:n], Y[:n])[0]
            n = min(n, wrong)
        if n == 0:
            return e_prev
        T, Y = T[:n], Y[:n]
        # the rows among them: the next grid instants (the others are the stepper's
        # own exact instants between rows, samples for RANGE)
        times = self.plan.grid.times
        rows = np.zeros(n, bool)
        ahead = times[rec.out_i:rec.out_i + n]
        at = np.searchsorted(T, ahead)
        hit = at < n
        hit[hit] = T[at[hit]] == ahead[hit]
        if not hit.all():
            # a grid instant not among them must come after them (else: one at a time)
            first_miss = int(np.argmin(hit))
            if first_miss < len(ahead) and ahead[first_miss] < T[-1]:
                return e_prev
        rows[at[hit]] = True
        k = int(np.count_nonzero(rows))
        samples = stepper.samples(float(T[-1]))
        if not rows.all():
            S = np.concatenate([samples[0], T[~rows]])
            order = np.argsort(S, kind="stable")
            SY = np.concatenate([samples[1].reshape(-1, Y.shape[1]), Y[~rows]])
            samples = (S[order], SY[order])
        e_last = self.c.surf(float(T[-1]), Y[-1].tolist(), m, z) \
            if self.plan.watch_idx else e_prev
        TR, YR = T[rows], Y[rows]
        if k:
            def over_rows() -> np.ndarray:
                with np.errstate(all="ignore"):
                    return output_table(self.c.out_v(TR, list(YR.T), m, z), k)

            rec.block(TR, YR, rows_table(over_rows, rec, TR, YR, [m] * k, z), m, z, samples)
        else:
            rec.samples(*samples, m, z)
        stepper.consume(n)
        self._passed(stepper.t)
        cur.t, cur.y = stepper.t, stepper.y
        interrupts.check()
        if self.deadline is not None and _clock.perf_counter() > self.deadline:
            raise Stop(Failure.TIME_LIMIT, cur.t, limit=self.opts.max_time)
        self._report(cur.t, stepper)
        return e_last

    # --------------------------------------------------------- the compiled path
    def _take_compiled(self, stepper: KernelStepper, cur: Cursor, rec: Recorder | None,
                       e_prev, seg_start: float):
        """Run the compiled kernel until it holds a step for this loop: record its rows
        (each in its own branches) and the crossings it located, with the
        same events, restarts and limits as `_restart`. Returns the surfaces where
        it stands and the last restart (the segment's start for `locate`)."""
        c, m, z = self.c, cur.m, cur.z
        times = self.plan.grid.times
        while not stepper.done:
            self._check_limits(cur.t, stepper)
            gi = rec.out_i if rec is not None else len(times)
            got = stepper.advance(m, z, times, gi)
            if rec is not None and len(got.T):
                # (each row's branches too: RANGE re-integrates from rows)
                table = rows_table(partial(self._compiled_outputs, got, z), rec, got.T,
                                   got.Y, got.M, z)
                rec.block(got.T, got.Y, table, got.M, z)
            if rec is not None and len(got.S):
                rec.samples_with_modes(got.S, got.SY, got.SM, z)
            ranged = rec is not None and bool(rec.extrema.names)
            for j in range(len(got.event_t)):
                k, t = int(got.event_k[j]), float(got.event_t[j])
                self._event(t, k, float(got.event_m[j, k]), float(got.event_new[j]))
                if ranged:  # (RANGE re-integrates from the restarts, reads both sides)
                    new_m = got.event_m[j].tolist()
                    new_m[k] = float(got.event_new[j])
                    rec.sample(t, got.event_y[j], got.event_m[j].tolist(), z)
                    rec.restarted(t, got.event_y[j].copy(), new_m, z)
                    rec.sample(t, got.event_y[j], new_m, z)
                if not self._recent or self._recent[-1] != t:
                    self._recent.append(t)  # one restart, however many cross at t
                seg_start = t
                if len(self.events) > self.opts.max_events:
                    raise Stop(Failure.EVENTS, t, limit=self.opts.max_events)
                self._check_chatter()
            m[:] = got.m.tolist()
            self._note_stiff(stepper)
            cur.t, cur.y = stepper.t, stepper.y
            self.last_good = (cur.t, cur.y, list(m))
            self._passed(cur.t)
            self._report(cur.t, stepper)
        if c.z0 and stepper.fallback is None:
            # the memory as the Python route keeps it after an accepted step (the
            # kernel reads it as it stands: see `advance`)
            z[:] = c.mem(cur.t, cur.y.tolist(), m, m, z)
        if self.plan.watch_idx:
            e_prev = c.surf(cur.t, cur.y.tolist(), m, z)
        return e_prev, seg_start

    def _compiled_outputs(self, got, z) -> np.ndarray:
        """The output table of a kernel call's rows: one evaluation over all of them,
        each row's branches as columns (the vector code selects per element), or
        row group by row group where that code needs one branch at a time."""
        c, n = self.c, len(got.T)
        cols = list(got.Y.T)
        try:
            with np.errstate(all="ignore"):
                return output_table(c.out_v(got.T, cols, list(got.M.T), z), n)
        except (ValueError, TypeError):
            pass
        table = np.empty((n, len(c.out_names)))
        modes, group = np.unique(got.M, axis=0, return_inverse=True)
        for j, m in enumerate(modes):
            rows = group.ravel() == j
            with np.errstate(all="ignore"):
                outs = c.out_v(got.T[rows], [col[rows] for col in cols], m.tolist(), z)
            table[rows] = output_table(outs, int(rows.sum()))
        return table

    # ------------------------------------------------------------------ failures
    def _passed(self, t: float) -> None:
        """Faults before an accepted TIME were at trial points the solver stepped
        around; those at or after it may still be the run's end."""
        self.faults[:] = [f for f in self.faults if f.t >= t]

    def fault_or(self, stop: Stop) -> Stop:
        """A non-finite value or a solver's failure that follows an arithmetic fault
        is that fault's doing: report the fault (the statement that failed), not the
        symptom in some state."""
        if not self.faults:
            return stop
        fault = self.faults[-1]
        return Stop(Failure.FAULT, fault.t, detail=fault_text(self.model, self.c, fault))

    def _stop_for(self, failure: StepFailure, stepper: Stepper) -> Stop:
        """The outcome of a step that failed."""
        name = self.c.state_names[failure.index] if failure.index is not None else None
        if failure.kind is Failure.UNSTABLE:
            return Stop(Failure.UNSTABLE, stepper.t, name=name, since=failure.since,
                        method=self.plan.method, delt=self.plan.timer["DELT"],
                        detail=failure.detail, safe=failure.safe_delt)
        if failure.kind is Failure.STEPS:
            return Stop(Failure.STEPS, failure.t, limit=self.opts.max_steps)
        if failure.kind is Failure.STEP_SPACING and name is not None:
            return self.fault_or(Stop(Failure.STEP_SPACING, stepper.t, name=name,
                                      value=float(stepper.y[failure.index])))
        if failure.kind is Failure.NOT_FINITE and name is not None:
            return self.fault_or(Stop(Failure.NOT_FINITE, stepper.t, name=name,
                                       detail=f": {failure.detail}"))
        return self.fault_or(Stop(Failure.SOLVER, stepper.t, detail=failure.detail))



def kernel_arguments(kernel, c: Compiled, plan: RunPlan, m, z, plain: bool,
                     follow: bool = True) -> dict:
    """The compiled stepper's arguments for a segment in branches m. `plain`: the
    kernel may locate a crossing and switch itself (nothing else happens there:
    no memory to sample, no state to reset, no stop); `follow`: it may follow a
    branch nothing uses (as `_watch_step`); else every crossing is the loop's."""
    watched = plan.watched
    handled = np.array([LOOP if watched[k].kind is not SurfaceKind.SIGN or
                        watched[k].purpose is not Purpose.SWITCH or not follow
                        else PLAIN if plain else QUIET for k in range(len(m))], dtype=np.int64)
    level = np.array([watched[k].kind is SurfaceKind.LEVEL for k in range(len(m))],
                     dtype=bool)
    return {"kernel": kernel, "m": m, "z": z, "p": kernel.parameter_values(c),
            "watch": np.array(plan.watch_idx, dtype=np.int64), "handled": handled,
            "level": level, "lookahead": plan.lookahead_h,
            "stability_limit": plan.route.stability_limit, "h_floor": plan.h_floor}


def rows_table(over_rows: Callable[[], np.ndarray], rec: Recorder, T: np.ndarray,
               Y: np.ndarray, M, z) -> np.ndarray:
    """The output table of rows, from the code over all rows at once (`over_rows`),
    or, where that meets a fault (a variable the derivatives do not read), one row
    at a time, the variables that fault NaN (`Recorder.output_rows`)."""
    try:
        return over_rows()
    except ArithmeticError:
        return rec.output_rows(T, Y, M, z)


def output_table(outs, n: int) -> np.ndarray:
    """The vector output functions' results over n rows as an (n, outputs) table."""
    return np.column_stack([column(v, n) for v in outs]) if outs else np.empty((n, 0))


def column(v, n: int) -> np.ndarray:
    """A vector function's result as n values (a constant comes back as a float)."""
    if isinstance(v, np.ndarray) and v.shape == (n,):
        return v
    return np.full(n, float(v))
