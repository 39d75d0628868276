"""Equilibria: the state where every derivative is zero, in the switch branches
that hold there, its eigenvalues and stability, and the linear model (A, B, C,
D) about it.

The field is taken at a fixed TIME (`at`, default the run's start), so what TIME
drives (a STEP, a forcing) is frozen there. Three kinds of state are not
unknowns:
- *held*: a state whose derivative reads no state (a forcing phase PH' = W, a
  clock): no state can make its rate zero; it is held at its value, like TIME,
  and its rate is reported (nonzero: the equilibrium is the one with it frozen);
- *free*: a state nothing reads (a running integral of work): held, its rate
  reported;
- the rest are the unknowns x, with f_x(x) = 0 the equations.

Solving. Newton from the guess, the branches chosen afresh at every iterate as
at a start (a dead zone's contact, a Filippov sliding motion: the branch is part
of the answer, and an iterate that crosses a surface continues in the branch on
the other side). Each step is the minimum-norm least-squares one in coordinates
scaled by the states' sizes, so a direction the field does not change along (a
drive chain written with absolute speeds: V1 = V2 = V3 drifting together) keeps
the guess's value. Where Newton does not converge (a branch whose equations
cannot be solved: teeth in the gap cannot carry a load), pseudo-transient
continuation: implicit Euler steps (I/tau - J) dx = f whose tau grows as the
residual falls (Kelley & Keyes 1998, "switched evolution relaxation"), which
follows the damped dynamics towards a stable equilibrium and becomes Newton
near it. Converged: every equation's residual below TOL of its rate scale
(sum_j |J_ij| s_j, s the states' sizes), in branches that the solution itself
selects.

The linear model about the equilibrium: A = d f_x/d x (the model's own
Jacobian, as `modes`), B = d f_x/d u for the inputs u (data values: central
differences of the run's generated functions bound to u +- h, the INITIAL
section worked out again for each), C = d y/d x and D = d y/d u for the outputs
y (states or DYNAMIC variables), by central differences of the generated output
function in the equilibrium's branches (exact to rounding where the branch is
linear).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..diagnostics import AmilError, UsageError, with_hint
from ..run import Flow, FlowFailed, State
from ..run.jacobian import refined
from .linear import ZERO, Mode, jacobian, mode_list
from .problem import ATOL, RTOL, SYMMETRY, free_states, read_closure
from .sensitivity import moved_flows

TOL = 1e-10  # a residual below this fraction of its equation's rate scale is zero
MAX_NEWTON = 30
POLISH = 2  # Newton steps taken past convergence while the residual still falls
MAX_PSEUDO = 400  # pseudo-transient steps

HELD, FREE, SOLVED = "held", "free", "solved"


class NoEquilibrium(FlowFailed):
    """No equilibrium was found from the guess: the best point and its residuals
    are in `best` (a State) and the message."""

    def __init__(self, message: str, best: State | None = None) -> None:
        self.best = best
        super().__init__(message)


@dataclass(frozen=True)
class Linear:
    """x' = A x + B u, y = C x + D u about the equilibrium (deviations)."""

    states: list[str]
    inputs: list[str]
    outputs: list[str]
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    d: np.ndarray

    def transfer(self, w: np.ndarray) -> np.ndarray:
        """G(jw) = C (jw I - A)^-1 B + D: shape (len(w), outputs, inputs)."""
        n = len(self.states)
        out = np.empty((len(w), len(self.outputs), len(self.inputs)), dtype=complex)
        eye = np.eye(n)
        for k, wk in enumerate(np.asarray(w, dtype=float)):
            x = np.linalg.solve(1j * wk * eye - self.a, self.b) if n else \
                np.zeros((0, len(self.inputs)))
            out[k] = self.c @ x + self.d
        return out

    def frequencies(self, points: int = 400) -> np.ndarray:
        """A frequency range [rad/s] covering the modes: a decade below the slowest
        nonzero eigenvalue's magnitude to a decade above the fastest."""
        lam = np.abs(np.linalg.eigvals(self.a)) if len(self.states) else np.array([])
        top = float(np.max(lam)) if lam.size else 0.0
        lam = lam[lam > ZERO * top] if top else lam[:0]
        lo, hi = (float(np.min(lam)) / 10, float(np.max(lam)) * 10) if lam.size else (0.1, 10.0)
        return np.logspace(math.log10(lo), math.log10(hi), points)


