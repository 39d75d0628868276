"""What a run records: output rows on the grid, RANGE candidates, and the `Run`.

`Recorder` takes rows from the loop (one at a time from the step-by-step path,
whole blocks from an odeint chunk) and keeps them as arrays. `shown_modes` is
the one rule for what a row at a switching instant shows. `Extrema` watches the
RANGE variables' rows for the brackets where their minimum and maximum may lie;
`simulate.locate_range` zooms into them. `Recorder.run` assembles the `Run`.
"""

from __future__ import annotations

import math
from array import array
from bisect import bisect_left, bisect_right
from dataclasses import dataclass, replace

import numpy as np

from ..codegen import ModelCode
from ..language import RESERVED
from ..result import Event, Run, Status
from .plan import RunPlan
from .watch import SurfaceWatch


class Rows:
    """The recorded output rows, in order: single rows from the step-by-step path,
    whole blocks from an odeint chunk. Kept column by column, each column one array
    grown in place (`ndarray.resize`: realloc, which moves a large block by remapping
    its pages, not by copying them) and cut to its length at the end: a long run
    holds its rows once. Many small parts kept for the whole run would sit among the
    run's short-lived arrays on the C heap, whose freed holes the system never gets
    back: 75 MB more than the rows for the 1,000 s hoist (1E6 rows) that way."""

    BATCH = 32768  # rows handed to `on_part` at a time (a streamed run)
    SINGLE = 4096  # single rows kept as lists at most
    GROW = 1.5  # a column's capacity grows by this factor, at least to what it must hold
    FIRST = 8192  # rows a column has room for at most before any is kept (64 kB)

    def __init__(self, width: int, on_part=None, expect: int = 0) -> None:
        self.width = width
        # `on_part(t, g, values, final) -> rows kept`: each part as it is merged (a
        # CSV streamed as the run goes: output/stream.py), the run's last one final
        self.on_part = on_part
        # the kept rows: TIME, grid index and each column, the first `n` of each
        # (`expect`: the rows the run is planned to keep; room for FIRST of them at
        # most at first, then for all at the first growth: one copy of 64 kB a
        # column, and a run that stops early has not asked for its whole grid)
        self.expect = int(expect)
        cap = max(min(self.expect, self.FIRST), 16)
        self.n = 0
        self.kept_t = np.empty(cap)
        self.kept_g = np.empty(cap, np.int32)  # (a grid has at most 2E7 instants)
        self.kept = [np.empty(cap) for _ in range(width)]
        self.blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # not merged yet
        self.in_blocks = 0
        self.t: list[float] = []
        self.g: list[int] = []
        self.v: list[list[float]] = []
        self.last_t: float | None = None

    def add(self, t: float, g: int, values: list[float]) -> None:
        self.t.append(t)
        self.g.append(g)
        self.v.append(values)
        self.last_t = t
        if len(self.t) >= self.SINGLE:  # (as arrays, a row takes a tenth of the memory)
            self._flush()

    def _flush(self) -> None:
        if self.t:
            v = np.asarray(self.v, float).reshape(len(self.t), self.width)
            self._block(np.asarray(self.t, float), np.asarray(self.g, int), v)
            self.t, self.g, self.v = [], [], []

    def _block(self, t: np.ndarray, g: np.ndarray, values: np.ndarray) -> None:
        if self.on_part is None:  # (kept as they come: nothing waits to be handed on)
            self._keep(t, g, values)
            return
        # (TIME may be a view of a stepper's chunk, which it would keep alive until the
        # merge: copied; the indices and the table are the block's own)
        self.blocks.append((np.array(t, float), g, values))
        self.in_blocks += len(t)
        if self.in_blocks >= self.BATCH:
            self._merge()

    def _merge(self, final: bool = False) -> None:
        if self.on_part is None:
            return
        if not self.blocks:
            if final:
                self.on_part(np.empty(0), np.empty(0, int), np.empty((0, self.width)), True)
            return
        t, g, v = (np.concatenate(p) for p in zip(*self.blocks, strict=True))
        self.blocks, self.in_blocks = [], 0
        keep = self.on_part(t, g, v, final)
        self._keep(t[keep], g[keep], v[keep])

    def _keep(self, t: np.ndarray, g: np.ndarray, v: np.ndarray) -> None:
        n, k = self.n, len(t)
        if n + k > len(self.kept_t):
            cap = len(self.kept_t)
            self._resize(max(n + k, self.expect if cap < self.expect else int(cap * self.GROW)))
        self.kept_t[n:n + k] = t
        self.kept_g[n:n + k] = g
        for column, values in zip(self.kept, v.T, strict=True):
            column[n:n + k] = values
        self.n = n + k

    def _resize(self, size: int) -> None:
        # (the arrays are Rows' own and nothing holds a view of them: see take)
        for a in (self.kept_t, self.kept_g, *self.kept):
            a.resize(size, refcheck=False)

    def add_block(self, t: np.ndarray, g: np.ndarray, values: np.ndarray) -> None:
        self._flush()
        self._block(t, g, values)
        self.last_t = float(t[-1])

    def replace_last(self, values: list[float]) -> bool:
        """The last row's values replaced, if it is a grid row still held here (not
        yet handed to a stream); whether it was."""
        if self.t:
            if self.g[-1] < 0:
                return False
            self.v[-1] = values
            return True
        if self.blocks:
            t, g, v = self.blocks[-1]
            if g[-1] < 0:
                return False
            v[-1] = values
            return True
        if self.on_part is None and self.n and self.kept_g[self.n - 1] >= 0:
            for column, value in zip(self.kept, values, strict=True):
                column[self.n - 1] = value
            return True
        return False

    def take(self) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
        """TIME, the grid indices and each column, as arrays cut to their length;
        the rows are given away."""
        self._flush()
        self._merge(final=True)
        self._resize(self.n)
        out = (self.kept_t, self.kept_g, self.kept)
        self.__init__(self.width, self.on_part)
        return out


