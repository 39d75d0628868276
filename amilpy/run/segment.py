"""The start of a segment (`Integrator`'s part): its vector field (faults kept,
sliding fields, the evaluation log AUTO's chunks read), the stepper its route
asks for, and the look at the surfaces over many instants that chunks use."""

from __future__ import annotations

import math
import time as _clock
from collections.abc import Callable

import numpy as np

from ..codegen.jacobian import for_compiled as jacobian_for
from ..codegen.jacobian import structure_for
from ..codegen.rolled import for_compiled as rolled_rhs
from ..outcome import Failure
from ..steppers import LOG_BUDGET, Evaluations, Stepper, first_bad, make_stepper
from ..steppers.jacobian import SegmentJacobian
from .cursor import Cursor, Stop
from .edges import expected_event
from .faults import Fault
from .plan import sliding_in, train_instants
from .record import Recorder, column
from .slide import MAX_SLIDING
from .watch import TooManySlides, crossings

CHUNK_SHARE = 0.02  # of --max-time, the most one odeint chunk may take
# ... and with no time limit: a Ctrl-C inside a chunk loses the chunk (odeint gives
# back nothing of a call an exception ends), so none takes long
CHUNK_SECONDS = 0.25


class SegmentStart:
    """`Integrator`'s segment start (a mixin: it reads the integrator's state)."""

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
        rhs, sliding, field = self.c.rhs, sliding_in(m), self.watch.field
        rolled = rolled_rhs(self.c)  # a large model's repeated equations on arrays

        def f(t, y):
            if deadline is not None:
                calls[0] += 1
                if calls[0] % 256 == 0 and _clock.perf_counter() > deadline:
                    raise Stop(Failure.TIME_LIMIT, t, limit=self.opts.max_time)
            try:
                # no surface slides: the generated derivatives themselves (the hot path)
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
        given `rhs`, the generated derivatives straight (f for a fault only)."""
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
        chunked = plan.chunked and not sliding_in(cur.m) and not dense
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
            # (searchsorted: bisect on an array compares NumPy scalars one by one)
            lo = rec.out_i if rec else 0
            lo += int(times[lo:].searchsorted(cur.t, "right"))
            checks = times[lo:lo + int(times[lo:].searchsorted(seg_end, "left"))]
            if self.c.memory_trains:
                # (the instants it pauses at, known now: inserted later, each would cost
                # an integration of its own)
                checks = np.union1d(checks, train_instants(self.c.memory_trains, cur.t,
                                                           seg_end))
        # with nothing to watch nothing is thrown away after a chunk: longer first
        # chunks (growing four times a chunk, up to 4096 instants and CHUNK_SECONDS),
        # unless it may pause and start afresh (the caller's code, a memory the
        # integrator sees); never the whole segment in one call, whose output and
        # counts would take 200 bytes a row of a long run; nor under a time limit,
        # until the chunks' time is known
        pausing = t_end is not None and seg_end > t_end
        chunk = 16 if plan.watch_idx or pausing or self.opts.max_time else 256
        stepper = make_stepper(
            plan.route.name, f, cur.t, cur.y, seg_end, rtol=plan.tol.rtol, atol=plan.tol.atol,
            delt=plan.timer["DELT"], max_step=plan.max_step, first_step=self._last_step,
            checks=checks, chunk=chunk, max_steps=self.opts.max_steps - self.nsteps,
            expect=expected_event(self._recent, cur.t), jac=self._jacobian(cur, f),
            kernel=self._kernel_arguments(cur, dense, rec), log=log,
            watch=(self._wrong_at(cur), cur.m, cur.z) if plan.watch_idx else None,
            # (a chunk the time limit ends inside is lost: none may take long)
            chunk_seconds=min(CHUNK_SHARE * self.opts.max_time, CHUNK_SECONDS)
            if self.opts.max_time else CHUNK_SECONDS)
        return stepper, f

    def _wrong_at(self, cur: Cursor) -> Callable[..., tuple[int, int]]:
        """`wrong_at(T, Y, only=None) -> (first, loud)`: the index of the first of the
        instants T (states Y, as rows) at which a watched surface (of `only`, if given)
        is on the wrong side of the branches in force, and of the first at which one
        that matters is (len(T) if none). One matters unless its branch is silent
        (where it is first and last on the wrong side there): the loop follows its sign
        without a restart, and an output instant shows where it stays crossed.
        `wrong_at(T, Y, behind=(t, y))`: the same for the surfaces that are on their
        side at (t, y), an instant after T (one evaluation for both)."""
        c, plan, watch, m, z = self.c, self.plan, self.watch, cur.m, cur.z

        def wrong_at(T: np.ndarray, Y: np.ndarray, only=None, behind=None
                     ) -> tuple[int, int]:
            if not len(T):
                return 0, 0
            n = len(T)
            if behind is not None:
                T, Y = np.append(T, behind[0]), np.vstack([Y, behind[1]])
            try:
                with np.errstate(all="ignore"):
                    E = [column(v, len(T)) for v in c.surf_v(T, list(Y.T), m, z)]
            except (ArithmeticError, ValueError):
                # a surface with no value at one of the instants (1/(X - 1) where X = 1):
                # the instants before it are taken, and the fault is met and said
                # where it happens, step by step
                bad = next((i for i in range(n) if _faults(c, T[i], Y[i], m, z)), None)
                if bad is None:
                    if behind is not None:
                        return n, n  # (at the instant behind them)
                    raise
                return bad, bad
            found = crossings(plan, E, m)
            if behind is not None:
                found = {k: mask[:n] for k, mask in found.items() if not mask[n]}
            if only is not None:
                found = {k: mask for k, mask in found.items() if k in only}
            found = {k: mask for k, mask in found.items() if mask.any()}
            if not found:
                return n, n
            # (the surfaces in the order they cross: the first loud one is the answer,
            # and a crossing is mostly an event, so one look at silence is enough)
            first = sorted((int(np.argmax(mask)), k) for k, mask in found.items())
            for i, k in first:
                last = int(n - 1 - np.argmax(found[k][::-1]))
                if not (watch.silent(k, float(T[i]), Y[i], m, z) and
                        watch.silent(k, float(T[last]), Y[last], m, z)):
                    return first[0][0], i
            return first[0][0], n
        return wrong_at

    def _jacobian(self, cur: Cursor, f) -> SegmentJacobian | None:
        """The segment's Jacobian from the model's equations, for the routes that use
        one (built the first time a stepper asks for it); none while surfaces slide."""
        route = self.plan.route
        if route.fixed or route.explicit or sliding_in(cur.m) or not len(cur.y):
            return None
        c = self.c
        return SegmentJacobian(len(cur.y), lambda: jacobian_for(c), cur.m, cur.z, f,
                               lambda: structure_for(c))


def _faults(c, t: float, y: np.ndarray, m, z) -> bool:
    """Whether the surfaces have no value at (t, y)."""
    try:
        c.surf(float(t), y.tolist(), m, z)
    except (ArithmeticError, ValueError):
        return True
    return False
