"""Integrator routes behind one small interface.

A stepper integrates one smooth segment (modes frozen) from `t0` towards
`t_bound`, one accepted step at a time. The runner needs only:

    step() -> str | None     advance one accepted step; a message if it failed
    t, y, t_old              where the last step ended and began
    interpolant()            callable t -> y on [t_old, t] (dense output)
    truncate(t)              end the last step at t in [t_old, t] (an event)
    nfev                     right-hand-side evaluations so far

Event location, breakpoints and output sampling live in the runner and use only
these, so a route can be added without touching them: subclass `Stepper`, add
a row to `routes.ROUTES` (its `stepper` names the class).
"""

from __future__ import annotations

import bisect
import math
import warnings
from collections.abc import Callable

import numpy as np

from .routes import BY_NAME

Rhs = Callable[[float, np.ndarray], np.ndarray]


class Stepper:
    t: float
    t_old: float
    y: np.ndarray
    nfev: int = 0
    njev: int = 0
    nlu: int = 0
    stiff_at: float | None = None  # where an explicit method became stability-limited

    def step(self) -> str | None:  # pragma: no cover - interface
        raise NotImplementedError

    def interpolant(self) -> Callable[[float], np.ndarray]:  # pragma: no cover
        raise NotImplementedError

    def truncate(self, t: float) -> None:
        """End the last step at `t` (default: take the dense output there)."""
        self.y = np.asarray(self.interpolant()(t), dtype=float)
        self.t = t


class Hermite:
    """The cubic through both ends of a step with their derivatives: the dense
    output of the fixed-step methods, and of a step whose own interpolant is not
    to be trusted (stability-bound, or overflowing inside)."""

    def __init__(self, t0: float, y0: np.ndarray, f0: np.ndarray, t1: float, y1: np.ndarray,
                 f1: np.ndarray) -> None:
        self.t0, self.h = t0, t1 - t0
        self.y0, self.y1 = y0, y1
        self.f0, self.f1 = f0, f1

    def __call__(self, t: float) -> np.ndarray:
        if self.h == 0:
            return self.y1
        s = (t - self.t0) / self.h
        h00 = (1 + 2 * s) * (1 - s) ** 2
        h01 = s * s * (3 - 2 * s)
        h10 = s * (1 - s) ** 2
        h11 = s * s * (s - 1)
        with np.errstate(all="ignore"):
            return h00 * self.y0 + h01 * self.y1 + self.h * (h10 * self.f0 + h11 * self.f1)