@dataclass(frozen=True)
class Bracket:
    """An interval that may hold an extremum, and the state where it starts."""

    ta: float
    tb: float
    y: np.ndarray
    m: tuple[float, ...]
    z: tuple[float, ...]


FORGET_FROM = 4096  # restarts kept before those no RANGE bracket can want are forgotten


class RestartStates:
    """The states where a run restarted, in time order, kept compactly: a long run
    restarts at every event (445,000 times in 10,000 s of the hoist), and as
    `Bracket`s they took 600 bytes each, as arrays and shared tuples 80 (7 states)."""

    def __init__(self) -> None:
        self.times = array("d")
        self._y = array("d")  # the states one after the other, `_n` each
        self._n = 0
        self._m: list[tuple] = []
        self._z: list[tuple] = []
        self._shared: dict[tuple, tuple] = {}  # (a run goes through few branch sets)

    def add(self, t: float, y: np.ndarray, m, z) -> None:
        self.times.append(t)
        self._n = len(y)
        self._y.frombytes(np.ascontiguousarray(y, dtype=float).tobytes())
        m, z = tuple(m), tuple(z)
        self._m.append(self._shared.setdefault(m, m))
        self._z.append(self._shared.setdefault(z, z))

    def __len__(self) -> int:
        return len(self.times)

    def keep(self, spans: list[tuple[float, float]], after: float) -> None:
        """Forget the restarts outside the spans and before `after`."""
        t = np.frombuffer(self.times, float)
        wanted = t >= after
        for ta, tb in spans:
            wanted[bisect_left(self.times, ta):bisect_right(self.times, tb)] = True
        rows = np.flatnonzero(wanted)
        y = np.frombuffer(self._y, float).reshape(len(t), self._n)[rows]
        self.times = array("d", t[rows].tobytes())
        self._y = array("d", y.tobytes())
        self._m = [self._m[k] for k in rows]
        self._z = [self._z[k] for k in rows]

    def between(self, ta: float, tb: float) -> list[Bracket]:
        """The restarts strictly inside (ta, tb), as brackets starting there."""
        n = self._n
        return [Bracket(self.times[k], math.nan,
                        np.frombuffer(self._y, float, n, 8 * n * k).copy(),
                        self._m[k], self._z[k])
                for k in range(bisect_right(self.times, ta), bisect_left(self.times, tb))]


@dataclass(frozen=True)
class Candidate:
    """Where a variable's maximum (or, negated, minimum) may lie."""

    score: float  # the vertex of the parabola through three rows (at an edge: the row)
    t: float  # where the score is
    sample: float  # the middle row's own value
    bracket: Bracket
    edge: Bracket | None = None  # the run's first or last row, when the candidate is it
    middle: Bracket | None = None  # the middle row (ta: its TIME), for a local maximum


