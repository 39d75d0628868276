"""One run of a checked model driven from its start to its `Run`.

`simulate` prepares the run (constants, generated functions, plan), starts it
(`start`: the branches in force at t0, MODINT resets, memory, the first row),
integrates it to FINISH, TERMT or a failure, locates the RANGE extrema
(`locate_range`), evaluates TERMINAL in written order, and assembles the `Run`.
A failing integration is a `Run` with status FAILED and every row computed; a
fault in the data is an AmilError.
"""

from __future__ import annotations

import heapq
import time as _clock
from itertools import count

import numpy as np

from .. import interrupts, ir
from ..codegen import ModelCode, evaluate_constant
from ..codegen.faults import fault_point
from ..diagnostics import AmilError
from ..library.runtime import table_warnings
from ..outcome import Failure, message
from ..result import Event, EventKind, Run, Status
from .code import Calls, code_fault, run_terminal
from .faults import Fault, fault_text
from .loop import Cursor, Integrator, Stop
from .peaks import Context, locate_range
from .plan import Options, Purpose, RunPlan, SurfaceKind, same_instant, slides, within
from .prepare import Prepared
from .record import Recorder
from .slide import MAX_SLIDING
from .steppoint import StepPoint
from .watch import SurfaceWatch, TooManySlides, literal_modes
from .zeno import accumulation, cut


def backstop(max_time: float | None) -> float | None:
    """When a run's wall-clock limit interrupts code that never looks at the clock:
    a little after the run loop's own look would have ended it."""
    return None if not max_time else max_time + max(1.0, 0.1 * max_time)


def start_cursor(c: ModelCode, plan: RunPlan, watch: SurfaceWatch, opts: Options,
                 y: np.ndarray, z: list[float], m: list[float] | None,
                 t0: float | None = None) -> Cursor:
    """The state a run (or a flow) starts from at t0 (default the run's): the
    branches in force (given, or chosen the way the dynamics go), MODINT resets
    and memory applied."""
    t0 = plan.t0 if t0 is None else t0
    if m is None or len(m) != len(plan.watched):
        m = watch.choose_modes(t0, y, z, [0.0] * len(plan.watched), set(), first=True)
    y = watch.apply_resets(y, m, t0, z)
    if c.z0:
        memory = c.mem(t0, y.tolist(), m, m, z)
        m = watch.after_memory(t0, y, list(m), z, memory)
        z = memory
    return Cursor(t0, y, list(m), list(z))


