"""Reference for acsl/spring.csl (woodwards/csl2cpp, spring/Spring.csl): a released mass.

The listing (ACSL form, one DERIVATIVE section) transcribed:

    xdd  = (mass*g - k*xd - a*x)/mass        k = 0.12, a = 1.0, g = 9.81, mass = 0.03
    xd   = INTEG(xdd, xdic)                  xdic = 0
    x    = INTEG(xd, xic)                    xic = 0
    time = INTEG(1.0, 0.0)                   a state the listing calls "time": equal to t
    TERMT(t .GE. tstp, 'Time Limit')         tstp = 3.99;  CINTERVAL cint = 0.02

so x'' + (k/m) x' + (a/m) x = g, an under-damped oscillator whose closed form is exact:
with s = k/(2m) = 2, w0^2 = a/m, wd = sqrt(w0^2 - s^2), xs = m*g/a,

    x(t)  = xs * (1 - exp(-s t) (cos wd t + (s/wd) sin wd t))
    xd(t) = xs * (w0^2/wd) exp(-s t) sin wd t

Rows: t = 0, 0.02, ..., 3.98 (every CINT) and the TERMT instant 3.99 (contract section 9:
rows every CINT and at the end). The C++ translation's printout in the same repository
(spring/spring_cpp_output.tsv, columns: step count, t, time, xd, x, six digits) gives e.g.
xd(0.02) = 0.188138, x(0.02) = 0.0019086, x(3.98) = 0.294377; SOURCES.md quotes them.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

K = 0.12  # damping coefficient
A = 1.0  # spring constant
W = 1.0  # declared, unused by the equations
G = 9.81
MASS = 0.03
XIC = 0.0
XDIC = 0.0
TSTP = 3.99
CINT = 0.02


def output_times() -> NDArray[np.float64]:
    """Row instants: every CINT from 0 while below TSTP, then TSTP itself."""
    n = int(math.floor(TSTP / CINT + 1e-9))
    grid = np.arange(n + 1) * CINT
    grid = grid[grid < TSTP - 1e-12]
    return np.append(grid, TSTP)


def solution(t: NDArray[np.float64] | float) -> dict[str, NDArray[np.float64]]:
    """Closed-form x, xd, xdd and time at t (valid for the listing's zero initial state)."""
    t = np.asarray(t, dtype=float)
    s = K / (2.0 * MASS)
    w0sq = A / MASS
    wd = math.sqrt(w0sq - s * s)
    xs = MASS * G / A
    e = np.exp(-s * t)
    x = xs * (1.0 - e * (np.cos(wd * t) + (s / wd) * np.sin(wd * t)))
    xd = xs * (w0sq / wd) * e * np.sin(wd * t)
    xdd = (MASS * G - K * xd - A * x) / MASS
    return {"T": t, "TIME": t.copy(), "X": x, "XD": xd, "XDD": xdd}


def run() -> dict[str, NDArray[np.float64]]:
    """The listing's printout: T and every state at each row instant."""
    return solution(output_times())


# The C++ translation's rows quoted in SOURCES.md: (t, xd, x), six significant digits.
PUBLISHED_CPP = ((0.02, 0.188138, 0.0019086), (0.04, 0.359404, 0.00741298),
                 (0.06, 0.512902, 0.0161662), (0.08, 0.648033, 0.0278066),
                 (3.94, 0.000415701, 0.294364), (3.96, 0.000340498, 0.294371),
                 (3.98, 0.000266718, 0.294377))
