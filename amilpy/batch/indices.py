"""Global sensitivity indices: which drawn data value moves an output, over the
whole of the values' distributions (`amilpy sensitivity --method morris|sobol`).

Outputs (`measure`): "VAR" its final value, "VAR@T" its value at output instant
T, "max(VAR)" / "min(VAR)" its extremes over the run (located between the
output rows, like RANGE), or a TERMINAL value's name.

Sobol (variance-based). A scrambled Sobol sequence (scipy.stats.qmc, seeded) of
N points in 2k dimensions gives two sample matrices A and B in the unit cube,
mapped to values by each distribution's inverse CDF; AB_i is A with column i from
B: N (k + 2) runs. With V the variance of f over A and B together,
    first order  S_i  = mean(f_B (f_AB_i - f_A)) / V        (Saltelli et al. 2010)
    total        ST_i = mean((f_A - f_AB_i)^2) / (2 V)      (Jansen 1999)
with f centred on its mean first (the same expectations, a smaller variance),
and 95 % intervals from 1,000 bootstrap resamples of the N rows (percentile).

Morris (elementary effects). r trajectories on a grid of p = 4 equally likely
levels per value (the probabilities (l + 1/2)/p): each starts on a random level
and moves one value at a time, in random order, by two levels (up from the
lower half, down from the upper), r (k + 1) runs. An effect is the change of f
over the change of probability (1/2): mu* = mean |EE| (the importance), mu =
mean EE, sigma = sd of EE (interaction or nonlinearity) (Campolongo et al. 2007).

The draws depend on the seed alone: the same indices whatever --jobs. Runs that
fail are listed; Sobol's estimators then use the rows whose runs all succeeded,
Morris's the effects whose two runs did."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from ..diagnostics import UsageError
from ..result import Status
from .distributions import Dist
from .members import Batch
from .montecarlo import check_names, reported, run_sets

METHODS = ("morris", "sobol")
LEVELS = 4  # Morris's grid
BOOTSTRAP = 1000


@dataclass(frozen=True)
class Measure:
    text: str  # as given
    kind: str  # "final", "at", "max", "min", "terminal"
    name: str
    time: float = math.nan


def parse_measure(text: str, model) -> Measure:
    """"X", "X@2.5", "max(X)", "min(X)" or a TERMINAL name (see the module)."""
    raw = text.strip()
    m = re.fullmatch(r"(max|min)\s*\(\s*([A-Za-z_]\w*)\s*\)", raw, re.IGNORECASE)
    if m:
        name = model.known_names(m.group(2))[0]
        return Measure(raw, m.group(1).lower(), name)
    if "@" in raw:
        name, _, when = raw.partition("@")
        from ..language import fortran_float

        try:
            t = fortran_float(when)
        except ValueError:
            raise UsageError(f"--measure {raw}: write VAR@TIME, e.g. X@2.5") from None
        return Measure(raw, "at", model.known_names(name)[0], t)
    name = raw.upper()
    if name in _terminal_names(model):
        return Measure(raw, "terminal", name)
    return Measure(raw, "final", model.known_names(name)[0])


def _terminal_names(model) -> set[str]:
    """The names TERMINAL assigns (equations, written-order code, ACSL's)."""
    ir = model.ir
    names = {eq.target for eq in ir.terminal}
    codes = list(ir.terminal_code) + (list(ir.acsl.terminal) if ir.acsl else [])
    for code in codes:
        names.update(code.assigned)
    return names


def value_of(measure: Measure, member, variables: list[str]) -> float:
    """The measure of one run (NaN: the run has none)."""
    if member is None or member.status == str(Status.FAILED):
        return math.nan
    if measure.kind == "terminal":
        return float(member.terminal.get(measure.name, math.nan))
    j = variables.index(measure.name)
    if measure.kind == "final":
        return float(member.final[j])
    if measure.kind in ("max", "min"):
        lo, _, hi, _ = member.extrema.get(measure.name, (math.nan,) * 4)
        return float(hi if measure.kind == "max" else lo)
    from ..run.plan import nearest_instants

    pick, same = nearest_instants(member.times, [measure.time])
    # (not there: the run stopped before T, a FINISH condition; T itself was checked
    # against the output grid before the runs)
    return float(member.values[pick[0], j]) if same[0] else math.nan


@dataclass
class Indices:
    """Global indices of each measure to each drawn name."""

    method: str
    names: list[str]
    dists: dict[str, Dist]
    measures: list[Measure]
    seed: int
    runs: int  # in all
    base: int  # N (Sobol) or r (Morris)
    values: np.ndarray  # (runs, measures): each run's measures
    samples: dict[str, np.ndarray]  # each name's value per run
    failed: list[int]
    messages: dict[int, str]
    # Sobol: (measures, names), and (measures, names, 2) intervals
    first: np.ndarray | None = None
    total: np.ndarray | None = None
    first_ci: np.ndarray | None = None
    total_ci: np.ndarray | None = None
    variance: np.ndarray | None = None
    # Morris: (measures, names)
    mu_star: np.ndarray | None = None
    mu: np.ndarray | None = None
    sigma: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)
    interrupted: bool = False
    timed_out: bool = False


