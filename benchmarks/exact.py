"""Piecewise-affine references: exact between switches, by the matrix exponential.

Between two switches the Exercise 4 drives and the hoist are affine systems
y' = A y + b (the hoist's forcing M0*sin(W*t) becomes affine with sin and cos
as two more states). Their solution over a step h is exactly

    [y(t + h); 1] = expm([[A, b], [0, 0]] h) [y(t); 1]

so a reference needs no integration tolerance: the states are propagated over
a sub-grid of the output grid by one matrix-vector product a step, each
switching surface (affine in the states, g = c.y + d) is watched on the
sub-grid, and a crossing is located by Brent's method on the exact solution
inside the sub-step, to a few ulps of TIME. Its only errors are rounding
(about 1e-14 relative after 10^5 products here) and a pair of crossings
inside one sub-step, which the cross-check against DOP853 at rtol 1e-13
(`cases.Case.agreement`) would show.

Nothing here imports amilpy.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

SUBSTEPS = 16  # sub-steps per output interval on which surfaces are watched


@dataclass(frozen=True)
class Surface:
    """g(y) = c.y + d; `direction` +1: rising crossings only, -1 falling, 0 both."""

    c: np.ndarray
    d: float
    direction: float


@dataclass
class AffineHybrid:
    """An affine system per mode. `system(mode, t)` gives (A, b) in force at t;
    `surfaces(mode, t)` the surfaces that end the mode; `jump(mode, k, t, y)` the
    mode and state after surface k is reached; `breaks` instants where `system`
    changes with TIME (a clutch), with `at_break(mode, t, y)` the mode after."""

    system: Callable[[object, float], tuple[np.ndarray, np.ndarray]]
    surfaces: Callable[[object, float], list[Surface]]
    jump: Callable[[object, int, float, np.ndarray], tuple[object, np.ndarray]]
    breaks: tuple[float, ...] = ()
    at_break: Callable[[object, float, np.ndarray], object] | None = None


def affine_columns(fun: Callable[[np.ndarray], np.ndarray], n: int
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(A, b) of an affine map y -> A y + b from n + 1 evaluations."""
    b = np.asarray(fun(np.zeros(n)), dtype=float)
    a = np.empty((len(b), n))
    for k in range(n):
        e = np.zeros(n)
        e[k] = 1.0
        a[:, k] = np.asarray(fun(e), dtype=float) - b
    return a, b


class _Flow:
    """The exact flow of one affine system: propagators cached by step length."""

    def __init__(self, a: np.ndarray, b: np.ndarray) -> None:
        n = len(b)
        self.m = np.zeros((n + 1, n + 1))
        self.m[:n, :n] = a
        self.m[:n, n] = b
        self.cache: dict[float, np.ndarray] = {}

    def step(self, y: np.ndarray, h: float) -> np.ndarray:
        e = self.cache.get(h)
        if e is None:
            e = expm(self.m * h)
            if len(self.cache) < 64:
                self.cache[h] = e
        return (e @ np.append(y, 1.0))[:-1]


def _crossing(s: Surface, g0: float, g1: float) -> bool:
    if s.direction > 0:
        return g0 < 0.0 <= g1
    if s.direction < 0:
        return g0 > 0.0 >= g1
    return (g0 < 0.0 <= g1) or (g0 > 0.0 >= g1)


def simulate(h: AffineHybrid, mode0, y0: np.ndarray, grid: np.ndarray,
             substeps: int = SUBSTEPS) -> tuple[np.ndarray, list[tuple[float, object]]]:
    """The states on `grid` (rows) and the events [(t, new mode)]."""
    y = np.array(y0, dtype=float)
    mode = mode0
    out = np.empty((len(grid), len(y)))
    out[0] = y
    events: list[tuple[float, object]] = []
    t = float(grid[0])
    breaks = sorted(b for b in h.breaks if grid[0] < b < grid[-1])
    flows: dict[tuple, _Flow] = {}

    def flow_for(m, at: float) -> _Flow:
        key = (m, sum(1 for b in breaks if b <= at))
        if key not in flows:
            flows[key] = _Flow(*h.system(m, at))
        return flows[key]

    for i in range(1, len(grid)):
        target = float(grid[i])
        dt = (target - float(grid[i - 1])) / substeps
        while t < target:
            stop = min([b for b in breaks if t < b <= target], default=target)
            mode, y, t = _advance(h, flow_for, mode, y, t, stop, dt, events)
            if t == stop and stop in breaks and h.at_break is not None:
                mode = h.at_break(mode, t, y)
                events.append((t, mode))
        out[i] = y
    return out, events


