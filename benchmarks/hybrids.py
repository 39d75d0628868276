"""Hand-written models with their switches on states as events, and the solve_ivp
driver a user would write for them (the `+ev` routes of the work-precision
benchmark): one plain-float function per branch, each switch a terminal event, a
restart in the new branch after it.

Nothing here imports amilpy.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass
class Hybrid:
    """A hand-written model with its switches on states as events.

    `field(mode, segment)`: f(t, y) on floats in that branch and TIME segment;
    `events(mode)`: [(g(t, y), direction)] that end the branch; `jump(mode, k, t, y)`:
    the branch and state after event k (mode None: the run stops there);
    `at_segment(mode, segment, y)`: the branch entering a new TIME segment."""

    mode0: object
    field: Callable[[object, int], Callable]
    events: Callable[[object], list[tuple[Callable, float]]]
    jump: Callable[[object, int, float, list], tuple[object, list]]
    at_segment: Callable[[object, int, list], object] | None = None


def ex4_hybrid(kind: str) -> Callable[[], Hybrid]:
    """Stiction as a hand-written user would write it: slip +, slip - and stick, each
    its own function; W1 = 0 ends a slip, |MNET| = MF ends a stick."""

    def make() -> Hybrid:
        from tests.references import ex4

        U, R, L, KT, KE, MF = ex4.U, ex4.R, ex4.L, ex4.KT, ex4.KE, ex4.MF
        J1, JOBC, MOBC, C, B = ex4.J_ROTOR, ex4.J_OBC, ex4.M_OBC, ex4.C_COUPLING, \
            ex4.B_COUPLING
        J2, CT, BT = ex4.J_METER_HALF, ex4.C_METER, ex4.B_METER
        STICK = ex4.STICK

        if kind == "meter":
            def make_f(mode, seg):
                mfr = mode * MF
                moving = 1.0 if mode != STICK else 0.0

                def f(t, y):
                    ia, th12, th23, th34, w1, w2, w3, w4 = y
                    m12 = C * th12 + B * (w1 - w2)
                    m23 = CT * th23 + BT * (w2 - w3)
                    m34 = C * th34 + B * (w3 - w4)
                    return [(U - R * ia - KE * w1) / L, w1 - w2, w2 - w3, w3 - w4,
                            moving * (KT * ia - m12 - mfr) / J1, (m12 - m23) / J2,
                            (m23 - m34) / J2, (m34 - MOBC) / JOBC]
                return f

            def mnet(y):
                return KT * y[0] - (C * y[1] + B * (y[4] - y[5]))
            w1_index = 4
        else:
            def make_f(mode, seg):
                mfr = mode * MF
                moving = 1.0 if mode != STICK else 0.0
                sw = 0.0 if kind == "clutch" and seg == 0 else 1.0

                def f(t, y):
                    ia, th, w1, w2 = y
                    mc = sw * (C * th + B * (w1 - w2))
                    return [(U - R * ia - KE * w1) / L, sw * (w1 - w2),
                            moving * (KT * ia - mc - mfr) / J1, sw * (mc - MOBC) / JOBC]
                return f

            def mnet(y, sw=1.0):
                return KT * y[0] - sw * (C * y[1] + B * (y[2] - y[3]))
            w1_index = 2
        segment = {"k": 0}

        def field(mode, seg):
            segment["k"] = seg
            return make_f(mode, seg)

        def net(y):
            if kind == "clutch" and segment["k"] == 0:
                return KT * y[0]
            return mnet(y)

        def events(mode):
            if mode == STICK:
                return [(lambda t, y: net(y) - MF, 1.0), (lambda t, y: net(y) + MF, -1.0)]
            return [(lambda t, y: y[w1_index], -float(mode))]

        def jump(mode, k, t, y):
            if mode == STICK:
                return (1 if k == 0 else -1), y
            y = list(y)
            y[w1_index] = 0.0
            m = net(y)
            return (STICK if abs(m) <= MF else (1 if m > 0 else -1)), y

        def at_segment(mode, seg, y):
            segment["k"] = seg
            if mode == STICK and abs(net(y)) > MF:
                return 1 if net(y) > 0 else -1
            return mode

        return Hybrid(STICK, field, events, jump, at_segment)

    return make


def hoist_hybrid() -> Hybrid:
    """Backlash as a hand-written user would write it: gap, contact + and contact -,
    each its own function; |Y| = DELTA/2 ends a branch."""
    from tests.references import hoist

    h = hoist.Hoist()
    i1, i2, i3, c1, c2 = h.i1, h.i2, h.i3, h.c1, h.c2
    d1, d2, e = h.beta * h.c1, h.beta * h.c2, h.half_gap
    mn, m0, w = h.mn, h.m0, 70.0
    sin = math.sin

    def field(mode, seg):
        if mode == 0:
            def f(t, s):
                x1, y, v1, v2, v3, ph = s
                m1 = c1 * x1 + d1 * (v1 - v2)
                return [v1 - v2, v2 - v3, (mn - m1) / i1, (m1 + m0 * sin(ph)) / i2, -mn / i3, w]
            return f
        off = mode * e

        def f(t, s):
            x1, y, v1, v2, v3, ph = s
            yd = v2 - v3
            t2 = c2 * (y - off) + d2 * yd
            m1 = c1 * x1 + d1 * (v1 - v2)
            return [v1 - v2, yd, (mn - m1) / i1, (m1 - t2 + m0 * sin(ph)) / i2, (t2 - mn) / i3,
                    w]
        return f

    def events(mode):
        if mode == 0:
            return [(lambda t, s: s[1] - e, 1.0), (lambda t, s: s[1] + e, -1.0)]
        return [(lambda t, s, off=mode * e: s[1] - off, -float(mode))]

    def jump(mode, k, t, s):
        s = list(s)
        new = (1 if k == 0 else -1) if mode == 0 else 0
        s[1] = (new if new else mode) * e
        return new, s

    return Hybrid(0, field, events, jump)


def crank_hybrid() -> Hybrid:
    """FINISH W = 10 as a terminal event."""
    from tests.references import crank_slider

    return Hybrid(0, lambda mode, seg: crank_slider.rhs, lambda mode: [
        (lambda t, s: s[1] - 10.0, 1.0)], lambda mode, k, t, s: (None, s))


def hybrid_solve(case, method: str, rtol: float, atol: float):
    """The hand-written branches with `solve_ivp`: every switch on a state a terminal
    event, a restart in the new branch after it; TIME segments as in `hand_solve`."""
    from scipy.integrate import solve_ivp

    hy = case.hybrid()
    grid = case.grid()
    n = len(case.y0)
    rows = np.empty((len(grid), n))
    rows[0] = case.y0
    filled, nfev = 1, 0
    t, y, mode = 0.0, np.array(case.y0, dtype=float), hy.mode0
    for seg, (t_seg, _) in enumerate(case.segments()):
        if seg and hy.at_segment is not None and mode is not None:
            mode = hy.at_segment(mode, seg, y.tolist())
        while t < t_seg and mode is not None:
            f = hy.field(mode, seg)
            events = []
            for g, direction in hy.events(mode):
                def ev(tt, yy, g=g):
                    return g(tt, yy)
                ev.terminal, ev.direction = True, direction
                events.append(ev)
            hi = int(np.searchsorted(grid, t_seg + 1e-9 * case.outdel, side="right"))
            want = grid[filled:hi]
            on_grid = len(want)
            if not on_grid or abs(want[-1] - t_seg) > 1e-12 * max(t_seg, 1.0):
                want = np.append(want, t_seg)
            sol = solve_ivp(lambda tt, yy, f=f: f(tt, yy.tolist()), (t, t_seg), y,
                            method=method, t_eval=want, events=events, rtol=rtol, atol=atol)
            if sol.status < 0:
                raise RuntimeError(sol.message)
            nfev += sol.nfev
            k = min(len(sol.t), on_grid)
            if k:  # (an event before the first instant asked for gives no rows)
                rows[filled:filled + k] = sol.y.T[:k]
            filled += k
            if sol.status == 1:
                j = next(i for i, te in enumerate(sol.t_events) if len(te))
                t = float(sol.t_events[j][0])
                mode, ylist = hy.jump(mode, j, t, sol.y_events[j][0].tolist())
                y = np.array(ylist, dtype=float)
            else:
                t, y = t_seg, sol.y[:, -1].copy()
    return grid[:filled], {n: rows[:filled, i] for i, n in enumerate(case.states)}, nfev, 0