class Extrema:
    """Brackets of each RANGE variable's minimum and maximum, from its rows.

    A row whose value is at least its neighbours' is a local maximum of the
    samples; the true one lies between the neighbours. Its score is the vertex
    of the parabola through the three rows; the KEEP best-scoring candidates are
    kept (with the state where their bracket starts), so a peak between two rows
    that rises above the sampled maximum is found whatever OUTDEL is, as long as
    the variable turns at most once between two rows. The first and the last
    row are candidates of the interval next to them. Rows are buffered and
    scanned with NumPy a batch at a time, every variable at once. Columns: each
    variable's maximum, then each one's minimum (of the negated values).
    """

    KEEP = 1
    BATCH = 8192

    def __init__(self, names: list[str], columns: list[int]) -> None:
        self.names = names
        self.columns = columns
        k = 2 * len(names)
        self.best = np.full(k, -np.inf)
        self.best_t = np.full(k, np.nan)
        self.candidates: list[list[Candidate]] = [[] for _ in range(k)]
        self.parts: list[tuple] = []  # (T, values, Y, modes, memory) not scanned yet
        self.single: list[tuple[float, np.ndarray, np.ndarray, tuple, tuple]] = []
        self.buffered = 0
        self._starts = np.zeros(1, int)  # where each part begins in a scan
        self._order: np.ndarray | None = None  # the scan's time order of its points
        self.started = False
        # the points of one stretch still coming, some before those in (a compiled
        # kernel call's rows, then its step ends and events among them): no scan, the
        # rows already scanned must all come before the rest (`settle` ends it)
        self.held = False

    def add(self, t: float, values: list[float], y: np.ndarray, m, z) -> None:
        """One row (y is kept, not copied: the loop never changes a state in place)."""
        if self.names:
            self.single.append((t, values, y, tuple(m), tuple(z)))
            self.buffered += 1
            if self.buffered >= self.BATCH and not self.held:
                self._scan_buffer()

    def add_many(self, T: np.ndarray, V: np.ndarray, Y: np.ndarray, m, z,
                 more: bool = False) -> None:
        """Rows T (values V, states Y), all taken with modes m and memory z (m may
        be an array of each row's modes). `more`: points of the same stretch of
        time follow (samples among these rows): no scan before they are in."""
        if self.names and len(T):
            self._gather()
            modes = m if isinstance(m, np.ndarray) else tuple(m)
            self.parts.append((T, V[:, self.columns], Y, modes, tuple(z)))
            self.buffered += len(T)
            if not more and self.buffered >= self.BATCH and not self.held:
                self._scan_buffer()

    def settle(self) -> None:
        """Scan the buffer if it is full (after rows added with `more`, or held)."""
        self.held = False
        if self.buffered >= self.BATCH:
            self._scan_buffer()

    def _gather(self) -> None:
        """Single rows become one part (their modes and memory kept per row)."""
        if self.single:
            rows, self.single = self.single, []
            values = np.array([r[1] for r in rows], dtype=float)[:, self.columns]
            self.parts.append((np.array([r[0] for r in rows]), values,
                               np.array([r[2] for r in rows], dtype=float),
                               [r[3] for r in rows], [r[4] for r in rows]))

    def _state(self, i: int) -> Bracket:
        """Row i (in time order) of the buffered parts, as the start of a bracket."""
        if self._order is not None:
            i = int(self._order[i])
        starts = self._starts
        k = int(np.searchsorted(starts, i, side="right")) - 1
        T, _, Y, m, z = self.parts[k]
        j = i - starts[k]
        many = isinstance(m, list)
        modes = tuple(m[j].tolist()) if isinstance(m, np.ndarray) else m[j] if many else m
        return Bracket(float(T[j]), math.nan, np.array(Y[j], float), modes,
                       z[j] if many else z)

    def _scan_buffer(self) -> None:
        """Scan the buffered rows; keep the last two (their neighbours come later)."""
        self._gather()
        if not self.parts:
            return
        ts = np.concatenate([p[0] for p in self.parts])
        vs = np.vstack([p[1] for p in self.parts])
        self._starts = np.cumsum([0] + [len(p[0]) for p in self.parts])
        if len(ts) > 1 and (np.diff(ts) < 0).any():
            # samples come as parts of their own, after the rows around them
            self._order = np.argsort(ts, kind="stable")
            ts, vs = ts[self._order], vs[self._order]
        self._scan(ts, vs)
        keep = max(0, len(ts) - 2)
        tail = [self._state(i) for i in range(keep, len(ts))]
        self.parts = [(ts[keep:], vs[keep:], np.array([b.y for b in tail]),
                       [b.m for b in tail], [b.z for b in tail])]
        self._starts = np.array([0, len(tail)])
        self._order = None
        self.buffered = len(tail)

    def _scan(self, ts: np.ndarray, vs: np.ndarray) -> None:
        """Offer the local maxima and minima of every variable that are not at an
        end (those wait for their next row), and the run's first row."""
        n, nv = vs.shape
        cols = np.arange(nv)
        hi, lo = vs, vs
        if not np.isfinite(vs).all():
            hi, lo = np.where(np.isnan(vs), -np.inf, vs), np.where(np.isnan(vs), np.inf, vs)
        for j, i in ((cols, hi.argmax(axis=0)), (cols + nv, lo.argmin(axis=0))):
            v = vs[i, cols] if j[0] == 0 else -vs[i, cols]
            better = v > self.best[j]
            self.best[j[better]] = v[better]
            self.best_t[j[better]] = ts[i[better]]
        if not self.started and n >= 2:
            self.started = True
            first = self._state(0)
            for j in range(2 * nv):
                v0, v1 = (vs[0, j], vs[1, j]) if j < nv else (-vs[0, j - nv], -vs[1, j - nv])
                if v0 >= v1:
                    self._offer(j, Candidate(float(v0), float(ts[0]), float(v0),
                                             replace(first, tb=float(ts[1])), first))
        if n < 3:
            return
        a, b, c = vs[:-2], vs[1:-1], vs[2:]
        for mask, sign, shift in (((b >= a) & (b >= c), 1.0, 0), ((b <= a) & (b <= c), -1.0, nv)):
            for j in np.flatnonzero(mask.any(axis=0)):
                self._peaks(int(j) + shift, ts, sign * vs[:, j], np.flatnonzero(mask[:, j]) + 1)

    def _peaks(self, j: int, ts: np.ndarray, v: np.ndarray, mid: np.ndarray) -> None:
        """Offer the best of the local maxima `mid` of column j (values v)."""
        kept = self.candidates[j]
        floor = max(kept[-1].score if len(kept) >= self.KEEP else -math.inf, self.best[j])
        # A parabola through three rows rises above its middle one by at most the
        # middle one's rise over the lower neighbour (for equal spacing, a quarter of
        # it): rows that cannot reach the best sampled value need no vertex.
        rise = v[mid] - np.minimum(v[mid - 1], v[mid + 1])
        mid = mid[v[mid] + 2.0 * rise >= floor]
        if not mid.size:
            return
        scores, times = vertices(ts, v, mid)
        good = np.flatnonzero(scores > floor)
        for g in good[np.argsort(-scores[good])][:self.KEEP]:
            i = int(mid[g])
            self._offer(j, Candidate(float(scores[g]), float(times[g]), float(v[i]),
                                     replace(self._state(i - 1), tb=float(ts[i + 1])),
                                     middle=replace(self._state(i), tb=float(ts[i + 1]))))

    def _offer(self, j: int, c: Candidate) -> None:
        kept = self.candidates[j]
        if not math.isfinite(c.score) or (len(kept) >= self.KEEP and c.score <= kept[-1].score):
            return
        kept.append(c)
        kept.sort(key=lambda k: -k.score)
        del kept[self.KEEP:]

    def wanted(self) -> tuple[list[tuple[float, float]], float]:
        """Where a restart may still be wanted: inside the brackets of the candidates
        kept (`peaks.locate_range` integrates them again piece by piece), and after
        the first row not yet scanned (brackets to come start there or later)."""
        spans = [(c.bracket.ta, c.bracket.tb) for kept in self.candidates for c in kept]
        firsts = [float(p[0].min()) for p in self.parts if len(p[0])]
        firsts += [r[0] for r in self.single[:1]]
        return spans, min(firsts, default=math.inf if self.started else -math.inf)

    def close(self) -> None:
        """Scan what is left; the last row is a candidate too when it is the larger
        of the last two."""
        self._scan_buffer()
        if not self.parts or len(self.parts[0][0]) < 2:
            return
        ts, vs = self.parts[0][0], self.parts[0][1]
        before, last = self._state(len(ts) - 2), self._state(len(ts) - 1)
        v = np.concatenate([vs[-2:], -vs[-2:]], axis=1)
        for j in np.flatnonzero(v[1] >= v[0]):
            self._offer(j, Candidate(float(v[1, j]), float(ts[-1]), float(v[1, j]),
                                     replace(before, tb=float(ts[-1])),
                                     replace(last, tb=float(ts[-1]))))

    def sampled(self) -> dict[str, tuple[float, float, float, float]]:
        """name -> (min, time, max, time) over the rows."""
        n = len(self.names)
        return {name: (float(-self.best[n + j]), float(self.best_t[n + j]),
                       float(self.best[j]), float(self.best_t[j]))
                for j, name in enumerate(self.names)}