class _Run:
    def __init__(self, model: ir.Model, spec: ir.RunSpec, opts: Options, prepared: Prepared,
                 started: float) -> None:
        self.model, self.spec, self.opts = model, spec, opts
        self.constants, self.c, self.plan = prepared.constants, prepared.code, prepared.plan
        self.watch = SurfaceWatch(self.c, self.plan)
        ranged = [n for r in spec.reports if r.kind == "RANGE" for n in r.names]
        self.rec = Recorder(self.plan, self.c, self.watch, ranged + list(opts.extrema),
                            self.plan.t0 + opts.settle if opts.settle > 0 else None,
                            opts.row_sink)
        if opts.row_sink is not None:
            opts.row_sink.begin(self.c.out_names, self.constants, spec.reports,
                                len(self.plan.grid.times), opts.extra_times)
        # step-point mode runs the classic loop (steppoint.py) instead of the located one
        self.integ = (StepPoint if self.plan.step_point else Integrator)(
            model, self.plan, self.c, self.watch, opts, started)
        if self.plan.step_point:  # (a crossing's code runs at the point it is seen)
            self.integ.crossed = self.crossed
        self.started = started
        # FST's EVENTs by the surface of their ZEROCONDITION (two may share one), and
        # the time events' next instants: (TIME, order, event)
        self.events_on: dict[int, list[int]] = {}
        self.timed: list[tuple[float, int, int]] = []
        for k, e in enumerate(model.events):
            if e.surface is not None:
                self.events_on.setdefault(e.surface, []).append(k)
            else:
                at = evaluate_constant(model, e.first, self.constants, spec.tables, e.span)
                heapq.heappush(self.timed, (at, k, k))
        self.order = count(len(model.events))
        if self.plan.step_point and self.timed:  # (at the first step point at or after)
            self.integ.due = self.time_events

    def run(self) -> Run:
        """The run, within its wall-clock limit even where no loop looks at the clock
        (`backstop`): what was computed is kept."""
        try:
            with interrupts.time_limit(backstop(self.opts.max_time)):
                return self._run()
        except interrupts.TimeLimit:  # (before the integration: INITIAL, the start)
            interrupts.silence_alarm()
            t0 = self.plan.t0
            cur = Cursor(t0, np.array(self.c.y0, dtype=float), [0.0] * len(self.plan.watched),
                         list(self.c.z0))
            self.integ.events.clear()
            return self.finish(Status.FAILED, message(Failure.TIME_LIMIT, t=t0,
                                                      limit=self.opts.max_time), cur, {})

    def _run(self) -> Run:
        c, plan, integ, start = self.c, self.plan, self.integ, self.opts.start
        y = np.array(start["y"] if start else c.y0, dtype=float)
        z = list(start["z"]) if start else list(c.z0)
        m = [0.0] * len(plan.watched)
        cur = Cursor(plan.t0, y, m, z)
        table_warnings(c.tables)  # LINT's notes start afresh
        if not plan.step_point:  # (in step-point mode t0 is the loop's first point)
            try:
                cur = self._start(y, z)
            except (ArithmeticError, ValueError) as exc:
                # a fault in the switching surfaces at the start (QNTZR with P = 0, say)
                text = fault_text(self.model, c, Fault(exc, cur.t, y.tolist(), m, z))
                integ.events.clear()
                return self.finish(Status.FAILED, message(Failure.CANNOT_START, t=plan.t0,
                                                          detail=text), cur, {})
            except TooManySlides as exc:  # (seven masses stuck by dry friction at rest)
                integ.events.clear()
                return self.finish(Status.FAILED, message(Failure.SLIDES, t=plan.t0,
                                                          count=exc.count, limit=MAX_SLIDING),
                                   cur, {})
        return self._integrate(cur)

    def _start(self, y: np.ndarray, z: list[float]) -> Cursor:
        """The branches in force at t0, and the first row."""
        c, plan, integ, start = self.c, self.plan, self.integ, self.opts.start
        cur = start_cursor(c, plan, self.watch, self.opts, y, z, start and start.get("m"))
        for k, w in enumerate(plan.watched):
            if slides(cur.m[k]):  # sliding from the start is an event too
                integ.events.append(w.event(plan.t0, 0.0, cur.m[k],
                                                  EventKind.SLIDE))
        self.first_row(cur)
        return cur

    def _integrate(self, cur: Cursor) -> Run:
        c, plan, rec, integ = self.c, self.plan, self.rec, self.integ
        try:
            status, text = Status.FINISHED, ""
            # (an overflow inside a solver's step is what the loop finds as a state or
            # derivative that is not finite, and says so, with TIME and the variable:
            # NumPy's warning about it, with a SciPy source line, is noise)
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                stopped = self.advance(cur)
            if stopped is not None:
                status, text = Status.STOPPED, message(Status.STOPPED, t=cur.t, what=stopped)
        except Stop as stop:
            status, text = Status.FAILED, message(stop.kind, t=stop.t, **stop.fields)
            cur.t = stop.t
            self._keep_last_good(cur)
        except (interrupts.TimeLimit, KeyboardInterrupt) as ended:
            # Ctrl-C, or the wall-clock limit where the loop never came back to look at
            # its deadline (a PROCEDURAL loop, one long step: `run`). The rows of the
            # step under way may reach past where it began: the run was computed to
            # the last of them.
            if isinstance(ended, KeyboardInterrupt):
                interrupts.handled()
                failure = Failure.INTERRUPTED
            else:
                interrupts.silence_alarm()
                failure = Failure.TIME_LIMIT
            cur.t = max(cur.t, rec.last_t if rec.last_t is not None else cur.t)
            return self.finish(Status.FAILED, message(failure, t=cur.t,
                                                      limit=self.opts.max_time), cur, {})
        except TooManySlides as exc:
            status, text = Status.FAILED, message(Failure.SLIDES, t=cur.t, count=exc.count,
                                                  limit=MAX_SLIDING)
        except (ArithmeticError, ValueError) as exc:
            # arithmetic in generated code (surfaces, outputs), or SciPy refusing the
            # non-finite values an earlier fault gave: the run ends here, with what it
            # computed so far, and the fault that really happened
            status = Status.FAILED
            # (at the point the generated code was evaluated at, where it says: a
            # surface inside a step is past the cursor)
            t, y, m, z = fault_point(exc) or (cur.t, cur.y.tolist(), cur.m, cur.z)
            stop = Stop(Failure.FAULT, t, detail=fault_text(self.model, c,
                                                            Fault(exc, t, y, m, z)))
            if c.fault_line(exc) is None:
                stop = integ.fault_or(stop)
            text = message(stop.kind, t=stop.t, **stop.fields)
            self._keep_last_good(cur)
        if status == Status.FINISHED and rec.out_i < len(plan.grid.times):
            rec.row(plan.fintim, cur.y, cur.m, cur.z, len(plan.grid.times) - 1)
        integ.warnings.extend(table_warnings(c.tables))
        if rec.output_fault is not None:
            integ.warnings.append(f"{rec.output_fault}; it is NaN in the rows where it "
                                  "cannot be computed, and so is what is computed from it")
        if plan.step_point:
            run = self.finish(status, text, cur, integ.range_values())
        else:
            ctx = Context(self.model, plan, c, self.watch, self.opts, self.started)
            run = self.finish(status, text, cur, locate_range(ctx, rec.extrema, rec.restarts))
        return self._zeno(run)

    @staticmethod
    def _zeno(run: Run) -> Run:
        """A run that went past an accumulation of events ends there (`zeno`)."""
        if run.status == Status.FAILED:
            return run
        found = accumulation(run.events, run.t_end)
        if found is not None:
            cut(run, found.t)
            run.status = Status.FAILED
            run.message = message(Failure.ZENO, t=found.t, what=found.what,
                                  ratio=found.ratio)
        return run

    def first_row(self, cur: Cursor) -> None:
        """The row at t0 (the ACSL form runs the events due at t0 first)."""
        self.rec.grid_row(cur.t, cur.y, cur.m, cur.z,
                          shown=self.rec.shown_modes(cur.t, cur.y, cur.m, cur.z))

    def advance(self, cur: Cursor) -> str | None:
        """Integrate to the end; what stopped the run early (FINISH, TERMT), if any. A
        located EVENT crossing ends the integration there: its NEWVALUEs run, and the
        run goes on from the new values (the row of that instant after them)."""
        plan, integ, rec = self.plan, self.integ, self.rec
        if not plan.step_point:
            # a TERMT that holds where the run starts (a routine's STOP on a PARAM's
            # value checked, `IF (SLA .LE. 0.) STOP`) stops it there, as in step-point
            # mode: the condition halts the run wherever it holds
            # (from the surface's value: one exactly at zero that the motion leaves has
            # the mode of the side it goes to, and T >= TSTOP holds at zero)
            termts = integ.terminating
            e = self.c.surf(cur.t, cur.y.tolist(), cur.m, cur.z) if termts else ()
            held = next((k for k in termts if plan.watched[k].stops(0.0, cur.m[k]) or
                         (e[k] == 0.0 and plan.watched[k].closed)), None)
            if held is not None:
                w = plan.watched[held]
                integ.events.append(w.event(cur.t, 0.0, cur.m[held], EventKind.TERMT))
                integ.stop_reason = held
                return w.description
        while True:
            # (a time event's instant: the loop pauses there, its row held for after it)
            timed = not plan.step_point and bool(self.timed) and self.timed[0][0] < plan.fintim
            t_end = self.timed[0][0] if timed else plan.fintim
            if timed and t_end - cur.t <= within(cur.t):
                cur.t = max(cur.t, t_end)  # (an instant a few floats on: nothing to step)
            else:
                rec.hold = t_end if timed else None
                integ.integrate(cur, t_end, rec, pause=timed)
                rec.hold = None
            reason, fired = integ.stop_reason, integ.fired
            stops = reason is not None and plan.watched[reason].purpose is not Purpose.SCHEDULE
            if not fired and stops:
                return plan.watched[reason].description
            integ.stop_reason, integ.fired = None, []
            reached = None
            if fired:
                reached = self.crossed(cur, fired)
            elif timed and cur.t >= t_end:
                self.time_events(cur.t, cur)
                reached, _ = self.restart(cur)
            elif cur.t >= plan.fintim:
                ahead = self.crossing_at_end(cur)
                if not ahead:
                    return None
                reached = self.crossed(cur, ahead)
            on_grid = rec.out_i < len(plan.grid.times) and \
                same_instant(cur.t, plan.grid.times[rec.out_i])
            if on_grid:
                rec.grid_row(cur.t, cur.y, cur.m, cur.z,
                             shown=rec.shown_modes(cur.t, cur.y, cur.m, cur.z))
            else:  # (the instant's row taken a float before the crossing: after it)
                rec.retake(cur.t, cur.y, cur.m, cur.z)
            if stops or reached is not None:
                # (a FINISH or TERMT at the instant, or one the new values reach: the
                # run stops there, its last row the values after the code)
                k = reason if stops else reached
                if not on_grid:
                    rec.row(cur.t, cur.y, cur.m, cur.z)
                integ.stop_reason = k
                return plan.watched[k].description
            if cur.t >= plan.fintim:
                return None

    def crossing_at_end(self, cur: Cursor) -> list[int]:
        """The crossings that run code which the motion takes across zero at FINTIM,
        to rounding (X = TIME reaching FINTIM a float after it): they are FINTIM's,
        as in step-point mode, where the last point's events run before its row."""
        ks = self.integ.scheduling
        if not ks or self.plan.step_point:
            return []
        _, near = self.near_zero(cur, ks)
        if not near:
            return []
        new = self.watch.choose_modes(cur.t, cur.y, cur.z, cur.m, near)
        return [k for k in sorted(near) if self.plan.watched[k].fires(cur.m[k], new[k])]

    def time_events(self, t: float, cur: Cursor) -> None:
        """The time events due at t (at or before it, to rounding), in the order of
        their instants; each gives its next instant (NEXTTIME), which must be later."""
        while self.timed and self.timed[0][0] <= t + within(t):
            _, _, k = heapq.heappop(self.timed)
            cur.t = t
            after = self.run_event(cur, k)
            if after is not None:
                if not after > t:
                    raise Stop(Failure.FAULT, t, detail=(
                        f"EVENT at line {self.model.events[k].span.line}: NEXTTIME = "
                        f"{after:.9g} is not after TIME = {t:.9g}: the event would run "
                        "again at once, for ever"))
                heapq.heappush(self.timed, (after, next(self.order), k))

    def crossed(self, cur: Cursor, ks: list[int]) -> int | None:
        """The code the crossings of watched surfaces `ks` run, at cur.t, in the order
        the listing writes it; then the branches in force after it, and the code of
        crossings the motion takes here too (each runs once at an instant). The FINISH
        or TERMT the new values reach, if any."""
        done: set[int] = set()
        reached = None
        while ks:
            before = None if self.plan.step_point or not self.plan.watch_idx else \
                self.c.surf(cur.t, cur.y.tolist(), cur.m, cur.z)
            for k in sorted(ks, key=lambda k: self.plan.watched[k].surface):
                self.run_crossing(cur, self.plan.watched[k].surface)
            done.update(ks)
            reached, more = self.restart(cur, before)
            ks = [k for k in more if k not in done]
        return reached

    def run_crossing(self, cur: Cursor, surface: int) -> None:
        """The EVENTs whose ZEROCONDITION is `surface`, in written order."""
        for k in self.events_on.get(surface, ()):
            self.run_event(cur, k)

    def run_event(self, cur: Cursor, k: int) -> float | None:
        """EVENT k's code at cur.t: its new values given; its NEXTTIME, if it has one."""
        event = self.model.events[k]
        try:
            y, z, values = self.c.code[f"event_{k}"][1](cur.t, cur.y.tolist(), cur.m,
                                                        cur.z, Calls())
        except (ArithmeticError, ValueError) as exc:
            raise Stop(Failure.FAULT, cur.t, detail=f"EVENT at line {event.span.line}: "
                       f"{code_fault(exc)}") from None
        cur.y = np.asarray(y, dtype=float)
        cur.z[:] = z
        given = [n for n in event.code.assigned if "#" not in n]
        self.integ.events.append(Event(
            cur.t, f"EVENT at line {event.span.line} (NEWVALUE {', '.join(given)})", -1,
            0.0, 0.0, EventKind.DISCRETE))
        if len(self.integ.events) > self.opts.max_events:
            raise Stop(Failure.EVENTS, cur.t, limit=self.opts.max_events)
        if event.next is None:
            return None
        return float(values[event.code.assigned.index(event.next)])

    def restart(self, cur: Cursor, before: list[float] | None = None,
                fired: frozenset[int] | set[int] = frozenset()
                ) -> tuple[int | None, list[int]]:
        """The branches in force after code changed states or kept names. A surface
        at zero to rounding (a crossing just located) goes the way the motion takes
        it, not by the sign of its rounding error. Returns the FINISH or TERMT the new
        values reach, if any, and the crossings that run code which the motion takes
        across here too, their values the same as `before` the code (X - 1.5 a float
        short of zero where TIME - 1.5 is a breakpoint); one the code itself moved
        (1 - FLAG back to 1) is no event: its crossing was; nor is one in `fired`,
        whose crossing ran its code at this instant: the motion leaves its zero."""
        c, plan = self.c, self.plan
        if plan.step_point:  # the branches as they read here, nothing located
            new = literal_modes(c, plan, cur.t, cur.y.tolist(), cur.m, cur.z)
            after = None
        else:
            after, near = self.near_zero(cur, plan.watch_idx)
            new = self.watch.choose_modes(cur.t, cur.y, cur.z, cur.m, near)
        more = [k for k in self.integ.scheduling if before is not None and after is not None
                and k not in fired and after[k] == before[k]
                and plan.watched[k].fires(cur.m[k], new[k])]
        self.integ.record_changes(cur.t, cur.y, cur.m, new, cur.z, set(),
                                  set(self.integ.scheduling) - set(more))
        reached = self.reached(cur.m, new)
        cur.m[:] = new
        if not plan.step_point:
            cur.y = self.watch.apply_resets(cur.y, cur.m)
        return reached, more

    def near_zero(self, cur: Cursor, ks) -> tuple[list[float] | None, set[int]]:
        """The surfaces at cur, and which of the sign surfaces `ks` stand on zero to
        rounding there (a crossing just located, or a float away)."""
        if not ks:
            return None, set()
        e = self.c.surf(cur.t, cur.y.tolist(), cur.m, cur.z)
        scale = 1e-12 * max(1.0, float(np.max(np.abs(cur.y))) if len(cur.y) else 1.0)
        return e, {k for k in ks if abs(e[k]) <= scale
                   and self.plan.watched[k].kind is SurfaceKind.SIGN}

    def reached(self, old: list[float], new: list[float]) -> int | None:
        """The FINISH or TERMT surface that new values given at an instant reach (FINISH
        K = 2.5, K a SET variable an EVENT counts up), if any."""
        return next((k for k, w in enumerate(self.plan.watched)
                     if old[k] != new[k] and w.stops(old[k], new[k])), None)

    def terminal(self, run: Run, cur: Cursor) -> dict[str, float]:
        """TERMINAL's values, in written order."""
        codes = self.model.terminal_code or (self.model.acsl.terminal if self.model.acsl
                                             else [])
        if codes:
            return run_terminal(self.c, codes, cur)
        return evaluate_terminal(self.model, self.spec, self.constants, run.final, cur.t)

    def _keep_last_good(self, cur: Cursor) -> None:
        """The last accepted state is the final row (everything computed)."""
        last = self.integ.last_good
        if last is not None and (self.rec.last_t is None or last[0] > self.rec.last_t) \
                and np.all(np.isfinite(last[1])):
            self.rec.row(last[0], np.asarray(last[1], float), last[2], cur.z)
            cur.t, cur.y = last[0], np.asarray(last[1], float)

    def finish(self, status: Status, text: str, cur: Cursor, extrema: dict) -> Run:
        integ = self.integ
        terminal: dict[str, float] = {}
        notes = [f"line {d.span.line}: {d.message}" if d.span else d.message
                 for d in self.model.warnings]
        run = self.rec.run(
            self.spec, self.constants, integ.events, status, text, notes + integ.warnings,
            dict(nsteps=integ.nsteps, nfev=integ.nfev, nevents=len(integ.events),
                 seconds=_clock.perf_counter() - self.started,
                 stiff_from=getattr(integ, "stiff_from", None)),
            cur.t, cur.y, cur.z, cur.m, terminal, extrema)
        if status != Status.FAILED and (self.model.terminal or self.model.terminal_code
                                        or (self.model.acsl and self.model.acsl.terminal)):
            try:
                terminal.update(self.terminal(run, cur))
            except AmilError as err:
                d = err.diagnostics[0]
                where = f" (line {d.span.line})" if d.span else ""
                run.status = Status.FAILED
                run.message = message(Failure.TERMINAL, t=cur.t, detail=d.message + where)
            run.terminal = dict(terminal)
            run.final.update(terminal)
        return run


def evaluate_terminal(model: ir.Model, spec: ir.RunSpec, constants: dict[str, float],
                      final: dict[str, float], t_end: float) -> dict[str, float]:
    """TERMINAL, once, in written order: each statement sees the run's constants,
    the final values of the states and DYNAMIC variables, TIME at the end, and the
    TERMINAL values before it."""
    values = {**constants, **final, "TIME": t_end}
    out: dict[str, float] = {}
    for eq in model.terminal:
        out[eq.target] = values[eq.target] = evaluate_constant(model, eq.expr, values,
                                                               spec.tables, eq.span)
    return out
