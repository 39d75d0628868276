"""DOP853 for the compiled loop: SciPy's Dormand-Prince 8(5,3) (`scipy.integrate.
_ivp.rk`) written for numba -- its coefficients, a step's stages and error norm,
the initial step, the dense output and Hairer's stiffness test -- and one accepted
step (`step`). The loop that uses them, with the rows and the switching
surfaces, is `kernel.advance`.

The model's two functions come in as pointers of one signature (`MODEL`), so this
code is compiled once per machine and kept in numba's cache.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from scipy.integrate._ivp import dop853_coefficients as _dc

from .layout import CALM, H_LAMBDA, LIMIT, POSITIVE, STIFF_AT, STIFF_H_LAMBDA

N_STAGES = _dc.N_STAGES
A = np.ascontiguousarray(_dc.A[:N_STAGES, :N_STAGES])
B = np.ascontiguousarray(_dc.B)
C = np.ascontiguousarray(_dc.C[:N_STAGES])
E3 = np.ascontiguousarray(_dc.E3)
E5 = np.ascontiguousarray(_dc.E5)
D = np.ascontiguousarray(_dc.D)
A_EXTRA = np.ascontiguousarray(_dc.A[N_STAGES + 1:])
C_EXTRA = np.ascontiguousarray(_dc.C[N_STAGES + 1:])
N_EXTENDED = _dc.N_STAGES_EXTENDED
POWER = _dc.INTERPOLATOR_POWER
ROWS = POWER + 4  # a step's interpolant: DOP853's terms, then both ends and their slopes

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
EXPONENT = -1.0 / 8.0  # the error estimator's order is 7

# NaN and infinities, not exceptions, where arithmetic fails (as the model's own code)
_jit = njit(cache=True, error_model="numpy")
# the parts of one step of the loop: inlined into it by numba (no call per step)
_part = njit(cache=True, error_model="numpy", inline="always")

_F8, _I8 = types.float64, types.int64
_V, _M = types.float64[::1], types.float64[:, ::1]  # C-ordered vectors and matrices
# the model's functions: (t, y, m, z, p, out) -> None, the values written into out
MODEL = types.void(_F8, _V, _V, _V, _V, _V)
_FN = types.FunctionType(MODEL)
_I, _B = types.int64[::1], types.boolean[::1]


def _entry(restype, *argtypes):
    """An entry point from Python, compiled when this module is imported (from
    numba's cache after the first time), with the model's functions as pointers:
    one machine code for every model."""
    return njit(restype(*argtypes), cache=True, error_model="numpy")




@_jit
def _rms(v):
    return math.sqrt(np.sum(v * v) / max(v.size, 1))


@_entry(_F8, _FN, _F8, _V, _V, _F8, _F8, _V, _V, _V, _V, _V)
def first_step(rhs, t, y, f, t_bound, max_step, rtol, atol, m, z, p):
    """SciPy's `select_initial_step` for an 8th-order pair (error order 7)."""
    n = y.size
    interval = abs(t_bound - t)
    if interval == 0.0:
        return 0.0
    scale = atol + np.abs(y) * rtol
    d0 = _rms(y / scale)
    d1 = _rms(f / scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, interval)
    y1 = y + h0 * f
    f1 = np.empty(n)
    rhs(t + h0, y1, m, z, p, f1)
    d2 = _rms((f1 - f) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1, interval, max_step)


@_jit
def _stages(rhs, t, y, f, h, m, z, p, K, y_new, ys):
    """One DOP853 step from (t, y) with f = rhs(t, y): K[0..12] and y_new (K[12] is
    the derivative there); returns the error norm's square terms (err5, err3)."""
    n = y.size
    K[0, :] = f
    for s in range(1, N_STAGES):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += A[s, j] * K[j, i]
            ys[i] = y[i] + h * acc
        rhs(t + C[s] * h, ys, m, z, p, K[s])
    for i in range(n):
        acc = 0.0
        for j in range(N_STAGES):
            acc += B[j] * K[j, i]
        y_new[i] = y[i] + h * acc
    rhs(t + h, y_new, m, z, p, K[N_STAGES])


@_jit
def _error_norm(y, y_new, K, h, rtol, atol):
    n = y.size
    e5 = 0.0
    e3 = 0.0
    for i in range(n):
        scale = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol[i]
        a5 = 0.0
        a3 = 0.0
        for j in range(N_STAGES + 1):
            a5 += E5[j] * K[j, i]
            a3 += E3[j] * K[j, i]
        a5 /= scale
        a3 /= scale
        e5 += a5 * a5
        e3 += a3 * a3
    if e5 == 0.0 and e3 == 0.0:
        return 0.0
    return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * n)