def _advance(h: AffineHybrid, flow_for, mode, y: np.ndarray, t: float, t_end: float,
             dt: float, events: list) -> tuple[object, np.ndarray, float]:
    """From t to t_end in equal sub-steps of at most dt, switching on the way."""
    while t < t_end:
        flow = flow_for(mode, t)
        surfaces = h.surfaces(mode, t)
        n = max(1, int(np.ceil((t_end - t) / dt - 1e-9)))
        step = (t_end - t) / n
        ta, ya, hit = t, y, None
        for j in range(1, n + 1):
            tb = t_end if j == n else t + j * step
            yb = flow.step(ya, step)
            for k, s in enumerate(surfaces):
                if _crossing(s, float(s.c @ ya + s.d), float(s.c @ yb + s.d)):
                    root = brentq(lambda x, s=s, ya=ya, ta=ta, flow=flow: float(
                        s.c @ flow.step(ya, x - ta) + s.d), ta, tb,
                        xtol=1e-16 * max(abs(tb), 1.0), rtol=4 * np.finfo(float).eps,
                        maxiter=200)
                    if hit is None or root < hit[0]:
                        hit = (root, k)
            if hit is not None:
                break
            ta, ya = tb, yb
        if hit is None:
            return mode, ya, t_end
        root, k = hit
        mode, y = h.jump(mode, k, root, flow.step(ya, root - ta))
        events.append((root, mode))
        t = root
    return mode, y, t


# ---------------------------------------------------------------- the two systems


def ex4_system(chain, t_end: float):
    """The Exercise 4 drive (tests/references/ex4.Chain) as an AffineHybrid, and its
    initial mode: modes are (friction mode, clutch factor)."""
    from tests.references import ex4

    n_state = 1 + 2 * chain.n - 1

    def system(mode, t):
        fm = mode
        sw = 1.0 if chain.t_clutch is None or t >= chain.t_clutch else 0.0
        return affine_columns(lambda y: chain.rhs(y, fm, sw), n_state)

    def net(t):
        sw = 1.0 if chain.t_clutch is None or t >= chain.t_clutch else 0.0
        return affine_columns(lambda y: np.array([chain.net_torque(y, sw)]), n_state)

    def surfaces(mode, t):
        if mode == ex4.STICK:
            a, b = net(t)
            c, d = a[0], float(b[0])
            return [Surface(c, d - ex4.MF, 1.0), Surface(c, d + ex4.MF, -1.0)]
        c = np.zeros(n_state)
        c[1] = 1.0
        return [Surface(c, 0.0, -float(mode))]

    def jump(mode, k, t, y):
        y = y.copy()
        sw = 1.0 if chain.t_clutch is None or t >= chain.t_clutch else 0.0
        if mode == ex4.STICK:
            return (1 if k == 0 else -1), y
        y[1] = 0.0
        mnet = float(chain.net_torque(y, sw))
        return (ex4.STICK if abs(mnet) <= ex4.MF else (1 if mnet > 0 else -1)), y

    def at_break(mode, t, y):
        if mode == ex4.STICK and abs(float(chain.net_torque(y, 1.0))) > ex4.MF:
            return 1 if float(chain.net_torque(y, 1.0)) > 0 else -1
        return mode

    breaks = (chain.t_clutch,) if chain.t_clutch is not None else ()
    return AffineHybrid(system, surfaces, jump, breaks, at_break), ex4.STICK, n_state


def ex4_exact(chain, grid: np.ndarray) -> np.ndarray:
    """States [IA, W1..Wn, TH1..TH(n-1)] of the drive on `grid` (rows)."""
    h, mode0, n = ex4_system(chain, float(grid[-1]))
    y, _ = simulate(h, mode0, np.zeros(n), grid)
    return y


def hoist_exact(hoist, w: float, grid: np.ndarray) -> np.ndarray:
    """States [X1, Y, V1, V2, V3, PH] of the hoist (tests/references/hoist) on `grid`,
    from rest; sin and cos of the forcing phase are states S, C of the affine system."""
    from tests.references import hoist as ref

    e = hoist.half_gap

    def system(mode, t):
        def f(z):
            x1, y, v1, v2, v3, s, c = z
            d = ref.rhs(hoist, w, mode, np.array([x1, y, v1, v2, v3, 0.0]))
            d[3] += hoist.m0 * s / hoist.i2  # rhs(PH = 0) has no forcing: add it as S
            return np.array([d[0], d[1], d[2], d[3], d[4], w * c, -w * s])

        return affine_columns(f, 7)

    def unit(k):
        c = np.zeros(7)
        c[k] = 1.0
        return c

    def surfaces(mode, t):
        if mode == ref.GAP:
            return [Surface(unit(1), -e, 1.0), Surface(unit(1), e, -1.0)]
        return [Surface(unit(1), -mode * e, -float(mode))]

    def jump(mode, k, t, z):
        z = z.copy()
        if mode == ref.GAP:
            new = ref.PLUS if k == 0 else ref.MINUS
            z[1] = new * e
        else:
            new = ref.GAP
            z[1] = mode * e
        return new, z

    h = AffineHybrid(system, surfaces, jump)
    z0 = np.zeros(7)
    z0[6] = 1.0  # cos(0)
    z, _ = simulate(h, ref.GAP, z0, grid)
    return np.column_stack([z[:, :5], w * grid])
