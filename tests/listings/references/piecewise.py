"""Integration between known instants, with the state or the inputs changed at each.

The ACSL listings here change their inputs at scheduled instants (SCHEDULE .AT.,
DISCRETE with INTERVAL, a relational test on T): between two instants the system is
smooth, so the reference integrates each interval on its own with solve_ivp at rtol 1e-10
and applies the listing's DISCRETE action at the instant. Output instants that coincide
with an event show the post-event values, as ACSL prints them (contract section 9).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

RTOL = 1e-10
ATOL = 1e-12

Action = Callable[[float, NDArray[np.float64], dict], NDArray[np.float64]]


def integrate_piecewise(
    rhs: Callable[[float, NDArray[np.float64], dict], NDArray[np.float64]],
    y0: Sequence[float],
    t_out: NDArray[np.float64],
    events: Sequence[tuple[float, Action]],
    inputs: dict,
    *,
    rtol: float = RTOL,
    atol: float = ATOL,
) -> NDArray[np.float64]:
    """States at each of t_out (rows), integrating rhs(t, y, inputs) between events.

    events are (instant, action) in time order; action(t, y, inputs) may change inputs
    in place and returns the state after the event. Events at t_out[0] run before the
    first row; rows at an event instant show the post-event state.
    """
    t_out = np.asarray(t_out, dtype=float)
    y = np.asarray(y0, dtype=float).copy()
    out = np.empty((t_out.size, y.size))
    t = float(t_out[0])
    pending = sorted(events, key=lambda e: e[0])
    k = 0
    i = 0
    while True:
        while k < len(pending) and pending[k][0] <= t:
            y = np.asarray(pending[k][1](t, y, inputs), dtype=float)
            k += 1
        while i < t_out.size and t_out[i] <= t:
            out[i] = y
            i += 1
        if i == t_out.size:
            return out
        t_next = pending[k][0] if k < len(pending) else t_out[-1]
        t_next = min(t_next, t_out[-1])
        # rows strictly inside the interval; the row at t_next is taken after its events
        grid = np.append(t_out[(t_out > t) & (t_out < t_next)], t_next)
        # no step longer than the output interval: DOP853's dense output (order 7)
        # between long steps is off by ~1e-7 of a slowly varying state (gefitinib's
        # PERK), far above rtol; within one interval it is below round-off
        spacing = float(np.min(np.diff(t_out))) if t_out.size > 1 else np.inf
        sol = solve_ivp(rhs, (t, t_next), y, method="DOP853", rtol=rtol, atol=atol,
                        t_eval=grid, args=(inputs,), max_step=spacing)
        if not sol.success:
            raise RuntimeError(sol.message)
        out[i:i + grid.size - 1] = sol.y[:, :-1].T
        i += grid.size - 1
        y = sol.y[:, -1].copy()
        t = t_next
