"""Integration of a smooth system (no events) to the output rows, tightly.

A run bounded by TERMT(T >= TSTOP) with rows every CINT: rows at 0, CINT, ... and
at TSTOP (contract section 9). No step is longer than CINT, so the dense output
between steps adds nothing to the integration error (see piecewise.py).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

RTOL = 1e-11
ATOL = 1e-13


def output_times(tstop: float, cint: float) -> NDArray[np.float64]:
    """Every CINT from 0 while below TSTOP, then TSTOP itself."""
    n = int(np.floor(tstop / cint + 1e-9))
    grid = np.arange(n + 1) * cint
    grid = grid[grid < tstop - 1e-9 * cint]
    return np.append(grid, tstop)


def integrate(rhs: Callable, y0: Sequence[float], tstop: float, cint: float,
              method: str = "Radau") -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(rows, states at the rows), integrated at rtol 1e-11."""
    t = output_times(tstop, cint)
    sol = solve_ivp(rhs, (0.0, tstop), np.asarray(y0, float), method=method, rtol=RTOL,
                    atol=ATOL, t_eval=t, max_step=cint)
    if not sol.success:
        raise RuntimeError(sol.message)
    return t, sol.y.T
