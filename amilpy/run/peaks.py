"""RANGE: each variable's minimum and maximum located between the output instants.

`record.Extrema` points, from the rows, to where each extremum may lie. Here a
candidate whose parabola through three rows differs from the middle row by less
than 1E-9 of the variable's size is taken at the vertex: the parabola's own
error is smaller than that by the ratio of the output interval to the variable's
time scale. The first or the last row is the extremum itself unless the
variable's rate there points into the run. Any other candidate (a coarse OUTDEL,
a kink at a switch) is located on the integrator's dense output: the rate at the
middle row says on which side of it the turn is, and that interval is integrated
again from the row where it starts:

- on the AUTO route, when no switch, breakpoint or slide can come into it, by
  `odeint` itself, whose values at requested instants are its own interpolation
  (`_sampled`): 33 instants, then 33 around the best, and the parabola through
  the best three (1/512 of an output interval apart); on the COMPILED route the
  same way by its kernel, whose rows are its own dense output;
- otherwise through the run loop (events, slides and all) with the route's dense
  output, and the turn is solved for like a switch (`turns`: Brent's method on
  the sign change of the rate, which also closes in on a kink).

An interval that cannot be integrated again keeps the rows' values.
"""

from __future__ import annotations

import math
import warnings
from bisect import bisect_left
from dataclasses import dataclass, replace

import numpy as np

from .. import ir
from ..codegen import ModelCode
from ..steppers import solver_tolerance
from .fastpaths import kernel_arguments
from .loop import Cursor, Integrator, Stop
from .plan import Options, RunPlan, sliding_in
from .record import Bracket, Extrema, RestartStates, column, vertices
from .watch import SurfaceWatch, TooManySlides

SAMPLES = 33  # instants per zoom level on the AUTO route
_EPS = float(np.finfo(float).eps)
LEVELS = 2


@dataclass(frozen=True)
class Context:
    """What locating needs of a run."""

    model: ir.Model
    plan: RunPlan
    c: ModelCode
    watch: SurfaceWatch
    opts: Options
    started: float  # the run's start, for its wall-clock limit


def locate_range(ctx: Context, extrema: Extrema, restarts: RestartStates
                 ) -> dict[str, tuple[float, float, float, float]]:
    """name -> (min, time, max, time) for every RANGE variable (see the module);
    `restarts`: the states where the run restarted, in time order."""
    extrema.close()
    n = len(extrema.names)
    found = {name: list(v) for name, v in extrema.sampled().items()}
    todo: dict[tuple[float, float], tuple[Bracket, set[tuple[int, bool]]]] = {}
    for j, kept in enumerate(extrema.candidates):
        col, top = j % n, j < n
        name, out = extrema.names[col], extrema.columns[col]
        size = max(abs(extrema.best[col]), abs(extrema.best[n + col]), 1e-300)
        for c in kept:
            if c.score < extrema.best[j]:
                continue
            if c.edge is not None:
                at_start = c.edge.ta == c.bracket.ta
                rate = _rate(ctx, c.edge, out, c.bracket.tb - c.bracket.ta)
                inward = rate is not None and (rate > 0 if top else rate < 0) == at_start
                interval = c.bracket if inward else None
            elif c.score - c.sample <= 1e-9 * size:
                _better(found[name], top, c.score if top else -c.score, c.t)
                continue
            else:
                rate = _rate(ctx, c.middle, out, c.bracket.tb - c.bracket.ta)
                if rate is None or rate == 0.0:
                    continue  # the middle row is the extremum (or nothing better is known)
                rising = (rate > 0) == top
                interval = c.middle if rising else replace(c.bracket, tb=c.middle.ta)
            if interval is not None:
                todo.setdefault((interval.ta, interval.tb), (interval, set()))[1].add((col, top))
    for b, wanted in todo.values():
        columns = [(extrema.names[k], extrema.columns[k], top) for k, top in sorted(wanted)]
        # between the restarts inside (a switch, a breakpoint: a kink may be the
        # extremum) nothing switches, so each piece may be sampled as it is
        inside = restarts.between(b.ta, b.tb)
        starts = [b] + inside
        ends = [r.ta for r in inside] + [b.tb]
        if not all(_sampled(ctx, replace(s, tb=e), columns, found)
                   for s, e in zip(starts, ends, strict=True) if e > s.ta):
            _integrated(ctx, b, columns, found)
    return {name: tuple(v) for name, v in found.items()}


