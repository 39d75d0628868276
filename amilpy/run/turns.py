"""Where a play (HSTRSS, BCKLSH) turns inside a step.

A play's memory is its value at the last update: between two updates the value is
clamp(Z, X - P2, X - P1), the input X pushing it one way while it leans on an edge
of the play. Where X reverses inside a step while pushing, the play should hold
the extreme it reached; the value the last update left instead follows X back. So
an update at the step's end only would hold a value short of the extreme by about
|X''| h^2 / 2 (BCKLSH(0, 0.5, 2 SIN(TIME)) held -1.49988 for -1.5 at RELERR 1e-10).

The value with the memory as the step found it is monotone while it is right: its
first turn on the step's dense output is the play's turning point. The loop cuts
the step there and updates the memory at that instant (`StepWatch`), as it does at
a located crossing; what the step integrated past it is integrated again. An
extremum is flat, so locating it to sqrt(eps) of the step in TIME gets its value to
rounding.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize_scalar

from .dense import sample

SAMPLES = 16  # intervals of a step the value is looked at on, before the turn is located
END = 1e-3  # of the step: where its slope at the end is looked at (a turn after the
# last interior sample)


def play_turn(c, interp, ta: float, tb: float, m, z) -> float | None:
    """The first instant in (ta, tb) at which a play's value (`c.play_slots`) with
    the memory `z` turns back, or None."""
    times = np.linspace(ta, tb, SAMPLES + 1)
    times = np.append(times, tb - END * (tb - ta))
    states = sample(interp, times)

    def values(k: int) -> list[float]:
        return c.mem(float(times[k]), states[:, k].tolist(), m, m, list(z))

    rows = np.array([values(k) for k in range(len(times))])[:, c.play_slots]
    first = None
    for j in range(rows.shape[1]):
        w = rows[:SAMPLES + 1, j]
        # (the last interval seen twice: up to tb - END h, then to tb)
        w = np.concatenate([w[:-1], [rows[-1, j], w[-1]]])
        t = np.concatenate([times[:-2], [times[-1], tb]])
        turn = _first_turn(t, w)
        if turn is None:
            continue
        lo, hi, sign = turn

        def minus(u: float, j=j, sign=sign) -> float:
            y = np.asarray(interp(u), dtype=float).tolist()
            return -sign * c.mem(u, y, m, m, list(z))[c.play_slots[j]]

        found = minimize_scalar(minus, bounds=(lo, hi), method="bounded",
                                options={"xatol": 4 * np.finfo(float).eps * max(abs(hi), 1.0)
                                         + 1e-9 * (hi - lo)})
        at = float(found.x)
        if ta < at < tb and (first is None or at < first):
            first = at
    return first


def _first_turn(t: np.ndarray, w: np.ndarray) -> tuple[float, float, float] | None:
    """(lo, hi, direction) bracketing the first extremum of the sampled w where it
    turns back against the direction it first moved in, or None if it is monotone."""
    d = np.diff(w)
    scale = np.finfo(float).eps * 8 * max(float(np.max(np.abs(w))), 1e-300)
    moving = np.flatnonzero(np.abs(d) > scale)
    if not len(moving):
        return None
    sign = float(np.sign(d[moving[0]]))
    back = moving[d[moving] * sign < 0]
    if not len(back):
        return None
    # the extreme sample before the first move back, and its neighbours
    upto = int(back[0])
    top = int(np.argmax(sign * w[:upto + 1]))
    return float(t[max(top - 1, 0)]), float(t[min(top + 1, len(t) - 1)]), sign
