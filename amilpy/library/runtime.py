"""The run-time helpers generated code calls, on floats and (for the chunked paths)
elementwise on NumPy arrays.

These are the only callables generated code can reach besides the language's
mathematical functions (`library` lists both; `codegen` puts them in the code's
namespace under a leading underscore). Stdlib only at import: NumPy is imported
when the vector table is first asked for.
"""

from __future__ import annotations

import bisect
import functools
import hashlib
import math
from collections.abc import Callable
from statistics import NormalDist

from .surfaces import amod_at, level, level_edge, sign, slides

Table = tuple[tuple[float, ...], tuple[float, ...]]


# ----------------------------------------------------- Fortran meanings, no faults
def fortran_sign(a: float, b: float) -> float:
    return abs(a) if b >= 0.0 else -abs(a)


def fortran_aint(x: float) -> float:
    """Fortran AINT, truncation toward 0, in floats (numba compiles this as written:
    an integer there would wrap past 2**63, AINT(1E20) = -9.2E18)."""
    if x != x:
        raise ValueError("AINT of NaN")
    if x - x != 0.0:
        raise OverflowError("AINT of an infinity")
    return (x // 1.0 if x >= 0.0 else -((-x) // 1.0)) + 0.0


def fortran_nint(x: float) -> float:
    """Fortran NINT/ANINT: the nearest whole number, halves rounded away from 0
    (exact: |x| - floor(|x|) is computed without rounding)."""
    a = abs(x)
    n = math.floor(a)
    if a - n >= 0.5:
        n += 1
    return math.copysign(float(n), x)


def fortran_dim(x: float, y: float) -> float:
    """Fortran DIM: x - y if x > y, else 0 (the positive difference)."""
    return x - y if x > y else 0.0


def fortran_amod(a: float, b: float) -> float:
    """Fortran MOD: the remainder with the sign of a (NaN for b = 0)."""
    try:
        return math.fmod(a, b)
    except ValueError:
        return math.nan


def safe_exp(x: float) -> float:
    try:
        return math.exp(x)
    except OverflowError:
        return math.inf


def safe_pow(a: float, b: float) -> float:
    try:
        r = a**b
    except (OverflowError, ZeroDivisionError):
        return math.inf
    if isinstance(r, complex):
        return math.nan
    return r


def safe_sqrt(x: float) -> float:
    return math.sqrt(x) if x >= 0.0 else math.nan


def safe_log(x: float) -> float:
    if x > 0.0:
        return math.log(x)
    return -math.inf if x == 0.0 else math.nan


def safe_log10(x: float) -> float:
    if x > 0.0:
        return math.log10(x)
    return -math.inf if x == 0.0 else math.nan


def notnul(x: float) -> float:
    """NOTNUL: 1 for 0 (either sign), else x, so that y/NOTNUL(x) never divides by 0."""
    return 1.0 if x == 0.0 else x


def element(k: float, *xs: float) -> float:
    """ELEMENT(K, X1, ..., Xn): Xk, an array's element at a subscript known only as the
    run goes (parse/arrays.py); a K that is no whole number in 1..n is a fault."""
    i = int(k) if k == k and abs(k) < 2**31 else 0
    if i != k or not 1 <= i <= len(xs):
        raise HelperFault(f"a subscript {k:g} outside 1..{len(xs)} (ELEMENT)")
    return xs[i - 1]


def vector_element(np):
    def element_v(k, *xs):
        k = np.asarray(k, dtype=float)
        i = np.where(np.isfinite(k), k, 0.0)
        outside = np.ravel((i != k) | (i < 1) | (i > len(xs)))
        if outside.any():
            bad = float(np.ravel(k)[outside][0])
            raise HelperFault(f"a subscript {bad:g} outside 1..{len(xs)} (ELEMENT)")
        return np.choose(i.astype(int) - 1, np.broadcast_arrays(*xs))
    return element_v


def nan_on_domain(f: Callable[[float], float]) -> Callable[[float], float]:
    """f, with NaN instead of a ValueError/OverflowError (SINH, COSH)."""
    def g(x: float) -> float:
        try:
            return f(x)
        except (ValueError, OverflowError):
            return math.nan

    g.__name__ = f.__name__
    return g


# ------------------------------------------------------------------- tables
def _outside(table: Table, x: float) -> float | None:
    """A lookup's value where no interpolation is needed: NaN for NaN (never an
    index off the table), the end values outside it."""
    xs, ys = table
    if x != x:
        return math.nan
    if x <= xs[0]:
        return ys[0]
    if x >= xs[-1]:
        return ys[-1]
    return None


class DayTable:
    """One weather variable by day (FST's WEATHER): `values[d - first]` holds from
    TIME = d to d + 1; a missing value (NaN) read is an error naming the file and day
    (`missing[d]`)."""

    def __init__(self, first: int, values: tuple[float, ...], missing: dict[int, str]) -> None:
        self.first, self.values, self.missing = first, values, missing

    def __repr__(self) -> str:  # the cache keys of a run read it
        return f"DayTable({self.first}, {self.values!r})"


def weather_day(table: DayTable, x: float) -> float:
    """The value of the day floor(x)."""
    if x != x:
        return math.nan
    day = math.floor(x)
    k = day - table.first
    if 0 <= k < len(table.values) and table.values[k] == table.values[k]:
        return table.values[k]
    raise ValueError(table.missing.get(day, f"no weather for day {day} (TIME = {x:g})"))


def impl_fail(name: str, t: float, residual: float) -> None:
    """IMPL's loop did not converge (contract section 13): a fault naming Y."""
    from ..ir import IMPL_ITERATIONS

    raise ArithmeticError(f"IMPL for {name} did not converge in {IMPL_ITERATIONS} iterations "
                          f"at TIME = {t:.9g}: |FOFY - {name}| = {abs(residual):.3g}")


def afgen(table: Table, x: float) -> float:
    """Linear interpolation; the end values hold outside the table; NaN for NaN."""
    end = _outside(table, x)
    if end is not None:
        return end
    xs, ys = table
    i = bisect.bisect_right(xs, x) - 1
    x0, x1 = xs[i], xs[i + 1]
    return ys[i] + (ys[i + 1] - ys[i]) * (x - x0) / (x1 - x0)


def nlfgen(table: Table, x: float) -> float:
    """Three-point Lagrange interpolation; the end values hold outside the table;
    NaN for NaN."""
    end = _outside(table, x)
    if end is not None:
        return end
    xs, ys = table
    n = len(xs)
    if n < 3:
        return afgen(table, x)
    i = bisect.bisect_right(xs, x) - 1
    # the three points nearest x: i-1, i, i+1 (shifted inside the table)
    j = min(max(i - 1 if (x - xs[i]) < (xs[i + 1] - x) else i, 0), n - 3)
    x0, x1, x2 = xs[j], xs[j + 1], xs[j + 2]
    y0, y1, y2 = ys[j], ys[j + 1], ys[j + 2]
    return (y0 * (x - x1) * (x - x2) / ((x0 - x1) * (x0 - x2))
            + y1 * (x - x0) * (x - x2) / ((x1 - x0) * (x1 - x2))
            + y2 * (x - x0) * (x - x1) / ((x2 - x0) * (x2 - x1)))


class Extending(tuple):
    """A FUNCTION table read by LINT, which extends its end segments outside it: the
    table notes how far outside it was read, for the run's one warning."""

    def __new__(cls, name: str, table: Table) -> Extending:
        obj = super().__new__(cls, table)
        obj.name = name
        obj.reset()
        return obj

    def reset(self) -> None:
        self.low, self.high = math.inf, -math.inf  # the x read below / above the table

    def note(self, x: float) -> None:
        self.low, self.high = min(self.low, x), max(self.high, x)

    def warning(self) -> str | None:
        """The run's warning when the table was read outside, else None."""
        xs = self[0]
        outside = [f"down to {self.low:.6g}"] if self.low < xs[0] else []
        outside += [f"up to {self.high:.6g}"] if self.high > xs[-1] else []
        if not outside:
            return None
        return (f"LINT read table {self.name} outside its x range [{xs[0]:g}, {xs[-1]:g}] "
                f"({' and '.join(outside)}): the end segments were extended")


def lint(table: Extending, x: float) -> float:
    """Linear interpolation; outside the table the end segment is extended (and the
    table notes it); NaN for NaN."""
    xs, ys = table
    if x != x:
        return math.nan
    if x < xs[0] or x > xs[-1]:
        table.note(x)
    i = min(max(bisect.bisect_right(xs, x) - 1, 0), len(xs) - 2)
    return ys[i] + (ys[i + 1] - ys[i]) * (x - xs[i]) / (xs[i + 1] - xs[i])


def table_warnings(tables: dict) -> list[str]:
    """The warnings of the LINT tables a run read outside (and they start afresh)."""
    out = []
    for table in tables.values():
        if isinstance(table, Extending):
            text = table.warning()
            if text:
                out.append(text)
            table.reset()
    return out


# ------------------------------------------------------------- time switches
def pulse_on(t: float, tz: float, p: float, w: float) -> float:
    """The surface of PULSE(TZ, P, W): the time left in the pulse while it is on
    (> 0), minus the time to the next pulse while it is off (< 0).

    Its sign changes exactly at the instants TZ + k*P and (TZ + W) + k*P, computed
    as these very float expressions (the run's breakpoints are computed the same
    way), and nowhere else: at a breakpoint the sign is already the new one."""
    if t < tz:
        return t - tz
    k = math.floor((t - tz) / p)
    # the pulse that started last, by the breakpoints' own arithmetic
    while tz + (k + 1) * p <= t:
        k += 1
    while k > 0 and tz + k * p > t:
        k -= 1
    end = (tz + w) + k * p
    if t < end:
        return end - t
    return t - (tz + (k + 1) * p)


def impulse_step(t: float, start: float, period: float, delt: float) -> float:
    """IMPULS in step-point mode: 1.0 when an instant start + k*period (k >= 0) lies
    in (t - DELT, t], so each instant is seen at the first step point at or after
    it (to rounding), as a switch on TIME is; else 0.0. Integrated over the steps of
    any of the fixed-step methods, each instant weighs exactly DELT."""
    tol = 1e-9 * delt
    lo, hi = t - delt + tol, t + tol
    if period <= 0.0:
        return 1.0 if lo < start <= hi else 0.0
    k = max(0, math.ceil((lo - start) / period))
    if start + k * period <= lo:
        k += 1
    return 1.0 if start + k * period <= hi else 0.0


# ---------------------------------------------------------------- random streams
# GAUSS, UNIF, RNDGEN and OU draw a new value at t0 + k*h (h: one output interval, or
# DELT with a fixed step) and hold it until the next. Draw k of a call site is a pure
# function of (seed, call site, the call's own seed, k), so a run is reproducible bit
# for bit, a restart or a re-integration (RANGE, flows) draws the same numbers, and
# the sites are independent streams. Slots: the value, the next draw's instant (a
# wake-up for the loop), the index k of the draw held (-1: none yet), and t0.
NORMAL, UNIFORM, ORNSTEIN_UHLENBECK = 0.0, 1.0, 2.0
_UNIT = NormalDist()


def uniform_draw(seed: float, site: int, own: float, k: int) -> float:
    """Draw k of a stream, uniform on (0, 1): 53 bits of a BLAKE2b hash of its key."""
    key = f"{float(seed)!r}:{int(site)}:{float(own)!r}:{int(k)}".encode()
    bits = int.from_bytes(hashlib.blake2b(key, digest_size=8).digest(), "little") >> 11
    return (bits + 0.5) * 2.0**-53


def normal_draw(seed: float, site: int, own: float, k: int) -> float:
    """Draw k of a stream, standard normal (the inverse normal CDF of a uniform)."""
    return _UNIT.inv_cdf(uniform_draw(seed, site, own, k))


def draw(kind: float, t: float, hold: float, seed: float, site: float, own: float, z,
         o: int, a: float, b: float, c: float) -> list[float]:
    """The four slots of a random function after a step ending at t: unchanged until
    the next draw is due, then the draw of the interval t falls in. NORMAL: a + b*N;
    UNIFORM: a + (b - a)*U; ORNSTEIN_UHLENBECK (a = tc, b = mean, c = s): the exact
    transition over each interval from y(t0) = mean."""
    value, due, k, t0 = z[o], z[o + 1], int(z[o + 2]), z[o + 3]
    if k >= 0 and t < due:
        return [value, due, float(k), t0]
    if k < 0:
        t0, new = t, 0
    else:
        new = k + 1
        while t0 + (new + 1) * hold <= t:
            new += 1
    if kind == NORMAL:
        value = a + b * normal_draw(seed, site, own, new)
    elif kind == UNIFORM:
        value = a + (b - a) * uniform_draw(seed, site, own, new)
    elif k < 0:
        value = b
    else:
        decay = math.exp(-hold / a)
        spread = c * math.sqrt(-math.expm1(-2.0 * hold / a))
        for j in range(k + 1, new + 1):
            value = b + (value - b) * decay + spread * normal_draw(seed, site, own, j)
    return [value, t0 + (new + 1) * hold, float(new), t0]


# ------------------------------------------------------------ memory functions
def deriv(x: float, t: float, x1: float, t1: float, x2: float, t2: float,
          previous: float) -> float:
    """DERIV: dX/dt from the last two accepted points and the current one.

    Second order (exact for a quadratic in time) once two earlier points are
    known; a plain difference after a start; the last value at a step end.
    """
    if not t > t1:
        return previous
    if t2 < t1:
        return (x2 * (t - t1) / ((t2 - t1) * (t2 - t))
                + x1 * (t - t2) / ((t1 - t2) * (t1 - t))
                + x * ((t - t2) + (t - t1)) / ((t - t2) * (t - t1)))
    return (x - x1) / (t - t1)


def impulse_at(t: float, start: float, period: float) -> float:
    """1.0 when t is (to rounding) one of start + k*period, k >= 0; else 0.0."""
    if t < start - 1e-12 * max(1.0, abs(start)):
        return 0.0
    if period <= 0.0:
        return 1.0 if abs(t - start) <= 1e-12 * max(1.0, abs(t)) else 0.0
    k = round((t - start) / period)
    return 1.0 if abs(start + k * period - t) <= 1e-9 * max(period, abs(t) * 1e-3) else 0.0


# DELAY's store, both forms: X sampled every H (the spacing the call asks for: P/N for
# CSMP's DELAY(N, P, X), max(DMIN, TDL/NMX) for ACSL's DELAY(X, IC, TDL, NMX, DMIN)),
# kept as (t, X) pairs in a ring of K entries, read at t - delay by linear
# interpolation. The run loop takes every sampling instant inside an accepted step
# from its dense output (`ModelCode.sample`: X at (g, y(g))); a step's end is recorded
# by the memory update after the step, which also fills any instant the loop did not
# sample (step-point mode) on the straight line from the last point. Slots from `o`:
#   o: how many samples were taken (0: the store has not started)
#   o+1, o+2: t0 and X(t0), the first sample (CSMP's value before t0 + P)
#   o+3: the spacing H in force; o+4, o+5: its anchor (an instant and the number of
#        the sample due there): sample j is due at anchor + (j - number)*H
#   o+6: the next sampling instant (the loop reads it: `MemorySpec.samples`)
#   o+7, o+8: the newest point (t, X): a sample or a step's end
#   o+9 ...: the ring, sample j at o + 9 + 2*(j mod K) (its t, then its X)
_COUNT, _T0, _X0, _H, _ANCHOR_T, _ANCHOR_J, _NEXT, _TLAST, _XLAST, _RING = range(10)
DELAY_NEXT = _NEXT  # the slot the library names as the store's next sampling instant


def delay_clock(nslots: int) -> list[int]:
    """The slots of a store of `nslots` that hold instants and counts, not values of
    X: a data value that moves X moves none of them (the sampling instants are fixed
    by the spacing), so a tangent carries no row for them (`MemorySpec.clock`)."""
    ring = range(_RING, nslots, 2)  # (each sample's t; its X follows)
    return [_COUNT, _T0, _H, _ANCHOR_T, _ANCHOR_J, _NEXT, _TLAST, *ring]


def delay_knots(z, o: int, nslots: int, d: float, ta: float, tb: float) -> list[float]:
    """The instants in (ta, tb) at which a read d back passes one of the store's
    samples (at o, `nslots` slots): s + d for each sample s. The read is a straight
    line between two samples, so its slope jumps there. A step no longer than d
    (`ModelCode.step_limit`) takes no sample that lands inside it."""
    count, k = int(z[o + _COUNT]), (nslots - _RING) // 2
    ring = o + _RING
    out = []
    for j in range(max(0, count - k), count):
        t = z[ring + 2 * (j % k)] + d
        if ta < t < tb:
            out.append(t)
    return out


class HelperFault(ValueError):
    """A run-time helper's fault that says itself what is wrong (the fault report
    quotes it, with the statement, instead of the generated call)."""


class HistoryLost(HelperFault):
    """A DELAY read further back than its store holds (a TDL that grew beyond what
    NMX points DMIN apart cover): a fault, never a value made up. The store's update
    raises it too, so the run stops there even where only outputs read the value."""


def delay_init(k: float) -> list[float]:
    """The slots of a store of K samples that has not started (it starts at the
    first memory update, at t0)."""
    slots = [0.0] * (_RING + 2 * int(k))
    slots[_NEXT] = math.inf  # (nothing to sample before the start)
    return slots


def delay_store(t: float, h: float, d: float, x: float, z, o: int, k: float) -> list[float]:
    """The store after the trajectory reached (t, X) (a sampling instant or a step's
    end): every sampling instant since the newest point is recorded, on the straight
    line from it (exact at t itself), and (t, X) becomes the newest point. `h` is
    the spacing asked for now; a new one applies after the sample due next. `d` is
    the delay now: a past the ring no longer holds stops the run (`HistoryLost`)."""
    k = int(k)
    s = list(z[o:o + _RING + 2 * k])
    if not (h > 0.0 and h < math.inf):
        h = math.inf  # (a delay that is not positive: the read says so)
    if s[_COUNT] == 0.0:
        s[_COUNT], s[_T0], s[_X0], s[_H], s[_ANCHOR_T], s[_ANCHOR_J] = 1.0, t, x, h, t, 0.0
        s[_NEXT], s[_TLAST], s[_XLAST] = t + h, t, x
        s[_RING], s[_RING + 1] = t, x
        return s
    t_last, x_last = s[_TLAST], s[_XLAST]
    if not t > t_last:
        if t == t_last:
            s[_XLAST] = x  # (a restart: X in the new branches)
        return s
    count = int(s[_COUNT])
    # (a spacing that differs by rounding alone is the same: a tangent moves the store
    # and the delay it is asked for together, `ProgramTangent._along`)
    if h != s[_H] and not abs(h - s[_H]) <= 1e-12 * h:
        # a new spacing (ACSL's TDL/NMX as TDL changes) from the sample due next on
        due = s[_NEXT] if s[_NEXT] < math.inf else t_last + h
        s[_H], s[_ANCHOR_T], s[_ANCHOR_J], s[_NEXT] = h, due, float(count), due
    anchor, j0, nxt = s[_ANCHOR_T], s[_ANCHOR_J], s[_NEXT]
    if nxt <= t:
        # only the last K instants matter: skip those a long step would overwrite
        skip = int((t - nxt) / h) - k
        if skip > 0:
            count += skip
            nxt = anchor + (count - j0) * h
        dt = t - t_last
        while nxt <= t:
            i = _RING + 2 * (count % k)
            s[i], s[i + 1] = nxt, x_last + (x - x_last) * ((nxt - t_last) / dt)
            count += 1
            nxt = anchor + (count - j0) * h
        s[_COUNT], s[_NEXT] = float(count), nxt
    s[_TLAST], s[_XLAST] = t, x
    if count > k and t - d >= s[_T0]:
        oldest = s[_RING + 2 * (count % k)]
        if t - d < oldest:
            raise HistoryLost(_lost(t, t - d, k, oldest))
    return s


def _lost(t: float, s: float, k: int, oldest: float) -> str:
    return (f"at TIME = {t:.9g} it reads TIME - delay = {s:.9g}, older than the {k - 2} "
            f"points of its store keep (back to TIME = {oldest:.9g}); with a delay that "
            "grows, give DMIN so that NMX*DMIN covers the longest delay: "
            "DELAY(X, IC, TDL, NMX, DMIN)")


def delay(t: float, d: float, x: float, ic: float, held: float, z, o: int,
          k: float) -> float:
    """X(t - d) from the store: linear between the samples, then from the newest
    sample to the newest point and on to the current (t, X). Before the store's start
    (t - d < t0) IC, or X(t0) when `held` (CSMP); the current X (CSMP) or IC before
    the store has started. A delay that is negative, or a read older than the ring
    holds, is a fault that names the statement."""
    if not d >= 0.0:
        if d != d:
            return math.nan
        raise HelperFault(f"the delay must not be negative (got {d:.6g} at TIME = {t:.9g})")
    count = int(z[o + _COUNT])
    if count == 0:
        return x if held else ic
    s = t - d
    t_last, x_last = z[o + _TLAST], z[o + _XLAST]
    if not s >= z[o + _T0]:
        if s != s:
            return math.nan
        # (within a difference's step of t0 -- and of the delay -- on the history
        # branch, its first segment goes on; further back, IC: ACSL's switch is at
        # TIME = TDL, which is t0 + TDL only for a run from 0)
        if held or count > int(k) or \
                z[o + _T0] - s > _NEAR_START * max(abs(d), abs(t), 1.0):
            return z[o + _X0] if held else ic
        return _before_start(s, t, x, z, o, count, t_last, x_last)
    if s >= t_last:
        return x_last + (x - x_last) * ((s - t_last) / (t - t_last)) if t > t_last else x_last
    k = int(k)
    ring = o + _RING
    newest = count - 1
    i = ring + 2 * (newest % k)
    tn = z[i]
    if s >= tn:
        return z[i + 1] + (x_last - z[i + 1]) * ((s - tn) / (t_last - tn))
    oldest = max(0, count - k)
    if s < z[ring + 2 * (oldest % k)]:
        raise HistoryLost(_lost(t, s, k, z[ring + 2 * (oldest % k)]))
    # sample lo at or before s, hi after it: first a guess from the spacing (exact on
    # a regular grid), then halving
    lo, hi = oldest, newest
    h = z[o + _H]
    guess = newest - 1 - int((tn - s) / h) if h < math.inf else lo
    if lo <= guess < hi and z[ring + 2 * (guess % k)] <= s < z[ring + 2 * ((guess + 1) % k)]:
        lo, hi = guess, guess + 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if z[ring + 2 * (mid % k)] <= s:
            lo = mid
        else:
            hi = mid
    a, b = ring + 2 * (lo % k), ring + 2 * (hi % k)
    return z[a + 1] + (z[b + 1] - z[a + 1]) * ((s - z[a]) / (z[b] - z[a]))


_NEAR_START = 1e-4  # (of the delay: the Jacobian's and a tangent's difference steps, 6e-6)


def _before_start(s: float, t: float, x: float, z, o: int, count: int, t_last: float,
                  x_last: float) -> float:
    """ACSL's DELAY read a little before the store's start t0 on its history branch:
    the first segment, extended. That branch is taken where its switch (TIME - TDL - t0)
    says t - TDL has reached t0, so such a read is that instant's rounding or a
    difference's step in the delay (a TDL that reads a state: d XD/d X): IC there put
    a jump inside the branch, which a central difference across t0 halved into the
    Jacobian (1e-2 of d X/d TD0 after the turn)."""
    t0, x0 = z[o + _T0], z[o + _X0]
    if count >= 2:
        t1, x1 = z[o + _RING + 2], z[o + _RING + 3]
    elif t_last > t0:
        t1, x1 = t_last, x_last
    elif t > t0:
        t1, x1 = t, x
    else:
        return x0
    return x0 + (x1 - x0) * ((s - t0) / (t1 - t0))


# ------------------------------------------------- helpers of the generated code
def _where(c, a, b):
    return a if c else b


def _all(*v) -> bool:
    return all(v)


def _any(*v) -> bool:
    return any(v)


# name -> the callable; generated code reads it as `_NAME`
def loop_count(start: float, stop: float, step: float) -> int:
    """How many times FOR/DO i = start, stop, step runs (Fortran's trip count), at
    most language.MAX_LOOP."""
    from ..language import MAX_LOOP

    if step == 0.0:
        raise HelperFault(f"a FOR/DO loop from {start:g} to {stop:g} with step 0 never "
                          "ends: give its step a value that is not 0")
    n = math.floor((stop - start + step) / step)
    if n > MAX_LOOP:
        raise HelperFault(f"a FOR/DO loop of {n} iterations (at most {MAX_LOOP})")
    return max(0, int(n))


def loop_range(count: int) -> range:
    """The passes of a FOR/DO loop, `loop_count` of them. A count that could not be
    computed (NaN: the copy of the code that gives NaN for a fault and goes on, when
    the count's own statement faulted) is that fault again, not a TypeError."""
    if count != count:
        raise HelperFault("a FOR/DO loop whose count could not be computed")
    return range(count)


HELPERS: dict[str, Callable] = {
    "AFGEN": afgen, "NLFGEN": nlfgen, "DERIV": deriv, "IMPULS": impulse_at, "POW": safe_pow,
    "DELAY": delay, "DELAY_STORE": delay_store, "DELAY_INIT": delay_init,
    "LINT": lint, "PULSE_ON": pulse_on, "IMPULS_STEP": impulse_step, "DRAW": draw,
    "SGN": sign, "LEVEL": level, "LEDGE": level_edge, "AMODAT": amod_at, "WHERE": _where,
    "ALL": _all, "ANY": _any,
    "NITER": loop_count, "RANGE": loop_range,  # FOR/DO loops of procedural code
    "WDAY": weather_day, "IMPL_FAIL": impl_fail,
}


def _vector_level(np):
    def level_of(v):  # surfaces.level elementwise
        v = np.asarray(v, dtype=float)
        k = np.ceil(v - 0.5)
        return np.where(v <= k - 0.5, k - 1.0, np.where(v > k + 0.5, k + 1.0, k))
    return level_of


@functools.lru_cache(maxsize=1)
def vector_helpers() -> dict[str, Callable]:
    """HELPERS elementwise on NumPy arrays: the runner evaluates the generated surface
    and output functions over a whole chunk of output instants at once (the same
    code object, run with these in its namespace)."""
    import numpy as np

    def many(f):
        return lambda *args: functools.reduce(f, args)

    def each(f, **kw):
        return np.vectorize(f, otypes=[float], **kw)

    return {
        "AFGEN": lambda table, x: np.interp(x, table[0], table[1]),
        "NLFGEN": lambda table, x: each(lambda v: nlfgen(table, v))(x),
        "DERIV": each(deriv), "IMPULS": each(impulse_at), "POW": np.power,
        "DELAY": each(delay, excluded={5, 6, 7}),
        "LINT": lambda table, x: each(lambda v: lint(table, v))(x),
        "WDAY": lambda table, x: each(lambda v: weather_day(table, v))(x),
        "PULSE_ON": each(pulse_on), "IMPULS_STEP": each(impulse_step),
        "LEVEL": _vector_level(np), "SGN": np.sign,
        "LEDGE": lambda v, k: v - k if slides(k) else 0.5 - np.abs(v - k),
        "AMODAT": each(amod_at),
        "WHERE": np.where, "ALL": many(np.logical_and), "ANY": many(np.logical_or),
    }
