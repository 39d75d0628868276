"""Restarts and outcomes (`Integrator`'s part): new branches where a crossing was
located, their events, memory and resets, chatter; and what a failed step or an
arithmetic fault makes of the run's end."""

from __future__ import annotations

import numpy as np

from ..outcome import Failure
from ..steppers import StepFailure, Stepper
from .cursor import Cursor, Stop, WatchedStep
from .faults import fault_text
from .plan import Purpose, same_instant
from .record import Recorder


class Restarts:
    """`Integrator`'s restarts and stops (a mixin)."""

    def _restart(self, cur: Cursor, step: WatchedStep, h: float, at_output: bool,
                 at_boundary: bool, rec: Recorder | None, stop_at_event: bool) -> bool:
        """New branches at step.tb, their events, memory and resets. True if the
        segment ends here (a restart, or the run stops); `h`: the step to try first
        after it."""
        c, watch, m, z = self.c, self.watch, cur.m, cur.z
        tb, yb = step.tb, step.yb
        new_m = watch.choose_modes(tb, yb, z, m, step.triggered, forced=step.exits)
        self._exited = set(step.exits)
        z_before = list(z)
        crossed = new_m  # (the branches taken here before any the motion takes back)
        if c.z0:
            memory = c.mem(tb, yb.tolist(), m, new_m, z)
            new_m = watch.after_memory(tb, yb, new_m, z, memory)
            z[:] = memory
            back = watch.returning(tb, yb, new_m, z, step.triggered)
            if back:
                crossed, new_m = new_m, list(new_m)
                for k in back:
                    new_m[k] = -new_m[k]
                z[:] = c.mem(tb, yb.tolist(), crossed, new_m, z)
        stop = None
        # (a TERMT that turns true at a restart another surface made, one over a value
        # a branch selects -- a routine's STOP flag set in an IF -- stops the run here)
        turned = [k for k in self.terminating
                  if k not in step.triggered and new_m[k] > 0 >= m[k]]
        for k in (*step.triggered, *self._jumped(tb, yb, m, new_m, z, step.triggered),
                  *turned):
            w = self.plan.watched[k]
            if (w.purpose is Purpose.TERMT and new_m[k] > 0) or \
                    (w.purpose is Purpose.FINISH and new_m[k] != m[k]):
                stop = k if stop is None else stop
            elif w.purpose is Purpose.SCHEDULE and w.fires(m[k], new_m[k]):
                self.fired.append(k)  # (the caller runs their code, then goes on or stops)
        if stop is not None or self.fired:
            self.stop_reason = stop if stop is not None else self.fired[0]
        n_events = len(self.events)
        if crossed is not new_m:  # (there and back: both crossings are events)
            self.record_changes(tb, yb, m, crossed, z, step.triggered, step.quiet)
            self.record_changes(tb, yb, crossed, new_m, z, step.triggered, step.quiet,
                                returned=True)
        else:
            self.record_changes(tb, yb, m, new_m, z, step.triggered, step.quiet)
        changed = new_m != m
        if rec is not None and changed:
            rec.sample(tb, yb, m, z_before)  # (RANGE reads both sides of a jump)
        m[:] = new_m
        y = watch.apply_resets(yb, m, tb, z)
        if watch.resets and not np.array_equal(y, yb):
            # (the reset moved a surface the reset reads: its branch is taken anew here,
            # not at the next step's end -- MODINT integrating again from its IC)
            again = watch.after_reset(tb, yb, y, m, z)
            if again != m:
                self.record_changes(tb, y, m, again, z, set(), returned=True)
                changed = True
                m[:] = again
                y = watch.apply_resets(y, m, tb, z)
        cur.t, cur.y = tb, y
        if rec is not None:
            rec.restarted(tb, y, m, z)
            if changed or not np.array_equal(y, yb):
                rec.sample(tb, y, m, z)
        scheduled = bool(self.fired)
        if at_output and not scheduled:  # (the code a crossing runs comes before its row)
            rec.grid_row(tb, y, m, z, shown=rec.shown_modes(tb, y, m, z))
        if self.stop_reason is not None:
            # (the stop's row, unless the grid's row just taken is this instant: a grid
            # instant a float from the stop, 3 x 0.1 against TERMT(T >= 0.3), printed
            # the same state twice, the second row a float before the first)
            if rec is not None and (rec.last_t is None or not same_instant(rec.last_t, tb)):
                # (a grid instant a float after the stop is this row: the grid's; a
                # crossing's row there is taken after its code)
                g = rec.out_i if rec.out_i < len(rec.times) and not scheduled and \
                    same_instant(rec.times[rec.out_i], tb) else -1
                rec.row(tb, y, m, z, g)
                rec.out_i += g >= 0
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

    def _jumped(self, tb: float, yb: np.ndarray, m, new_m, z, triggered) -> list[int]:
        """The crossings that run code (SCHEDULE, EVENT) whose value jumped over zero
        at this restart because other surfaces changed branch (1 - RSW(X > 1, 1, 0)
        reaches zero where X - 1 does), or that stand on zero at a restart another
        made (X - 1.5 where TIME - 1.5 is a breakpoint): in the old branches still on
        their side or at zero, in the new ones not. (One the motion took across
        unseen is no such jump.)"""
        ks = [k for k in self.scheduling if new_m[k] != m[k] and k not in triggered]
        if not ks:
            return []
        e = self.c.surf(tb, yb.tolist(), m, z)
        return [k for k in ks if (m[k] > 0 and e[k] >= 0) or (m[k] < 0 and e[k] <= 0)]

    def record_changes(self, t: float, y: np.ndarray, m, new_m, z, at_zero: set[int],
                       quiet: set[int] = frozenset(), returned: bool = False) -> None:
        """An event for every watched surface whose branch changes at t (`quiet`:
        located, but changing no derivative: not an event). A crossing that runs code
        is an event where it runs it (1 - FLAG leaving zero is none)."""
        for k in range(len(self.plan.watched)):
            if new_m[k] == m[k] or k in quiet:
                continue
            w = self.plan.watched[k]
            if w.purpose is Purpose.SCHEDULE and not w.fires(m[k], new_m[k]):
                continue
            if k not in at_zero and self.watch.silent(k, t, y, new_m, z):
                continue  # a branch nothing uses now: not an event
            if m[k] == 0.0 and k not in at_zero and self.watch.quiet(k, t, y, new_m, z):
                # leaving an exact zero (ABS(Y) from Y(0) = 0) that no derivative
                # feels: seen at whatever step end comes first, so not an event (the
                # event list would otherwise depend on the output grid)
                continue
            self._event(t, k, m[k], new_m[k], returned)

    def _event(self, t: float, k: int, old: float, new: float, returned: bool = False
               ) -> None:
        """Surface k's branch changes from old to new at t (a located crossing;
        `returned`: a memory trigger the motion takes back at once, or a reset's
        trigger the reset sends back: an event both ways, since the memory or the
        state took what the other branch gave)."""
        w = self.plan.watched[k]
        last = next((e for e in reversed(self.events) if e.surface == w.surface), None)
        if not returned and last is not None and last.old == new and \
                abs(last.time - t) <= 1e-12 * max(abs(t), 1e-300):
            # switched and switched back at one instant (noise at a tangential
            # crossing): nothing happened
            self.events.remove(last)
            return
        self.events.append(w.event(t, old, new))

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
        # (the earliest: a solver that fails tries points further on, past the
        # boundary the model's values end at, before it gives up)
        fault = min(self.faults, key=lambda f: f.t)
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