def _better(best: list[float], top: bool, v: float, t: float) -> None:
    """Keep v at t if it is a lower minimum (top False) or a higher maximum."""
    if top and v > best[2]:
        best[2], best[3] = v, t
    elif not top and v < best[0]:
        best[0], best[1] = v, t


def _rate(ctx: Context, at: Bracket, col: int, span: float) -> float | None:
    """d/dt of output `col` along the flow at the row `at` (by a difference)."""
    m, z = list(at.m), list(at.z)
    try:
        y = np.asarray(at.y, float)
        f = np.asarray(ctx.watch.field(at.ta, y, m, z), float)
        # (a switch only printed is read as it stands: a row a batch of steps
        # recorded keeps the batch's branch of it, and its rate had the wrong sign)
        m = ctx.watch.as_they_are(at.ta, y, m, z)
        # (a bracket between two points at one TIME, a sample and a row: the rate there)
        d = 1e-7 * span if span > 0 else 1e-13 * max(abs(at.ta), 1e-300)
        v0 = ctx.watch.outputs(at.ta, y, m, z)[col]
        v1 = ctx.watch.outputs(at.ta + d, y + d * f, m, z)[col]
    except (ArithmeticError, ValueError, TooManySlides):
        return None
    rate = (v1 - v0) / d
    return rate if math.isfinite(rate) else None


def _sampled(ctx: Context, b: Bracket, columns: list[tuple[str, int, bool]], found: dict
             ) -> bool:
    """AUTO and COMPILED, on an interval no switch can come into: the integrator's
    values at fine instants, zoomed once. False when this way does not apply."""
    c, plan, m, z = ctx.c, ctx.plan, list(b.m), list(b.z)
    if sliding_in(m) or any(b.ta < t < b.tb for t in plan.breakpoints) or \
            any(b.ta < t < b.tb for t in c.memory_times(z, b.ta)):
        return False
    integrate = _by_odeint(ctx, m, z) if plan.chunked else _by_kernel(ctx, m, z)
    if integrate is None:
        return False

    def sample(ts: np.ndarray, y0: np.ndarray) -> tuple[np.ndarray, list] | None:
        """States and outputs at ts, integrated from y0 at ts[0]."""
        try:
            ys = integrate(ts, y0)
        except (ArithmeticError, ValueError):
            return None
        if ys is None or not np.isfinite(ys).all():
            return None
        # (a switch inside, even one the derivatives do not see: its kink may be the
        # extremum, which a parabola through samples misses; the loop's way solves
        # for it)
        modes = ctx.watch.standing(ts, ys, m, z)
        if modes is None or any(isinstance(v, np.ndarray) for v in modes):
            return None
        with np.errstate(all="ignore"):
            return ys, [column(v, len(ts)) for v in c.out_v(ts, list(ys.T), modes, z)]

    ts = np.linspace(b.ta, b.tb, SAMPLES)
    first = sample(ts, b.y)
    if first is None:
        return False
    for name, col, top in columns:
        window, (ys, outs) = ts, first
        for level in range(LEVELS):
            v = outs[col] if top else -outs[col]
            i = int(np.argmax(v))
            if level == LEVELS - 1:
                break
            # around the best instant (beside it, when it is an end: the rate
            # said the turn is in this interval, so it may lie just inside)
            lo, hi = max(i - 1, 0), min(i + 1, len(window) - 1)
            window, start = np.linspace(window[lo], window[hi], SAMPLES), ys[lo]
            zoomed = sample(window, start)
            if zoomed is None:
                return False
            ys, outs = zoomed
        peak, t = float(v[i]), float(window[i])
        if 0 < i < len(window) - 1:
            peak_v, peak_t = vertices(window, v, np.array([i]))
            peak, t = float(peak_v[0]), float(peak_t[0])
        _better(found[name], top, peak if top else -peak, t)
    return True


def _by_odeint(ctx: Context, m, z):
    """AUTO: odeint from y0 through ts (its rows, ts[0]'s included), or None."""
    from scipy.integrate import odeint

    rhs, plan = ctx.c.rhs, ctx.plan

    def f(t, y):
        return rhs(t, y.tolist(), m, z)

    options = {"rtol": solver_tolerance(plan.tol.rtol), "atol": solver_tolerance(plan.tol.atol),
               "tfirst": True, "full_output": True, "mxstep": 100_000}

    def integrate(ts: np.ndarray, y0: np.ndarray) -> np.ndarray | None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ys, info = odeint(f, y0, ts, **options)
        return ys if info["message"] == "Integration successful." else None
    return integrate


