"""Dense output from what an integrator already computed: states and derivatives at
a few instants, joined by cubic Hermite pieces.

The AUTO route's odeint integrates through check instants and returns only the
states there. Between two of them the motion is smooth (the branches are frozen
for the whole chunk, and the rows past a crossing continue the same smooth flow),
so the cubic through both ends and their derivatives is a fourth-order dense
output, two evaluations of the derivatives per interval. Its error is estimated
by the quintic through a third instant (`Nodes.error`); where that is larger than
the run's tolerance, `OdeintStepper.refine` integrates a narrow window once more
with odeint and puts its exact ends in as new nodes (a cubic over 2 % of the
interval is 10^-7 of the first cubic's error).
"""

from __future__ import annotations

import bisect

import numpy as np


def _cubic(t0: float, y0, f0, t1: float, y1, f1, t: float) -> np.ndarray:
    h = t1 - t0
    if h == 0:
        return y1
    s = (t - t0) / h
    r = 1.0 - s
    # the four weights as floats: four array products (finite states and
    # derivatives only reach here: the loop stops at a non-finite one)
    return ((1 + 2 * s) * r * r) * y0 + (s * s * (3 - 2 * s)) * y1 + \
        (h * s * r * r) * f0 - (h * s * s * r) * f1


def _cubic_rate(t0: float, y0, f0, t1: float, y1, f1, t: float) -> np.ndarray:
    """The derivative of `_cubic` in t."""
    h = t1 - t0
    s = (t - t0) / h
    return (6 * s * (s - 1) / h) * (y0 - y1) + ((1 - s) * (1 - 3 * s)) * f0 + \
        (s * (3 * s - 2)) * f1


class Nodes:
    """A piecewise cubic Hermite through instants with states and derivatives; the
    first piece may carry a quintic correction (`sharpen`)."""

    def __init__(self, t: list[float], y: list[np.ndarray], f: list[np.ndarray]) -> None:
        self.t, self.y, self.f = list(t), list(y), list(f)
        self.correction: tuple[float, float, np.ndarray, np.ndarray] | None = None

    def __call__(self, t: float) -> np.ndarray:
        k = min(max(bisect.bisect_left(self.t, t), 1), len(self.t) - 1)
        y = _cubic(self.t[k - 1], self.y[k - 1], self.f[k - 1], self.t[k], self.y[k],
                   self.f[k], t)
        if self.correction is not None and len(self.t) == 2:
            t0, t1, a, b = self.correction
            u = t - t0
            y = y + (u * u * (t - t1) ** 2) * (a + b * u)
        return y

    def sharpen(self, terms) -> None:
        """Make the single piece the quintic through a third instant: `terms` from
        `quintic_terms` on this piece's ends."""
        self.correction = terms

    def along(self, g: np.ndarray):
        """The dense output projected on g (g . y(t)), as a function of t on floats:
        the root finder's fast path for surfaces linear in the states."""
        ts = self.t
        vs = [float(g @ y) for y in self.y]
        ds = [float(g @ f) for f in self.f]
        corr = None
        if self.correction is not None and len(ts) == 2:
            t0, t1, a, b = self.correction
            corr = (t0, t1, float(g @ a), float(g @ b))
        last = len(ts) - 1

        def value(t: float) -> float:
            k = 1
            while k < last and ts[k] < t:
                k += 1
            t0, t1 = ts[k - 1], ts[k]
            h = t1 - t0
            s = (t - t0) / h
            r = 1.0 - s
            v = (1 + 2 * s) * r * r * vs[k - 1] + s * s * (3 - 2 * s) * vs[k] + \
                h * s * (r * r * ds[k - 1] - s * r * ds[k])
            if corr is not None:
                u = t - corr[0]
                v += u * u * (t - corr[1]) ** 2 * (corr[2] + corr[3] * u)
            return v
        return value

    def insert(self, t: float, y: np.ndarray, f: np.ndarray) -> None:
        """A new node (an instant integrated exactly); the pieces become cubics."""
        self.correction = None
        k = bisect.bisect_left(self.t, t)
        if k < len(self.t) and self.t[k] == t:
            self.y[k], self.f[k] = y, f
            return
        self.t.insert(k, t)
        self.y.insert(k, y)
        self.f.insert(k, f)


def quintic_terms(t0: float, y0, f0, t1: float, y1, f1, t2: float, y2, f2):
    """(t0, t1, a, b) with Q = C + (t - t0)^2 (t - t1)^2 (a + b (t - t0)) the quintic
    through three instants with values and derivatives, C the cubic through the first
    two (the correction vanishes with its derivative at t0 and t1; a and b make Q and
    Q' match at t2)."""
    d = t2 - t0
    w2 = d * d * (t2 - t1) ** 2
    dw2 = 2 * d * (t2 - t1) ** 2 + 2 * d * d * (t2 - t1)
    c2 = _cubic(t0, y0, f0, t1, y1, f1, t2)
    dc2 = _cubic_rate(t0, y0, f0, t1, y1, f1, t2)
    with np.errstate(all="ignore"):
        ab = (y2 - c2) / w2
        b = ((f2 - dc2) - dw2 * ab) / w2
        a = ab - b * d
    return t0, t1, a, b


def quintic_gap(terms, at: float) -> np.ndarray:
    """|Q(at) - C(at)| for `quintic_terms`: an estimate of the cubic's error in
    [t0, t1] (Q is two orders better), per state."""
    t0, t1, a, b = terms
    u = at - t0
    with np.errstate(all="ignore"):
        gap = np.abs(u * u * (at - t1) ** 2 * (a + b * u))
    return np.where(np.isfinite(gap), gap, np.inf)