@dataclass(frozen=True)
class Equilibrium:
    """The equilibrium of one run, the field frozen at TIME = `time`."""

    time: float
    state: State
    names: list[str]  # every state, in `state.y` order
    roles: dict[str, str]  # name -> HELD, FREE or SOLVED
    rates: np.ndarray  # the derivatives there (zero to TOL for the solved ones)
    residual: float  # the largest |f_i| / rate scale_i over the solved states
    iterations: int
    how: str  # "Newton" or "pseudo-transient continuation, then Newton"
    surfaces: list[tuple[str, float]]  # each watched surface and its branch there
    jacobian: np.ndarray  # d f_x/d x over the solved states
    error: float  # the Jacobian's estimated relative error (0: the model's own)
    modes: list[Mode]  # of `jacobian`
    linear: Linear | None = None
    params: dict[str, float] | None = None

    @property
    def solved(self) -> list[str]:
        return [n for n in self.names if self.roles[n] == SOLVED]

    @property
    def stability(self) -> str:
        """"stable" (every mode decays, zero modes apart: `zero_modes`), "unstable"
        (one grows), "marginal" (none grows, a nonzero one neither grows nor
        decays: an undamped oscillation), or "none" (no state is solved for: every
        one is held or free)."""
        if not self.solved:
            return "none"
        top = max((abs(m.eigenvalue) for m in self.modes), default=0.0)
        live = [m for m in self.modes if not m.zero]
        if any(m.eigenvalue.real > ZERO * top for m in live):
            return "unstable"
        if any(m.eigenvalue.real >= -ZERO * top for m in live):
            return "marginal"
        return "stable"

    @property
    def zero_modes(self) -> int:
        """Eigenvalues ~ 0: directions the field does not change along (a drift)."""
        return sum(m.zero for m in self.modes)

    def __getitem__(self, name: str) -> float:
        return float(self.state.y[self.names.index(name.upper())])


def roles(model) -> dict[str, str]:
    """Each state's role (see the module): HELD, FREE or SOLVED."""
    free = free_states(model)
    states = {s.name for s in model.states}
    out = {}
    for s in model.states:
        if s.name in free:
            out[s.name] = FREE
        elif not read_closure(model, [s.deriv]) & states:
            out[s.name] = HELD
        else:
            out[s.name] = SOLVED
    return out


class _Problem:
    """f_x(x) with the held and free states fixed, the branches chosen afresh."""

    def __init__(self, flow: Flow, start: State, t: float, unknown: np.ndarray) -> None:
        self.flow, self.t, self.unknown = flow, t, unknown
        self.memory = start.memory
        self.trouble = ""  # why the field could not be had at the last point tried
        self._last: tuple | None = None  # (state, its Linearisation)
        tol = flow.plan.tol
        self.floor = np.broadcast_to(np.asarray(tol.atol / tol.rtol, dtype=float),
                                     (len(start.y),)).copy()

    def at(self, y: np.ndarray) -> tuple[State | None, np.ndarray]:
        """The state at y with its branches as at a start, and the field there; (None,
        infinities) where the field cannot be had (a fault, an implicit loop that does
        not converge): the caller shortens its step."""
        try:
            state = self.flow.state(y, None, self.memory, self.t)
            f = np.asarray(self.flow.field(state, self.t)(self.t, np.array(state.y)),
                           dtype=float)
        except (AmilError, ArithmeticError, ValueError) as exc:
            self.trouble = str(exc.diagnostics[0].message if isinstance(exc, AmilError)
                               and exc.diagnostics else exc)
            return None, np.full(len(y), np.inf)
        if not np.all(np.isfinite(f)):
            bad = self.flow.state_names[int(np.argmin(np.isfinite(f)))]
            self.trouble = f"d{bad}/dt is not finite"
            return None, np.full(len(y), np.inf)
        return state, f

    def jac(self, state: State) -> tuple[np.ndarray, float]:
        lin = self.linearisation(state)
        return lin.jacobian, lin.error

    def linearisation(self, state: State):
        """`linear.jacobian` at `state`; the last one kept (the solution's is asked for
        again once it is found)."""
        if self._last is None or self._last[0] is not state:
            self._last = (state, jacobian(self.flow, state, self.t))
        return self._last[1]

    def scales(self, y: np.ndarray) -> np.ndarray:
        return np.maximum(np.abs(y), self.floor)

    def measure(self, f: np.ndarray, jac: np.ndarray, y: np.ndarray) -> float:
        """The largest |f_i| / rate scale_i over the unknowns (see the module)."""
        x = self.unknown
        if not len(x):
            return 0.0
        rate = np.abs(jac[np.ix_(x, x)]) @ self.scales(y)[x]
        size = np.abs(f[x])
        # (a row of zeros: nothing moves that rate in this branch; unconverged unless 0)
        ratio = np.divide(size, rate, out=np.where(size > 0, np.inf, 0.0), where=rate > 0)
        return float(np.max(ratio))


