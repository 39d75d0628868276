"""AUTO: Fortran LSODA (`odeint`) over chunks of check instants, every internal step
watched.

`odeint` returns states only at the instants it is asked for, and nothing of the
steps it takes between them; a switch that flips and flips back between two
output instants would pass unseen. But every step LSODA takes evaluates the
derivatives at its end: all of a step's corrector iterations are at the step's
new TIME, a rejected step is followed by evaluations at an earlier TIME, and the
last evaluation at an accepted TIME is within the corrector's convergence test
(a fraction of a tolerance unit) of the accepted state. So the log of the
evaluations (`Evaluations`, filled by the run loop's vector field during a chunk)
gives every accepted step end: the evaluations that no later one precedes
(`Evaluations.step_ends`). The surfaces are looked at there too (`watch`), and where
one is on the wrong side at a step end before any output instant shows it, the
exact states at that step end and at the one before are integrated once more and
put in as check instants (`_examine`): the loop then finds the crossing between two
exact instants one LSODA step apart, as on any step-by-step route. The step ends
are also the samples the RANGE search reads between output instants (`samples`).
"""

from __future__ import annotations

import bisect
import gc
import math
import time
import warnings

import numpy as np

from ..outcome import Failure
from .base import Chunked, Rhs, StepFailure
from .dense import Nodes, quintic_gap, quintic_terms
from .ivp import ScipyStepper, solver_tolerance
from .jacobian import DENSE_UP_TO, Banded, SegmentJacobian

MXSTEP = 1_000_000  # odeint's steps per output interval when no limit is nearer
UNLIMITED = 2**62


