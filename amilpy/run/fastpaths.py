"""The routes' fast paths (`Integrator`'s part), chosen by what the segment's
stepper declares it can do (`Stepper.fast_path`), never by its class:

- "batch" (AUTO's odeint chunks): many accepted instants handed over at once,
  recorded with the surface and output functions over NumPy columns up to the
  first that needs a look;
- "ahead" (METHOD COMPILED): the compiled kernel steps, locates and switches on
  its own, and hands back its rows, samples and events.

Anything a fast path cannot take (a crossing, a breakpoint) is left to the
step-by-step path of `Integrator._segment`."""

from __future__ import annotations

import time as _clock
from collections.abc import Callable
from functools import partial

import numpy as np

from .. import interrupts
from ..codegen import ModelCode
from ..compiled.layout import LOOP, PLAIN, QUIET
from ..outcome import Failure
from ..steppers import Stepper
from .cursor import Cursor, Stop
from .plan import Purpose, RunPlan, SurfaceKind, sliding_in
from .record import Recorder, close_to, output_table


class FastPaths:
    """`Integrator`'s fast paths (a mixin)."""

    def _fast_path(self, stepper: Stepper, cur: Cursor, rec: Recorder | None):
        """The fast path the stepper declares, where it can be taken now: a bound
        `take(stepper, cur, seg_end, rec, e_prev, seg_start) -> (e_prev, seg_start)`,
        or None."""
        if stepper.fast_path == "batch" and not sliding_in(cur.m) and rec is not None:
            return self._take_batch
        if stepper.fast_path == "ahead":
            return self._take_ahead
        return None

    def _kernel_arguments(self, cur: Cursor, dense: bool, rec: Recorder | None = None
                          ) -> dict | None:
        """METHOD COMPILED: what its stepper needs (None: run on SciPy's DOP853, while
        a surface slides, for an observer that wants every step, or when the model
        has no compiled form -- said once)."""
        plan, c = self.plan, self.c
        if plan.route.stepper != "compiled" or sliding_in(cur.m) or dense or not len(cur.y):
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

    def _take_batch(self, stepper: Stepper, cur: Cursor, seg_end: float, rec: Recorder,
                    e_prev, seg_start: float):
        """Record at once the pending odeint instants before the first one that needs
        a look (a surface crossed, a non-finite state, the segment's end), using the
        surface and output functions over NumPy columns. Returns the surfaces at the
        last instant taken (or e_prev), and the segment's start."""
        return self._batch(stepper, cur, seg_end, rec, e_prev), seg_start

    def _batch(self, stepper: Stepper, cur: Cursor, seg_end: float, rec: Recorder, e_prev):
        T, Y = stepper.pending()
        # the segment's end (a breakpoint, a pause) is the step-by-step path's, and so
        # is a row the recorder holds for its caller (an ACSL instant a float from a
        # grid instant: the row is taken there, after the instant's code)
        n = int(np.searchsorted(T, seg_end, side="left"))
        if rec.hold is not None:
            held = np.flatnonzero(close_to(T[:n], rec.hold))
            n = int(held[0]) if held.size else n
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
            if wrong < n and self.scheduling:
                # (the instant before a crossing may be the crossing's own, to rounding,
                # where code runs before the row: the step-by-step path takes that row)
                wrong = max(wrong - 1, 0)
            n = min(n, wrong)
        if n == 0:
            return e_prev
        T, Y = T[:n], Y[:n]
        # the rows among them: the next grid instants (the others are the stepper's
        # own exact instants between rows, samples for RANGE)
        times = self.plan.grid.times
        rows = np.zeros(n, bool)
        ahead = np.asarray(times[rec.out_i:rec.out_i + n])
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

    def _take_ahead(self, stepper: Stepper, cur: Cursor, _seg_end: float,
                    rec: Recorder | None, e_prev, seg_start: float):
        """Run the compiled kernel until it holds a step for this loop: record its rows
        (each in its own branches) and the crossings it located, with the
        same events, restarts and limits as `_restart`. Returns the surfaces where
        it stands and the last restart (the segment's start for `locate`)."""
        if stepper.done:  # (the step-by-step path's now: a fallback, the segment's end)
            return e_prev, seg_start
        c, m, z = self.c, cur.m, cur.z
        times = self.plan.grid.times
        while not stepper.done:
            self._check_limits(cur.t, stepper)
            gi = rec.out_i if rec is not None else len(times)
            got = stepper.advance(m, z, times, gi)
            if rec is not None:  # (the step ends and events come after the rows)
                rec.extrema.held = True
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
            if rec is not None:
                rec.extrema.settle()
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


def kernel_arguments(kernel, c: ModelCode, plan: RunPlan, m, z, plain: bool,
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