class ScipyStepper(Stepper):
    """SciPy's `OdeSolver` classes: RK45, DOP853, Radau, BDF, LSODA.

    The explicit pairs (RK45, DOP853) also run Hairer's stiffness test on their
    steps. A step beyond the pair's stability boundary is limited by stability, not
    by accuracy, and there the solver's dense output is not to be trusted: its
    polynomial is built from stage derivatives that carry the stiff components
    undamped. DOP853's is 20 tolerance units off on the two-mass drive at
    h*|lambda| ~ 6, where its step ends are within one. Such a step is
    interpolated from its two ends only (a cubic Hermite): it is short, since
    stability made it so, and the ends lie on the slow motion.
    """

    # Hairer's thresholds for h*|lambda| in DOPRI5 and DOP853: the stability
    # boundary of each pair on the negative real axis
    STABILITY_LIMITS = {"RK45": 3.25, "DOP853": 6.1}
    # BDF advances with the solution whose error it estimates (no local
    # extrapolation, unlike RK45, DOP853 and Radau), so on a lightly damped mode its
    # errors per step add up: 25 tolerance units on the two-mass drive at K = 1E2,
    # RELERR 1E-6, 77 at 1E-9. A decade tighter locally keeps it within 4 (12 at
    # 1E-9) for 15-40% more evaluations; see docs/robustness.md.
    LOCAL_TOLERANCE = {"BDF": 0.1}
    STIFF_STEPS = 15  # positive tests before the run is told (Hairer's)
    CALM_STEPS = 6  # negative tests in a row that start the count again (Hairer's)
    TEST_EVERY = 4  # steps between tests while none is positive

    def __init__(self, name: str, fun: Rhs, t0: float, y0: np.ndarray, t_bound: float,
                 rtol: float, atol, max_step: float, first_step: float | None) -> None:
        from scipy import integrate

        cls = getattr(integrate, name)
        scale = self.LOCAL_TOLERANCE.get(name, 1.0)
        options = {"rtol": rtol * scale, "atol": np.asarray(atol) * scale,
                   "max_step": max_step}
        if first_step is not None:
            options["first_step"] = min(first_step, abs(t_bound - t0))
        self.solver = cls(fun, t0, y0, t_bound, **options)
        self.t = self.t_old = t0
        self.y = np.asarray(y0, dtype=float)
        self._dense = None
        self._limit = self.STABILITY_LIMITS.get(name)
        if self._limit is not None:
            # the last stage's row of the Butcher tableau: its argument is at c = 1
            self._a_last = self.solver.A[self.solver.n_stages - 1, :self.solver.n_stages - 1]
        self._count = 0
        self._positive = 0  # positive stiffness tests
        self._calm = 0  # negative ones since the last positive
        self.h_lambda = 0.0  # the last estimate of h*|lambda|

    @property
    def nfev(self) -> int:  # type: ignore[override]
        return self.solver.nfev

    @property
    def njev(self) -> int:  # type: ignore[override]
        return self.solver.njev

    @property
    def nlu(self) -> int:  # type: ignore[override]
        return self.solver.nlu

    def step(self) -> str | None:
        solver = self.solver
        msg = solver.step()
        if solver.status == "failed":
            return msg or "the integrator failed"
        self.t_old = solver.t_old
        self.t = solver.t
        self.y = solver.y
        self._dense = None
        if self._limit is not None:
            self._stiffness_test()
        return None

    def _stiffness_test(self) -> None:
        """h*|lambda| from two evaluations at t+h: the last stage (c = 1) and the
        new point (Hairer, DOPRI5/DOP853): |f(y1) - f(y_s)| / |y1 - y_s|. Tested at
        every step while positive, else at every TEST_EVERY-th (Hairer's codes test
        every 1000th), which keeps its cost at about 2 us a step."""
        self._count += 1
        if self._positive == 0 and self._count % self.TEST_EVERY:
            return
        solver = self.solver
        s = solver.n_stages
        k = solver.K
        h = solver.h_previous
        d = solver.y - solver.y_old - h * (self._a_last @ k[:s - 1])
        den = float(d @ d)
        if not 0.0 < den < math.inf:
            return
        g = k[s] - k[s - 1]
        self.h_lambda = abs(h) * math.sqrt(float(g @ g) / den)
        if self.h_lambda > self._limit:
            self._calm = 0
            self._positive += 1
            if self._positive == self.STIFF_STEPS and self.stiff_at is None:
                self.stiff_at = self.t
        else:
            self._calm += 1
            if self._calm == self.CALM_STEPS:
                self._positive = 0

    def interpolant(self):
        if self._dense is None:
            solver = self.solver
            if self._positive >= self.STIFF_STEPS and self.h_lambda > self._limit:
                # a stability-limited step: its stage derivatives carry the stiff
                # components undamped, so interpolate from the ends only
                k = solver.K
                self._dense = Hermite(solver.t_old, solver.y_old, k[0].copy(), solver.t,
                                      solver.y, k[-1].copy())
            else:
                self._dense = solver.dense_output()
        return self._dense

    @property
    def step_size(self) -> float | None:
        return self.solver.step_size