def indices(model, method: str, dists: dict[str, Dist], measures: list[str], runs: int,
            seed: int, *, options, jobs: int = 1, scheduler: str | None = None,
            progress=None, max_time: float | None = None,
            params: dict[str, float] | None = None) -> Indices:
    """Global indices (see the module); `runs`: N for Sobol (rounded up to a power of
    two), r for Morris."""
    if method not in METHODS:
        raise UsageError(f"--method {method}: the global methods are {', '.join(METHODS)}")
    params = dict(params or {})
    if not dists:
        raise UsageError("give each value's distribution: --dist NAME=DIST")
    if any(d.kind == "table" for d in dists.values()):
        raise UsageError("a global sensitivity draws its own points: give distributions, "
                         "not table(FILE)")
    check_names(model, dists, params)
    if runs < 2:
        raise UsageError(f"--runs must be at least 2, got {runs}")
    parsed = [parse_measure(m, model) for m in measures or reported(model)[:1]]
    _check_instants(model, parsed, options, params)
    names = list(dists)
    notes = []
    if method == "sobol":
        n = 1 << math.ceil(math.log2(runs))
        if n != runs:
            notes.append(f"N = {runs} rounded up to {n}, a power of two (a Sobol sequence's "
                         "balance)")
        units = _saltelli(len(names), n, seed)
    else:
        n = runs
        units, steps = _morris(len(names), n, seed)
    samples = {name: np.asarray(dists[name].quantile(units[:, j]), dtype=float)
               for j, name in enumerate(names)}
    # (the runs keep the variables measured; only TERMINAL values: the first reported)
    variables = list(dict.fromkeys(m.name for m in parsed if m.kind != "terminal")) or \
        reported(model)[:1]
    from dataclasses import replace

    opts = replace(options, extrema=tuple(m.name for m in parsed if m.kind in ("max", "min")))
    batch: Batch = run_sets(model, samples, variables, opts, jobs=jobs, scheduler=scheduler,
                            progress=progress, max_time=max_time, params=params)
    values = np.array([[value_of(m, member, variables) for m in parsed]
                       for member in batch.members]).reshape(len(units), len(parsed))
    failed = [k for k in range(len(units)) if batch.status(k) == str(Status.FAILED)]
    messages = {k: batch.message(k) for k in failed}
    out = Indices(method, names, dists, parsed, seed, len(units), n, values, samples, failed,
                  messages, notes=notes + ([batch.how] if batch.how else []),
                  interrupted=batch.interrupted, timed_out=batch.timed_out)
    if method == "sobol":
        _sobol(out, n, len(names), seed)
    else:
        _morris_effects(out, steps, len(names))
    return out


def _check_instants(model, measures: list[Measure], options, params) -> None:
    """Each VAR@T's T an output instant of the run (CSMP form; an ACSL program's grid
    is known only as it runs: a T off it gives no value, NaN)."""
    timed = [m for m in measures if m.kind == "at"]
    if not timed or model.ir.acsl is not None:
        return
    from ..run import prepare
    from ..run.plan import nearest_instants

    grid = prepare(model.ir, model._specs(params)[0], options, model.cache).plan.grid.times
    for m in timed:
        if not nearest_instants(grid, [m.time])[1][0]:
            raise UsageError(f"--measure {m.text}: TIME = {m.time:g} is not an output "
                             "instant of the run; choose one on the OUTDEL or PRDEL grid")


