"""The pieces the tangents of a flow (`analysis.sensitivity`) and of a program in
ACSL form (`analysis.program`) share: the observer that reads the tangent at the
instants asked for, an output's row from the states' tangent, a difference's
step."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..run.jacobian import STEP
from ..run.plan import sliding_in
from ..run.variational import ParameterTangent, along_clock, filippov, has_slope, held


class Sampler:
    """An observer of the flow's steps that cuts each at the instants asked for and
    keeps the state and the tangent there (`Trajectory.at`; a
    program's: `analysis.program`)."""

    def __init__(self, tangent: ParameterTangent, times: np.ndarray, n: int) -> None:
        self.tangent, self.times, self.n = tangent, times, n
        self.at: dict[float, tuple] = {}
        # an instant asked for at a step's end: its row is the one after what happens
        # there (the memory's update, a switch, as the run's row has them), taken as
        # the next step starts; the one before stands if no step follows
        self._due: float | None = None

    def __call__(self, ta: float, tb: float, interp, m, z) -> None:
        if self._due is not None:
            due, self._due = self._due, None
            if due == ta:
                self.tangent(ta, ta, interp, m, z)  # (joins what happened at ta)
                if self.tangent.failed is not None:
                    return
                self._keep(ta, interp, m, z)
        lo = int(np.searchsorted(self.times, ta, side="right"))
        hi = int(np.searchsorted(self.times, tb, side="right"))
        t = ta
        for tk in self.times[lo:hi].tolist():
            if tk in self.at:
                continue
            self.tangent(t, tk, interp, m, z)
            if self.tangent.failed is not None:
                return
            self._keep(tk, interp, m, z)
            if tk == tb:
                self._due = tk
            t = tk
        if tb > t:
            self.tangent(t, tb, interp, m, z)

    def finish(self, end) -> None:
        """The flow's end state `end` (a State, after what happened at its instant): an
        instant asked for there is read after it too, as the run's last row is."""
        if self._due is not None and self._due == end.t:
            y = np.asarray(end.y, dtype=float)
            self(end.t, end.t, lambda _: y, list(end.modes), list(end.memory))

    def _keep(self, t: float, interp, m, z) -> None:
        from ..run import State

        y = np.asarray(interp(t), dtype=float)
        # (the memory as the derivatives read it: a pushed play's leaning into its clamp,
        # so that an output's row is on the branch the motion takes)
        z = self.tangent.leaned(t, y, list(m), list(z))
        self.at[t] = (State(y, tuple(m), tuple(z), t), self.tangent.phi[:self.n].copy())


def output_row(c, variants, i: int, t: float, state, sens: np.ndarray, floor: np.ndarray,
               watch, halves: Callable[[], list] | None = None) -> np.ndarray:
    """d out_i / d p = d out_i/d y . S + d out_i/d p at (t, state); where S has rows
    for the memory values too (a program's: `analysis.program`), + d out_i/d z . S_z.
    While a surface slides the outputs are weighted as its field (`filippov`)."""
    y = np.asarray(state.y, dtype=float)
    m, z = list(state.modes), list(state.memory)
    if sliding_in(m):  # (a weight past its bound: the run's motion is on that branch)
        m = held(watch, c, t, y, m, z, floor)
    sliding = sliding_in(m)

    def out(code, yv: np.ndarray, zv: list) -> float:
        if sliding:
            weights, modes = filippov(watch, code, t, yv, m, zv, floor)
            return float(weights @ [code.out(t, yv.tolist(), mc, zv)[i] for mc in modes])
        return code.out(t, yv.tolist(), m, zv)[i]

    grad = np.zeros(len(sens))
    for j in range(len(y)):
        h = STEP * max(abs(y[j]), float(floor[j]))
        up, down = y.copy(), y.copy()
        up[j] += h
        down[j] -= h
        grad[j] = (out(c, up, z) - out(c, down, z)) / (2 * h)
    for j in range(len(sens) - len(y)):
        if not has_slope(c, z, j):
            continue
        h = STEP * max(abs(z[j]), 1.0)  # (as the program's tangent moves them)
        up, down = list(z), list(z)
        up[j] += h
        down[j] -= h
        grad[len(y) + j] = (out(c, y, up) - out(c, y, down)) / (up[j] - down[j])
    clock = np.array(sorted(c.clock_slots), dtype=int)
    rows = sens[len(y) + clock] if len(clock) and len(sens) > len(y) else None
    if rows is not None and np.any(rows):  # (a free delay moves a store's instants)
        direct = along_clock(lambda code, v: out(code, y, v), c, variants,
                             halves() if halves is not None else None, z, clock, rows)
    else:
        direct = np.array([(out(plus, y, z) - out(minus, y, z)) / (2.0 * h)
                           for plus, minus, h in variants])
    return grad @ sens + direct


def start_slope(hi: np.ndarray, lo: np.ndarray, h: float) -> np.ndarray:
    """The central difference (hi - lo)/2h of a start moved by +-h: 0 for a slot the
    same in both (an instant not yet set, +-INF in both: no dependence)."""
    with np.errstate(invalid="ignore"):
        return np.where(hi == lo, 0.0, (hi - lo) / (2.0 * h))


def step_for(value: float, relative: float) -> float:
    """A central difference's step for a data value: relative to it (a value of 1E-12
    is moved by a fraction of itself, never by more than itself); 1e-8 for 0."""
    return relative * abs(value) if value else 1e-8


def outputs_asked(code, variables: list[str] | None) -> list[int] | None:
    """The positions in `code.out_names` of the outputs a tangent will be asked for
    (None: every one): a memory only other outputs read may change (ZHOLD's held
    value of a variable nobody observed)."""
    if variables is None:
        return None
    return [i for i, name in enumerate(code.out_names) if name in set(variables)]