class FixedStepper(Stepper):
    """CSMP's fixed-step methods with step DELT on a grid anchored at TIME = 0.

    Steps end on the DELT grid (so output instants that are multiples of DELT are
    hit exactly); a step is shortened to end at the segment bound (a breakpoint)
    and, after an event, at the located instant. Dense output is the cubic
    Hermite through both ends, of the same order as RK4.
    """

    order = 1
    # |h*lambda| where the method's stability region ends on the negative real axis
    STABILITY_LIMIT = 2.0
    UNSTABLE_STEPS = 3
    GROWTH = 1e3
    TEST_EVERY = 4  # steps between tests while none is past the limit

    def __init__(self, fun: Rhs, t0: float, y0: np.ndarray, t_bound: float, delt: float) -> None:
        self.fun = fun
        self.t = self.t_old = t0
        self.y = np.asarray(y0, dtype=float)
        self.t_bound = t_bound
        self.delt = delt
        self.f = self._call(t0, self.y)
        self.y_old = self.y
        self.f_old = self.f
        self.steps_taken = 0  # in this segment (Adams starts with a one-step method)
        self._nfev = 1
        self._count = 0
        self._beyond = 0  # tests in a row past the stability limit
        self._dy_start = 0.0  # |y_new - y| when that streak began
        self._since = 0.0  # TIME it began
        # (TIME the growth began, the largest stable DELT) once the run must stop
        self.unstable: tuple[float, float] | None = None

    @property
    def nfev(self) -> int:  # type: ignore[override]
        return self._nfev

    def _call(self, t: float, y: np.ndarray) -> np.ndarray:
        self._nfev = getattr(self, "_nfev", 0) + 1
        return np.asarray(self.fun(t, y), dtype=float)

    def next_time(self) -> float:
        k = math.floor(self.t / self.delt + 1e-9) + 1
        t_next = k * self.delt
        # a sliver left before the grid point after an event: merge into one step
        if t_next - self.t < 1e-6 * self.delt:
            t_next += self.delt
        return min(t_next, self.t_bound)

    def advance(self, t: float, y: np.ndarray, f: np.ndarray, h: float) -> np.ndarray:
        raise NotImplementedError

    def step(self) -> str | None:
        if self.t >= self.t_bound:
            return "the segment is already finished"
        t_new = self.next_time()
        h = t_new - self.t
        y_new = self.advance(self.t, self.y, self.f, h)
        if not np.all(np.isfinite(y_new)):
            bad = int(np.flatnonzero(~np.isfinite(y_new))[0])
            self.bad_index = bad
            return f"the state is no longer finite (step DELT = {self.delt:g} may be unstable)"
        self.steps_taken += 1
        self.t_old, self.y_old, self.f_old = self.t, self.y, self.f
        self.t, self.y = t_new, y_new
        self.f = self._call(t_new, y_new)
        self._count += 1
        if self._beyond or self._count % self.TEST_EVERY == 0:
            return self._stability_test(h)
        return None

    def _stability_test(self, h: float) -> str | None:
        """h*|lambda| along the last step, |f(y1) - f(y0)| / |y1 - y0|, with no extra
        evaluations. Past the method's limit on a decaying mode, the numerical
        solution grows by a factor each step. After UNSTABLE_STEPS such steps, once
        the step's change has grown GROWTH-fold, the run is stopped, long before
        the state overflows. AB2 at K = 1E5 in the stress suite used to print a
        finished table ending at 5.7E149."""
        dy = self.y - self.y_old
        den = float(dy @ dy)
        if not 0.0 < den < math.inf:
            self._beyond = 0
            return None
        df = self.f - self.f_old
        h_lambda = abs(h) * math.sqrt(float(df @ df) / den)
        # along a decaying mode (df.dy < 0) growth is the method's, not the model's:
        # a finite-time singularity grows with df.dy > 0 and is left to the non-finite
        # check, with its own message
        if not (h_lambda > self.STABILITY_LIMIT and float(df @ dy) < 0.0):
            self._beyond = 0
            return None
        if self._beyond == 0:
            self._dy_start = math.sqrt(den)
            self._since = self.t_old
        self._beyond += 1
        if self._beyond >= self.UNSTABLE_STEPS and math.sqrt(den) > self.GROWTH * \
                self._dy_start:
            self.bad_index = int(np.argmax(np.abs(dy)))
            # |lambda| from this step's own length (shorter than DELT after an event)
            self.unstable = (self._since, self.STABILITY_LIMIT * abs(h) / h_lambda)
            return (f"h*|lambda| = {h_lambda:.3g} is past the method's stability limit "
                    f"{self.STABILITY_LIMIT:g}")
        return None

    def interpolant(self):
        return Hermite(self.t_old, self.y_old, self.f_old, self.t, self.y, self.f)

    def truncate(self, t: float) -> None:
        """Redo the last step with the method itself, ending exactly at t."""
        h = t - self.t_old
        self.steps_taken -= 1
        self.t, self.y, self.f = self.t_old, self.y_old, self.f_old
        if h > 0:
            y_new = self.advance(self.t, self.y, self.f, h)
            self.steps_taken += 1
            self.t_old = self.t
            self.t, self.y = t, y_new
            self.f = self._call(t, y_new)


class Euler(FixedStepper):
    order = 1
    STABILITY_LIMIT = 2.0

    def advance(self, t, y, f, h):
        return y + h * f


class Heun(FixedStepper):
    """TRAPZ: Euler predictor, trapezoid corrector."""

    order = 2
    STABILITY_LIMIT = 2.0

    def advance(self, t, y, f, h):
        yp = y + h * f
        return y + 0.5 * h * (f + self._call(t + h, yp))