def equilibrium(model, at: float | None = None, guess: dict[str, float] | None = None, *,
                method: str | None = None, rtol: float | None = None,
                atol: float | None = None, inputs=(), outputs=(), progress=None,
                **params: float) -> Equilibrium:
    """The equilibrium of `model` (an api.Model) near its initial state, or near
    `guess` (state name -> value), with the field frozen at TIME `at` (default its
    start); with `inputs`/`outputs` (data values / variables) its linear model."""
    flow = model.flow(method=method, rtol=rtol or RTOL, atol=atol or ATOL, **params)
    flow.opts.progress = progress
    start = flow.initial_state()
    t = start.t if at is None else float(at)
    names = flow.state_names
    y = np.array(start.y, dtype=float)
    for key, value in (guess or {}).items():
        name = key.upper()
        if name not in names:
            raise UsageError(with_hint(f"--guess {name}: not a state of this model (the "
                                       "INTGRL variables are)", name, names))
        y[names.index(name)] = float(value)
    bad = [n for n, v in zip(names, y, strict=True) if not math.isfinite(v)]
    if bad:
        raise NoEquilibrium(f"the start is not finite ({bad[0]} = {y[names.index(bad[0])]}):"
                            f" give --guess {bad[0]}=VALUE, or values that make it finite")
    role = roles(model.ir)
    unknown = np.array([k for k, n in enumerate(names) if role[n] == SOLVED], dtype=int)
    problem = _Problem(flow, start, t, unknown)
    state, f, jac, its, how = _solve(problem, y)
    state, f, jac = _keep_guess(problem, state, f, jac, y)
    jx = jac[np.ix_(unknown, unknown)]
    lin = problem.linearisation(state)
    linear = _linear(model, flow, state, t, names, unknown, lin.jacobian, inputs, outputs,
                     params) if inputs or outputs else None
    return Equilibrium(t, state, names, role, f, problem.measure(f, jac, state.y), its, how,
                       list(zip(flow.surfaces, state.modes, strict=True)), jx, lin.error,
                       mode_list(jx), linear, dict(params))


def _solve(problem: _Problem, y0: np.ndarray):
    """(state, f, J, iterations, how): Newton from y0, else pseudo-transient
    continuation and then Newton (see the module)."""
    found = _newton(problem, y0)
    if found[0] is not None:
        return (*found[:4], "Newton")
    best = found[4]
    state, iterations = _pseudo_transient(problem, y0)
    found = _newton(problem, np.array(state.y, dtype=float)) if state is not None else \
        (None, None, None, 0, best)
    if found[0] is not None:
        return (found[0], found[1], found[2], iterations + found[3],
                "pseudo-transient continuation, then Newton")
    best = min((best, found[4]), key=lambda b: b[0])
    if best[1] is None:
        raise NoEquilibrium(f"no equilibrium found: the field cannot be had at the guess "
                            f"or near it ({problem.trouble}); give --guess NAME=VALUE "
                            "where the listing's equations hold")
    raise NoEquilibrium(
        f"no equilibrium found from the guess: the best point has a residual of "
        f"{best[0]:.3g} of its rate scale{_where(problem, best[1])} "
        f"({_worst(problem, best[2])}); give "
        "--guess NAME=VALUE nearer one, or check that one exists (a state driven at "
        "a constant rate by a load nothing balances has none)", best[1])


