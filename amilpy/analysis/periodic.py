"""The periodic steady state by shooting: a settling run, then Newton on the
period map (`problem.Problem`), with the monodromy matrix from the flow map
(`Flow.advance(..., sensitivity=True)`: every switch inside the orbit located,
its saltation in the matrix).

Settling. With a period T the run goes on for whole periods from its start
(at least the settling time, default the listing's FINTIM), so the orbit's
start t0 has the forcing's phase at the run's start. With an angle it goes on
for the settling time, then to where the angle next reaches its initial value
plus a whole number of advances (the section), once more round to measure a
first period, and the angle is set back to its initial value: the orbit starts
on the section angle = initial value.

Newton. Unknowns and residual are scaled by each state's size along the first
period (its largest magnitude, at least ABSERR/RELERR), the period by itself,
the angle's residual by its advance. A step that does not reduce the largest
scaled residual is halved (up to 6 times). Converged when the largest scaled
residual is below `TOL`; 30 steps without that, or a step that cannot reduce
it, is a `NotConverged` carrying the residual history, never an orbit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..diagnostics import AmilError
from ..progress import Progress, report
from ..run import FlowFailed, State
from ..run.dense import sample
from .measure import Stats, measure
from .problem import Closure, Evaluation, Problem

TOL = 1e-8  # the largest scaled residual of a converged orbit
MAX_NEWTON = 30
HALVINGS = 6
MAX_SECTION = 30  # iterations to land on the section
UNIT = 1e-6  # |mu| - 1 below this: neutral (the monodromy's own accuracy)


class NotConverged(AmilError):
    """Newton did not find the orbit: `history` holds the scaled residuals."""

    def __init__(self, message: str, history: list[float]) -> None:
        self.history = list(history)
        text = ", ".join(f"{r:.3g}" for r in history)
        super().__init__(f"{message}; residual history: {text}" if history else message)


@dataclass
class Orbit:
    """A periodic orbit of one run, with data values `params`."""

    closure: Closure
    params: dict[str, float]
    t0: float
    period: float
    start: State  # every state at t0 (free ones too)
    end: State  # after one period
    names: list[str]  # the states, in the order of start.y
    cyclic: list[str]  # the states that repeat
    free: list[str]  # the states left out (nothing depends on them)
    angle: str | None
    multipliers: np.ndarray  # Floquet multipliers (of the cyclic states)
    events: list  # the switches over the period
    residuals: list[float]  # Newton's scaled residuals, first to last
    measures: dict[str, Stats] = field(default_factory=dict)
    x: np.ndarray | None = None  # the unknowns (cyclic states, and the period)
    jacobian: np.ndarray | None = None  # of the residual, at x
    samples: tuple | None = None  # (times, values) of the measured variables
    symmetries: np.ndarray | None = None  # cyclic states x k: directions of trivial 1s

    @property
    def mu_max(self) -> float:
        return float(np.max(np.abs(self.multipliers))) if len(self.multipliers) else 0.0

    @property
    def stable(self) -> bool:
        return self.mu_max < 1.0 - UNIT

    @property
    def neutral(self) -> bool:
        return abs(self.mu_max - 1.0) <= UNIT

    def value(self, name: str) -> float:
        """A state's value at the start of the orbit."""
        return float(self.start.y[self.names.index(name)])


class Peak:
    """Observer: the largest magnitude of each state over the steps it sees, and
    the states at the ends of the steps (a few, spread, for the symmetries)."""

    SPREAD = 8

    def __init__(self, n: int) -> None:
        self.size = np.zeros(n)
        self.ends: list[State] = []

    def __call__(self, ta: float, tb: float, interp, m, z) -> None:
        ys = sample(interp, (0.5 * (ta + tb), tb))
        np.maximum(self.size, np.max(np.abs(ys), axis=1), out=self.size)
        self.ends.append(State(ys[:, 1], tuple(m), tuple(z), tb))

    def spread(self) -> list[State]:
        if not self.ends:
            return []
        k = np.unique(np.linspace(0, len(self.ends) - 1, self.SPREAD).astype(int))
        return [self.ends[i] for i in k]