class RK4(FixedStepper):
    order = 4
    STABILITY_LIMIT = 2.785

    def advance(self, t, y, f, h):
        k1 = f
        k2 = self._call(t + 0.5 * h, y + 0.5 * h * k1)
        k3 = self._call(t + 0.5 * h, y + 0.5 * h * k2)
        k4 = self._call(t + h, y + h * k3)
        return y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


class AdamsBashforth2(FixedStepper):
    """ADAMS: two-step Adams-Bashforth; starts (and restarts) with a Heun step."""

    order = 2

    STABILITY_LIMIT = 1.0

    def advance(self, t, y, f, h):
        if self.t_old < t and self.steps_taken and self.t > self.t_old:
            h_prev = t - self.t_old
            f_prev = self.f_old
            # variable-step AB2 (steps after a shortened one keep second order)
            r = h / h_prev
            return y + h * ((1.0 + 0.5 * r) * f - 0.5 * r * f_prev)
        yp = y + h * f
        return y + 0.5 * h * (f + self._call(t + h, yp))


class OdeintStepper(Stepper):
    """AUTO: Fortran LSODA (`odeint`) over chunks of check instants.

    One `odeint` call integrates through many output instants with no Python
    between its internal steps (only the right-hand side is Python), which is
    what makes it several times faster than driving a solver step by step. Its
    "steps" here are the check instants (the output grid): the runner looks at
    the switching surfaces there. Where a surface has crossed, `interpolant()`
    integrates that one interval again with SciPy's LSODA class, whose dense
    output is accurate to the tolerance, so the crossing is located as
    precisely as with any other route. A chunk grows geometrically after each
    start, so the work thrown away after an event stays small.
    """

    def __init__(self, fun: Rhs, t0: float, y0: np.ndarray, t_bound: float, checks,
                 rtol: float, atol, max_step: float, first_step: float | None,
                 chunk: int = 16) -> None:
        self.fun = fun
        self.t = self.t_old = t0
        self.y = np.asarray(y0, dtype=float)
        self.y_old = self.y
        self.t_bound = t_bound
        # the runner passes the instants strictly inside (t0, t_bound), in order
        self.checks = np.append(np.asarray(checks, dtype=float), t_bound)
        self.rtol, self.atol, self.max_step = rtol, atol, max_step
        self.first_step = first_step
        self.T = np.empty(0)  # the check instants integrated so far ...
        self.Y = np.empty((0, len(self.y)))  # ... their states ...
        self.pos = 0  # ... and how many of them the runner has taken
        self.next_check = 0
        self.chunk = chunk
        self._nfev = 0
        self._dense = None

    @property
    def nfev(self) -> int:  # type: ignore[override]
        return self._nfev + (self.fallback.nfev if self.fallback is not None else 0)

    def _fill(self) -> None:
        from scipy.integrate import odeint

        ts = self.checks[self.next_check:self.next_check + self.chunk]
        self.chunk = min(self.chunk * 4, 4096)
        grid = np.concatenate(([self.t], ts))
        options = {"rtol": self.rtol, "atol": self.atol, "tfirst": True, "full_output": True,
                   "mxstep": 1_000_000}
        if math.isfinite(self.max_step):
            options["hmax"] = self.max_step
        if self.first_step:
            options["h0"] = min(self.first_step, ts[0] - self.t)
        if ts[-1] >= self.t_bound:
            options["tcrit"] = np.array([self.t_bound])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a failure is handled below, not printed
            ys, info = odeint(self.fun, self.y, grid, **options)
        self._nfev += int(info["nfe"][-1]) if len(info["nfe"]) else 0
        self.first_step = float(info["hu"][-1]) if len(info["hu"]) else None
        if info["message"] != "Integration successful.":
            # keep the instants LSODA really passed, then let SciPy's LSODA class
            # take over from the last of them: it fails (or not) with a clear message
            tcur = np.asarray(info["tcur"])
            good = 0
            while (good < len(ts) and good < len(tcur) and tcur[good] >= ts[good]
                   and np.all(np.isfinite(ys[good + 1]))):
                good += 1
            self.T, self.Y, self.pos = ts[:good], ys[1:good + 1], 0
            t_last, y_last = (ts[good - 1], ys[good]) if good else (self.t, self.y)
            self.fallback = ScipyStepper("LSODA", self.fun, float(t_last), y_last,
                                         self.t_bound, self.rtol, self.atol, self.max_step,
                                         None)
            return None
        self.T, self.Y, self.pos = ts, ys[1:], 0
        self.next_check += len(ts)
        return None

    fallback: ScipyStepper | None = None

    def pending(self) -> tuple[np.ndarray, np.ndarray]:
        """The integrated check instants the runner has not taken yet (integrating
        the next chunk if there are none); empty once LSODA's class has taken over."""
        if self.pos >= len(self.T) and self.fallback is None:
            self._fill()
        return self.T[self.pos:], self.Y[self.pos:]

    def consume(self, n: int) -> None:
        """Take the next n pending instants at once (the runner found them clean)."""
        last = self.pos + n - 1
        if n >= 2:
            self.t_old, self.y_old = float(self.T[last - 1]), self.Y[last - 1]
        else:
            self.t_old, self.y_old = self.t, self.y
        self.t, self.y = float(self.T[last]), self.Y[last]
        self.pos += n
        self._dense = None

    def step(self) -> str | None:
        if self.pos >= len(self.T) and self.fallback is None:
            self._fill()
        if self.pos >= len(self.T) and self.fallback is not None:
            err = self.fallback.step()
            self.t_old, self.t, self.y = self.fallback.t_old, self.fallback.t, self.fallback.y
            self._dense = None
            return err
        self.consume(1)
        return None

    def interpolant(self):
        if self.fallback is not None and self.pos >= len(self.T) and \
                self.t == self.fallback.t:
            return self.fallback.interpolant()
        if self._dense is None:
            from scipy.integrate import LSODA

            # Integrate the interval once more with dense output. Tighter than the
            # run: the state at the located crossing starts the next segment, and
            # a run with many switches must not add a tolerance's worth at each.
            rtol = max(self.rtol * 0.01, 1e-13)
            atol = np.maximum(np.asarray(self.atol, dtype=float) * 0.01, 1e-300)
            solver = LSODA(self.fun_ivp, self.t_old, self.y_old, self.t, rtol=rtol,
                           atol=atol)
            pieces = []
            while solver.status == "running":
                solver.step()
                if solver.status == "failed":
                    break
                pieces.append((solver.t_old, solver.t, solver.dense_output()))
            self._nfev += solver.nfev
            end_y = solver.y

            ends = [b for _, b, _ in pieces]

            def dense(t: float) -> np.ndarray:
                k = bisect.bisect_left(ends, t)
                return pieces[k][2](t) if k < len(pieces) else end_y

            self._dense = dense
            self.y = end_y  # consistent with the dense output at the interval's end
        return self._dense

    def fun_ivp(self, t, y):
        return self.fun(t, y)