def _keep_guess(problem: _Problem, state: State, f: np.ndarray, jac: np.ndarray,
                guess: np.ndarray):
    """The solution moved back towards the guess along the directions the field does
    not change along (null vectors of the scaled Jacobian): a drift keeps the guess's
    value, as the minimum-norm Newton steps do, also after the pseudo-transient
    steps have moved it. Kept only if it is still an equilibrium."""
    x = problem.unknown
    if not len(x):
        return state, f, jac
    s = problem.scales(state.y)[x]
    if not np.all(np.isfinite(jac)):
        return state, f, jac
    _, sv, vt = np.linalg.svd(jac[np.ix_(x, x)] * s)
    null = vt[np.append(sv, np.zeros(len(x) - len(sv))) <= SYMMETRY * (sv[0] if len(sv)
                                                                      else 0.0)]
    if not len(null):
        return state, f, jac
    y = np.array(state.y, dtype=float)
    moved = (y[x] - guess[x]) / s
    y[x] -= (null.T @ (null @ moved)) * s
    back, fb = problem.at(y)
    if back is None:
        return state, f, jac
    jb, _ = problem.jac(back)
    if tuple(back.modes) == tuple(state.modes) and problem.measure(fb, jb, back.y) <= TOL:
        return back, fb, jb
    return state, f, jac


def _worst(problem: _Problem, f: np.ndarray) -> str:
    x = problem.unknown
    k = int(x[int(np.argmax(np.abs(f[x])))])
    return f"d{problem.flow.state_names[k]}/dt = {f[k]:.6g} there"


def _where(problem: _Problem, state: State | None) -> str:
    if state is None:
        return ""
    names = problem.flow.state_names
    shown = ", ".join(f"{names[k]} = {state.y[k]:.6g}" for k in problem.unknown[:6])
    return f" at {shown}{', ...' if len(problem.unknown) > 6 else ''}"


def _newton(problem: _Problem, y: np.ndarray):
    """(state, f, J, iterations, best) on convergence, else (None, ..., best):
    best = (measure, state, f). A step to where the field cannot be had is halved."""
    x = problem.unknown
    best = (math.inf, None, None)
    seen: set[tuple] = set()
    polish, last, kept = 0, math.inf, None
    back = None  # (the last iterate, its step): for halving
    for k in range(MAX_NEWTON):
        state, f = problem.at(y)
        if state is None:
            if back is None or not np.any(back[1]):
                break
            y = back[0].copy()
            back = (back[0], back[1] / 2)
            y[x] += back[1]
            continue
        jac, _ = problem.jac(state)
        r = problem.measure(f, jac, state.y)
        if r < best[0]:
            best = (r, state, f)
        if r <= TOL and (r == 0 or polish >= POLISH or r >= last):
            return (state, f, jac, k, best) if r <= last else (*kept, k, best)
        if r <= TOL:  # (converged: a step or two more while the residual falls)
            polish += 1
        last, kept = r, (state, f, jac)
        s = problem.scales(state.y)[x]
        step = np.linalg.lstsq(jac[np.ix_(x, x)] * s, -f[x], rcond=1e-12)[0] * s
        key = (tuple(state.modes), tuple(np.round(step / s, 12)))
        if key in seen:  # (a cycle between branches)
            break
        seen.add(key)
        y = np.array(state.y, dtype=float)
        back = (y.copy(), step)
        y[x] += step
    if last <= TOL:  # (converged, and the polishing steps went round)
        return (*kept, k, best)
    return None, None, None, MAX_NEWTON, best


