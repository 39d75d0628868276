"""METHOD COMPILED: the numba kernel (`amilpy.compiled.kernel`) as a stepper.

`advance` runs the kernel over as many output instants and plain crossings as it
can (the run loop records its rows and events: `run.fastpaths.FastPaths._take_ahead`);
the step it holds back -- the segment's last, or one with a crossing the loop must
decide -- is this stepper's `step()`, with the method's own dense output, so the
loop treats it as it treats any SciPy step. If the kernel's step size collapses
(a fault, a singularity), SciPy's DOP853 takes over from where it stood and fails
or not with the message the Python route gives.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..compiled.layout import (
    AT,
    BOUND,
    CUBIC,
    FLOOR,
    HELD,
    HELD_END,
    LIMIT,
    LOOKAHEAD,
    MAX_STEP,
    NFEV,
    NSTEPS,
    SLOTS,
    SMALL,
    STEP,
    STEPS,
    STIFF_AT,
    STIFF_H_LAMBDA,
)
from ..outcome import Failure
from .base import Rhs, StepFailure, Stepper, Stiffness
from .ivp import ScipyStepper


@dataclass
class Advance:
    """What one kernel call produced: output rows and located crossings (TIME,
    surface, new branch, state)."""

    status: int
    T: np.ndarray
    Y: np.ndarray
    M: np.ndarray  # each row's branches
    event_t: np.ndarray
    event_k: np.ndarray
    event_new: np.ndarray
    event_y: np.ndarray
    event_m: np.ndarray  # the branches just before each
    m: np.ndarray  # the branches where the kernel stands
    # the steps' ends (and crossings) among the rows, with their branches (`sampling`)
    S: np.ndarray
    SY: np.ndarray
    SM: np.ndarray


_ENTRIES: dict[int, object] = {}


def _entry(dispatcher):
    """A compiled function's machine code as Python calls it, past numba's dispatcher
    (which types every argument on every call: 0.3 ms for the kernel's 30); each
    has the one signature it was compiled for."""
    entry = _ENTRIES.get(id(dispatcher))
    if entry is None:
        entry = _ENTRIES[id(dispatcher)] = \
            dispatcher.overloads[dispatcher.signatures[0]].entry_point
    return entry


class KernelStepper(Stepper):
    """The compiled DOP853 over one segment (branches frozen but for the crossings
    the kernel locates itself)."""

    fast_path = "ahead"
    EVENTS_PER_CALL = 64
    ROWS_BUFFER = 4096  # rows a kernel call fills at most

    def __init__(self, kernel, fun: Rhs | None, t0: float, y0: np.ndarray, t_bound: float, *,
                 rtol, atol, max_step: float, first_step: float | None, max_steps: int,
                 m, z, p: np.ndarray, watch: np.ndarray, handled: np.ndarray,
                 level: np.ndarray, lookahead: float, stability_limit: float,
                 h_floor: float, sampling: bool = False) -> None:
        self.k = kernel.loop
        # the model's functions go to the kernel as C functions (a dispatcher costs
        # 0.1 ms a call to convert), and are called here past their dispatchers
        self.rhs, self.surf = kernel.module.model_rhs_c, kernel.module.model_surf_c
        self._rhs = _entry(kernel.module.model_rhs)
        self._surf = _entry(kernel.module.model_surf)
        self._advance, self._interpolate = _entry(self.k.advance), _entry(self.k.interpolate)
        self.fun = fun
        n = len(y0)
        self.t = self.t_old = t0
        self.y = np.array(y0, dtype=float)
        self._y = self.y.copy()  # where the kernel stands
        self.z = np.asarray(z, dtype=float)
        self.p = p
        self.rtol = np.broadcast_to(np.asarray(rtol, dtype=float), (n,)).copy()
        self.atol = np.broadcast_to(np.asarray(atol, dtype=float), (n,)).copy()
        self.watch, self.handled, self.level = watch, handled, level
        self.max_steps = max_steps
        m_arr = np.asarray(m, dtype=float)
        self._f = np.empty(n)
        self._rhs(t0, self._y, m_arr, self.z, p, self._f)
        self._e = np.empty(max(len(m_arr), 1))  # the surfaces where it stands (`advance`)
        h = first_step if first_step else _entry(self.k.first_step)(
            self.rhs, t0, self._y, self._f, t_bound, max_step, self.rtol, self.atol, m_arr,
            self.z, p)
        sc = self.sc = np.zeros(SLOTS)  # the kernel's scalar state (`compiled.layout`)
        sc[AT], sc[STEP], sc[BOUND], sc[MAX_STEP] = t0, min(h, abs(t_bound - t0)), t_bound, \
            max_step
        sc[NFEV] = 1.0  # (the derivative above)
        sc[LOOKAHEAD], sc[LIMIT], sc[FLOOR] = lookahead, stability_limit, h_floor
        sc[HELD_END] = sc[STIFF_AT] = math.nan
        self._held_y, self._held_f = np.empty(n), np.empty(n)
        self._held_F = np.empty((self.k.ROWS, n))
        self._held = False
        self._F: np.ndarray | None = None  # the last step's interpolant
        self._h = 0.0
        self._cubic = False
        self._y_old = self.y
        e = max(self.EVENTS_PER_CALL, 2 * len(m_arr) + 2)
        self._ev = (np.empty(e), np.empty(e, np.int64), np.empty(e), np.empty((e, n)),
                    np.empty((e, len(m_arr))))
        self._failure: StepFailure | None = None
        self.fallback: ScipyStepper | None = None
        # every step's end as a sample for RANGE (when it is asked for)
        s = max(64, min(4096, 2_000_000 // max(n, 1))) if sampling else 0
        self._smp = (np.empty(s), np.empty((s, n)), np.empty((s, len(m_arr))))
        self._rows: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    @property
    def nfev(self) -> int:
        return int(self.sc[NFEV]) + (self.fallback.nfev if self.fallback is not None else 0)

    @property
    def nstep(self) -> int:
        return int(self.sc[NSTEPS]) + (self.fallback.nstep if self.fallback is not None else 0)

    @property
    def done(self) -> bool:
        """No kernel call is due: a step is held, the kernel failed, or SciPy took over."""
        return self._held or self._failure is not None or self.fallback is not None

    def advance(self, m, z, grid: np.ndarray, gi: int) -> Advance:
        """Run the kernel from where it stands with the branches `m` (updated in the
        array returned with the crossings it locates) and the memory `z` as the loop
        keeps it now."""
        m_arr = np.asarray(m, dtype=float)
        self.z = np.asarray(z, dtype=float)
        if self._rows is None:
            # (reused: the rows are copied out of it; `advance` in the kernel ends its
            # steps where the buffer is full)
            size = max(1, min(max(len(grid) - gi, 0), self.ROWS_BUFFER,
                              4_000_000 // max(len(self._y) + len(m_arr), 1)))
            self._rows = (np.empty(size), np.empty((size, len(self._y))),
                          np.empty((size, len(m_arr))))
        T, Y, M = self._rows
        # the instants the buffer has room for, and one more: the kernel stops where
        # its buffer is full only while an instant is left (a view of an array; a long
        # grid made as it is read, `run.plan.GridTimes`, written out this far)
        grid = np.asarray(grid[gi:gi + len(T) + 1], dtype=float)
        gi = 0
        et, ek, en, ey, em = self._ev
        # the surfaces where the kernel stands, in the branches now in force (the loop
        # may have changed a silent one)
        self._surf(float(self.sc[AT]), self._y, m_arr, self.z, self.p, self._e)
        st, sy, sm = self._smp
        status, rows, nev, _, ns = self._advance(
            self.rhs, self.surf, self._y, self._f, self._e, m_arr, self.z, self.p, self.sc,
            self.rtol, self.atol, self.watch, self.handled, self.level, grid, gi, T, Y, M,
            et, ek, en, ey, em, self._held_y, self._held_f, self._held_F, self.max_steps,
            st, sy, sm)
        # where the kernel stands now; its own steps are not the loop's to interpolate
        self.t = self.t_old = float(self.sc[AT])
        self.y = self._y.copy()
        self._F = None
        if self.stiff is None and self.sc[STIFF_AT] == self.sc[STIFF_AT]:
            self.stiff = Stiffness(float(self.sc[STIFF_AT]), float(self.sc[STIFF_H_LAMBDA]))
        if status == HELD:
            self._held = True
        elif status == STEPS:
            self._failure = StepFailure(Failure.STEPS, float(self.sc[AT]))
        elif status == SMALL:
            self._take_over()
        return Advance(status, T[:rows].copy(), Y[:rows].copy(), M[:rows].copy(),
                       et[:nev].copy(), ek[:nev].copy(), en[:nev].copy(), ey[:nev].copy(),
                       em[:nev].copy(),
                       m_arr, st[:ns].copy(), sy[:ns].copy(), sm[:ns].copy())

    def _take_over(self) -> None:
        if self.fun is None:  # no Python field to go on with (RANGE's sampling)
            self._failure = StepFailure(Failure.SOLVER, float(self.sc[AT]), "step size too small")
            return
        self.fallback = ScipyStepper("DOP853", self.fun, float(self.sc[AT]), self._y.copy(),
                                     float(self.sc[BOUND]), rtol=self.rtol, atol=self.atol,
                                     max_step=float(self.sc[MAX_STEP]), first_step=None,
                                     stability_limit=float(self.sc[LIMIT]))

    def step(self) -> StepFailure | None:
        if self._held:
            self._held = False
            self.t_old, self._y_old = float(self.sc[AT]), self._y.copy()
            self.t = float(self.sc[HELD_END])
            self.y = self._held_y.copy()
            self._F = self._held_F.copy()
            self._h = self.t - self.t_old  # the interpolant's own (truncate moves t)
            self._cubic = bool(self.sc[CUBIC])
            # the kernel goes on from the held step's end
            self.sc[AT] = self.t
            self._y[:] = self._held_y
            self._f[:] = self._held_f
            return None
        if self._failure is not None:
            return self._failure
        if self.fallback is None:
            self._take_over()
        failure = self.fallback.step()
        self.t_old, self.t, self.y = self.fallback.t_old, self.fallback.t, self.fallback.y
        self._F = None
        return failure

    def interpolant(self):
        if self._F is None:
            return self.fallback.interpolant()
        t_old, h, F, cubic, interpolate = self.t_old, self._h, self._F, self._cubic, \
            self._interpolate
        n = len(self._y_old)

        def at(t: float) -> np.ndarray:
            out = np.empty(n)
            interpolate(t_old, h, F, cubic, float(t), out)
            return out
        return at
