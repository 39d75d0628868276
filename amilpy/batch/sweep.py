"""Parameter sweeps: one run per value, optionally each continuing from the last.

With `carry_state` a run starts from the previous run's final state (states,
memory, branches) and TIME goes on, which is how an amplitude-frequency
characteristic with jumps is measured: sweeping up and then down, the system
stays on the branch it is on until that branch ends at a fold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..diagnostics import AmilError, UsageError, with_hint
from ..language import fortran_float, given_name
from ..progress import report
from ..result import Run


@dataclass(frozen=True)
class SweepPoint:
    value: float
    direction: str  # "up" or "down"
    minimum: float
    maximum: float
    status: str
    t_start: float
    t_end: float
    second: float | None = None  # a grid's second value at this point
    unsteady: float = math.nan  # `farm.unsteadiness`: how far from settled it was

    @property
    def amplitude(self) -> float:
        """Half the peak-to-peak of the measured variable after the settling time."""
        return 0.5 * (self.maximum - self.minimum)


JUMP_FACTOR = 5.0  # a jump misses both sides' trends by this many times their noise
SIDE = 3  # points each side of a jump whose trend it is set against
# the noise of a quadratic's extrapolation one step on, in units of the points' own:
# 3 a[k] - 3 a[k-1] + a[k-2] - a[k+1], sqrt(9 + 9 + 1 + 1)
EXTRAPOLATION_GAIN = math.sqrt(20.0)
# a point whose own window moved by this share of the step around it had not settled
# (the forced Duffing oscillator's point past its lower fold: 0.069 of 0.708)
HALFWAY = 0.05
NOISE_POINTS = 4  # a side's noise: the largest miss of this many of its own extrapolations


@dataclass(frozen=True)
class Jump:
    """A jump of the characteristic between two neighbouring values."""

    direction: str  # the sweep's: "up" or "down"
    start: float  # the value before the jump ...
    stop: float  # ... and after it
    before: float  # the amplitude at `start`
    after: float  # ... and at `stop`
    ratio: float  # how far it misses the trends of both sides, over their noise

    @property
    def rise(self) -> bool:
        return self.after > self.before


@dataclass
class Sweep:
    name: str
    measure: str
    settle: float
    points: list[SweepPoint] = field(default_factory=list)
    runs: list[Run] = field(default_factory=list)
    # with a carried state, the first point starts from the listing's initial state
    # (a transient) and every later one from a settled state: it is left out of
    # the jump search
    carry_state: bool = False
    second: str | None = None  # a grid: the second data value swept
    errors: list[str] = field(default_factory=list)  # points that could not run, why

    def along(self, direction: str, second: float | None = None) -> list[SweepPoint]:
        """The points of one direction (of one value of a grid's second data value)."""
        return [p for p in self.points if p.direction == direction and p.second == second]

    def branch(self, direction: str, second: float | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
        pts = self.along(direction, second)
        return (np.array([p.value for p in pts]), np.array([p.amplitude for p in pts]))

    def lines(self) -> list[tuple[str, np.ndarray, np.ndarray]]:
        """(label, values, amplitudes) of each curve: a direction swept, or for a grid
        each value of the second data value."""
        if self.second is None:
            return [(f"sweep {d}", *self.branch(d))
                    for d in dict.fromkeys(p.direction for p in self.points)]
        return [(f"{self.second} = {w:g}", *self.branch("up", w))
                for w in dict.fromkeys(p.second for p in self.points)]

    def jumps(self) -> dict[str, list[Jump]]:
        """For each direction swept (with enough points: SIDE on each side of a step),
        its jumps: the steps where the measured amplitude leaves the branch it was on
        (`jumps_along`). A grid has none (no one line to search along)."""
        out: dict[str, list[Jump]] = {}
        if self.second is not None:
            return out
        for direction in ("up", "down"):
            pts = self.along(direction)
            if direction == "up" and self.carry_state:
                pts = pts[1:]
            if len(pts) < 2 * SIDE:
                continue
            v = np.array([p.value for p in pts])
            a = np.array([p.amplitude for p in pts])
            u = np.array([p.unsteady for p in pts])
            out[direction] = [Jump(direction, float(v[i]), float(v[j]), float(a[i]),
                                   float(a[j]), ratio) for i, j, ratio in jumps_along(v, a, u)]
        return out


def _extrapolated(v: np.ndarray, a: np.ndarray, idx: list[int], x: float) -> float:
    """The quadratic through the points idx, at x."""
    (x0, x1, x2), (y0, y1, y2) = v[idx], a[idx]
    return float(y0 * (x - x1) * (x - x2) / ((x0 - x1) * (x0 - x2))
                 + y1 * (x - x0) * (x - x2) / ((x1 - x0) * (x1 - x2))
                 + y2 * (x - x0) * (x - x1) / ((x2 - x0) * (x2 - x1)))


def _side_noise(v: np.ndarray, a: np.ndarray, u: np.ndarray, points: list[int],
                step: int) -> float | None:
    """How well a side's own trend predicts it: the largest error of extrapolating
    each of `points` from the three beyond it (step -1: those before, +1: after),
    and at least the points' unsteadiness carried through the extrapolation; None
    when neither is known (a side of SIDE points whose unsteadiness is not given)."""
    points = [j for j in points if 0 <= j < len(v)]
    errors = []
    for j in points:
        idx = [j + step, j + 2 * step, j + 3 * step]
        if 0 <= min(idx) and max(idx) < len(v):
            errors.append(abs(a[j] - _extrapolated(v, a, idx, v[j])))
    spread = [x for x in u[points] if x == x]
    if not errors and not spread:
        return None
    return max(float(np.max(errors)) if errors else 0.0,
               EXTRAPOLATION_GAIN * float(np.max(spread)) if spread else 0.0)


def jumps_along(v: np.ndarray, a: np.ndarray, u: np.ndarray) -> list[tuple[int, int, float]]:
    """The jumps of amplitudes a at values v (u: each point's unsteadiness), as
    (first index, last index, ratio). A step k -> k+1 is a jump when a[k+1] misses
    the quadratic through the SIDE points up to k by JUMP_FACTOR times what that
    trend misses by one step further back (or the points' unsteadiness carried
    through, if larger), and a[k] likewise misses the trend of the SIDE points from
    k+1 on, read backwards. A point caught halfway (its run ended before the orbit
    had moved to the new branch, so its amplitude lies between the branches or its
    window moved by HALFWAY of the step) may stand between the two: the trend after
    the jump is then taken from the points after it; the jump is the step where the
    branch was left.
    Steep slopes and sharp bends are not jumps: their trend foretells them. A step
    with fewer than SIDE points on either side is not judged."""
    n = len(a)
    scale = float(np.max(np.abs(a))) if n else 0.0
    tiny = 1e-12 * scale + 1e-300
    found: list[tuple[int, int, float]] = []
    reached = -1  # the last point of the jump found last
    for k in range(SIDE - 1, n - SIDE):
        left = [k, k - 1, k - 2]
        noise = _side_noise(v, a, u, [k - i for i in range(NOISE_POINTS)], -1)
        if noise is None:
            continue
        miss = abs(a[k + 1] - _extrapolated(v, a, left, v[k + 1]))
        ratio_left = miss / max(noise, tiny)
        if ratio_left <= JUMP_FACTOR:
            continue
        best, last = 0.0, k + 1
        for skip in (0, 1):
            right = [k + 1 + skip, k + 2 + skip, k + 3 + skip]
            if right[-1] >= n:
                continue
            if skip and not (min(a[k], a[k + 2]) < a[k + 1] < max(a[k], a[k + 2]) or
                             u[k + 1] >= HALFWAY * abs(a[k + 2] - a[k])):
                continue  # (only a point halfway, or one still moving, is passed over)
            noise = _side_noise(v, a, u, [right[0] + i for i in range(NOISE_POINTS)], 1)
            if noise is None:
                continue
            ratio = abs(a[k] - _extrapolated(v, a, right, v[k])) / max(noise, tiny)
            if ratio > best:
                best, last = ratio, k + 1 + skip
        if best > JUMP_FACTOR and k > reached:  # (else the same jump, seen again)
            found.append((k, k + 1, min(ratio_left, best)))
            reached = last
    return found


MAX_POINTS = 100_000


def parse_range(text: str) -> tuple[str, list[float]]:
    """NAME=START:STOP:STEP -> (NAME, values), STOP included. A malformed range
    is an AmilError saying what to write (the command line makes it a usage error)."""
    try:
        name, spec = text.split("=", 1)
        start, stop, step = (fortran_float(x) for x in spec.split(":"))
    except ValueError:
        raise AmilError("write it NAME=START:STOP:STEP, e.g. W=60:80:0.5") from None
    if given_name(name) is None:
        raise AmilError(f"{name.strip()!r} is not a name (NAME=START:STOP:STEP)")
    if not all(math.isfinite(x) for x in (start, stop, step)):
        raise AmilError("START, STOP and STEP must be finite numbers")
    if step == 0 or (stop - start) / step < 0:
        raise AmilError(f"the step {step:g} does not lead from {start:g} to {stop:g}")
    count = (stop - start) / step
    if not count < MAX_POINTS:
        raise AmilError(f"the sweep has {count + 1:.3g} points (limit {MAX_POINTS})")
    n = int(math.floor(count + 1e-9))
    values = [round(start + k * step, 12) for k in range(n + 1)]
    return given_name(name), values


def default_measure(model) -> str:
    """The variable a sweep or an analysis measures when none is named: the first
    OUTPUT/PRINT variable of the first run, else the first variable (an ir.Model)."""
    named = [n for r in model.runs[0].reports if r.kind in ("OUTPUT", "PRINT")
             for n in r.names]
    if not named and not model.variables:
        raise UsageError("the listing has no variable to measure: give it an equation or "
                         "a state (and an OUTPUT or PRINT of it)")
    return named[0] if named else model.variables[0]


def sweep(model, name: str, values: list[float], *, both_ways: bool = False,
          carry_state: bool = False, settle: float = 0.0, measure: str | None = None,
          method: str | None = None, rtol: float | None = None, atol: float | None = None,
          fintim: float | None = None, keep_runs: bool = False, progress=None,
          step_point: bool | None = None, seed: float | None = None,
          weather_dirs: tuple[str, ...] = (), jobs: int = 1, scheduler: str | None = None,
          grid: tuple[str, list[float]] | None = None, max_time: float | None = None,
          max_steps: int | None = None, max_events: int | None = None,
          **params: float) -> Sweep:
    """Run `model` once per value of data value `name` and measure `measure`.
    `progress` (`amilpy.progress`) is given a Report after each point (task "sweep")
    and during each run (task "run"; runs in this process only). Points that do not carry the
    state are independent: `jobs` worker processes or a Dask `scheduler` run them
    (see `amilpy.batch.farm`), in any order, the result in the points' order. `grid`:
    (name, values) of a second data value: every pair of values is a point.
    `max_time`, `max_steps`, `max_events`: each point's run's limits, as `run`'s."""
    from ..run import Options

    name = name.upper()
    for n in [name] + ([grid[0].upper()] if grid else []):
        if n not in model.ir.data_names:
            raise UsageError(with_hint(f"{n} is not a PARAM/CONST/INCON value of this model",
                                       n, model.ir.data_names))
    if grid and (carry_state or both_ways):
        raise UsageError("a grid of two data values cannot carry the state or sweep both "
                         "ways: each point is a run of its own")
    variables = model.ir.variables
    measure = (measure or default_measure(model.ir)).upper()
    if measure not in variables:
        raise UsageError(with_hint(f"{measure} is not a variable of the model", measure,
                                   variables))
    second = grid[0].upper() if grid else None
    sequence = [(v, "up", None) for v in values]
    if grid:
        sequence = [(v, "up", w) for w in grid[1] for v in values]
    elif both_ways:
        sequence += [(v, "down", None) for v in reversed(values[:-1])]
    result = Sweep(name, measure, settle, carry_state=carry_state, second=second)

    limits = {k: v for k, v in (("max_time", max_time), ("max_steps", max_steps),
                                 ("max_events", max_events)) if v}

    def options(start=None) -> Options:
        return Options(method=method, rtol=rtol, atol=atol, start=start, fintim=fintim,
                       progress=progress, extrema=(measure,), settle=settle,
                       step_point=step_point, seed=seed, weather_dirs=weather_dirs,
                       **limits)

    if carry_state:
        _carried(model, result, sequence, options, params, keep_runs, progress)
        return result
    from .farm import Task, farm

    tasks = []
    for value, _, w in sequence:
        data = {**params, name: value, **({second: w} if second else {})}
        label = f"{name} = {value:g}" + (f", {second} = {w:g}" if second else "")
        tasks.append(Task(model._specs(data)[0], options(), label, measure, settle,
                          keep_runs))
    finished = [0]

    def done(i: int, _outcome) -> None:
        finished[0] += 1
        report(progress, "sweep", finished[0], len(sequence), name=name,
               value=sequence[i][0])

    outcomes = farm(model.ir, tasks, jobs, scheduler, done, model.cache)
    for k, ((value, direction, w), task, outcome) in enumerate(zip(sequence, tasks, outcomes,
                                                                    strict=True)):
        if outcome.point is None and outcome.interrupted:
            # Ctrl-C: the points computed are kept, the rest were never run
            rest = [t.label for t, o in zip(tasks[k:], outcomes[k:], strict=True)
                    if o.point is None]
            result.errors.append(f"interrupted: {rest[0]}" + (
                f" to {rest[-1]} ({len(rest)} points)" if len(rest) > 1 else "") + " not run")
            break
        if outcome.point is None:
            result.errors.append(f"{task.label}: {outcome.error or 'not run'}")
            nan = math.nan
            result.points.append(SweepPoint(value, direction, nan, nan, "failed", nan, nan, w))
            continue
        lo, hi, status, t0, t_end, unsteady = outcome.point
        result.points.append(SweepPoint(value, direction, lo, hi, status, t0, t_end, w,
                                        unsteady))
        if keep_runs:
            result.runs.append(outcome.run)
    return result


def _carried(model, result: Sweep, sequence, options, params, keep_runs: bool,
             progress) -> None:
    """One point after the other, each from the previous one's final state."""
    from ..run import simulate
    from .farm import extent, unsteadiness

    start = None
    for i, (value, direction, _) in enumerate(sequence):
        spec = model._specs({**params, result.name: value})[0]
        run = simulate(model.ir, spec, options(start), model.cache)
        t0 = float(run.times[0])
        lo, hi = extent(run, result.measure)
        result.points.append(SweepPoint(value, direction, lo, hi, str(run.status), t0,
                                        float(run.t_end),
                                        unsteady=unsteadiness(run, result.measure,
                                                              result.settle)))
        if keep_runs:
            result.runs.append(run)
        report(progress, "sweep", i + 1, len(sequence), name=result.name, value=value)
        if not run.ok:
            break  # what follows would start from a failed state
        start = run.final_state