def column(v, n: int) -> np.ndarray:
    """A vector function's result as n values (a constant comes back as a float)."""
    if isinstance(v, np.ndarray) and v.shape == (n,):
        return v
    return np.full(n, float(v))


def output_table(outs, n: int) -> np.ndarray:
    """The vector output functions' results over n rows as an (n, outputs) table."""
    return np.column_stack([column(v, n) for v in outs]) if outs else np.empty((n, 0))


def vertices(t: np.ndarray, v: np.ndarray, mid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each row i in mid, the largest value within [t[i-1], t[i+1]] of the
    parabola through rows i-1, i, i+1, and where it is."""
    t0, t1, t2 = t[mid - 1], t[mid], t[mid + 1]
    v0, v1, v2 = v[mid - 1], v[mid], v[mid + 1]
    with np.errstate(all="ignore"):
        d1 = (v1 - v0) / (t1 - t0)
        a = ((v2 - v1) / (t2 - t1) - d1) / (t2 - t0)
        ts = np.clip(0.5 * (t0 + t1) - d1 / (2.0 * a), t0, t2)
        top = v0 + d1 * (ts - t0) + a * (ts - t0) * (ts - t1)
    use = (a < 0.0) & (top > v1)
    return np.where(use, top, v1), np.where(use, ts, t1)



def close_to(t, instant: float):
    """Whether t (a float or an array) is `instant` to 1e-12 relative: a grid row
    printed at its grid instant, the row held for an instant of the caller's."""
    return np.abs(np.asarray(t) - instant) <= 1e-12 * np.maximum(np.abs(t), 1e-300)

class Recorder:
    """The rows of one run, and the `Run` made of them."""

    def __init__(self, plan: RunPlan, c: ModelCode, watch: SurfaceWatch,
                 range_names: list[str], range_from: float | None = None,
                 sink=None) -> None:
        self.plan = plan
        self.c = c
        self.watch = watch
        self.times = plan.grid.times
        # `sink`: where the rows are streamed as the run goes (output/stream.py's
        # CsvStream, begun by the caller), keeping in memory what it says
        self.sink = sink
        # (a run kept whole is planned to keep a row an instant of its grid; a streamed
        # one keeps its PRDEL rows, how many is found as it goes)
        self.rows = Rows(len(c.out_names), self._stream if sink is not None else None,
                         len(plan.grid.times) + 1 if sink is None else Rows.BATCH)
        self.out_i = 0  # the next grid instant to record
        # an instant whose row the caller takes itself, after its events (ACSL form)
        self.hold: float | None = None
        index = {n: i for i, n in enumerate(c.out_names)}
        states = {n: i for i, n in enumerate(c.state_names)}
        # (column, state) of the printed states: a row whose outputs fault still
        # shows them, they were integrated
        self._state_columns = [(index[n], states[n]) for n in c.out_names if n in states]
        named = [n for n in dict.fromkeys(range_names) if n in index]
        self.extrema = Extrema(named, [index[n] for n in named])
        # the state after every restart, where a RANGE variable may have a kink
        self.restarts = RestartStates()
        self._forget_at = FORGET_FROM
        # rows before this TIME are not searched (a sweep's settling time); the
        # first row after it is then an end of the searched window, like a run's start
        self.range_from = range_from
        # the first fault of a variable in a row (shown as NaN there), for a warning
        self.output_fault: str | None = None

    @property
    def last_t(self) -> float | None:
        return self.rows.last_t

    def outputs(self, t: float, y: np.ndarray, m, z) -> list[float]:
        try:
            return self.watch.outputs(t, y, m, z)
        except (ArithmeticError, ValueError) as exc:
            # a variable that cannot be computed here (a division by zero the run
            # stops on, or in a variable the derivatives do not read) is NaN; the
            # states are what they are
            if self.output_fault is None:
                text = str(self.c.explain_fault(exc, t, list(y), m, z) or exc)
                self.output_fault = text if "TIME =" in text else f"{text} at TIME = {t:.9g}"
            try:  # (each statement that faults NaN, and no other)
                values = [float(v) for v in self.c.outputs_tolerant(t, y.tolist(), m, z)]
            except (ArithmeticError, ValueError):
                values = [math.nan] * len(self.c.out_names)
            for j, i in self._state_columns:
                values[j] = float(y[i])
            return values

    def output_rows(self, T: np.ndarray, Y: np.ndarray, M, z) -> np.ndarray:
        """The output table of rows (TIME T, states Y, each row's modes M) one row at
        a time: where the code over all rows at once meets a fault, the rows before
        it and after it are still right, and the variables that fault are NaN."""
        return np.array([self.outputs(float(t), y, list(m), z)
                         for t, y, m in zip(T, Y, M, strict=True)]).reshape(
                             len(T), len(self.c.out_names))

    def shown_modes(self, t: float, y: np.ndarray, m, z) -> list[float]:
        """At a switching instant a row shows the branch in force from then on; a
        sign surface exactly at zero shows its X = 0 branch (FSW's B), as the
        function is defined there (`SurfaceWatch.at_zero`)."""
        return self.watch.at_zero(t, y, m, z)

    def row(self, t: float, y: np.ndarray, m, z, g: int = -1, shown=None) -> None:
        """One row at t (grid instant g, or -1), in modes m (shown: as displayed)."""
        if g >= 0 and close_to(t, self.times[g]):
            t = float(self.times[g])  # print the grid instant, not a float next to it
        values = self.outputs(t, y, m if shown is None else shown, z)
        self.rows.add(t, g, values)
        if self.range_from is None or t >= self.range_from:
            self.extrema.add(t, values, y, m, z)

    def restarted(self, t: float, y: np.ndarray, m, z) -> None:
        """The run restarts at t in modes m (kept when there is RANGE to locate)."""
        if self.extrema.names:
            self.restarts.add(t, y, m, z)
            if len(self.restarts) >= self._forget_at:  # (a long run restarts 10^5 times)
                self.restarts.keep(*self.extrema.wanted())
                self._forget_at = max(FORGET_FROM, 2 * len(self.restarts))

    def retake(self, t: float, y: np.ndarray, m, z) -> None:
        """The row just taken at a grid instant a float from t, again in the values at
        t (code ran there after it: a crossing located a float past the instant)."""
        last = self.last_t
        if last is not None and self.out_i > 0 and close_to(t, self.times[self.out_i - 1]) \
                and close_to(last, self.times[self.out_i - 1]):
            self.rows.replace_last(self.outputs(last, y, m, z))

    def grid_row(self, t: float, y: np.ndarray, m, z, shown=None) -> bool:
        """The row of the next grid instant (none at the instant held for the caller:
        False)."""
        if self.hold is not None and close_to(t, self.hold):
            return False
        self.row(t, y, m, z, self.out_i, shown)
        self.out_i += 1
        return True

    def block(self, T: np.ndarray, Y: np.ndarray, table: np.ndarray, m, z,
              samples: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        """Rows for the next len(T) grid instants at once (m: their modes, or an
        array of each row's); `samples`: the integrator's step ends among them (TIME,
        states; modes m), which RANGE reads with the rows."""
        n = len(T)
        self.rows.add_block(T, np.arange(self.out_i, self.out_i + n), table)
        self.out_i += n
        if not self.extrema.names:
            return
        more = samples is not None and len(samples[0]) > 0 and not isinstance(m, np.ndarray)
        if self.range_from is None:
            self.extrema.add_many(T, table, Y, m, z, more)
        else:
            keep = T >= self.range_from
            self.extrema.add_many(T[keep], table[keep], Y[keep],
                                  m[keep] if isinstance(m, np.ndarray) else m, z, more)
        if more:
            self._samples(T, m, z, *samples)

    def _samples(self, T: np.ndarray, m, z, S: np.ndarray, SY: np.ndarray,
                 every: bool = False) -> None:
        """The samples among rows T, for RANGE (after the rows: `Extrema` puts them in
        time order). Rows alone find a variable's turn wherever it turns at most once
        between two of them, which it does where no two steps end between them: only
        the samples of the other row intervals are needed (`every`: all of them)."""
        if not every:
            cut = np.searchsorted(S, T)
            counts = np.diff(np.concatenate([[0], cut, [len(S)]]))
            keep = np.repeat(counts >= 2, counts)
            S, SY = S[keep], SY[keep]
        if self.range_from is not None:
            S, SY = S[S >= self.range_from], SY[S >= self.range_from]
        if not len(S):
            self.extrema.settle()
            return
        # (a switch only printed, which the loop follows at step ends without a
        # restart, as it stands at each sample: in m, ABS(SIN(3 T) - 0.2) read -0.799)
        modes = self.watch.standing(S, SY, m, z)
        with np.errstate(all="ignore"):
            outs = self.c.out_v(S, list(SY.T), m if modes is None else modes, z)
        table = np.zeros((len(S), len(outs)))
        for j in self.extrema.columns:
            table[:, j] = column(outs[j], len(S))
        self.extrema.add_many(S, table, SY, m, z)

    def sample(self, t: float, y: np.ndarray, m, z) -> None:
        """A point of the trajectory that is no row (a step's end): RANGE reads it."""
        if self.extrema.names and (self.range_from is None or t >= self.range_from):
            self.extrema.add(t, self.outputs(t, y, m, z), y, m, z)

    def samples_with_modes(self, S: np.ndarray, SY: np.ndarray, SM: np.ndarray, z) -> None:
        """Samples each in its own branches (the compiled kernel's step ends)."""
        if not self.extrema.names:
            return
        if self.range_from is not None:
            keep = S >= self.range_from
            S, SY, SM = S[keep], SY[keep], SM[keep]
        for mode in np.unique(SM, axis=0):
            rows = (SM == mode).all(axis=1)
            self._samples(S[rows], mode.tolist(), z, S[rows], SY[rows], every=True)

    def samples(self, S: np.ndarray, SY: np.ndarray, m, z) -> None:
        """Several such points, in order, in the branches m."""
        if self.extrema.names and len(S):
            self._samples(S, m, z, S, SY, every=True)

    def _stream(self, t: np.ndarray, g: np.ndarray, v: np.ndarray, final: bool) -> np.ndarray:
        # (the plan's grid as it is now: the ACSL form's CINT may change it in the run)
        outdel, prdel = self.plan.grid.masks(g)
        return self.sink.part(t, g, list(v.T), outdel, prdel, final)

    def run(self, spec, constants: dict[str, float], events: list[Event], status: Status,
            message: str, warnings: list[str], stats: dict, t: float, y: np.ndarray, z, m,
            terminal: dict[str, float], extrema: dict[str, tuple]) -> Run:
        names = self.c.out_names
        grid = self.plan.grid
        times, g, columns = self.rows.take()
        values = dict(zip(names, columns, strict=True))
        outdel_mask, prdel_mask = grid.masks(g)
        if len(g):
            # the stop instant (FINISH, TERMT, failure) is always shown
            outdel_mask[-1] = prdel_mask[-1] = True
        final = {k: float(v) for k, v in constants.items() if k not in RESERVED}
        final.update({n: float(v[-1]) for n, v in values.items()} if len(times) else {})
        for i, n in enumerate(self.c.state_names):
            if "#" not in n:
                final[n] = float(y[i])
        final.update(terminal)
        plan = self.plan
        return Run(
            label=spec.label, params=dict(spec.data), constants=dict(constants),
            times=times, values=values, outdel_mask=outdel_mask, prdel_mask=prdel_mask,
            events=events, status=status, message=message, final=final, stats=stats,
            method=plan.method, rtol=plan.tol.relerr, atol=plan.tol.abserr,
            settings=plan.settings, titles=list(spec.titles), reports=list(spec.reports),
            warnings=warnings, t_end=float(t), terminal=dict(terminal), extrema=extrema,
            final_state={"t": float(t), "y": y.tolist(), "z": list(z), "m": list(m)},
        )
