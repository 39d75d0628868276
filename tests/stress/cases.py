"""Stress listings and their closed-form or independent reference solutions.

Shared by tests/stress/ (CI sizes) and benchmarks/stress.py (long runs).
"""

from __future__ import annotations

import math

import numpy as np

from amilpy.routes import ROUTES

# one METHOD spelling per route, from the registry
METHODS = [r.aliases[0] for r in ROUTES]


def warnings_of(run) -> list[str]:
    """The run's warnings, but METHOD COMPILED's note that it ran as DOP853 (numba
    not installed: the plain install CI runs first)."""
    return [w for w in run.warnings if not w.endswith("it ran as DOP853")]
VARIABLE = [r.aliases[0] for r in ROUTES if not r.fixed]
IMPLICIT = [r.aliases[0] for r in ROUTES if not r.explicit]  # stiff-capable routes
EXPLICIT_VARIABLE = [r.aliases[0] for r in ROUTES if r.explicit and not r.fixed]
FIXED = [r.aliases[0] for r in ROUTES if r.fixed]

# --------------------------------------------------------------- stiffness
# Two inertias J1, J2 joined by a shaft of stiffness K with a stiffness-
# proportional damper D = BETA*K; motor torque T0 on J1, viscous load B on J2.
# Eigenvalues: the rigid-body mode -B/(J1+J2) = -5E-3 and, for large K, the
# overdamped shaft mode -BETA*K*(1/J1 + 1/J2) = -2E-2*K: a stiffness ratio of
# 4 (K = 1) up to 4E8 (K = 1E8).
TWO_MASS = """TITLE TWO-MASS DRIVE, COUPLING STIFFNESS K
PARAM K = 1.0
CONST J1 = 1.0, J2 = 1.0, BETA = 1.0E-2, B = 1.0E-2, T0 = 1.0
INITIAL
  D = BETA*K
DYNAMIC
  PHI = INTGRL(0.0, W1 - W2)
  MC  = K*PHI + D*(W1 - W2)
  W1  = INTGRL(0.0, (T0 - MC)/J1)
  W2  = INTGRL(0.0, (MC - B*W2)/J2)
TIMER FINTIM = {fintim}, OUTDEL = {outdel}
PRINT W1, W2, PHI
END
"""


def two_mass_reference(k: float, times: np.ndarray, j1=1.0, j2=1.0, beta=1e-2, b=1e-2,
                       t0=1.0) -> dict[str, np.ndarray]:
    """Exact solution of the linear drive: y' = A y + c, y(0) = 0, by expm."""
    from scipy.linalg import expm

    d = beta * k
    a = np.array([[0.0, 1.0, -1.0],
                  [-k / j1, -d / j1, d / j1],
                  [k / j2, d / j2, -(d + b) / j2]])
    c = np.array([0.0, t0 / j1, 0.0])
    aug = np.zeros((4, 4))
    aug[:3, :3] = a
    aug[:3, 3] = c
    out = np.array([expm(aug * t)[:3, 3] for t in times])
    return {"PHI": out[:, 0], "W1": out[:, 1], "W2": out[:, 2]}


def stiffness_ratio(k: float, j1=1.0, j2=1.0, beta=1e-2, b=1e-2) -> float:
    d = beta * k
    a = np.array([[0.0, 1.0, -1.0], [-k / j1, -d / j1, d / j1], [k / j2, d / j2, -(d + b) / j2]])
    lam = np.abs(np.linalg.eigvals(a).real)
    lam = lam[lam > 0]
    return float(lam.max() / lam.min())


def scaled_error(run, ref: dict[str, np.ndarray], rtol: float, atol: float) -> float:
    """max |y - y_ref| / (rtol*max|y_ref| + atol) over the variables and the OUTDEL grid:
    1 means an error of one tolerance unit."""
    worst = 0.0
    for name, yr in ref.items():
        scale = rtol * float(np.max(np.abs(yr))) + atol
        worst = max(worst, float(np.max(np.abs(run[name] - yr))) / scale)
    return worst


# ----------------------------------------------------------------- backlash
# x'' = -W^2 DEADSP(-GAP/2, GAP/2, x), released at rest at x = A: a harmonic arc
# outside the gap, constant speed W*(A - GAP/2) across it.
DEAD_ZONE = """TITLE DEAD-ZONE (BACKLASH) OSCILLATOR
PARAM GAP = 0.1, A = 1.0, W = 1.0
INITIAL
  H = 0.5*GAP
DYNAMIC
  X = INTGRL(A, V)
  V = INTGRL(0.0, -W*W*DEADSP(-H, H, X))
TIMER FINTIM = {fintim}, OUTDEL = 0.1
PRINT X, V
END
"""


def dead_zone_period(gap: float, a: float = 1.0, w: float = 1.0) -> float:
    return 2.0 * math.pi / w + 2.0 * gap / (w * (a - gap / 2.0))


