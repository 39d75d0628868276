"""An accepted step, looked at (`Integrator`'s part): its checks (a step too
small, a state not finite, stiffness), the watch over the switching surfaces
(crossings located, the step cut at the first, silent switches followed), the
rows inside it and the memory that samples it."""

from __future__ import annotations

import numpy as np

from ..outcome import Failure
from ..steppers import Hermite, Stepper, first_bad
from .cursor import Cursor, Stop, WatchedStep
from .edges import locate_crossings
from .plan import SurfaceKind, slides
from .record import Recorder
from .turns import play_turn

_EPS = float(np.finfo(float).eps)


class StepWatch:
    """`Integrator`'s look at each accepted step (a mixin)."""

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
        near = [k for k in exited if not slides(cur.m[k]) and
                abs(e0[k]) <= 1e3 * float(np.max(scale, initial=0.0))]
        out = {}
        for k in near:
            g = plan.watched[k].gradient
            if g is None:
                g = self._surface_gradient(cur, e0, k)
            if g is not None:
                # (and twice where the slide left it: its drift, which a long slide at
                # a tight tolerance takes past ten units)
                band = max(10.0 * float(np.abs(g) @ scale), 2.0 * abs(e0[k]))
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
                    yb: np.ndarray, e_prev, seg_start: float) -> WatchedStep:
        c, watch, m, z = self.c, self.watch, cur.m, cur.z
        step = WatchedStep(tb, yb, set(), set(), {}, False, e_prev)
        # a play turning inside the step: the step ends there (its memory is updated
        # at the turn), unless a crossing comes first
        turn = play_turn(c, stepper.interpolant(), ta, tb, m, z) \
            if c.play_slots and tb > ta and self.plan.route.uses_tolerances else None
        if not self.plan.watch_idx:
            if turn is not None:
                stepper.truncate(turn)
                step.tb, step.yb, step.truncated = stepper.t, stepper.y, True
            return step
        e_b = c.surf(tb, yb.tolist(), m, z)
        hits, silent = [], []
        for k in self.plan.watch_idx:
            if watch.crossed(k, m[k], e_b[k]) and not slides(m[k]):
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
        if hits or slide_exit or turn is not None:
            # departed: no crossing to bracket, sign at tb
            roots, step.departed = locate_crossings(watch, stepper, hits, m, z, ta, tb,
                                                    seg_start, (e_prev, e_b))
            interp = stepper.interpolant()
            for k, mode in slide_exit:
                roots[k] = watch.locate_slide_exit(k, mode, m, z, interp, ta, tb)
            t_star = min(roots.values(), default=tb if turn is None else turn)
            if turn is not None and turn < t_star:
                roots, step.departed, slide_exit, t_star = {}, set(), [], turn
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
            step.exits = {k: mode for k, mode in slide_exit if k in step.triggered}
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
            if not rec.grid_row(to, yo, m, cur.z):
                # (the instant held for the caller, inside a step that went past it --
                # a Zeno point an INTERVAL instant shares: the caller takes that row;
                # looping on it never ended)
                break

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
