"""Reference for the crank-slider start-up (seed 000, Skalmierski & Kaczmarczyk).

    I(phi)*phi'' + 0.5*I'(phi)*phi'^2 = Q,   I = 2/3*m*l^2*(1 + 3*sin^2 phi),
    Q = M1 - 2*phi' - m*g*l*sqrt(2)*sin(phi + pi/4)

``exact`` integrates this at rtol 1e-12 and locates every instant at which phi' passes
an integer level as an event. ``paper_method`` re-does the paper's stepwise energy method
(eqs. 3.2-3.7b: speed steps h = 1 rad/s, M2 replaced on each step by its mean, the
energy balance solved for phi_i, times from the mean of the end speeds), which is how
Table 1 was computed. Nothing here imports amilpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

M, L, M1, K2, G = 10.0, 1.0, 200.0, 2.0, 9.81
I0 = 2.0 / 3.0 * M * L**2

# Table 1 of the paper: (phi' [1/s], phi [rad], t* [s]).
TABLE1: tuple[tuple[float, float, float], ...] = (
    (0.0, 0.0, 0.0),
    (1.0, 0.0368, 0.0736),
    (2.0, 0.1104, 0.1227),
    (3.0, 1.6322, 0.7314),
    (4.0, 2.0740, 0.8576),
    (5.0, 2.3194, 0.9122),
    (6.0, 2.3992, 0.9267),
    (7.0, 2.5510, 0.9500),
    (8.0, 2.6875, 0.9682),
    (9.0, 2.7857, 0.9798),
    (10.0, 2.8901, 0.9908),
)


def inertia(phi: float) -> float:
    return I0 * (1.0 + 3.0 * math.sin(phi) ** 2)


def rhs(_t: float, s: np.ndarray, sqrt2: float = math.sqrt(2.0)) -> list[float]:
    phi, w = s
    q = M1 - K2 * w - M * G * L * sqrt2 * math.sin(phi + math.pi / 4.0)
    di = 3.0 * I0 * math.sin(2.0 * phi)
    return [w, (q - 0.5 * di * w * w) / inertia(phi)]


@dataclass
class Crossing:
    level: float
    t: float
    phi: float
    upward: bool


def exact(w_stop: float = 10.0, rtol: float = 1e-12) -> tuple[list[Crossing], object]:
    """All crossings of the levels 1..w_stop by phi' (up and down), and the dense solution."""
    levels = np.arange(1.0, w_stop + 0.5)
    events = []
    for lv in levels:

        def ev(_t: float, s: np.ndarray, lv: float = lv) -> float:
            return float(s[1] - lv)

        ev.terminal = bool(lv == w_stop)  # type: ignore[attr-defined]
        if lv == w_stop:
            ev.direction = 1.0  # type: ignore[attr-defined]
        events.append(ev)
    sol = solve_ivp(
        rhs,
        (0.0, 10.0),
        [0.0, 0.0],
        method="DOP853",
        rtol=rtol,
        atol=1e-14,
        events=events,
        dense_output=True,
    )
    out: list[Crossing] = []
    for lv, te, ye in zip(levels, sol.t_events, sol.y_events, strict=True):
        for t, y in zip(te, ye, strict=True):
            slope = rhs(t, y)[1]
            out.append(Crossing(float(lv), float(t), float(y[0]), slope > 0))
    out.sort(key=lambda c: c.t)
    return out, sol


def first_reach(crossings: list[Crossing]) -> dict[float, Crossing]:
    """The first upward crossing of each level (what Table 1 tabulates)."""
    res: dict[float, Crossing] = {}
    for c in crossings:
        if c.upward and c.level not in res:
            res[c.level] = c
    return res


def paper_method(
    h: float = 1.0, n: int = 10, sqrt2: float = math.sqrt(2.0)
) -> list[tuple[float, float, float]]:
    """The paper's stepwise energy method; returns (phi'_i, phi_i, t_i) like Table 1."""
    mgl = M * G * L * sqrt2
    rows = [(0.0, 0.0, 0.0)]
    phi_prev, w_prev, t_prev = 0.0, 0.0, 0.0
    for i in range(1, n + 1):
        w = i * h
        m2 = K2 * (w_prev + w) / 2.0  # mean of M2 = 2*phi' over the speed step (3.3)

        def g(
            phi: float, pp: float = phi_prev, wp: float = w_prev, ww: float = w, m2: float = m2
        ) -> float:
            work = (M1 - m2) * (phi - pp) + mgl * (
                math.cos(phi + math.pi / 4) - math.cos(pp + math.pi / 4)
            )
            return 0.5 * inertia(phi) * ww * ww - 0.5 * inertia(pp) * wp * wp - work

        # first root beyond phi_prev: scan, then bisect (the paper: "np. metoda bisekcji")
        grid = np.linspace(phi_prev + 1e-12, phi_prev + 2 * math.pi, 20001)
        vals = np.array([g(x) for x in grid])
        k = int(np.nonzero(np.sign(vals[1:]) != np.sign(vals[:-1]))[0][0])
        phi = brentq(g, grid[k], grid[k + 1], xtol=1e-14)
        t = t_prev + (phi - phi_prev) / ((w_prev + w) / 2.0)  # (3.7b), mean speed of the step
        rows.append((w, phi, t))
        phi_prev, w_prev, t_prev = phi, w, t
    return rows


if __name__ == "__main__":
    cr, _ = exact()
    fr = first_reach(cr)
    pm = paper_method()
    pm141 = paper_method(sqrt2=1.41)
    print("level  table(phi,t)   exact(phi,t)   paper-method(phi,t)  paper-method sqrt2=1.41")
    for (w, p, t), r, r2 in zip(TABLE1[1:], pm[1:], pm141[1:], strict=True):
        c = fr[w]
        cells = [(p, t), (c.phi, c.t), (r[1], r[2]), (r2[1], r2[2])]
        print(f"{w:4.0f} " + " | ".join(f"{a:8.4f} {b:8.4f}" for a, b in cells))
    print([(c.level, round(c.t, 4), c.upward) for c in cr])