def dead_zone_events(gap: float, fintim: float, a: float = 1.0, w: float = 1.0) -> list[float]:
    """Instants at which x crosses +-GAP/2, in order."""
    q = math.pi / (2.0 * w)  # from A down to GAP/2
    tg = gap / (w * (a - gap / 2.0))  # across the gap
    half = math.pi / w  # the harmonic arc outside the gap
    out, t = [], q
    steps = [tg, half, tg, half]
    i = 0
    while t < fintim:
        out.append(t)
        t += steps[i % 4]
        i += 1
    return out


# --------------------------------------------------------------- stick-slip
# Mass MS on a spring K, on a belt moving at VB; Coulomb friction FC written with
# FSW on the relative velocity. Released at rest: it slips (friction drags it
# forward), reaches belt speed with the spring force below FC and sticks (the
# Filippov sliding motion on VR = 0), rides with the belt until K*X = FC, then
# slips on a harmonic arc around FC/K, which touches belt speed again
# tangentially after one period.
STICK_SLIP = """TITLE STICK-SLIP: MASS ON A SPRING DRAGGED BY A BELT
PARAM VB = 0.1, FC = 1.0, K = 1.0, MS = 1.0
DYNAMIC
  VR = V - VB
  F  = FSW(VR, FC, 0.0, -FC)
  X  = INTGRL(0.0, V)
  V  = INTGRL(0.0, (F - K*X)/MS)
TIMER FINTIM = {fintim}, OUTDEL = 0.05
PRINT X, V, F
END
"""


def stick_slip_exact(t, vb=0.1, fc=1.0, k=1.0, ms=1.0):
    """(x, v, t_stick, t_slip): closed form of the run above."""
    w = math.sqrt(k / ms)
    t1 = math.asin(vb * k / (fc * w)) / w  # reaches belt speed: sticks
    x1 = fc / k * (1.0 - math.cos(w * t1))
    t2 = t1 + (fc / k - x1) / vb  # spring force reaches the friction limit
    t = np.asarray(t, dtype=float)
    x = np.where(t < t1, fc / k * (1 - np.cos(w * t)),
                 np.where(t < t2, x1 + vb * (t - t1), fc / k + vb / w * np.sin(w * (t - t2))))
    v = np.where(t < t1, fc / k * w * np.sin(w * t),
                 np.where(t < t2, vb, vb * np.cos(w * (t - t2))))
    return x, v, t1, t2


# ------------------------------------------------------------------- relays
RELAY_INTEGRATOR = """TITLE RELAY ON AN INTEGRATOR
X = INTGRL(1.0, -FSW(X, -1.0, 0.0, 1.0))
TIMER FINTIM = 3.0, OUTDEL = 0.01
PRINT X
END
"""

# reaching phase x = 1 - t^2/2 (U = -1) until S = X + C*V = 0, then sliding
# (|V| < C there, so both branches push S back): X' = -X/C on S = 0
RELAY_SLIDING = """TITLE RELAY ON A DOUBLE INTEGRATOR, SWITCHING LINE S = X + C*V
PARAM C = 2.0
S = X + C*V
U = FSW(S, 1.0, 0.0, -1.0)
V = INTGRL(0.0, U)
X = INTGRL(1.0, V)
TIMER FINTIM = 6.0, OUTDEL = 0.01
PRINT X, V, U
END
"""


def relay_sliding_exact(t, c=2.0):
    # reaching: x = 1 - t^2/2, v = -t, S = 1 - t^2/2 - c t = 0
    tr = -c + math.sqrt(c * c + 2.0)
    xr = 1.0 - tr * tr / 2.0
    t = np.asarray(t, dtype=float)
    x = np.where(t < tr, 1.0 - t * t / 2.0, xr * np.exp(-(t - tr) / c))
    return x, tr

# a relay acting through a first-order lag: the switching accumulates (Zeno)
RELAY_LAG = """TITLE RELAY WITH A LAG
PARAM TAU = 0.01
U = FSW(X, 1.0, 0.0, -1.0)
Y = REALPL(0.0, TAU, U)
X = INTGRL(1.0, Y)
TIMER FINTIM = 3.0, OUTDEL = 0.01
PRINT X, Y
END
"""

# ------------------------------------------------------------------ blow-up
BLOW_UP = """TITLE FINITE-TIME BLOW-UP, X = 1/(1 - TIME)
X = INTGRL(1.0, X*X)
TIMER FINTIM = 2.0, OUTDEL = 0.01
PRINT X
END
"""

# ------------------------------------------------------------ long horizon
OSCILLATOR = """TITLE UNDAMPED OSCILLATOR, PERIOD 1
PARAM W = 6.283185307179586
X = INTGRL(1.0, V)
V = INTGRL(0.0, -W*W*X)
E = SQRT(X*X + V*V/(W*W))
TIMER FINTIM = {periods}, OUTDEL = 0.5
PRINT X, E
END
"""


def amplitude_drift(run) -> float:
    """Relative change of the amplitude sqrt(x^2 + v^2/w^2) at the end of the run."""
    return float(run["E"][-1] - 1.0)