def _pseudo_transient(problem: _Problem, y: np.ndarray) -> tuple[State | None, int]:
    """Implicit Euler steps with growing tau towards a stable equilibrium (see the
    module); the state reached (Newton then finishes)."""
    x = problem.unknown
    state, f = problem.at(y)
    if state is None:
        return None, 0
    jac, _ = problem.jac(state)
    s = problem.scales(state.y)[x]
    size = float(np.max(np.abs(jac[np.ix_(x, x)]) @ s / s)) if len(x) else 1.0
    tau = 1.0 / max(size, 1e-12)  # the fastest time scale
    norm = float(np.linalg.norm(f[x] / s))
    eye = np.eye(len(x))
    for k in range(MAX_PSEUDO):
        if problem.measure(f, jac, state.y) <= TOL * 1e3:
            return state, k
        try:
            step = np.linalg.solve(eye / tau - jac[np.ix_(x, x)], f[x])
        except np.linalg.LinAlgError:
            tau /= 10
            continue
        y = np.array(state.y, dtype=float)
        y[x] += step
        new_state, new_f = problem.at(y)
        if new_state is None:
            tau /= 10
            continue
        new_norm = float(np.linalg.norm(new_f[x] / problem.scales(new_state.y)[x]))
        if not math.isfinite(new_norm):
            tau /= 10
            continue
        tau *= min(max(norm / new_norm, 0.5), 10.0) if new_norm > 0 else 10.0
        state, f, norm = new_state, new_f, new_norm
        jac, _ = problem.jac(state)
    return state, MAX_PSEUDO


def _linear(model, flow: Flow, state: State, t: float, names: list[str], x: np.ndarray,
            jac: np.ndarray, inputs, outputs, params: dict[str, float]) -> Linear:
    c = flow.code
    inputs = [n.upper() for n in inputs]
    outputs = model.known_names(list(outputs)) if outputs else []
    data = {**model.ir.runs[0].data, **{k.upper(): float(v) for k, v in params.items()}}
    for name in inputs:
        if name not in data:
            raise UsageError(with_hint(f"--input {name}: not a PARAM/CONST/INCON value of "
                                       "this model (an input is a data value)", name,
                                       list(data)))
    x_names = {names[k] for k in x}
    for name in outputs:
        if name in names and name not in x_names:
            raise UsageError(f"--output {name}: a state held or free at the equilibrium "
                             "(its rate reads no state, or nothing reads it) is no state "
                             "of the linear model")
    y = np.array(state.y, dtype=float)
    m, z = list(state.modes), list(state.memory)
    def flow_at(**values):
        return model.flow(method=flow.opts.method, rtol=flow.opts.rtol, atol=flow.opts.atol,
                          **{**params, **values})

    variants = []
    for name in inputs:
        moved = moved_flows(flow_at, c, name, data[name])
        if moved is None:
            raise AmilError(f"--input {name}: changing it changes which switches the run "
                            "watches; it cannot be an input of a linear model here")
        plus, minus, h = moved
        variants.append((plus.code, minus.code, h))
    yl = y.tolist()
    b = np.array([(np.asarray(p.rhs(t, yl, m, z)) - np.asarray(q.rhs(t, yl, m, z))) / (2 * h)
                  for p, q, h in variants]).T.reshape(len(y), len(inputs))
    index = [c.out_names.index(n) if n not in names else None for n in outputs]
    floor = np.broadcast_to(np.asarray(flow.plan.tol.atol / flow.plan.tol.rtol, dtype=float),
                            y.shape)
    cm = np.zeros((len(outputs), len(y)))
    dm = np.zeros((len(outputs), len(inputs)))
    computed = [(i, k) for i, k in enumerate(index) if k is not None]
    for i, name in enumerate(outputs):
        if index[i] is None:
            cm[i, names.index(name)] = 1.0
    if computed:
        # (refined steps: exact to rounding where the branch is linear, as A is)
        rows, _ = refined(lambda v: [c.out(t, v, m, z)[k] for _, k in computed], y, floor)
        cm[[i for i, _ in computed]] = rows
        for j, (p, q, h) in enumerate(variants):
            hi, lo = p.out(t, yl, m, z), q.out(t, yl, m, z)
            for i, k in computed:
                dm[i, j] = (hi[k] - lo[k]) / (2 * h)
    return Linear([names[k] for k in x], inputs, outputs, jac[np.ix_(x, x)], b[x],
                  cm[:, x], dm)
