"""Reference for a forced Duffing oscillator and its periodic orbits, written with
SciPy alone (never imports amilpy):

    x'' + c x' + k x + a x^3 = F cos(w t)

A periodic orbit of period 2*pi/w is a fixed point of the period map, found by
Newton (scipy.optimize.root) with the map and its Jacobian from solve_ivp
(DOP853, rtol 1e-12) on the state and its variational equations together. A
fold of the response curve is a root of the extended system

    P(x0, v0; w) - (x0, v0) = 0,    det(dP/d(x0, v0) - I) = 0

solved by scipy.optimize.root from a harmonic-balance guess: a root-finding on
the fold's own defining equations, independent of any continuation. The
harmonic balance (x = A cos(w t - phi)) gives the guesses:

    A^2 [(k - w^2 + 3/4 a A^2)^2 + (c w)^2] = F^2.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar, root

C, K, A, F = 0.1, 1.0, 0.5, 0.2
RTOL, ATOL = 1e-12, 1e-14


def _rhs(t: float, s: np.ndarray, w: float) -> list[float]:
    x, v, p11, p12, p21, p22 = s
    dfdx = -K - 3.0 * A * x * x
    return [v, F * math.cos(w * t) - C * v - K * x - A * x ** 3,
            p21, p22, dfdx * p11 - C * p21, dfdx * p12 - C * p22]


def period_map(state: np.ndarray, w: float, dense: bool = False):
    """(the state after one period, the monodromy matrix[, the solution])."""
    sol = solve_ivp(_rhs, (0.0, 2.0 * math.pi / w), [state[0], state[1], 1, 0, 0, 1],
                    method="DOP853", rtol=RTOL, atol=ATOL, args=(w,), dense_output=dense)
    end = sol.y[:, -1]
    out = (end[:2], end[2:].reshape(2, 2))
    return out + (sol,) if dense else out


def orbit(w: float, guess) -> np.ndarray:
    """The start (x, v) at t = 0 of the periodic orbit near `guess`."""
    def g(s):
        end, m = period_map(s, w)
        return end - s, m - np.eye(2)
    sol = root(g, np.asarray(guess, dtype=float), jac=True, method="hybr",
               options={"xtol": 1e-13})
    # near a fold the map's Jacobian is nearly singular: hybr may stop short of
    # its xtol at a residual that is nonetheless the integration's noise
    if not (sol.success or np.max(np.abs(sol.fun)) <= 1e-11):
        raise RuntimeError(sol.message)
    return sol.x


def fold(guess_w: float, guess_state) -> tuple[float, np.ndarray]:
    """(w, start state) of the fold near the guess (see the module): the orbit at
    the guessed w first, then the extended system from there."""
    def h(z):
        s, w = z[:2], z[2]
        end, m = period_map(s, w)
        return np.append(end - s, np.linalg.det(m - np.eye(2)))
    sol = root(h, np.append(np.asarray(guess_state, dtype=float), guess_w), method="hybr",
               options={"xtol": 1e-13})
    if not sol.success:
        raise RuntimeError(sol.message)
    return float(sol.x[2]), sol.x[:2]


def half_pp(state, w: float) -> float:
    """Half peak-to-peak of x over one period of the orbit starting at `state`."""
    _, _, sol = period_map(state, w, dense=True)
    t = np.linspace(0.0, 2.0 * math.pi / w, 4001)
    x = sol.sol(t)[0]
    lo, hi = [], []
    for arr, pick in ((x, np.argmax), (-x, np.argmax)):
        i = int(pick(arr))
        a, b = t[max(i - 1, 0)], t[min(i + 1, len(t) - 1)]
        res = minimize_scalar(lambda s, sgn=(1 if arr is x else -1): -sgn * sol.sol(s)[0],
                              bounds=(a, b), method="bounded", options={"xatol": 1e-12})
        (hi if arr is x else lo).append(-res.fun if arr is x else res.fun)
    return 0.5 * (hi[0] - lo[0])


def hb_frequencies(amp: float) -> list[float]:
    """The w at which the harmonic balance gives amplitude `amp` (0, 1 or 2)."""
    kk = K + 0.75 * A * amp * amp
    b = 2 * kk - C * C
    disc = b * b - 4 * (kk * kk - F * F / (amp * amp))
    if disc < 0:
        return []
    return sorted(math.sqrt(u) for u in ((b - math.sqrt(disc)) / 2, (b + math.sqrt(disc)) / 2)
                  if u > 0)


def hb_state(w: float, amp: float) -> np.ndarray:
    """(x, v) at t = 0 of x = amp cos(w t - phi), the harmonic balance's orbit."""
    phi = math.atan2(C * w, K - w * w + 0.75 * A * amp * amp)
    return np.array([amp * math.cos(phi), amp * w * math.sin(phi)])


def hb_folds() -> list[tuple[float, float]]:
    """(w, amplitude) at the harmonic balance's two folds. For each amplitude the
    balance has two frequencies, w- on the rising side of the resonance and w+
    on the falling side, which meet at the top: the top is the fold where the
    large orbit ends (the largest w-), and the falling side turns back where
    w+ is least (the fold where the small orbit ends)."""
    sides = [(ws, float(amp)) for amp in np.linspace(0.1, 2.0, 19001)
             if len(ws := hb_frequencies(float(amp))) == 2]
    top = max((ws[0], amp) for ws, amp in sides)
    turn = min((ws[1], amp) for ws, amp in sides)
    return [top, turn]


if __name__ == "__main__":
    for w_hb, a_hb in hb_folds():
        w, s = fold(w_hb, hb_state(w_hb, a_hb))
        print(f"HB fold {w_hb:.6f} (A {a_hb:.4f}) -> shooting fold {w:.9f}, "
              f"half p-p {half_pp(s, w):.9f}")