def _sized(problem: Problem, peak: Peak, period: float) -> None:
    """The state sizes (at least ABSERR/RELERR) and the symmetries, from the
    first period."""
    tol = problem.flow.plan.tol
    problem.scale = np.maximum(peak.size, tol.atol / tol.rtol)
    problem.period_scale = period
    problem.find_symmetries(peak.spread())


# ------------------------------------------------------------------ settling

def settled(problem: Problem, model, length: float | None
            ) -> tuple[Problem, tuple[State, float, np.ndarray]]:
    """`settle`, on the AUTO route instead when the problem chose DOP853 itself and
    the settling run found the model stiff or could not go on."""
    try:
        out = settle(problem, length)
        if not (problem.chosen and problem.flow.stiff):
            return problem, out
    except FlowFailed:
        if not problem.chosen:
            raise
    problem = problem.on_auto(model)
    return problem, settle(problem, length)


def settle(problem: Problem, length: float | None) -> tuple[State, float, np.ndarray]:
    """Run towards the steady state; (base state, t0, first unknowns). Sets the
    problem's state sizes and symmetries."""
    flow = problem.flow
    s = flow.initial_state()
    t_init = s.t
    length = flow.plan.timer["FINTIM"] if length is None else length
    peak = Peak(len(problem.names))
    if problem.angle is None:
        period = problem.fixed_period
        k = max(1, math.ceil(length / period - 1e-9))
        if k > 1:
            s, _ = flow.advance(s, t_init, t_init + (k - 1) * period)
        t0 = t_init + k * period
        s, _ = flow.advance(s, s.t, t0, observer=peak)
        _check_end(s, t0)
        _sized(problem, peak, period)
        return s, t0, problem.unknowns(s, period)
    a, adv = problem.angle, problem.advance
    phi0 = float(s.y[a])
    if length > 0:
        s, _ = flow.advance(s, t_init, t_init + length)
        _check_end(s, t_init + length)
    k = math.ceil((s.y[a] - phi0) / adv + 1e-12)
    s1 = to_section(problem, s, phi0 + k * adv)
    s2 = to_section(problem, s1, phi0 + (k + 1) * adv, peak)
    period = s2.t - s1.t
    y = np.array(s2.y, dtype=float)
    y[a] = phi0  # the dynamics repeat with the angle: start on the section at phi0
    base = flow.state(y, s2.modes, s2.memory, s2.t)
    _sized(problem, peak, period)
    return base, s2.t, problem.unknowns(base, period)


def to_section(problem: Problem, s: State, target: float, observer=None) -> State:
    """Integrate from `s` until the angle equals `target`: Newton in time on the
    angle's rate, each try from the last state short of the target."""
    flow, a = problem.flow, problem.angle
    direction = 1.0 if target >= s.y[a] else -1.0
    short = s  # the latest state before the target

    def rate(state: State) -> float:
        return float(np.asarray(flow.field(state, state.t)(state.t, state.y), dtype=float)[a])

    r = rate(short)
    if r * direction <= 0:
        raise AmilError(f"{problem.names[a]} does not move towards {target:g} (its rate "
                        f"is {r:g} at TIME = {s.t:.9g}): it cannot mark the period")
    t_try = short.t + (target - short.y[a]) / r
    for _ in range(MAX_SECTION):
        cur, _ = flow.advance(short, short.t, t_try, observer=observer)
        _check_end(cur, t_try)
        gap = target - cur.y[a]
        if abs(gap) <= 1e-13 * max(1.0, abs(target)):
            return cur
        r = rate(cur)
        if gap * direction > 0:
            short = cur
        if r * direction <= 0:
            t_try = 0.5 * (short.t + cur.t) if cur is not short else cur.t + 0.1 * (
                cur.t - s.t + 1e-9)
            continue
        t_try = cur.t + gap / r
        if t_try <= short.t:
            t_try = 0.5 * (short.t + cur.t)
    raise AmilError(f"{problem.names[a]} does not settle on {target:g} (section not found "
                    f"after {MAX_SECTION} tries)")


