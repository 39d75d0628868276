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

from .diagnostics import AmilError
from .result import Run


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

    @property
    def amplitude(self) -> float:
        """Half the peak-to-peak of the measured variable after the settling time."""
        return 0.5 * (self.maximum - self.minimum)


JUMP_FACTOR = 5.0  # a jump changes the amplitude this many times more than its neighbours
NEIGHBOURS = 3  # steps each side whose changes measure the noise


@dataclass(frozen=True)
class Jump:
    """A jump of the characteristic between two neighbouring values."""

    direction: str  # the sweep's: "up" or "down"
    start: float  # the value before the jump ...
    stop: float  # ... and after it
    before: float  # the amplitude at `start`
    after: float  # ... and at `stop`
    ratio: float  # the change over the typical change of the neighbouring steps

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

    def branch(self, direction: str, second: float | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
        pts = [p for p in self.points if p.direction == direction and p.second == second]
        return (np.array([p.value for p in pts]), np.array([p.amplitude for p in pts]))

    def lines(self) -> list[tuple[str, np.ndarray, np.ndarray]]:
        """(label, values, amplitudes) of each curve: a direction swept, or for a grid
        each value of the second data value."""
        if self.second is None:
            return [(f"sweep {d}", *self.branch(d))
                    for d in dict.fromkeys(p.direction for p in self.points)]
        return [(f"{self.second} = {w:g}", *self.branch("up", w))
                for w in dict.fromkeys(p.second for p in self.points)]

    def jumps(self) -> dict[str, Jump | None]:
        """For each direction swept, its jump: the largest change of amplitude
        between neighbouring values, if it exceeds JUMP_FACTOR times the typical
        (median) change of the NEIGHBOURS steps each side; else None. Directions
        with fewer than three points to compare are left out (no noise to judge by)."""
        out: dict[str, Jump | None] = {}
        if self.second is not None:
            return out  # a grid: no one line to search along
        for direction in ("up", "down"):
            v, a = self.branch(direction)
            if direction == "up" and self.carry_state and len(v):
                v, a = v[1:], a[1:]
            if len(v) < 3:
                continue
            d = np.diff(a)
            best = None
            for k in range(len(d)):
                near = np.abs(np.delete(d[max(0, k - NEIGHBOURS): k + NEIGHBOURS + 1],
                                        min(k, NEIGHBOURS)))
                noise = max(float(np.median(near)), 1e-12 * float(np.max(np.abs(a))), 1e-300)
                ratio = abs(float(d[k])) / noise
                if ratio > JUMP_FACTOR and (best is None or abs(d[k]) > abs(d[best[0]])):
                    best = (k, ratio)
            out[direction] = None if best is None else Jump(
                direction, float(v[best[0]]), float(v[best[0] + 1]), float(a[best[0]]),
                float(a[best[0] + 1]), best[1])
        return out


MAX_POINTS = 100_000


def parse_range(text: str) -> tuple[str, list[float]]:
    """NAME=START:STOP:STEP -> (NAME, values), STOP included. A malformed range
    is an AmilError saying what to write (the command line makes it a usage error)."""
    try:
        name, spec = text.split("=", 1)
        start, stop, step = (float(x.replace("D", "E").replace("d", "e"))
                             for x in spec.split(":"))
    except ValueError:
        raise AmilError("write it NAME=START:STOP:STEP, e.g. W=60:80:0.5") from None
    if not name.strip().isidentifier():
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
    return name.strip().upper(), values


def default_measure(model) -> str:
    """The variable a sweep or an analysis measures when none is named: the first
    OUTPUT/PRINT variable of the first run, else the first variable (an ir.Model)."""
    named = [n for r in model.runs[0].reports if r.kind in ("OUTPUT", "PRINT")
             for n in r.names]
    return named[0] if named else model.variables[0]


def sweep(model, name: str, values: list[float], *, both_ways: bool = False,
          carry_state: bool = False, settle: float = 0.0, measure: str | None = None,
          method: str | None = None, rtol: float | None = None, atol: float | None = None,
          fintim: float | None = None, keep_runs: bool = False, progress=None,
          run_progress=None, step_point: bool | None = None, seed: float | None = None,
          jobs: int = 1, scheduler: str | None = None,
          grid: tuple[str, list[float]] | None = None, **params: float) -> Sweep:
    """Run `model` once per value of data value `name` and measure `measure`.
    `progress(i, n, value)` is called after each point, `run_progress` during each
    run (as `Options.progress`; one process only). Points that do not carry the
    state are independent: `jobs` worker processes or a Dask `scheduler` run them
    (see `amilpy.farm`), in any order, the result in the points' order. `grid`:
    (name, values) of a second data value: every pair of values is a point."""
    from .run import Options

    name = name.upper()
    for n in [name] + ([grid[0].upper()] if grid else []):
        if n not in model.ir.data_names:
            raise AmilError(f"{n} is not a PARAM/CONST/INCON value of this model")
    if grid and (carry_state or both_ways):
        raise AmilError("a grid of two data values cannot carry the state or sweep both "
                        "ways: each point is a run of its own")
    variables = model.ir.variables
    measure = (measure or default_measure(model.ir)).upper()
    if measure not in variables:
        raise AmilError(f"{measure} is not a variable of the model")
    second = grid[0].upper() if grid else None
    sequence = [(v, "up", None) for v in values]
    if grid:
        sequence = [(v, "up", w) for w in grid[1] for v in values]
    elif both_ways:
        sequence += [(v, "down", None) for v in reversed(values[:-1])]
    result = Sweep(name, measure, settle, carry_state=carry_state, second=second)

    def options(start=None) -> Options:
        return Options(method=method, rtol=rtol, atol=atol, start=start, fintim=fintim,
                       progress=run_progress, extrema=(measure,), settle=settle,
                       step_point=step_point, seed=seed)

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
        if progress is not None:
            progress(finished[0], len(sequence), sequence[i][0])

    for (value, direction, w), task, outcome in zip(sequence, tasks, farm(
            model.ir, tasks, jobs, scheduler, done, model.cache), strict=True):
        if outcome.point is None:
            result.errors.append(f"{task.label}: {outcome.error or 'not run'}")
            nan = math.nan
            result.points.append(SweepPoint(value, direction, nan, nan, "failed", nan, nan, w))
            continue
        result.points.append(SweepPoint(value, direction, *outcome.point, w))
        if keep_runs:
            result.runs.append(outcome.run)
    return result


def _carried(model, result: Sweep, sequence, options, params, keep_runs: bool,
             progress) -> None:
    """One point after the other, each from the previous one's final state."""
    from .farm import extent
    from .run import simulate

    start = None
    for i, (value, direction, _) in enumerate(sequence):
        spec = model._specs({**params, result.name: value})[0]
        run = simulate(model.ir, spec, options(start), model.cache)
        t0 = float(run.times[0])
        lo, hi = extent(run, result.measure)
        result.points.append(SweepPoint(value, direction, lo, hi, str(run.status), t0,
                                        float(run.t_end)))
        if keep_runs:
            result.runs.append(run)
        if progress is not None:
            progress(i + 1, len(sequence), value)
        if not run.ok:
            break  # what follows would start from a failed state
        start = run.final_state
