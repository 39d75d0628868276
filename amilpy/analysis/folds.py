"""Special points of a response curve: folds located, other losses of stability
flagged (see `response` for how they are found and what is said).

The test function of a fold is det(P - I), the product of (mu - 1) over the
Floquet multipliers: its sign changes when one real multiplier crosses +1, a
complex pair adding |mu - 1|^2 > 0. Between two points where it changes sign
the fold is located by bisection on that sign, on planes across the secant
of the two points, each try corrected onto the curve, until the last three
tries' values agree to a tenth of FOLD_RTOL: lam is at most Lipschitz in the
arclength there (a fold at a grazing is a corner, not a parabola), so the fold
is within twice that of them; its value is the extreme try, moved to the
vertex of the parabola through the three when that lies so close. Where the
planes miss the curve (a fold at a grazing turns within a tiny arclength) it is
located by existence instead: beyond a
fold there is no orbit, so bisection on lam for the last value at which Newton
in x from the orbit before the fold still converges.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..diagnostics import AmilError
from .periodic import NotConverged, newton

FOLD_RTOL = 1e-6  # a fold's value, relative


def flag(cont, a, b, out) -> None:
    """Locate a fold between nodes a and b (appended to out.points); note any
    other multiplier leaving or entering the unit circle."""
    if (a.test > 0) != (b.test > 0):
        point = fold(cont, a, b) or by_existence(cont, a, b)
        if point is not None:
            out.points.append(point)
            return
    mu_a, mu_b = a.point.multipliers, b.point.multipliers
    na, nb = int(np.sum(np.abs(mu_a) > 1)), int(np.sum(np.abs(mu_b) > 1))
    if na == nb:
        if (a.test > 0) != (b.test > 0):
            out.notes.append(f"a fold between {cont.name} = {a.lam:.7g} and {b.lam:.7g} "
                             "could not be located")
        return
    mu = mu_b if nb > na else mu_a  # the side where it is outside
    outside = mu[np.abs(mu) > 1]
    crossing = outside[np.argmin(np.abs(outside))]
    if abs(crossing.imag) > 1e-6 * abs(crossing):
        kind, what = "NS", "Neimark-Sacker: a complex pair of multipliers crosses |mu| = 1"
    elif crossing.real < 0:
        kind, what = "PD", "period doubling: a multiplier crosses -1"
    elif (a.test > 0) != (b.test > 0):
        kind, what = "fold", "a fold that could not be located"
    else:
        kind, what = "BP", "branch point: a multiplier crosses +1 and the value does not turn"
    out.notes.append(f"{kind} between {cont.name} = {a.lam:.7g} and {b.lam:.7g} ({what})")


def fold(cont, a, b):
    """Bisection on the sign of det(P - I) between nodes a and b; the fold's Point,
    or None when a try cannot be put on the curve."""
    normal = cont.reduce(b.x - a.x, b.lam - a.lam)
    length = float(np.linalg.norm(normal))
    if length == 0:
        return None
    normal = normal / length
    lo, hi = (0.0, a), (length, b)
    tries = [lo, hi]
    up = a.heading > 0  # lam grew towards the fold: it is a largest lam
    for _ in range(60):
        last = [t[1].lam for t in tries[-3:]]
        if len(tries) > 2 and max(last) - min(last) <= 0.1 * FOLD_RTOL * abs(last[-1]):
            break
        mid = 0.5 * (lo[0] + hi[0])
        w = (mid - lo[0]) / (hi[0] - lo[0])
        cont.anchor = (a.x, a.lam)
        try:
            node = cont.solve_on(lo[1].x + w * (hi[1].x - lo[1].x),
                                 lo[1].lam + w * (hi[1].lam - lo[1].lam), normal, mid, "fold")
        except (NotConverged, AmilError):
            return None
        tries.append((mid, node))
        if (node.test > 0) == (lo[1].test > 0):
            lo = (mid, node)
        else:
            hi = (mid, node)
    best = min((lo[1], hi[1]), key=lambda n: _nearest_one(n.point.multipliers))
    last = [t[1].lam for t in tries[-3:]]
    value = max(last) if up else min(last)
    vertex = _vertex(tries)
    if abs(vertex - value) <= 0.1 * FOLD_RTOL * abs(value):
        value = vertex
    return replace(best.point, kind="fold", value=value)


def by_existence(cont, a, b):
    """A fold located as the last value with an orbit (see the module)."""
    up = a.heading > 0  # lam grew towards the fold: it is a largest lam
    extreme = max(a.lam, b.lam) if up else min(a.lam, b.lam)
    width = max(abs(a.lam - b.lam), 1e-6 * cont.span)
    lo_lam, lo_x, best = a.lam, a.x, a
    hi_lam = None
    for k in (1, 4, 16):
        trial = extreme + (k if up else -k) * width
        if _solve_at(cont, lo_x, trial) is None:
            hi_lam = trial
            break
    if hi_lam is None:
        return None
    while abs(hi_lam - lo_lam) > 0.1 * FOLD_RTOL * max(abs(lo_lam), 1e-300):
        mid = 0.5 * (lo_lam + hi_lam)
        found = _solve_at(cont, lo_x, mid)
        if found is None:
            hi_lam = mid
        else:
            lo_lam, lo_x, best = mid, found.x, found
    return replace(best.point, kind="fold", value=0.5 * (lo_lam + hi_lam))


def _solve_at(cont, x: np.ndarray, lam: float):
    try:
        ev, history = newton(cont.problem(lam), x, cont.base, cont.t0(lam))
    except (NotConverged, AmilError):
        return None
    return cont.node(ev.x, lam, history[-1], "fold")


def _nearest_one(mu: np.ndarray) -> float:
    return float(np.min(np.abs(mu - 1.0))) if len(mu) else math.inf


def _vertex(tries: list) -> float:
    """lam at the fold: the extremum of the parabola lam(sigma) through the three
    tries nearest the fold (the last three of the bisection)."""
    pts = sorted(tries[-3:], key=lambda p: p[0])
    s = np.array([p[0] for p in pts])
    lam = np.array([p[1].lam for p in pts])
    if len(set(s.tolist())) < 3:
        return float(lam[-1])
    a, b, c = np.polyfit(s - s[1], lam, 2)
    if a == 0:
        return float(lam[1])
    top = -b / (2 * a)
    if not s[0] - s[1] <= top <= s[2] - s[1]:  # outside the tries: the extreme one
        return float(np.max(lam) if a < 0 else np.min(lam))
    return float(c - b * b / (4 * a))
