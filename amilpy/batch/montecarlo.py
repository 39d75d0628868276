"""Monte Carlo: the listing run once per set of data values drawn from their
distributions (`distributions.py`), and what the runs say together: quantile
bands of every reported variable on the output grid, quantiles of the final
and TERMINAL values, and the runs that failed, counted and listed with their
values (never dropped in silence).

The draws are made here, before any run, from the seed alone; the runs go to
`farm` (worker processes or a Dask cluster) in chunks, each coming back as a
`Member` (its rows of the reported variables, not the whole run), so the
result is the same bit for bit whatever `jobs` or `scheduler`. A run that
failed is left out of the bands and the quantiles (its partial history is no
draw of the complete one) and listed; a run a FINISH condition stopped early
counts in the bands up to where it stopped (`MonteCarlo.counts` says how many
runs each instant's quantiles are of).

Quantiles are NumPy's default (linear interpolation between order statistics,
Hyndman & Fan type 7)."""

from __future__ import annotations

import math
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from functools import partial

import numpy as np

from ..diagnostics import AmilError, UsageError
from ..progress import report
from ..result import Status
from .distributions import Dist, sample
from .members import Batch, member_of, shared_times

QUANTILES = (5.0, 50.0, 95.0)  # percent
CHUNK = 64  # runs handed to the farm at a time, per worker, at least
CHUNKS = 10  # and at most this many hand-overs in all
TIMED = 4  # runs per worker between looks at the clock, under a time limit


@dataclass
class MonteCarlo:
    """The runs of a Monte Carlo and their quantiles (see the module)."""

    dists: dict[str, Dist]
    samples: dict[str, np.ndarray]  # name -> its drawn value per run
    seed: int
    variables: list[str]
    quantiles: tuple[float, ...]  # percent
    times: np.ndarray  # the output grid (OUTDEL and PRDEL instants)
    prdel: np.ndarray  # which of `times` are PRDEL instants
    bands: np.ndarray  # (quantiles, times, variables), NaN where no run has a value
    mean: np.ndarray  # (times, variables)
    counts: np.ndarray  # runs with a value at each instant
    final: np.ndarray  # (runs, variables): each run's final values (NaN: failed)
    terminal_names: list[str]
    terminal: np.ndarray  # (runs, TERMINAL values)
    status: list[str]  # per run: finished, stopped, failed, or "" (not run)
    messages: list[str]
    correlation: dict[tuple[str, str], float] = field(default_factory=dict)
    interrupted: bool = False
    timed_out: bool = False
    params: dict[str, float] = field(default_factory=dict)
    how: str = ""  # how the runs were made, when not as a plain run would be

    @property
    def runs(self) -> int:
        return len(self.status)

    @property
    def done(self) -> int:
        return sum(1 for s in self.status if s)

    @property
    def failed(self) -> list[int]:
        """The runs (0-based) that failed."""
        return [k for k, s in enumerate(self.status) if s == str(Status.FAILED)]

    @property
    def kept(self) -> np.ndarray:
        """Which runs count in the quantiles: those that ran and did not fail."""
        return counted(self.status)

    def values_of(self, k: int) -> dict[str, float]:
        return {n: float(v[k]) for n, v in self.samples.items()}

    def final_quantiles(self) -> np.ndarray:
        """(quantiles, variables) of the final values over the runs kept."""
        return _quantiles(self.final[self.kept], self.quantiles)

    def terminal_quantiles(self) -> np.ndarray:
        return _quantiles(self.terminal[self.kept], self.quantiles)

    def band(self, name: str) -> np.ndarray:
        """(quantiles, times) of one variable."""
        return self.bands[:, :, self.variables.index(name.upper())]


def counted(status: list[str]) -> np.ndarray:
    """Which runs count in the quantiles: those that ran and did not fail."""
    return np.array([s not in ("", str(Status.FAILED)) for s in status], bool)