def _saltelli(k: int, n: int, seed: int) -> np.ndarray:
    """The unit points, row by row: A_r, B_r, AB_1,r, ..., AB_k,r for r = 1 ... N (a
    study stopped early then has whole rows)."""
    from scipy.stats import qmc

    u = qmc.Sobol(2 * k, scramble=True, seed=np.random.default_rng(seed)).random(n)
    a, b = u[:, :k], u[:, k:]
    blocks = [a, b]
    for i in range(k):
        ab = a.copy()
        ab[:, i] = b[:, i]
        blocks.append(ab)
    return np.stack(blocks, axis=1).reshape(n * (k + 2), k)


def _sobol(out: Indices, n: int, k: int, seed: int) -> None:
    f = out.values.reshape(n, k + 2, -1)  # (rows, blocks, measures): see _saltelli
    fa, fb = f[:, 0], f[:, 1]
    fab = np.stack([f[:, 2 + i] for i in range(k)])  # (k, n, measures)
    ok = np.all(np.isfinite(fa), axis=1) & np.all(np.isfinite(fb), axis=1) & \
        np.all(np.isfinite(fab), axis=(0, 2))
    if not np.all(ok):
        out.notes.append(f"{int(np.sum(~ok))} of the {n} rows left out: one of their runs "
                         "failed, was not run, or has no value of the output")
    rows = np.flatnonzero(ok)

    def estimate(idx):
        a, b, ab = fa[idx], fb[idx], fab[:, idx]
        # (centred: the estimators' expectations are unchanged, their variance is not
        # inflated by the output's mean, which f_B multiplies)
        mean = np.mean(np.concatenate([a, b]), axis=0)
        a, b, ab = a - mean, b - mean, ab - mean
        var = np.var(np.concatenate([a, b]), axis=0)
        with np.errstate(all="ignore"):
            first = np.mean(b[None] * (ab - a[None]), axis=1) / var
            total = 0.5 * np.mean((a[None] - ab) ** 2, axis=1) / var
        return first.T, total.T, var  # (measures, k)

    first, total, var = estimate(rows)
    rng = np.random.default_rng(seed + 1)
    boots = [estimate(rows[rng.integers(0, len(rows), len(rows))]) for _ in range(BOOTSTRAP)] \
        if len(rows) > 1 else []
    if boots:
        f_b = np.stack([b[0] for b in boots])
        t_b = np.stack([b[1] for b in boots])
        out.first_ci = np.stack(np.nanpercentile(f_b, [2.5, 97.5], axis=0), axis=-1)
        out.total_ci = np.stack(np.nanpercentile(t_b, [2.5, 97.5], axis=0), axis=-1)
    out.first, out.total, out.variance = first, total, var
    if np.any(var == 0):
        out.notes.append("a measure that does not vary over the draws has no indices (NaN)")


def _morris(k: int, r: int, seed: int) -> tuple[np.ndarray, list[tuple[int, int, int, float]]]:
    """The unit points of r trajectories, and each step (trajectory, from row, to row,
    signed change of probability) with the value it moves: (rows, steps)."""
    rng = np.random.Generator(np.random.PCG64(seed))
    levels = (np.arange(LEVELS) + 0.5) / LEVELS
    jump = LEVELS // 2  # levels moved: a change of probability of 1/2
    points, steps = [], []
    for _ in range(r):
        x = rng.integers(0, LEVELS, k)
        order = rng.permutation(k)
        points.append(levels[x])
        for i in order:
            x = x.copy()
            x[i] += jump if x[i] < LEVELS - jump else -jump
            points.append(levels[x])
            steps.append((int(i), len(points) - 2, len(points) - 1,
                          float(levels[x[i]] - points[-2][i])))
    return np.array(points), steps


def _morris_effects(out: Indices, steps, k: int) -> None:
    f = out.values
    effects: list[list[np.ndarray]] = [[] for _ in range(k)]
    for i, a, b, du in steps:
        effects[i].append((f[b] - f[a]) / du)
    m = f.shape[1]
    mu_star, mu, sigma = (np.full((m, k), np.nan) for _ in range(3))
    for i in range(k):
        e = np.array(effects[i]).reshape(-1, m)
        e = e[np.all(np.isfinite(e), axis=1)]
        if len(e):
            mu_star[:, i] = np.mean(np.abs(e), axis=0)
            mu[:, i] = np.mean(e, axis=0)
            sigma[:, i] = np.std(e, axis=0, ddof=1) if len(e) > 1 else np.nan
    out.mu_star, out.mu, out.sigma = mu_star, mu, sigma