def _check_end(s: State, t: float) -> None:
    if s.t < t * (1 - 1e-12) - 1e-300:
        raise AmilError(f"the run stops at TIME = {s.t:.9g} (a FINISH or TERMT) before the "
                        "steady state")


# -------------------------------------------------------------------- Newton

def newton(problem: Problem, x: np.ndarray, base: State, t0: float,
           progress: Progress | None = None) -> tuple[Evaluation, list[float]]:
    """Newton on the period map from unknowns x; (the converged evaluation with its
    Jacobian, the scaled residuals). `progress` is given a Report at every step
    (task "periodic")."""
    wx, wr = problem.weights
    u = problem.symmetries.basis_x
    history: list[float] = []
    ev = problem.evaluate(x, base, t0, jacobian=True)
    for it in range(MAX_NEWTON):
        norm = float(np.max(np.abs(ev.residual) / wr)) if ev.residual.size else 0.0
        history.append(norm)
        report(progress, "periodic", it, residual=norm)
        if ev.jacobian is None:
            ev = problem.evaluate(ev.x, base, t0, jacobian=True)
        if norm <= TOL:
            return ev, history
        scaled = (ev.jacobian * wx[None, :] / wr[:, None]) @ u
        dx = wx * (u @ np.linalg.lstsq(scaled, -ev.residual / wr, rcond=None)[0])
        step = 1.0
        for _ in range(HALVINGS + 1):
            try:
                trial = problem.evaluate(ev.x + step * dx, base, t0)
            except AmilError:
                trial = None
            if trial is not None and np.all(np.isfinite(trial.residual)):
                tnorm = float(np.max(np.abs(trial.residual) / wr))
                if tnorm < norm or tnorm <= TOL:
                    break
            step *= 0.5
        else:
            raise NotConverged("no Newton step reduces the residual" + _hint(problem, ev),
                               history)
        ev = trial
    raise NotConverged(f"not converged in {MAX_NEWTON} Newton steps" + _hint(problem, ev),
                       history)


def _hint(problem: Problem, ev: Evaluation) -> str:
    """With a period: the state that does not come back, and what to write if it
    is a phase that advances by a fixed amount each period."""
    if problem.angle is not None or not ev.residual.size:
        return ""
    wx, wr = problem.weights
    k = int(np.argmax(np.abs(ev.residual) / wr))
    name = problem.names[problem.cyclic[k]]
    return (f" ({name} changes by {ev.residual[k]:.6g} over the period and does not come "
            f"back; if it advances by a fixed amount each period, an angle or a forcing "
            f"phase, give --angle {name}=VALUE instead of --period)")


def floquet(problem: Problem, ev: Evaluation) -> np.ndarray:
    """The Floquet multipliers, largest first (the symmetries' trivial 1s apart)."""
    p = problem.quotient(ev.poincare)
    mu = np.linalg.eigvals(p) if p.size else np.empty(0)
    return mu[np.argsort(-np.abs(mu))]


def orbit_of(problem: Problem, ev: Evaluation, t0: float, history: list[float],
             names: list[str]) -> Orbit:
    """The Orbit at a converged evaluation, its variables measured over a period."""
    period = problem.period_of(ev.x)
    stats, tracker, end, events = measure(problem.flow, ev.start, t0, period, names)
    pick = problem.names
    return Orbit(problem.closure, problem.params, t0, period, ev.start, end, list(pick),
                 [pick[i] for i in problem.cyclic], [pick[i] for i in problem.free],
                 None if problem.angle is None else pick[problem.angle], floquet(problem, ev),
                 events, history, stats, ev.x, ev.jacobian, tracker.samples(),
                 problem.symmetries.vectors)


def periodic(model, closure: Closure, measure_names: list[str], *, settle_time=None,
             method: str | None = None, rtol: float | None = None, atol: float | None = None,
             progress: Progress | None = None, **params: float) -> Orbit:
    """The periodic steady state of `model` (an api.Model); see the module."""
    problem, (base, t0, x) = settled(Problem(model, closure, params, method, rtol, atol),
                                     model, settle_time)
    ev, history = newton(problem, x, base, t0, progress)
    return orbit_of(problem, ev, t0, history, measure_names)