class Clock(Stepper):
    """A model with no states: time advances in steps of at most `max_step`
    (an output interval) so that switches on TIME are still watched."""

    def __init__(self, t0: float, t_bound: float, max_step: float) -> None:
        self.t = self.t_old = t0
        self.t_bound = t_bound
        self.h = max_step if math.isfinite(max_step) else (t_bound - t0) / 100.0
        self.y = np.zeros(0)

    def step(self) -> str | None:
        self.t_old = self.t
        self.t = min(self.t + self.h, self.t_bound)
        return None

    def interpolant(self):
        return lambda t: np.zeros(0)


FIXED: dict[str, type[FixedStepper]] = {
    cls.__name__: cls for cls in (RK4, Euler, Heun, AdamsBashforth2)}


def make_stepper(route: str, fun: Rhs, t0: float, y0: np.ndarray, t_bound: float, *,
                 rtol: float, atol, delt: float, max_step: float = math.inf,
                 first_step: float | None = None, checks=None, chunk: int = 16) -> Stepper:
    """The stepper for a canonical route name (see `routes.ROUTES`). `checks` are
    the instants the runner needs to look at (the output grid); only the odeint
    stepper, which steps from check to check, uses them (without them it runs on
    SciPy's LSODA class, which sees every step)."""
    r = BY_NAME[route]
    if len(y0) == 0:
        return Clock(t0, t_bound, min(max_step, delt) if r.fixed else max_step)
    if r.stepper == "odeint" and checks is not None:
        return OdeintStepper(fun, t0, y0, t_bound, checks, rtol, atol, max_step, first_step,
                             chunk)
    if r.fixed:
        return FIXED[r.stepper](fun, t0, y0, t_bound, delt)
    return ScipyStepper(r.scipy, fun, t0, y0, t_bound, rtol, atol, max_step, first_step)