class Evaluations:
    """The derivative evaluations of one odeint call, in call order: TIME and the
    state (a list, or an array for a large model). `fun` is the run loop's vector
    field adding to `t` and `y` (a chunk's own integration calls it, the others the
    plain one), and calling `compact` when `t` is longer than `limit`: the step ends
    known by then are kept as arrays, so a long call holds its steps, not every
    evaluation."""

    __slots__ = ("fun", "t", "y", "limit", "_done_t", "_done_y")

    def __init__(self, limit: int = 1 << 30) -> None:
        self.fun: Rhs | None = None
        self.t: list[float] = []
        self.y: list = []
        self.limit = limit
        self._done_t: list[np.ndarray] = []
        self._done_y: list[np.ndarray] = []

    def start(self) -> None:
        self.t.clear()
        self.y.clear()
        self._done_t.clear()
        self._done_y.clear()

    @staticmethod
    def _ends(t: np.ndarray) -> np.ndarray:
        """Which evaluations end accepted steps: no later one is at an earlier TIME (a
        rejected step is tried again from before it) and the next one is at a later
        TIME (the corrector's iterations share theirs)."""
        later = np.minimum.accumulate(t[::-1])[::-1]  # min(t[k:])
        after = np.append(later[1:], np.inf)  # min(t[k+1:])
        last = np.append(t[1:] != t[:-1], True)
        return np.flatnonzero((t <= after) & last)

    def _states(self, keep: np.ndarray) -> np.ndarray:
        y = self.y
        if not len(keep):  # (none: a call that failed at its start, say)
            width = len(y[0]) if y else self._done_y[0].shape[1] if self._done_y else 0
            return np.empty((0, width))
        return np.array([y[k] for k in keep.tolist()], dtype=float).reshape(len(keep), -1)

    def compact(self) -> None:
        """Keep the step ends found so far as arrays, and the evaluations after the
        last of them (the step being tried may still be rejected) as they are."""
        t = np.asarray(self.t, dtype=float)
        keep = self._ends(t)[:-1]  # (the last one is the step being tried)
        if not len(keep):
            self.limit *= 2
            return
        self._done_t.append(t[keep])
        self._done_y.append(self._states(keep))
        cut = int(keep[-1]) + 1
        del self.t[:cut]
        del self.y[:cut]

    def step_ends(self, t0: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
        """The accepted step ends in (t0, t1] and their states (the last evaluation at
        each)."""
        t = np.asarray(self.t, dtype=float)
        keep = self._ends(t) if len(t) else np.empty(0, int)
        ts = np.concatenate([*self._done_t, t[keep]])
        ys = self._states(keep)
        if self._done_y:
            ys = np.concatenate([*self._done_y, ys.reshape(len(keep), -1)
                                 if len(keep) else np.empty((0, self._done_y[0].shape[1]))])
        inside = (ts > t0) & (ts <= t1)
        self.t.clear()
        self.y.clear()
        self._done_t.clear()
        self._done_y.clear()
        return ts[inside], ys[inside]


# Floats of logged states a chunk may hold (n states x evaluations): a large model's
# chunks are cut shorter rather than hold more
LOG_BUDGET = 4_000_000
# Check instants besides the output grid where it is coarse, about every ANCHOR_STEPS
# of LSODA's steps (from the step ends of the chunk before): an exact state is never
# far back, so a window integrated again to locate a crossing (or a hidden one made
# visible) starts a bounded number of steps before it, whatever OUTDEL is
ANCHOR_STEPS = 64
ANCHORS_PER_CHUNK = 65536  # (more would be many more than the chunk has steps)
# Bad step ends made exact check instants at once after the first (an excursion that
# lasts several steps needs only its start; a surface grazing within a tolerance
# unit of zero would otherwise cost one integration per step end)
INSERT_AHEAD = 3


class Instants:
    """The check instants a stepper has still to integrate, in order: the loop's grid
    (a view of it, never copied: a copy at every restart would cost, in time and in
    the rows that keep views of it, in proportion to the run's length) merged with
    the few instants put in since (`stop_at`) and the segment's end."""

    __slots__ = ("grid", "i", "extra")

    def __init__(self, grid, end: float) -> None:
        # (an array, or a long grid made as it is read, `run.plan.GridTimes`, kept so)
        self.grid = grid if hasattr(grid, "searchsorted") else np.asarray(grid, dtype=float)
        self.i = 0
        self.extra = [end]  # sorted; the end is always the last

    def first(self) -> float:
        g = float(self.grid[self.i]) if self.i < len(self.grid) else math.inf
        return min(g, self.extra[0])

    def ahead(self, n: int) -> np.ndarray:
        """The next n instants (fewer at the end), a new array."""
        ts = np.concatenate([self.grid[self.i:self.i + n], self.extra[:n]])
        if len(self.extra) > 1:
            ts.sort(kind="stable")
        return ts[:n]

    # (searchsorted, not bisect, on the grid: bisect compares NumPy scalars one by
    # one, 20 times slower)
    def count_upto(self, t: float) -> int:
        return self._after(t, "right") - self.i + bisect.bisect_right(self.extra, t)

    def _after(self, t: float, side: str) -> int:
        return self.i + int(self.grid[self.i:].searchsorted(t, side))

    def passed(self, t: float) -> None:
        """The instants up to t are integrated."""
        self.i = self._after(t, "right")
        del self.extra[:bisect.bisect_right(self.extra, t)]

    def put(self, t: float) -> None:
        """t becomes one of the instants (once)."""
        j = self._after(t, "left")
        if not (j < len(self.grid) and self.grid[j] == t) and t not in self.extra:
            bisect.insort(self.extra, t)


class OdeintStepper(Chunked):
    """One `odeint` call integrates through many check instants with no Python
    between its internal steps (only the right-hand side is Python), which is
    what makes it several times faster than driving a solver step by step. Its
    "steps" for the loop are the check instants (the output grid): the loop looks
    at the switching surfaces there. Where a surface has crossed, `interpolant()`
    is the cubic Hermite through the interval's two rows and their derivatives
    (`dense.Nodes`: two evaluations, no integration); `window(t)` says whether its
    error near t (estimated with a third row) is within the tolerance, and
    `refine(lo, hi)` integrates a narrow window around the crossing once more with
    odeint and makes its exact ends nodes of the dense output, so the crossing is
    located as precisely as with any other route. The first chunk covers the time
    the loop expects to the next event (`expect`, from the spacing of the recent
    ones), so little is integrated past it and thrown away; later chunks grow
    geometrically.

    `max_steps` bounds the internal steps this stepper may take: odeint's
    per-interval limit is set to what is left, a chunk is sized from the steps an
    instant has taken so far, and instants past the budget are dropped, so a run
    stops near its step limit instead of finishing a chunk of 4096 instants.

    `log` and `watch` (the module's doc): the evaluations the vector field logs, and
    `watch = (wrong_at, modes, memory)`, where `wrong_at(T, Y, only=None, behind=None)`
    gives the index of the first of the instants T (states Y) at which a surface (of
    `only`, if given; of those on their side at `behind` = (t, y), if given) is on the
    wrong side of the branches in force, and of the first at which one that matters is
    (one whose branch is silent the loop follows without a restart); len(T) for none.
    `modes`/`memory` are the lists the loop changes in place (a branch followed without
    a restart), read to know when an examination is out of date.
    """

    def __init__(self, fun: Rhs, t0: float, y0: np.ndarray, t_bound: float, checks, *,
                 rtol: np.ndarray | float, atol: np.ndarray | float, max_step: float,
                 first_step: float | None, chunk: int = 16,
                 max_steps: int = UNLIMITED, expect: float | None = None,
                 jac: SegmentJacobian | None = None, log: Evaluations | None = None,
                 watch=None, chunk_seconds: float | None = None) -> None:
        self.fun = fun
        self.jac = jac
        self._banded: Banded | None = None
        self.t = self.t_old = t0
        self.y = np.asarray(y0, dtype=float)
        self.y_old = self.y
        self.t_bound = t_bound
        # the loop passes the instants strictly inside (t0, t_bound), in order
        self.checks = Instants(checks, t_bound)
        self.rtol, self.atol = solver_tolerance(rtol), solver_tolerance(atol)
        self.max_step = max_step
        self.first_step = first_step
        self.T = np.empty(0)  # the check instants integrated so far ...
        self.Y = np.empty((0, len(self.y)))  # ... their states ...
        self.pos = 0  # ... and how many of them the loop has taken
        self.chunk = chunk
        # how far in time a chunk reaches at most (it ends there, at an instant of its
        # own when the output grid is coarser): after a restart, a little past the
        # next event the loop expects, else 64 steps of the one before the restart,
        # then four times further each time it is reached; else a chunk would run
        # to the segment's end, past the next switch, and be thrown away there
        self._horizon = 1.05 * expect if expect is not None else \
            64.0 * first_step if first_step and log is not None else math.inf
        self._reach = t0 + self._horizon  # where the chunks end for now
        self._expected = expect is not None
        if expect is not None and len(self.checks.grid):
            # cover the expected time to the next event, and a few instants more
            n = self.checks.count_upto(t0 + 1.05 * expect)
            self.chunk = max(4, n + 3)
        self.max_steps = max_steps
        self._nfev = 0
        self._steps = 0  # internal steps of the chunks so far
        self._instants = 0  # check instants those steps covered
        # the wall-clock a chunk may take (under a time limit: a chunk that the limit
        # ends is lost, one odeint call, so none may be long), and the time so far
        self._chunk_seconds = chunk_seconds
        self._seconds = 0.0
        self._dense: Nodes | None = None
        self._derivs: dict[float, np.ndarray] = {}  # f at recent rows
        self._before: tuple[float, np.ndarray] | None = None  # the row before t_old
        self._failure: StepFailure | None = None
        self.fallback: ScipyStepper | None = None
        self.log = log
        self.watch = watch
        self._evals = 0  # evaluations the logged chunks made
        # between anchors (`_anchored`): from the steps before a restart at first, then
        # from the chunk before (none in a run's first chunk: nothing is known yet)
        self._spacing: float | None = ANCHOR_STEPS * first_step \
            if first_step and log is not None else None
        self.S = np.empty(0)  # the chunk's step ends (approximate states) ...
        self.SY = np.empty((0, len(self.y)))
        self._handed = t0  # ... handed out as samples up to here
        # the chunk's examination (`_examine`): the modes and memory it holds for, the
        # first instant on the wrong side, the step ends looked at up to here
        self._exam_key: tuple | None = None
        self._exam_bad = math.inf  # the first instant on the wrong side
        self._exam_limit = t0  # the step ends before it looked at up to here
        self._exam_to = t0
        # the first instant a surface that matters is crossed at, and its state: the
        # surfaces not crossed there may cross and cross back before it
        self._exam_loud = t0
        self._exam_behind: tuple | None = None
        self._crossing: tuple | None = None  # (what `crossing_step` was asked, found)

    @property
    def nfev(self) -> int:
        return self._nfev + (self.fallback.nfev if self.fallback is not None else 0)

    @property
    def nstep(self) -> int:
        return self._steps + (self.fallback.nstep if self.fallback is not None else 0)

    def _chunk_size(self, left: int) -> int:
        n = self.chunk
        self.chunk = min(max(self.chunk, 4) * 4, 4096)
        if self._instants and self._chunk_seconds is not None and self._seconds > 0:
            n = min(n, max(1, int(self._chunk_seconds * self._instants / self._seconds)))
        if self._instants:
            per_instant = max(self._steps / self._instants, 1.0)
            n = min(n, max(1, int(left / per_instant)))
            if self.log is not None and self._evals:
                floats = max(self._evals / self._instants, 1.0) * len(self.y)
                n = min(n, max(1, int(LOG_BUDGET / floats)))
        return n

    def _odeint(self, y0: np.ndarray, grid, fun: Rhs | None = None, **options):
        """odeint from y0 through grid (of `fun`, else the stepper's own vector field),
        with the model's Jacobian when there is one (dense for a small model, else
        banded in a renumbering that narrows the band); the rows come back in the
        states' own order."""
        from scipy.integrate import odeint

        fun = fun or self.fun
        if self.jac is not None:
            if len(y0) <= DENSE_UP_TO:
                options["Dfun"] = self.jac.dense
            else:
                if self._banded is None:
                    self._banded = self.jac.banded()
                b = self._banded
                fun, y0 = b.wrap(fun), b.to_new(y0)
                options.update(ml=b.ml, mu=b.mu)
                if not b.differenced:
                    options["Dfun"] = b.dfun
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a failure is handled by the caller
            ys, info = odeint(fun, y0, grid, rtol=self.rtol, atol=self.atol, tfirst=True,
                              full_output=True, **options)
        if self._banded is not None:
            ys = self._banded.to_old(ys)
        return ys, info

    def _anchored(self, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The chunk's instants: the check instants ts and anchors between them (about
        every `_spacing`), and which are check instants. The anchors do not shorten
        the chunk: each end of one is a fresh start of LSODA's."""
        sp = self._spacing
        if sp is None or not len(ts):
            return ts, np.ones(len(ts), bool)
        pts = np.concatenate(([self.t], ts))
        gaps = np.diff(pts)
        sp = max(sp, float(pts[-1] - pts[0]) / ANCHORS_PER_CHUNK)
        with np.errstate(all="ignore"):
            k = np.clip(np.ceil(gaps / sp) - 1.0, 0, ANCHORS_PER_CHUNK).astype(int)
        if not k.any():
            return ts, np.ones(len(ts), bool)
        gap = np.repeat(np.arange(len(gaps)), k)
        j = np.arange(len(gap)) - np.repeat(np.cumsum(k) - k, k) + 1
        anchors = pts[gap] + gaps[gap] * (j / (k[gap] + 1.0))
        anchors = anchors[(anchors > pts[gap]) & (anchors < pts[gap + 1])]
        merged = np.concatenate([ts, anchors])
        order = np.argsort(merged, kind="stable")
        return merged[order], order < len(ts)

    def _fill(self) -> None:
        left = self.max_steps - self._steps
        if left <= 0:
            self._failure = StepFailure(Failure.STEPS, self.t)
            return
        if self.t >= self._reach or not self._expected:
            # (an expected event is expected where it is expected: a chunk that ends
            # at an instant before it leaves the horizon where it was)
            self._reach = self.t + self._horizon
            self._horizon *= 4.0
        end = self._reach
        if self.checks.first() > end:
            # (a grid coarser than the horizon: the chunk ends at `end`, an instant of
            # its own; the count of instants a chunk takes grows when it takes them)
            ts, checks = self._anchored(np.array([end]))
            checks[-1] = False
        else:
            ts = self.checks.ahead(self._chunk_size(left))
            # (and the chunk ends by the horizon: what it integrates past a crossing
            # is thrown away)
            ts = ts[:int(np.searchsorted(ts, end, side="right"))]
            ts, checks = self._anchored(ts)
        grid = np.concatenate(([self.t], ts))
        options = {"mxstep": min(MXSTEP, left)}
        if math.isfinite(self.max_step):
            options["hmax"] = self.max_step
        if self.first_step:
            options["h0"] = min(self.first_step, ts[0] - self.t)
        if ts[-1] >= self.t_bound:
            options["tcrit"] = np.array([self.t_bound])
        # (the log holds a list per evaluation: the cyclic collector would go over all
        # of them again and again while the chunk runs, and once more at the first
        # allocation after it, for nothing: it is off until they are read and freed)
        collecting = self.log is not None and gc.isenabled()
        if self.log is not None:
            self.log.start()
        if collecting:
            gc.disable()
        try:
            self._integrate_chunk(grid, ts, checks, left, options)
        finally:
            if collecting:
                gc.enable()

    def _integrate_chunk(self, grid: np.ndarray, ts: np.ndarray, checks: np.ndarray,
                         left: int, options: dict) -> None:
        started = time.perf_counter()
        try:
            ys, info = self._odeint(self.y, grid, self.log.fun if self.log else None, **options)
        finally:
            self._seconds += time.perf_counter() - started
        if info["message"] != "Integration successful.":
            self._keep_passed(ts, ys, info, left)
            self._log_steps()
            return
        self._nfev += int(info["nfe"][-1])
        self.first_step = float(info["hu"][-1])
        nst = np.asarray(info["nst"])
        good = len(ts) if nst[-1] <= left else int(np.searchsorted(nst, left, side="right"))
        self.T, self.Y, self.pos = ts[:good], ys[1:good + 1], 0
        self._steps += int(nst[good - 1]) if good else left
        self._instants += good
        passed = ts[:good][checks[:good]]
        if len(passed):
            self.checks.passed(float(passed[-1]))
        if good < len(ts):
            self._failure = StepFailure(Failure.STEPS, float(ts[good - 1]) if good else self.t)
        self._evals += int(info["nfe"][-1])
        self._log_steps()

    def _log_steps(self) -> None:
        """The chunk's step ends up to its last instant kept, from the log."""
        if self.log is None:
            return
        end = float(self.T[-1]) if len(self.T) else self.t
        self.S, self.SY = self.log.step_ends(self.t, end)
        self._exam_key = None
        if len(self.S) >= 2:
            # (the chunk's last steps, the longest: LSODA goes on with steps at least as
            # long where nothing happens, and an anchor too many costs more than one
            # too few)
            self._spacing = ANCHOR_STEPS * float(np.max(np.diff(self.S[-17:])))
    def _keep_passed(self, ts, ys, info, left: int) -> None:
        """Keep the instants LSODA really passed; then, if the step budget ran out,
        that is the failure, else SciPy's LSODA class takes over from the last of
        them: it fails (or not) with a clear message."""
        tcur = np.asarray(info["tcur"])
        good = 0
        while (good < len(ts) and good < len(tcur) and tcur[good] >= ts[good]
               and np.all(np.isfinite(ys[good + 1]))):
            good += 1
        self.T, self.Y, self.pos = ts[:good], ys[1:good + 1], 0
        # odeint fills its counts up to the interval that failed; past it, not at all
        last = min(good, len(info["nst"]) - 1)
        self._nfev += int(info["nfe"][last])
        self._steps += int(info["nst"][last])
        self._instants += good
        if left < MXSTEP and info["message"].startswith("Excess work"):
            self._failure = StepFailure(Failure.STEPS, float(ts[good - 1]) if good else self.t)
            return
        t_last, y_last = (ts[good - 1], ys[good]) if good else (self.t, self.y)
        self.fallback = ScipyStepper("LSODA", self.fun, float(t_last), y_last, self.t_bound,
                                     rtol=self.rtol, atol=self.atol, max_step=self.max_step,
                                     first_step=None, jac=self.jac)

    @property
    def step_size(self) -> float:
        """LSODA's own recent steps (its step ends, not the instants the loop takes)."""
        if self._spacing is not None:
            return self._spacing / ANCHOR_STEPS
        return self.first_step or (self.t - self.t_old)

    def pending(self) -> tuple[np.ndarray, np.ndarray]:
        """The integrated check instants the loop has not taken yet (integrating the
        next chunk if there are none); empty once LSODA's class has taken over. A
        step end where a surface is on the wrong side before any of them shows it is
        among them, exact, with the step end before it (`_examine`)."""
        if self.pos >= len(self.T) and self.fallback is None and self._failure is None:
            self._fill()
        self._examine()
        return self.T[self.pos:], self.Y[self.pos:]

    def _examine(self) -> None:
        """Look at the surfaces at the chunk's step ends ahead. A crossing the instants
        show is located between them (`refine` puts LSODA's step around it in); one
        they hide -- a step end on the wrong side in an interval whose end is not, or,
        in the interval whose end shows a crossing, of a surface not crossed there --
        becomes visible: that step end is made an exact check instant (integrated from
        the instant before it), with a few more on the wrong side after it
        (INSERT_AHEAD, in case it turns out on the right side after all)."""
        if self.watch is None or self.pos >= len(self.T):
            return
        wrong_at, modes, memory = self.watch
        key = (tuple(modes), tuple(memory))
        if key != self._exam_key or self._exam_bad <= self.t:
            # (a new chunk, a branch the loop followed without a restart, or the first
            # instant on the wrong side taken as one where nothing happens after all)
            T, Y = self.T[self.pos:], self.Y[self.pos:]
            bad, loud = wrong_at(T, Y)
            self._exam_key, self._exam_to = key, self.t
            self._exam_bad = float(T[bad]) if bad < len(T) else math.inf
            # the last instant before the first on the wrong side of a surface that
            # matters (one whose branch nothing uses is followed where it flips)
            self._exam_limit = float(T[loud - 1]) if 0 < loud < len(T) else \
                self.t if loud == 0 else float(T[-1])
            # the interval up to that instant shows the crossings of the surfaces wrong
            # there (located between its ends); another surface may cross and cross
            # back inside it, before them, where no instant shows it
            self._exam_behind = (float(T[loud]), Y[loud]) if loud < len(T) else None
            self._exam_loud = float(T[loud]) if loud < len(T) else self._exam_limit
        if not len(self.S):
            return
        for end, behind in ((self._exam_limit, None), (self._exam_loud, self._exam_behind)):
            if self._exam_to >= end:
                continue
            lo = int(np.searchsorted(self.S, max(self.t, self._exam_to), side="right"))
            hi = int(np.searchsorted(self.S, end, side="left"))
            wrong = wrong_at(self.S[lo:hi], self.SY[lo:hi], behind=behind)[1] \
                if hi > lo else 0
            if wrong < hi - lo:
                self._exam_hidden(lo + wrong, hi)
                return
            self._exam_to = end

    def _exam_hidden(self, k: int, hi: int) -> None:
        """Step end k (of the chunk's, those before `hi` examined) is on the wrong side
        where no pending instant shows it: it is made an exact instant, with a few
        after it, and the first on the wrong side is noted."""
        wrong_at = self.watch[0]
        tau = float(self.S[k])
        i = int(np.searchsorted(self.T, tau, side="left"))  # the first instant >= tau
        ahead = [float(self.S[j]) for j in range(k + 1, hi) if self.S[j] < self.T[i]]
        points = [tau] + ahead[:INSERT_AHEAD]
        self._exam_to = points[-1]
        if self._insert(points):
            # (the first instant on the wrong side may now be one of them)
            j = int(np.searchsorted(self.T, tau, side="left"))
            T, Y = self.T[j:j + len(points)], self.Y[j:j + len(points)]
            bad = wrong_at(T, Y)[0]
            if bad < len(T):
                self._exam_bad = min(self._exam_bad, float(T[bad]))

    def _insert(self, points: list[float]) -> bool:
        """Make instants (in order, between two pending instants or after the present
        one) exact check instants: integrated from the instant before them. False if
        odeint could not reach them all."""
        i = int(np.searchsorted(self.T, points[0], side="left"))
        start_t, start_y = (float(self.T[i - 1]), self.Y[i - 1]) if i > self.pos else \
            (self.t, self.y)
        ys, info = self._odeint(start_y, [start_t, *points], mxstep=MXSTEP)
        self._nfev += int(info["nfe"][-1])
        good = len(points) if info["message"] == "Integration successful." else 0
        while good and not np.all(np.isfinite(ys[good])):
            good -= 1
        if good:
            self.T = np.concatenate([self.T[:i], points[:good], self.T[i:]])
            self.Y = np.concatenate([self.Y[:i], ys[1:good + 1], self.Y[i:]])
        return good == len(points)

    def stop_at(self, t: float) -> bool:
        """Make t a check instant (the loop pauses there: an ACSL instant that may
        change nothing the derivatives read). False if it cannot be."""
        if self.fallback is not None or self._failure is not None or not t > self.t \
                or t > self.t_bound:
            return False
        T = self.T[self.pos:]
        if len(T) and t <= T[-1]:
            j = int(np.searchsorted(T, t, side="left"))
            return True if T[j] == t else self._insert([t])
        self.checks.put(t)  # one of the instants still to integrate
        return True

    def first_wrong(self) -> int | None:
        """The first pending instant on the wrong side, as `_examine` found it (with
        the branches in force: it looks again when they change)."""
        self._examine()
        if self._exam_key is None or self.pos >= len(self.T):
            return None
        return int(np.searchsorted(self.T, self._exam_bad, side="left")) - self.pos

    def samples(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The chunk's step ends strictly between the last ones handed out and t, with
        their (approximate) states: the RANGE search's samples between instants."""
        lo = np.searchsorted(self.S, self._handed, side="right")
        hi = np.searchsorted(self.S, t, side="left")
        self._handed = max(self._handed, t)
        return self.S[lo:hi], self.SY[lo:hi]

    def consume(self, n: int) -> None:
        last = self.pos + n - 1
        if n >= 3:
            self._before = (float(self.T[last - 2]), self.Y[last - 2])
        elif n == 2:
            self._before = (self.t, self.y)
        else:
            self._before = (self.t_old, self.y_old) if self.t_old < self.t else None
        if n >= 2:
            self.t_old, self.y_old = float(self.T[last - 1]), self.Y[last - 1]
        else:
            self.t_old, self.y_old = self.t, self.y
        self.t, self.y = float(self.T[last]), self.Y[last]
        self.pos += n
        self._dense = None

    def step(self) -> StepFailure | None:
        if self.pos >= len(self.T) and self.fallback is None and self._failure is None:
            self._fill()
        self._examine()
        if self.pos >= len(self.T):
            if self._failure is not None:
                return self._failure
            if self.fallback is not None:
                failure = self.fallback.step()
                self.t_old, self.t = self.fallback.t_old, self.fallback.t
                self.y = self.fallback.y
                self._dense = None
                return failure
        self.consume(1)
        return None

    def interpolant(self):
        if self.fallback is not None and self.pos >= len(self.T) and \
                self.t == self.fallback.t:
            return self.fallback.interpolant()
        if self._dense is None:
            self._dense = Nodes([self.t_old, self.t], [self.y_old, self.y],
                                [self._deriv(self.t_old, self.y_old), self._deriv(self.t, self.y)])
        return self._dense

    def _deriv(self, t: float, y: np.ndarray) -> np.ndarray:
        f = self._derivs.get(t)
        if f is None:
            if len(self._derivs) > 8:
                self._derivs.clear()
            f = self._derivs[t] = np.asarray(self.fun(t, y), dtype=float)
            self._nfev += 1
        return f

    refines = True  # (the cubic over an interval of many LSODA steps: `refine`)
    SHARP = 10.0  # a quintic whose cubic is this many tolerances off needs no window
    WINDOW = 0.01  # share of the interval integrated again around a crossing

    def sharpen(self) -> bool:
        """Make the dense output the quintic through a third row (the next one
        integrated, which continues the same smooth flow, else the one before) if
        the cubic's distance from it (the cubic's error) is within SHARP tolerances
        in the middle of the interval, where it is largest. False: `refine` is
        needed near a crossing."""
        dense = self.interpolant()
        if not isinstance(dense, Nodes) or len(dense.t) > 2:
            return False
        third = None
        if self.pos < len(self.T) and np.all(np.isfinite(self.Y[self.pos])):
            third = (float(self.T[self.pos]), self.Y[self.pos])
        elif self._before is not None:
            third = self._before
        if third is None:
            return False
        terms = quintic_terms(self.t_old, self.y_old, dense.f[0], self.t, self.y, dense.f[1],
                              third[0], third[1], self._deriv(*third))
        gap = quintic_gap(terms, 0.5 * (self.t_old + self.t))
        scale = self.rtol * np.abs(0.5 * (self.y_old + self.y)) + self.atol
        if not (gap <= self.SHARP * scale).all():
            return False
        dense.sharpen(terms)
        return True

    def refine(self, t: float, surfaces=None):
        """Integrate from the interval's start to a narrow window around t (one odeint
        call) and make its exact ends nodes of the dense output; returns it. Where
        LSODA took several steps in the interval, the window is the step its step ends
        say the crossing of `surfaces` (watched positions; None: any) is in (the first
        on the wrong side, and the one before), with a narrow window around t inside
        it."""
        dense = self.interpolant()
        if not isinstance(dense, Nodes):
            return dense  # (the fallback's step: its own solver's dense output)
        h = self.t - self.t_old
        points = [max(self.t_old, t - self.WINDOW * h), min(self.t, t + self.WINDOW * h)]
        step = self.crossing_step(surfaces)
        if step is not None:
            lo, hi = step
            w = 0.05 * (hi - lo)
            points = [lo, hi] if not lo < t < hi else [lo, max(lo, t - w), min(hi, t + w), hi]
        grid = [self.t_old] + sorted({x for x in points if self.t_old < x < self.t})
        if len(grid) > 1:
            ys, info = self._odeint(self.y_old, grid, mxstep=MXSTEP)
            self._nfev += int(info["nfe"][-1])
            if info["message"] == "Integration successful." and np.all(np.isfinite(ys)):
                for x, yx in zip(grid[1:], ys[1:], strict=True):
                    dense.insert(x, yx, self._deriv(x, yx))
        return dense

    def resolved(self, t: float, surfaces=None) -> bool:
        """Whether the dense output around t is a narrow window's: a cubic over a
        tenth of LSODA's step there at most (a cubic over a whole step of a high
        order is off by up to (h*omega)^4/384 of the motion)."""
        dense = self.interpolant()
        if not isinstance(dense, Nodes):
            return True  # (the fallback's step: nothing here can narrow it)
        k = min(max(bisect.bisect_left(dense.t, t), 1), len(dense.t) - 1)
        step = self.crossing_step(surfaces)
        h = step[1] - step[0] if step is not None else self.t - self.t_old
        return dense.t[k] - dense.t[k - 1] <= 0.11 * h

    def crossing_step(self, surfaces=None) -> tuple[float, float] | None:
        """The LSODA step of the present interval a crossing of `surfaces` is in, by
        its step ends: from the one before the first on the wrong side to that one
        (to the interval's end if none is); None when LSODA took one step or none
        here. (Only the surfaces being located: another one's departure from zero in
        the interval's first step is not where they cross.)"""
        if self.watch is None or not len(self.S):
            return None
        # (refine and resolved ask the same of one interval: looked at once)
        key = (self.t_old, self.t, frozenset(surfaces) if surfaces is not None else None,
               id(self.S), tuple(self.watch[1]), tuple(self.watch[2]))
        if self._crossing is not None and self._crossing[0] == key:
            return self._crossing[1]
        found = self._crossing_in(surfaces)
        self._crossing = (key, found)
        return found

    def _crossing_in(self, surfaces) -> tuple[float, float] | None:
        lo = int(np.searchsorted(self.S, self.t_old, side="right"))
        hi = int(np.searchsorted(self.S, self.t, side="left"))
        if hi <= lo:
            return None
        first, loud = self.watch[0](self.S[lo:hi], self.SY[lo:hi], surfaces)
        k = lo + (first if surfaces is not None else loud)
        start = float(self.S[k - 1]) if k > lo else self.t_old
        end = float(self.S[k]) if k < hi else self.t
        return start, end

    def truncate(self, t: float) -> None:
        dense = self.interpolant()
        self.y = np.asarray(dense(t), dtype=float)
        self.t = t