@_jit
def dense_terms(rhs, t, y, h, y_new, f_new, m, z, p, K, F, ys):
    """The step's interpolant, F[0..6] (SciPy's Dop853DenseOutput), with the three
    extra stages it needs, and its ends with their derivatives (F[7..10], for the
    cubic Hermite of `interpolate`)."""
    n = y.size
    for s in range(N_STAGES + 1, N_EXTENDED):
        a = A_EXTRA[s - N_STAGES - 1]
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += a[j] * K[j, i]
            ys[i] = y[i] + h * acc
        rhs(t + C_EXTRA[s - N_STAGES - 1] * h, ys, m, z, p, K[s])
    for i in range(n):
        F[POWER, i] = y[i]
        F[POWER + 1, i] = K[0, i]
        F[POWER + 2, i] = y_new[i]
        F[POWER + 3, i] = f_new[i]
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (f_new[i] + K[0, i])
        for r in range(POWER - 3):
            acc = 0.0
            for j in range(N_EXTENDED):
                acc += D[r, j] * K[j, i]
            F[3 + r, i] = h * acc


@_jit
def dense_at(t_old, h, y_old, F, t, out):
    """The interpolant at t (SciPy's evaluation order)."""
    x = (t - t_old) / h
    n = y_old.size
    for i in range(n):
        acc = 0.0
        for r in range(POWER - 1, -1, -1):
            acc += F[r, i]
            if (POWER - 1 - r) % 2 == 0:
                acc *= x
            else:
                acc *= 1.0 - x
        out[i] = acc + y_old[i]


@_entry(types.none, _F8, _F8, _M, types.boolean, _F8, _V)
def interpolate(t_old, h, F, cubic, t, out):
    """The step's state at t: DOP853's interpolant, or the cubic Hermite through its
    ends where that is not to be trusted -- a stability-bound step (`cubic`; see
    `steppers.ivp.ScipyStepper`) or a value that overflows inside."""
    n = out.size
    if not cubic:
        dense_at(t_old, h, F[POWER], F, t, out)
        finite = True
        for i in range(n):
            if not math.isfinite(out[i]):
                finite = False
        if finite:
            return
    s = (t - t_old) / h
    h00 = (1.0 + 2.0 * s) * (1.0 - s) ** 2
    h01 = s * s * (3.0 - 2.0 * s)
    h10 = s * (1.0 - s) ** 2
    h11 = s * s * (s - 1.0)
    for i in range(n):
        out[i] = h00 * F[POWER, i] + h01 * F[POWER + 2, i] + \
            h * (h10 * F[POWER + 1, i] + h11 * F[POWER + 3, i])


@_jit
def _stiffness(y, y_new, K, h, sc, tested, t_new):
    """Hairer's stiffness test (as `ScipyStepper._stiffness_test`): h*|lambda| from
    the last stage (c = 1) and the new point, its counts and its findings in sc
    (POSITIVE ... STIFF_H_LAMBDA, see `layout`)."""
    if sc[POSITIVE] == 0.0 and tested % 4:
        return
    n = y.size
    den = 0.0
    num = 0.0
    for i in range(n):
        acc = 0.0
        for j in range(N_STAGES - 1):
            acc += A[N_STAGES - 1, j] * K[j, i]
        d = y_new[i] - y[i] - h * acc
        den += d * d
        g = K[N_STAGES, i] - K[N_STAGES - 1, i]
        num += g * g
    if not (0.0 < den < np.inf):
        return
    sc[H_LAMBDA] = abs(h) * math.sqrt(num / den)
    if sc[H_LAMBDA] > sc[LIMIT]:
        sc[CALM] = 0.0
        sc[POSITIVE] += 1.0
        if sc[POSITIVE] == 15.0 and not sc[STIFF_AT] == sc[STIFF_AT]:
            sc[STIFF_AT] = t_new
            sc[STIFF_H_LAMBDA] = sc[H_LAMBDA]
    else:
        sc[CALM] += 1.0
        if sc[CALM] == 6.0:
            sc[POSITIVE] = 0.0


@_part
def step(rhs, t, y, f, h_abs, min_step, t_end, m, z, p, rtol, atol, K, y_new, ys):
    """One accepted step from (t, y), f its derivative, trying h_abs and shrinking it
    (SciPy's control) until the error norm passes, ending at t_end at the latest:
    (accepted, t_new, h, h_next, evaluations). Not accepted: the step fell below
    min_step (a NaN included). K and y_new hold the step's stages and end."""
    rejected = False
    nfev = 0
    while True:
        if not h_abs >= min_step:  # (NaN included)
            return False, t, 0.0, h_abs, nfev
        t_new = min(t + h_abs, t_end)
        h = t_new - t
        _stages(rhs, t, y, f, h, m, z, p, K, y_new, ys)
        nfev += N_STAGES
        err = _error_norm(y, y_new, K, h, rtol, atol)
        if err < 1.0:
            factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err ** EXPONENT)
            if rejected:
                factor = min(1.0, factor)
            return True, t_new, h, abs(h) * factor, nfev
        # a NaN or an infinity in the stages (a fault) shrinks the step too
        factor = SAFETY * err ** EXPONENT if err == err and err < np.inf else MIN_FACTOR
        h_abs = abs(h) * max(MIN_FACTOR, factor)
        rejected = True
