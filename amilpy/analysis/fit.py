"""Fitting data values to measurements (`amilpy fit`, `Model.fit`): weighted least
squares over the observations of a `--data` file (`amilpy.observed`), each
evaluation every run of the listing with the free values set, by SciPy's
trust-region reflective `least_squares` within the bounds.

The residuals are observed - simulated at the observed instants (the runs' own
values there, not interpolated), weighted by `weights`: "sd" divides by the
file's SD_<NAME> columns, "relative" by |observed|, "none" leaves them. The
Jacobian is central differences of whole runs, each free value moved by
cbrt(RELERR)-sized steps relative to it (the runs are accurate to about RELERR,
so a difference over h is good to RELERR/h^2 + h^2: best near the cube root;
cbrt(eps) on a fixed-step route, whose runs carry no error control's noise:
`sensitivity.difference_step`); or,
with `gradients="sensitivities"`, the variational equations of the flow with the
jumps at the switches (`analysis.sensitivity`: exact to the integration's accuracy,
through switching instants), central differences where they do not apply.

At the optimum: the covariance is (J^T J)^-1, times the residual variance
s^2 = 2 cost / (n - p) unless the weights are the data's own SDs (then the
residuals are in units of their SD already); standard errors its diagonal's
root, 95 % intervals from the normal quantile when the SDs are known, else from
Student's t with n - p degrees of freedom (none left, n = p: no standard
errors), and the correlation matrix. A value that stops at a bound is said. A
value fitted on a log scale (`log`) has its interval exp(log p +- t se). What
the data cannot determine is said: a Jacobian of deficient rank or condition
over 1e8, an interval wider than the bounds."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from ..diagnostics import AmilError, UsageError, with_hint
from ..observed import Observations
from ..progress import report
from .sensitivity import difference_step, observed_jacobian

WEIGHTS = ("sd", "relative", "none")
# the Jacobian: central differences of whole runs (the default: on the shipped
# models the cheaper, benchmarks/fitting.py), or the variational equations
GRADIENTS = ("differences", "sensitivities")
CONDITION_LIMIT = 1e8
# least_squares' ftol/xtol/gtol: its default 1e-8 leaves noise-free estimates 1e-5
# off where the data determine them weakly; the runs are good to ~1e-9
TOLERANCE = 1e-10


@dataclass
class Fit:
    """The estimates of a fit and what goes with them."""

    names: list[str]
    start: list[float]
    estimates: list[float]
    se: list[float]  # standard errors (of the value, by the delta method on a log scale)
    lower: list[float]  # 95 % confidence interval
    upper: list[float]
    correlation: np.ndarray
    n: int  # observations
    cost: float  # half the sum of squared weighted residuals
    runs: int  # model evaluations (each: every run of the listing)
    message: str  # why the optimiser stopped
    success: bool
    weights: str
    notes: list[str] = field(default_factory=list)  # identifiability, in words
    fitted: list = field(default_factory=list)  # the runs at the estimates (Run)
    log: list[str] = field(default_factory=list)
    jacobians: int = 0  # Jacobians from the variational equations
    gradients: str = ""  # how the Jacobian was had (and why not the sensitivities)
    quantile: float = math.nan  # of the 95 % intervals ...
    quantile_of: str = ""  # ... and whose: the normal's (SDs known) or Student's t

    @property
    def values(self) -> dict[str, float]:
        return dict(zip(self.names, self.estimates, strict=True))


def parse_free(items) -> dict[str, tuple[float, float]]:
    """NAME or NAME=LO:HI (strings), or a dict name -> (lo, hi) / None, as bounds."""
    from ..language import fortran_float

    if isinstance(items, dict):
        return {k.upper(): (-math.inf, math.inf) if v is None else (float(v[0]), float(v[1]))
                for k, v in items.items()}
    out = {}
    for item in [items] if isinstance(items, str) else items:
        name, _, span = item.partition("=")
        lo, hi = -math.inf, math.inf
        if span:
            try:
                lo, hi = (fortran_float(x) if x.strip() else default
                          for x, default in zip(span.split(":"), (-math.inf, math.inf),
                                                strict=True))
            except ValueError:
                raise UsageError(f"write NAME=LO:HI (either may be left empty), got "
                                 f"{item!r}") from None
        if not lo < hi:
            raise UsageError(f"{name}: the lower bound must be below the upper, got {item!r}")
        out[name.strip().upper()] = (lo, hi)
    return out


def fit(model, data, free, *, log=(), weights: str = "sd", method: str | None = None,
        rtol: float | None = None, atol: float | None = None, progress=None,
        max_evaluations: int = 200, gradients: str = "differences",
        **params: float) -> Fit:
    """Fit the `free` data values of `model` (an api.Model) to `data`; see the module."""
    from scipy.optimize import least_squares
    from scipy.stats import norm as normal
    from scipy.stats import t as student

    bounds = parse_free(free)
    if not bounds:
        raise UsageError("name at least one value to fit (--free NAME)")
    specs = model._specs(params)
    for name in bounds:
        if name not in specs[0].data:
            raise UsageError(with_hint(f"{name} is not a PARAM/CONST/INCON value of this "
                                       "model", name, specs[0].data))
        if any(name in s.changed and s.changed[name] != specs[0].data[name]
               for s in specs[1:]) and name not in params:
            raise UsageError(f"{name} differs from run to run (a value list): it cannot be "
                             "one fitted value; fit it with one run at a time (--set)")
    logged = {n.upper() for n in log}
    for name in logged - set(bounds):
        raise UsageError(f"--log {name}: {name} is not one of the values fitted (--free)")
    if weights not in WEIGHTS:
        raise UsageError(f"weights are one of {', '.join(WEIGHTS)}, got {weights!r}")
    if gradients not in GRADIENTS:
        raise UsageError(f"gradients are one of {', '.join(GRADIENTS)}, got {gradients!r}")
    obs = data if isinstance(data, Observations) else model._observations(data, len(specs))
    names = list(bounds)
    start = [float(params.get(n, specs[0].data[n])) for n in names]
    for n, p0 in zip(names, start, strict=True):
        lo, hi = bounds[n]
        if n in logged and not (p0 > 0 and lo >= 0):
            raise UsageError(f"--log {n} needs a positive value and bounds (it is {p0:g})")
        if not lo <= p0 <= hi:
            raise UsageError(f"{n} = {p0:g} is outside its bounds {lo:g}:{hi:g}")
    if weights == "sd" and any(s.sd is None for s in obs.series):
        raise UsageError("--weights sd needs an SD_<NAME> column for every variable "
                         "observed; give them, or --weights relative or none")
    if weights == "relative":
        for s in obs.series:
            zero = np.flatnonzero(s.values == 0.0)
            if zero.size:
                raise obs.error(f"--weights relative divides by |{s.name}|, which is 0 "
                                "here", s.lines[int(zero[0])],
                                s.value_columns[int(zero[0])],
                                "leave the observation out, or use --weights sd or none")

    def to_x(p):
        return np.array([math.log(v) if n in logged else v for n, v in zip(names, p,
                                                                            strict=True)])

    def to_p(x):
        return [math.exp(v) if n in logged else float(v) for n, v in zip(names, x,
                                                                         strict=True)]

    lo = to_x([max(bounds[n][0], 1e-300) if n in logged else bounds[n][0] for n in names])
    lo = np.where(np.isfinite(lo), lo, -np.inf)
    hi = np.array([math.log(bounds[n][1]) if n in logged and math.isfinite(bounds[n][1])
                   else bounds[n][1] for n in names])
    count = [0]
    options = dict(method=method, rtol=rtol, atol=atol, advice=False, data=obs)

    def runs_at(x):
        values = dict(zip(names, to_p(x), strict=True))
        runs = model.run(**options, **{**params, **values})
        count[0] += 1
        failed = [r for r in runs if not r.ok]
        if failed:
            raise AmilError(f"the run at {_values(values)} failed: {failed[0].message}",
                            model.ir.path)
        short = [(k, c) for k, r in enumerate(runs, start=1) for c in r.observed
                 if c.unreached]
        if short:
            k, c = short[0]
            raise AmilError(f"run {k} at {_values(values)} stops at TIME = "
                            f"{runs[k - 1].t_end:.9g} ({runs[k - 1].message or 'FINISH'}), "
                            f"before {c.unreached} observation(s) of {c.name}: a fit "
                            "compares every observation at every evaluation; leave those "
                            "out, or bound the values so that the run reaches them",
                            model.ir.path)
        report(progress, "fit", count[0], None, value=_values(values))
        return runs

    def weighted(runs, x) -> np.ndarray:
        r = _weighted(runs, weights)
        if not np.all(np.isfinite(r)):
            raise AmilError(f"the residuals at {_values(dict(zip(names, to_p(x), strict=True)))}"
                            " are not finite (a variable observed is NaN or infinite "
                            "there)", model.ir.path)
        return r

    def residuals(x):
        return weighted(runs_at(x), x)

    first = runs_at(to_x(start))
    n, p = len(weighted(first, to_x(start))), len(names)
    if n < p:
        raise UsageError(f"{n} observation(s) cannot determine {p} values")
    step = difference_step(model, method, rtol)
    # the residuals' weights, for the Jacobian of the sensitivities
    scale = np.concatenate([_weight(c, weights) for r in first for c in r.observed]) \
        if n else np.empty(0)
    sens = {"count": 0, "how": ""}
    flow_options = dict(method=method, rtol=rtol, atol=atol)

    known: dict[tuple, tuple] = {}  # (the Jacobian at the start, had to decide)

    def jacobian(x):
        values = dict(zip(names, to_p(x), strict=True))
        dsim, why = known.pop(tuple(x), None) or \
            observed_jacobian(model, obs, names, values, params, flow_options)
        if dsim is None or dsim.shape != (n, p) or not np.all(np.isfinite(dsim)):
            sens["how"] = _by_differences(why)
            return _differences(residuals, x, step, lo, hi)
        sens["count"] += 1
        chain = np.array([v if name in logged else 1.0 for name, v in
                          zip(names, to_p(x), strict=True)])
        return -dsim * scale[:, None] * chain[None, :]

    probe, why = observed_jacobian(model, obs, names, dict(zip(names, start, strict=True)),
                                   params, flow_options) \
        if gradients == "sensitivities" else (None, "")
    if probe is None:
        sens["how"] = _by_differences(why)
    else:
        sens["how"] = "variational equations (sensitivities through the switches" + \
            (" and the program's DISCRETE and DYNAMIC code)" if model.ir.acsl else ")")
        known[tuple(to_x(start))] = (probe, why)
    result = least_squares(residuals, to_x(start), bounds=(lo, hi), method="trf",
                           jac=jacobian if probe is not None else "3-point",
                           diff_step=step, x_scale="jac", max_nfev=max_evaluations,
                           ftol=TOLERANCE, xtol=TOLERANCE, gtol=TOLERANCE)
    x = result.x
    fitted = runs_at(x)
    r = _weighted(fitted, weights)
    jac = result.jac
    dof = n - p
    notes = []
    if weights == "sd":
        s2 = 1.0  # (the residuals are in units of their known SDs)
    elif dof > 0:
        s2 = float(r @ r) / dof
    else:
        s2 = math.nan
        notes.append(f"{n} observation(s) for {p} value(s): no degrees of freedom are "
                     "left to estimate the residuals' variance, so no standard errors")
    _, sv, vt = np.linalg.svd(jac)
    if sv.size and (sv[-1] == 0 or sv[0] / sv[-1] > CONDITION_LIMIT):
        weakest = int(np.argmax(np.abs(vt[-1])))
        notes.append(f"the data cannot determine {names[weakest]}: the fit's Jacobian is "
                     f"singular or nearly so (condition {sv[0] / max(sv[-1], 1e-300):.2g}); "
                     "fix it, or observe what it moves")
    cov_x = np.linalg.pinv(jac.T @ jac) * s2
    se_x = np.sqrt(np.maximum(np.diag(cov_x), 0.0))
    # (the SDs known: the normal quantile; estimated: Student's t with n - p)
    quantile = float(normal.ppf(0.975)) if weights == "sd" else \
        float(student.ppf(0.975, dof)) if dof > 0 else math.nan
    est = to_p(x)
    se, lower, upper = [], [], []
    for k, name in enumerate(names):
        xk, sk = float(x[k]), float(se_x[k])
        if name in logged:
            se.append(est[k] * sk)
            lower.append(math.exp(xk - quantile * sk))
            upper.append(math.exp(xk + quantile * sk))
        else:
            se.append(sk)
            lower.append(xk - quantile * sk)
            upper.append(xk + quantile * sk)
        b = bounds[name]
        near = 1e-9 * max(1.0, abs(float(x[k])))
        at_low, at_high = x[k] <= lo[k] + near, x[k] >= hi[k] - near
        if result.active_mask[k] != 0 or at_low or at_high:
            side, edge = ("lower", b[0]) if result.active_mask[k] < 0 or at_low else \
                ("upper", b[1])
            notes.append(f"{name} stopped at its {side} bound {edge:g}: the data would take "
                         "it further; its interval is not a confidence interval there "
                         "(widen the bound, or check the model)")
        elif (lower[-1] < b[0] or upper[-1] > b[1]) and all(map(math.isfinite, b)):
            notes.append(f"{name}: the 95 % interval {lower[-1]:.4g} .. {upper[-1]:.4g} is "
                         f"wider than its bounds {b[0]:g}:{b[1]:g}: the data hardly "
                         "determine it")
    d = np.sqrt(np.diag(cov_x))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov_x / np.outer(d, d)
    return Fit(names, start, est, se, lower, upper, corr, n, 0.5 * float(r @ r), count[0],
               result.message, bool(result.success), weights, notes, fitted,
               sorted(logged), sens["count"], sens["how"], quantile,
               "the normal quantile (the SDs known)" if weights == "sd" else
               f"Student's t, {dof} degrees of freedom")


def _values(values: dict[str, float]) -> str:
    return ", ".join(f"{k} = {v:.10g}" for k, v in values.items())


def _by_differences(why: str) -> str:
    return "finite differences of whole runs" + (f" ({why})" if why else "")


def _weight(c, weights: str) -> np.ndarray:
    """What each residual of a comparison is multiplied by."""
    if weights == "sd":
        return 1.0 / c.sd
    if weights == "relative":
        return 1.0 / np.maximum(np.abs(c.observed), 1e-300)
    return np.ones(len(c.t))


def _weighted(runs, weights: str) -> np.ndarray:
    parts = [c.residual * _weight(c, weights) for run in runs for c in run.observed]
    return np.concatenate(parts) if parts else np.empty(0)


def _differences(residuals, x: np.ndarray, step: float, lo, hi) -> np.ndarray:
    """Central differences of the residuals (one-sided at a bound)."""
    cols = []
    for j in range(len(x)):
        h = step * max(abs(x[j]), 1.0)
        up, down = x.copy(), x.copy()
        up[j], down[j] = min(x[j] + h, hi[j]), max(x[j] - h, lo[j])
        cols.append((residuals(up) - residuals(down)) / (up[j] - down[j]))
    return np.column_stack(cols)


_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][-+]?\d+)?"


def written_listing(model, values: dict[str, float]) -> str:
    """The listing's text with each fitted value written where the value was given
    (the rest of the line, its comment included, as it was)."""
    lines = model.ir.source.splitlines(keepends=True)
    for name, value in values.items():
        span = model.ir.spans.get(name)
        if span is None:
            raise UsageError(f"{name}: where it is given is not known; write it by hand")
        line = lines[span.line - 1]
        head, tail = line[:span.column - 1], line[span.column - 1:]
        found = re.match(rf"({re.escape(name)}\s*=\s*)({_NUMBER})(?!\s*,\s*{_NUMBER})",
                         tail, re.I)
        if found is None:
            raise UsageError(f"{name} at line {span.line} is not given as one number: "
                             "write its fitted value by hand")
        lines[span.line - 1] = head + found.group(1) + f"{value:.10G}" + \
            tail[found.end():]
    return "".join(lines)