@contextmanager
def _nan_columns():
    """A column of NaN (no run has a value there) gives NaN, without a warning."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        yield


BLOCK_VALUES = 1 << 22  # values sorted at once for the bands (32 MB): a block of rows


def _quantiles(values: np.ndarray, q) -> np.ndarray:
    """(quantiles, columns) of `values` (runs, columns), NaN left out."""
    if not len(values):
        return np.full((len(q), values.shape[1]), math.nan)
    qs = np.asarray(q) / 100.0
    # (nanquantile takes a column at a time where any holds a NaN: only those)
    holes = np.isnan(values).any(axis=0)
    if not holes.any():
        return np.quantile(values, qs, axis=0)
    out = np.empty((len(qs), values.shape[1]))
    out[:, ~holes] = np.quantile(values[:, ~holes], qs, axis=0)
    with _nan_columns():
        out[:, holes] = np.nanquantile(values[:, holes], qs, axis=0)
    return out


def parse_quantiles(value) -> tuple[float, ...]:
    """"5,50,95" or (5, 50, 95) -> (5.0, 50.0, 95.0): percents in [0, 100], sorted,
    distinct to ten digits (their names, P5 ..., must differ)."""
    items = value.split(",") if isinstance(value, str) else list(value)
    try:
        q = sorted({float(f"{float(p):.10g}") for p in items
                    if not isinstance(p, str) or p.strip()})
    except (TypeError, ValueError):
        raise UsageError(f"--quantiles takes percents, e.g. 5,50,95, got {value!r}") from None
    if not q or not all(0.0 <= v <= 100.0 for v in q):
        raise UsageError(f"--quantiles takes percents between 0 and 100, got {value!r}")
    return tuple(q)


def montecarlo(model, dists: dict[str, Dist], runs: int, seed: int, *,
               quantiles=QUANTILES, correlation=None, names: list[str] | None = None,
               options=None, jobs: int = 1, scheduler: str | None = None,
               progress=None, max_time: float | None = None,
               params: dict[str, float] | None = None, stacked: bool = True) -> MonteCarlo:
    """The Monte Carlo of `model` (an api.Model): `runs` runs of its first run's data
    (with `params`) and each name's value drawn from `dists`; `options` a
    run.Options (method, tolerances, limits) for every run; `max_time` wall-clock
    seconds for the whole study (the runs done by then are kept); `stacked`: all
    runs integrated at once where they can be (`stacked.py`)."""
    params = dict(params or {})
    check_names(model, dists, params)
    correlation = dict(correlation or {})
    samples = sample(dists, runs, seed, correlation)
    variables = names or reported(model)
    values_limit(model, variables, runs, options)
    batch = run_sets(model, samples, variables, options, jobs=jobs, scheduler=scheduler,
                     progress=progress, max_time=max_time, params=params, stacked=stacked)
    return _gather(dists, samples, seed, variables, tuple(quantiles), batch, correlation,
                   params)


def ensemble_route(model, spec, options):
    """The runs' options, and a note when they differ from a plain run's: where
    neither the caller nor the listing names a METHOD and numba is installed (the
    [fast] extra), the members run on METHOD COMPILED, whose kernel is compiled once
    for all of them (a hoist member then costs a tenth of a default run:
    `benchmarks/ensembles.py`); where the model has no compiled form, as a plain
    run."""
    from dataclasses import replace

    from .. import compiled

    if options.method is not None or spec.method is not None or options.step_point or \
            model.ir.acsl is not None or not compiled.available():
        return options, ""
    from ..run import prepare

    chosen = replace(options, method="COMPILED")
    try:
        kernel = compiled.kernel_for(prepare(model.ir, spec, chosen, model.cache).code)
    except AmilError:
        return options, ""
    if isinstance(kernel, str):
        return options, ""
    return chosen, ("the runs on METHOD COMPILED (numba; the listing names no METHOD): "
                    "its kernel compiled once for all of them")


def check_names(model, dists, params: dict[str, float]) -> None:
    """Each drawn name a data value of the model, and not also --set."""
    known = set(model.ir.data_names)
    for name in dists:
        if name not in known:
            from ..diagnostics import with_hint

            raise UsageError(with_hint(f"--dist {name}: not a PARAM/CONST/INCON value of "
                                       "this model", name, sorted(known)))
        if name in params:
            raise UsageError(f"{name} has both --set and --dist: give one")


def run_sets(model, sets: dict[str, np.ndarray], variables: list[str], options, *,
             jobs: int = 1, scheduler: str | None = None, progress=None,
             max_time: float | None = None, params: dict[str, float] | None = None,
             stacked: bool = True) -> Batch:
    """Run the model's first run (with `params`) once per set of values (`sets`: name
    -> a value per run): all at once where they can be (`stacked.py`; not with
    `stacked=False`), else on `jobs` workers or `scheduler`, in chunks; each run
    comes back as a Member of `variables` (and the extrema `options.extrema` asks
    for)."""
    from .farm import Task, default_jobs, farm

    runs = len(next(iter(sets.values()))) if sets else 0
    base = model._specs(dict(params or {}))[0]
    opts = replace(options, outputs=[v for v in variables if v in model.ir.variables],
                   progress=None)
    if stacked:
        from .stacked import run_stacked

        together = run_stacked(model, base, sets, runs, variables, opts)
        if together is not None:
            report(progress, "runs", runs, runs)
            return together
    opts, how = ensemble_route(model, base, opts)
    reduce = partial(member_of, tuple(variables))
    batch = Batch([None] * runs, {}, how=how)
    shared = None  # (the last member kept: its output instants, held once for all)
    start = time.monotonic()
    # (each chunk starts its workers afresh: a tenth of the runs at least, so that
    # starting them costs little, and the time limit and Ctrl-C are looked at often)
    workers = max(1, jobs if not scheduler else default_jobs())
    chunk = max(CHUNK * workers, math.ceil(runs / CHUNKS)) if max_time is None else \
        TIMED * workers  # (with a time limit: looked at after every few runs)
    for first in range(0, runs, chunk):
        if max_time is not None and time.monotonic() - start >= max_time:
            batch.timed_out = True
            break
        ks = range(first, min(runs, first + chunk))
        left = opts if max_time is None else \
            replace(opts, max_time=max(max_time - (time.monotonic() - start), 1e-3))
        tasks = [Task(base.overridden({n: float(v[k]) for n, v in sets.items()}), left,
                      f"run {k + 1}", reduce=reduce) for k in ks]

        def done(i: int, _outcome, offset=first) -> None:
            report(progress, "runs", offset + i + 1, runs)

        outcomes = farm(model.ir, tasks, jobs, scheduler, done, model.cache)
        for k, o in zip(ks, outcomes, strict=True):
            if o.point is not None:
                batch.members[k] = shared_times(o.point, shared)
                shared = batch.members[k]
            elif not o.interrupted:
                batch.errors[k] = o.error or "not run"
            batch.interrupted = batch.interrupted or o.interrupted
        if batch.interrupted:
            break
    if max_time is not None and not batch.timed_out and \
            any(m is None and k not in batch.errors for k, m in enumerate(batch.members)):
        batch.timed_out = True  # (the loop ended at the limit with runs left)
    return batch


def reported(model) -> list[str]:
    """Every PRINT and OUTPUT variable of the first run, once each, in order."""
    names: list[str] = []
    for r in model.ir.runs[0].reports:
        if r.kind in ("PRINT", "OUTPUT"):
            names += [n for n in r.names if n not in names and n != "TIME"]
    if not names:
        raise UsageError("the listing has no PRINT or OUTPUT variable: name the variables "
                         "with --vars")
    return names


def values_limit(model, variables: list[str], runs: int, options) -> None:
    """Refuse before the first run a study whose kept values would not fit."""
    from ..run.plan import DEFAULTS

    per_run = model.stored_values(options.fintim, variables) if model.ir.acsl is None \
        else 0.0
    total = per_run * runs
    limit = DEFAULTS["max_values"]
    if total > limit:
        raise AmilError(f"the {runs} runs would keep {total:.3g} values ({len(variables)} "
                        f"variables on every output row; limit {limit:.0e}): fewer --runs, "
                        "fewer --vars, or a coarser OUTDEL/PRDEL")


def _gather(dists, samples, seed, variables, quantiles, batch: Batch, correlation,
            params) -> MonteCarlo:
    members = batch.members
    runs = len(members)
    reference = max((m for m in members if m is not None), key=lambda m: len(m.times),
                    default=None)
    times = reference.times if reference is not None else np.empty(0)
    prdel = reference.prdel if reference is not None else np.empty(0, bool)
    cube = np.full((runs, len(times), len(variables)), np.nan)
    final = np.full((runs, len(variables)), np.nan)
    terminal_names = list(dict.fromkeys(n for m in members if m is not None
                                        for n in m.terminal))
    terminal = np.full((runs, len(terminal_names)), np.nan)
    status, messages = [""] * runs, [""] * runs
    from ..run.plan import nearest_instants

    for k, m in enumerate(members):
        status[k], messages[k] = batch.status(k), batch.message(k)
        if m is None or m.status == str(Status.FAILED):
            continue
        pick, same = nearest_instants(times, m.times)
        cube[k, pick[same]] = m.values[same]
        final[k] = m.final
        for j, n in enumerate(terminal_names):
            terminal[k, j] = m.terminal.get(n, math.nan)
    use = counted(status)
    kept = cube if use.all() else cube[use]  # (no copy where every run counts)
    bands = np.full((len(quantiles), len(times), len(variables)), np.nan)
    mean = np.full((len(times), len(variables)), np.nan)
    counts = np.zeros(len(times), int)
    # a block of rows at a time: the quantiles sort a copy of what they are given
    step = max(1, BLOCK_VALUES // max(len(kept) * len(variables), 1))
    for lo in range(0, len(times) if len(kept) and variables else 0, step):
        block = kept[:, lo:lo + step]
        bands[:, lo:lo + step] = _quantiles(block.reshape(len(kept), -1), quantiles).reshape(
            len(quantiles), -1, len(variables))
        with _nan_columns():
            mean[lo:lo + step] = np.nanmean(block, axis=0)
        counts[lo:lo + step] = np.sum(np.all(np.isfinite(block), axis=2), axis=0)
    return MonteCarlo(dists, samples, seed, list(variables), quantiles, times, prdel, bands,
                      mean, counts, final, terminal_names, terminal, status, messages,
                      correlation, batch.interrupted, batch.timed_out, params, batch.how)
