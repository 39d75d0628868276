"""SciPy's `OdeSolver` classes (RK45, DOP853, Radau, BDF, LSODA) as steppers."""

from __future__ import annotations

import math

import numpy as np

from ..outcome import Failure
from .base import Hermite, Rhs, StepFailure, Stepper, Stiffness


def solver_tolerance(v: np.ndarray | float) -> np.ndarray | float:
    """A tolerance as a solver takes it: a float when every state has the same one
    (so a run without per-state values computes exactly as before), else the vector."""
    a = np.asarray(v, dtype=float)
    if a.ndim == 0 or a.size == 0 or np.all(a == a.flat[0]):
        return float(a.flat[0]) if a.size else 0.0
    return a


class ScipyStepper(Stepper):
    """One of SciPy's `OdeSolver` classes, step by step.

    Tolerances are per state. Radau and BDF derive their Newton tolerance from a
    scalar RELERR, so they are built with the smallest RELERR (the stricter Newton
    test) and then measure their error against the vector, which is all their
    step control reads afterwards.

    An explicit pair (a route with a `stability_limit`) also runs Hairer's
    stiffness test on its steps. A step beyond the pair's stability boundary is
    limited by stability, not by accuracy, and there the solver's dense output is
    not to be trusted: its polynomial is built from stage derivatives that carry
    the stiff components undamped. DOP853's is 20 tolerance units off on the
    two-mass drive at h*|lambda| ~ 6, where its step ends are within one. Such a
    step is interpolated from its two ends only (a cubic Hermite): it is short,
    since stability made it so, and the ends lie on the slow motion.
    """

    STIFF_STEPS = 15  # positive tests before the run is told (Hairer's)
    CALM_STEPS = 6  # negative tests in a row that start the count again (Hairer's)
    TEST_EVERY = 4  # steps between tests while none is positive

    def __init__(self, name: str, fun: Rhs, t0: float, y0: np.ndarray, t_bound: float, *,
                 rtol: np.ndarray | float, atol: np.ndarray | float, max_step: float,
                 first_step: float | None, stability_limit: float | None = None,
                 jac=None) -> None:
        from scipy import integrate

        from .jacobian import DENSE_UP_TO

        cls = getattr(integrate, name)
        # SciPy's BDF predicts from its differences scaled to the step it meant and
        # corrects over t_new - t, the step the floats give: at TIME = 2.6e5 a first
        # step of 1e-9 (20 ulps) is 1.5 % longer than meant, and at RELERR 1e-9 /
        # ABSERR 1e-12 every try was rejected down to the floats' spacing (the Verner
        # PFAS listing, IALG 2, at its conception event). It runs from 0 in a time of
        # its own, TIME - t0, where a segment's first steps are what they mean.
        self._origin = t0 if name == "BDF" else 0.0
        self._bound = t_bound
        if self._origin:
            origin, field = self._origin, fun
            t0, t_bound = 0.0, t_bound - origin

            def fun(t, y):  # noqa: F811 - the same field in the solver's own time
                return field(t + origin, y)
        rtol, atol = solver_tolerance(rtol), solver_tolerance(atol)
        vector_rtol = isinstance(rtol, np.ndarray) and name in ("Radau", "BDF")
        options = {"rtol": float(np.min(rtol)) if vector_rtol else rtol, "atol": atol,
                   "max_step": max_step}
        if first_step is not None:
            options["first_step"] = min(first_step, abs(t_bound - t0))
        # the model's Jacobian for the implicit solvers (SciPy's LSODA class takes a
        # dense one only: a large model's stays with its differences)
        if jac is not None and name in ("Radau", "BDF", "LSODA") and \
                (name != "LSODA" or len(y0) <= DENSE_UP_TO):
            options["jac"] = jac.for_scipy()
            if self._origin and callable(options["jac"]):
                by_time, origin = options["jac"], self._origin
                options["jac"] = lambda t, y: by_time(t + origin, y)
        self.solver = cls(fun, t0, y0, t_bound, **options)
        # an instant the steps stop at (`stop_at`), and the rest of a step cut there:
        # the step's end, handed out as the next step when the run goes on
        self._stop: float | None = None
        self._rest: tuple[float, np.ndarray] | None = None
        if vector_rtol:
            self.solver.rtol = rtol
        self.t = self.t_old = t0 + self._origin
        self.y = np.asarray(y0, dtype=float)
        self._dense = None
        self._steps = 0
        self._limit = stability_limit
        if self._limit is not None:
            # the last stage's row of the Butcher tableau: its argument is at c = 1
            self._a_last = self.solver.A[self.solver.n_stages - 1, :self.solver.n_stages - 1]
        self._positive = 0  # positive stiffness tests
        self._calm = 0  # negative ones since the last positive
        self._h_lambda = 0.0  # the last estimate of h*|lambda|

    @property
    def nfev(self) -> int:
        return self.solver.nfev

    @property
    def nstep(self) -> int:
        return self._steps

    def _largest(self) -> int:
        """The state a blow-up is named by: the largest, where the stepper stands."""
        return int(np.argmax(np.abs(self.y)))

    def stop_at(self, t: float) -> bool:
        """The step over t is handed out in two, cut at t by its dense output; the
        run goes on from t with the rest of the same step (an ACSL CINT instant whose
        code changes nothing). The solver keeps its history (step size, order,
        differences): a new segment from t starts at order 1 from a guessed step
        (LSODA: 14 steps an interval where AUTO takes 1.4), and a bound at t cuts
        the steps short (LSODA: 5)."""
        if not self.t < t <= self._bound:
            return False
        self._stop = t
        return True

    def truncate(self, t: float) -> None:
        super().truncate(t)
        self._rest = None

    def _cut(self) -> bool:
        """Cut the step handed out at the stop, if it is inside (the rest kept)."""
        stop = self._stop
        if stop is None or not self.t_old < stop < self.t:
            return False
        self._rest = (self.t, self.y)
        self.y = np.asarray(self.interpolant()(stop), dtype=float)
        self.t, self._stop = stop, None
        return True

    def step(self) -> StepFailure | None:
        if self._rest is not None:  # the rest of the step cut at a stop
            self.t_old, (self.t, self.y), self._rest = self.t, self._rest, None
            self._cut()
            return None
        solver = self.solver
        try:
            msg = solver.step()
        except ValueError as exc:
            # (the model's own faults are the vector field's: this is SciPy refusing
            # what overflowed inside its step, RADAU's and BDF's Newton matrix)
            if "infs or NaNs" not in str(exc) or not len(self.y):
                raise
            return StepFailure(Failure.NOT_FINITE, self.t, str(exc), index=self._largest())
        if solver.status == "failed":
            # (SciPy's "Required step size is less than spacing between numbers.")
            if msg and "spacing between numbers" in msg and len(self.y):
                return StepFailure(Failure.STEP_SPACING, self.t, msg, index=self._largest())
            return StepFailure(Failure.SOLVER, self.t, msg or "the integrator failed")
        self._steps += 1
        if self._origin:
            self.t_old = self.t
            self.t = self._bound if solver.t == solver.t_bound else solver.t + self._origin
        else:
            self.t_old = solver.t_old
            self.t = solver.t
        self.y = solver.y
        self._dense = None
        if self._limit is not None:
            self._stiffness_test()
        self._cut()
        return None

    def _stiffness_test(self) -> None:
        """h*|lambda| from two evaluations at t+h: the last stage (c = 1) and the
        new point (Hairer, DOPRI5/DOP853): |f(y1) - f(y_s)| / |y1 - y_s|. Tested at
        every step while positive, else at every TEST_EVERY-th (Hairer's codes test
        every 1000th), which keeps its cost at about 2 us a step."""
        if self._positive == 0 and self._steps % self.TEST_EVERY:
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
        self._h_lambda = abs(h) * math.sqrt(float(g @ g) / den)
        if self._h_lambda > self._limit:
            self._calm = 0
            self._positive += 1
            if self._positive == self.STIFF_STEPS and self.stiff is None:
                self.stiff = Stiffness(self.t, self._h_lambda)
        else:
            self._calm += 1
            if self._calm == self.CALM_STEPS:
                self._positive = 0

    def interpolant(self):
        if self._dense is None:
            solver = self.solver
            if self._limit is not None and self._positive >= self.STIFF_STEPS and \
                    self._h_lambda > self._limit:
                # a stability-limited step: its stage derivatives carry the stiff
                # components undamped, so interpolate from the ends only
                k = solver.K
                self._dense = Hermite(solver.t_old, solver.y_old, k[0].copy(), solver.t,
                                      solver.y, k[-1].copy())
            elif self._origin:
                dense, origin = solver.dense_output(), self._origin
                self._dense = lambda t: dense(t - origin)
            else:
                self._dense = solver.dense_output()
        return self._dense