def _by_kernel(ctx: Context, m, z):
    """COMPILED: its kernel from y0 through ts, every crossing left to the loop (a
    crossing inside gives None), or None when the route is not compiled."""
    c, plan = ctx.c, ctx.plan
    if plan.route.stepper != "compiled" or c.memory_every_step:
        return None
    from ..compiled import kernel_for
    from ..steppers.compiled import KernelStepper

    kernel = kernel_for(c)
    if isinstance(kernel, str):
        return None
    arguments = kernel_arguments(kernel, c, plan, m, z, plain=False, follow=False)
    arguments.pop("kernel")

    def integrate(ts: np.ndarray, y0: np.ndarray) -> np.ndarray | None:
        stepper = KernelStepper(kernel, None, float(ts[0]), y0, float(ts[-1]),
                                rtol=plan.tol.rtol, atol=plan.tol.atol, max_step=plan.max_step,
                                first_step=None, max_steps=100_000, **arguments)
        ys = np.empty((len(ts), len(y0)))
        ys[0], n = y0, 1
        while not stepper.done:
            got = stepper.advance(m, z, ts, n)
            ys[n:n + len(got.T)] = got.Y
            n += len(got.T)
        if stepper.step() is not None or stepper.fallback is not None or stepper.t < ts[-1]:
            return None  # a failure, or a crossing the loop must see
        at = stepper.interpolant()
        for i in range(n, len(ts)):
            ys[i] = at(float(ts[i]))
        return ys
    return integrate


def _integrated(ctx: Context, b: Bracket, columns: list[tuple[str, int, bool]],
                found: dict) -> None:
    """Run the interval again through the loop with its dense output, and find its
    variables' turns there."""
    plan, watch = ctx.plan, ctx.watch
    pieces: list[tuple] = []
    integ = Integrator(ctx.model, plan, ctx.c, watch, ctx.opts, ctx.started)
    integ.first_step((b.tb - b.ta) / 8)
    try:
        integ.integrate(Cursor(b.ta, b.y.copy(), list(b.m), list(b.z)),
                        min(b.tb, plan.fintim), observer=lambda *p: pieces.append(p))
    except (Stop, ArithmeticError, ValueError, TooManySlides):
        return
    if not pieces:
        return
    ends = [p[1] for p in pieces]
    cache: dict[float, list[float]] = {}

    def values(t: float) -> list[float]:
        if t not in cache:
            _, _, interp, m, z = pieces[min(bisect_left(ends, t), len(pieces) - 1)]
            try:
                y = np.asarray(interp(t), float)
                cache[t] = watch.outputs(t, y, watch.as_they_are(t, y, m, z), z)
            except (ArithmeticError, ValueError):
                cache[t] = [math.nan] * len(ctx.c.out_names)
        return cache[t]

    for name, col, top in columns:
        for t, v in turns(lambda t, col=col: values(t)[col], pieces[0][0], ends[-1], 2):
            _better(found[name], top, v, t)


def turns(value, ta: float, tb: float, points: int = 3) -> list[tuple[float, float]]:
    """Candidate (time, value) pairs for the extrema of `value(t)` on [ta, tb]: the
    ends and each turn of its rate between them, solved like a switch (Brent's
    method on the rate's sign change; the rate by differences of the dense
    output, one-sided at the ends), the rate first looked at on `points`
    instants. A kink (a switch there) is a turn too: the rate changes sign across
    it and Brent's method closes in on it."""
    from scipy.optimize import brentq

    out = [(ta, value(ta)), (tb, value(tb))]
    if not tb - ta > 64 * _EPS * max(abs(ta), abs(tb)):
        return out  # (a restart an ulp after a row: no room for a rate)
    # (a few ulps at least: a span of a few hundred ulps made the step round to 0)
    d = max(1e-7 * (tb - ta), 4 * _EPS * max(abs(ta), abs(tb)))

    def rate(t: float) -> float:
        lo, hi = max(t - d, ta), min(t + d, tb)
        return (value(hi) - value(lo)) / (hi - lo) if hi > lo else math.nan

    grid = np.linspace(ta, tb, points)
    r = [rate(float(t)) for t in grid]
    for i in range(points - 1):
        if not (math.isfinite(r[i]) and math.isfinite(r[i + 1])):
            continue
        if r[i] == 0.0:
            out.append((float(grid[i]), value(float(grid[i]))))
        elif r[i] * r[i + 1] < 0.0:
            # to 1E-12 of TIME: the value at a smooth turn is then exact to rounding
            t = brentq(rate, float(grid[i]), float(grid[i + 1]),
                       xtol=1e-12 * max(abs(tb), tb - ta), maxiter=100)
            out.append((t, value(t)))
    return out
