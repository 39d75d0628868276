"""Minimum, maximum and mean of variables over one period, from the integrator's
own dense output (no output grid).

`Tracker` is an observer of `Flow.advance`: every accepted step (cut at each
located switch, so a step lies in one branch) is sampled at its ends and at
Gauss-Legendre nodes. The mean is the Gauss-Legendre sum over the steps divided
by the period (4 nodes a step: exact for the step's polynomial up to degree 7).
The steps' interpolants are kept (SciPy's copy what they need); at the end the
few largest (smallest) samples that are local extremes are located on them by
Brent's method (bounded, to 1E-9 of the bracket: the samples either side, in
the next or the previous step at a step's end), so the half peak-to-peak is
not the sampled one of an output grid (low by up to 6E-4 on the hoist at a 1 ms
grid).
Variables that are not states are evaluated by the compiled output function,
vectorised over the nodes (or with the sliding combination while a surface
slides).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..run import Flow, State
from ..run.dense import sample_step
from ..run.plan import sliding_in
from ..run.record import column

_GL_X, _GL_W = np.polynomial.legendre.leggauss(4)
# where a step is sampled, as fractions of it: both ends and the Gauss nodes
_NODES = np.concatenate([[0.0], 0.5 * (_GL_X + 1.0), [1.0]])


@dataclass(frozen=True)
class Stats:
    """One variable over one period."""

    minimum: float
    t_min: float
    maximum: float
    t_max: float
    mean: float

    @property
    def half_pp(self) -> float:
        return 0.5 * (self.maximum - self.minimum)


class Tracker:
    """Observer: the running extrema and integrals of `names`, and samples of
    them for a figure."""

    CANDIDATES = 3  # at most this many samples refined per variable and side
    CLOSE = 1e-3  # ... those within this (relative to the variable's range) of the best

    def __init__(self, flow: Flow, names: list[str]) -> None:
        self.flow = flow
        self.names = names
        states = flow.state_names
        self.state_idx = {n: states.index(n) for n in names if n in states}
        outs = flow.code.out_names
        self.out_idx = {n: outs.index(n) for n in names if n not in self.state_idx}
        self.integral = np.zeros(len(names))
        self.steps: list[tuple] = []  # (nodes, values, interpolant, modes, memory)

    def _values(self, t: np.ndarray, y: np.ndarray, m, z) -> np.ndarray:
        """Rows: the variables; columns: the instants t (y: states x instants)."""
        out = np.empty((len(self.names), len(t)))
        if self.out_idx:
            c, watch = self.flow.code, self.flow.watch
            if sliding_in(m):
                table = np.array([watch.outputs(float(ti), y[:, i], m, z)
                                  for i, ti in enumerate(t)]).T
            else:
                with np.errstate(all="ignore"):
                    cols = c.out_v(t, list(y), m, z)
                table = None
        for r, name in enumerate(self.names):
            if name in self.state_idx:
                out[r] = y[self.state_idx[name]]
            elif sliding_in(m):
                out[r] = table[self.out_idx[name]]
            else:
                out[r] = column(cols[self.out_idx[name]], len(t))
        return out

    fractions = _NODES  # of each step, where it samples (`run.dense.Observers`)

    def __call__(self, ta: float, tb: float, interp, m, z) -> None:
        if tb <= ta:
            return
        t, ys = sample_step(interp, ta, tb, _NODES)
        v = self._values(t, ys, m, z)
        self.integral += 0.5 * (tb - ta) * (v[:, 1:-1] @ _GL_W)
        self.steps.append((t, v, interp, list(m), list(z)))

    def _refine(self, r: int, sign: float, k: int, i: int) -> tuple[float, float]:
        """The largest of sign*variable r near node i of step k: Brent's method on
        the interpolants between the nodes either side."""
        from scipy.optimize import minimize_scalar

        t, v, *_ = self.steps[k]
        best = (float(v[r, i]), float(t[i]))
        brackets = [(k, max(i - 1, 0), min(i + 1, len(t) - 1))]
        if i == 0 and k > 0:
            brackets.append((k - 1, len(t) - 2, len(t) - 1))
        if i == len(t) - 1 and k + 1 < len(self.steps):
            brackets.append((k + 1, 0, 1))
        for j, lo, hi in brackets:
            tj, _, interp, m, z = self.steps[j]

            def g(s: float, interp=interp, m=m, z=z) -> float:
                ys = np.asarray(interp(s), dtype=float)[:, None]
                return -sign * float(self._values(np.array([s]), ys, m, z)[r, 0])

            a, b = float(tj[lo]), float(tj[hi])
            if b <= a:
                continue
            res = minimize_scalar(g, bounds=(a, b), method="bounded",
                                  options={"xatol": 1e-9 * (b - a) + 1e-300})
            value = -sign * float(res.fun)
            if sign * value > sign * best[0]:
                best = (value, float(res.x))
        return best

    def _extreme(self, r: int, sign: float) -> tuple[float, float]:
        """(value, TIME) of the largest of sign*variable r over the steps seen."""
        flat = [(sign * float(v[r, i]), k, i) for k, (_, v, *_) in enumerate(self.steps)
                for i in range(v.shape[1])]
        best = max(flat)
        spread = best[0] - min(flat)[0]
        # the best sample is refined, and any other near as good in another step
        # (two nearly equal peaks: the sampled one need not be the larger)
        peaks = sorted(flat, reverse=True)[: 4 * self.CANDIDATES]
        seen, out = set(), []
        for value, k, i in peaks:
            if k in seen or (seen and best[0] - value > self.CLOSE * spread):
                continue
            seen.add(k)
            out.append(self._refine(r, sign, k, i))
            if len(out) == self.CANDIDATES:
                break
        if not out:
            return sign * best[0], 0.0
        return max(out, key=lambda vt: sign * vt[0])

    def stats(self, period: float) -> dict[str, Stats]:
        out = {}
        for r, n in enumerate(self.names):
            if not self.steps:
                out[n] = Stats(math.nan, math.nan, math.nan, math.nan, math.nan)
                continue
            lo, t_lo = self._extreme(r, -1.0)
            hi, t_hi = self._extreme(r, 1.0)
            out[n] = Stats(lo, t_lo, hi, t_hi, float(self.integral[r] / period))
        return out

    def samples(self) -> tuple[np.ndarray, np.ndarray]:
        """(times, values[variable, instant]) in time order, for a figure."""
        if not self.steps:
            return np.empty(0), np.empty((len(self.names), 0))
        return (np.concatenate([s[0] for s in self.steps]),
                np.concatenate([s[1] for s in self.steps], axis=1))


def measure(flow: Flow, start: State, t0: float, period: float, names: list[str]
            ) -> tuple[dict[str, Stats], Tracker, State, list]:
    """Integrate one period from `start` at `t0` watching `names`."""
    tracker = Tracker(flow, names)
    end, events = flow.advance(start, t0, t0 + period, observer=tracker)
    return tracker.stats(period), tracker, end, events
