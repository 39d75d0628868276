"""The compiled ceiling: the six shipped models written by hand as numba functions and
integrated by one DOP853 compiled by numba, with the switches located as events.

    OPENBLAS_NUM_THREADS=1 python benchmarks/ceiling.py          # compile time, ms, error
    python benchmarks/ceiling.py ex4_clutch --land   # steps ending on the output points

This is the best a user who writes everything compiled by hand gets, the "ceiling" of
the work-precision benchmark (`work_precision.py` adds its points as kind "ceiling",
route "numba", when numba is importable):

* each model's right-hand side, switching surfaces, branch changes and TIME-segment
  entry are `@njit` functions written by hand, the constants in a float array `p`
  (the same equations and branches as the hand-written `hybrids.py` / `cases.py`);
* one integrator, `_solve`, compiled by numba for each model (the model functions are
  passed to it as arguments and bound in a per-model entry, `_entry`): SciPy's
  DOP853 (`scipy/integrate/_ivp/rk.py` with `dop853_coefficients`: the same initial
  step, step-size control, error norm and 7th-degree dense output with its 3 extra
  stages, computed only for a step that has an output row or an event in it);
* events as `solve_ivp` does them: after every accepted step the branch's surfaces are
  evaluated; a sign change in the surface's direction is located on the dense output by
  Brent's method (SciPy's `brentq`, xtol = rtol = 4 eps), the first one switches the
  branch (or stops the run: the crank-slider's FINISH W = 10) and the integration
  restarts there with a new initial step; the TIME breakpoints of the piecewise-in-time
  inputs (the clutch instant) end a segment the same way;
* the rows at the case's output grid go into one preallocated array from the dense
  output; or, `land=True`, no step passes an output point and its row is the step's end
  (Fortran DOP853 called point by point does that). The Exercise 4 drives need it: the
  23 us electrical lag holds DOP853's steps on its stability boundary, above OUTDEL, and
  the dense output inside such a step misses the current by 20-60 times the error at
  the step's end (6e-2 against 3e-3 of its range at rtol 1e-3). `work_precision.py`
  measures both drivers and takes the faster for each level.

The first call of each model compiles; `prepare` measures it apart, the timed runs are
warm.
"""

from __future__ import annotations

import math
import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from numba import njit  # noqa: E402
from scipy.integrate._ivp import dop853_coefficients as _dc  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import ROOT, Case, error_on_grid  # noqa: E402

if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

# DOP853 tableau (frozen into the compiled code as constants)
NS = _dc.N_STAGES  # 12 stages; K[12] is f at the step's end (FSAL)
NSX = _dc.N_STAGES_EXTENDED  # 16: 3 more stages for the dense output
A = np.ascontiguousarray(_dc.A, dtype=np.float64)
B = np.ascontiguousarray(_dc.B, dtype=np.float64)
C = np.ascontiguousarray(_dc.C, dtype=np.float64)
E3 = np.ascontiguousarray(_dc.E3, dtype=np.float64)
E5 = np.ascontiguousarray(_dc.E5, dtype=np.float64)
D = np.ascontiguousarray(_dc.D, dtype=np.float64)
NPOW = _dc.INTERPOLATOR_POWER  # 7

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
ERROR_EXPONENT = -1.0 / 8.0  # error estimator of order 7
EPS4 = 4.0 * np.finfo(float).eps
TERMINAL = -100  # a jump to this branch stops the run
MAX_EVENTS = 1_000_000

FINISHED, STOPPED, TOO_SMALL, TOO_MANY = 0, 1, -1, -2
STATUS = {FINISHED: "finished", STOPPED: "finished", TOO_SMALL: "ERROR step too small",
          TOO_MANY: "ERROR too many events"}


# --------------------------------------------------------------------------- integrator

@njit(cache=False)
def _rms(v, scale):
    s = 0.0
    for i in range(v.shape[0]):
        s += (v[i] / scale[i]) ** 2
    return math.sqrt(s / v.shape[0])


@njit(cache=False)
def _dense(rhs, p, mode, seg, t_old, h, y_old, y_new, f_new, K, F, ytmp):
    """The 3 extra stages and the interpolant's coefficients F (rk.py _dense_output_impl)."""
    n = y_old.shape[0]
    for s in range(NS + 1, NSX):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += K[j, i] * A[s, j]
            ytmp[i] = y_old[i] + h * acc
        rhs(t_old + C[s] * h, ytmp, p, mode, seg, K[s])
    for i in range(n):
        dy = y_new[i] - y_old[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (f_new[i] + K[0, i])
        for k in range(4):
            acc = 0.0
            for j in range(NSX):
                acc += D[k, j] * K[j, i]
            F[3 + k, i] = h * acc


@njit(cache=False)
def _eval(t, t_old, h, y_old, F, out):
    """The dense output at t (rk.py Dop853DenseOutput._call_impl)."""
    x = (t - t_old) / h
    n = y_old.shape[0]
    for i in range(n):
        v = 0.0
        for q in range(NPOW):
            v += F[NPOW - 1 - q, i]
            if q % 2 == 0:
                v *= x
            else:
                v *= 1.0 - x
        out[i] = v + y_old[i]


@njit(cache=False)
def _g_at(surf, p, mode, seg, k, t, t_old, h, y_old, F, ytmp, g, d):
    _eval(t, t_old, h, y_old, F, ytmp)
    surf(t, ytmp, p, mode, seg, g, d)
    return g[k]


@njit(cache=False)
def _brentq(surf, p, mode, seg, k, xa, xb, t_old, h, y_old, F, ytmp, g, d):
    """Surface k's zero on the dense output: SciPy's brentq (xtol = rtol = 4 eps)."""
    xpre, xcur = xa, xb
    xblk, fblk, spre, scur = 0.0, 0.0, 0.0, 0.0
    fpre = _g_at(surf, p, mode, seg, k, xpre, t_old, h, y_old, F, ytmp, g, d)
    fcur = _g_at(surf, p, mode, seg, k, xcur, t_old, h, y_old, F, ytmp, g, d)
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    for _ in range(100):
        if fpre != 0.0 and fcur != 0.0 and ((fpre < 0.0) != (fcur < 0.0)):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (EPS4 + EPS4 * abs(xcur)) / 2.0
        sbis = (xblk - xcur) / 2.0
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(spre), 3.0 * abs(sbis) - delta):
                spre, scur = scur, stry
            else:
                spre, scur = sbis, sbis
        else:
            spre, scur = sbis, sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0.0 else -delta
        fcur = _g_at(surf, p, mode, seg, k, xcur, t_old, h, y_old, F, ytmp, g, d)
    return xcur


@njit(cache=False)
def _solve(rhs, surf, jump, at_segment, p, y0, mode0, breaks, grid, grid_eps, rtol, atol,
           rows, land):
    """DOP853 from grid[0] through the TIME segments ending at `breaks`, events located
    and branches switched; rows[i] = y(grid[i]). Returns (rows filled, nfev, nsteps,
    nevents, status). `land`: no step passes an output point (its row is the step's
    end, not the dense output), as Fortran DOP853 called point by point does."""
    n = y0.shape[0]
    ng = grid.shape[0]
    K = np.empty((NSX, n))
    F = np.empty((NPOW, n))
    y = y0.copy()
    y_new = np.empty(n)
    f = np.empty(n)
    ytmp = np.empty(n)
    scale = np.empty(n)
    g_old = np.empty(2)
    g_new = np.empty(2)
    d_old = np.empty(2)
    d_new = np.empty(2)
    gs = np.empty(2)
    ds = np.empty(2)
    t = grid[0]
    mode = mode0
    rows[0, :] = y
    filled = 1
    nfev = nsteps = nevents = 0
    h_abs = 0.0
    for seg in range(breaks.shape[0]):
        t_bound = breaks[seg]
        if seg > 0:
            mode = at_segment(y, p, mode, seg)
        restart = True
        while t < t_bound:
            if restart:  # a new solver: f, initial step (common.select_initial_step), g
                rhs(t, y, p, mode, seg, f)
                interval = abs(t_bound - t)
                for i in range(n):
                    scale[i] = atol + abs(y[i]) * rtol
                d0 = _rms(y, scale)
                d1 = _rms(f, scale)
                h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
                h0 = min(h0, interval)
                for i in range(n):
                    ytmp[i] = y[i] + h0 * f[i]
                rhs(t + h0, ytmp, p, mode, seg, K[1])
                d2 = 0.0
                for i in range(n):
                    d2 += ((K[1, i] - f[i]) / scale[i]) ** 2
                d2 = math.sqrt(d2 / n) / h0
                if d1 <= 1e-15 and d2 <= 1e-15:
                    h1 = max(1e-6, h0 * 1e-3)
                else:
                    h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
                h_abs = min(100.0 * h0, h1, interval)
                nfev += 2
                ns = surf(t, y, p, mode, seg, g_old, d_old)
                restart = False
            # one accepted step (rk.py _step_impl)
            min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
            if h_abs < min_step:
                h_abs = min_step
            rejected = False
            while True:
                if h_abs < min_step:
                    return filled, nfev, nsteps, nevents, TOO_SMALL
                t_new = t + h_abs
                t_stop = t_bound
                if land and filled < ng and grid[filled] < t_bound:
                    t_stop = grid[filled]  # the step ends on the next output point
                if t_new > t_stop:
                    t_new = t_stop
                h = t_new - t
                h_abs = abs(h)
                for i in range(n):
                    K[0, i] = f[i]
                for s in range(1, NS):
                    for i in range(n):
                        acc = 0.0
                        for j in range(s):
                            acc += K[j, i] * A[s, j]
                        ytmp[i] = y[i] + h * acc
                    rhs(t + C[s] * h, ytmp, p, mode, seg, K[s])
                for i in range(n):
                    acc = 0.0
                    for j in range(NS):
                        acc += K[j, i] * B[j]
                    y_new[i] = y[i] + h * acc
                rhs(t + h, y_new, p, mode, seg, K[NS])
                nfev += NS
                e5 = 0.0
                e3 = 0.0
                for i in range(n):
                    s5 = 0.0
                    s3 = 0.0
                    for j in range(NS + 1):
                        s5 += K[j, i] * E5[j]
                        s3 += K[j, i] * E3[j]
                    sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
                    e5 += (s5 / sc) ** 2
                    e3 += (s3 / sc) ** 2
                if e5 == 0.0 and e3 == 0.0:
                    err = 0.0
                else:
                    err = h_abs * e5 / math.sqrt((e5 + 0.01 * e3) * n)
                if err < 1.0:
                    if err == 0.0:
                        factor = MAX_FACTOR
                    else:
                        factor = min(MAX_FACTOR, SAFETY * err ** ERROR_EXPONENT)
                    if rejected:
                        factor = min(1.0, factor)
                    h_abs *= factor
                    break
                h_abs *= max(MIN_FACTOR, SAFETY * err ** ERROR_EXPONENT)
                rejected = True
            nsteps += 1
            # events (ivp.py find_active_events, handle_events): the first zero
            have_dense = False
            te = math.inf
            ke = -1
            ns = surf(t_new, y_new, p, mode, seg, g_new, d_new)
            for k in range(ns):
                up = g_old[k] <= 0.0 and g_new[k] >= 0.0
                down = g_old[k] >= 0.0 and g_new[k] <= 0.0
                dk = d_new[k]
                if (up and dk > 0.0) or (down and dk < 0.0) or ((up or down) and dk == 0.0):
                    if not have_dense:
                        _dense(rhs, p, mode, seg, t, h, y, y_new, K[NS], K, F, ytmp)
                        nfev += NSX - NS - 1
                        have_dense = True
                    r = _brentq(surf, p, mode, seg, k, t, t_new, t, h, y, F, ytmp, gs, ds)
                    if r < te:
                        te, ke = r, k
            # output rows up to the event, or the step's end (the segment's end: + eps)
            lim = te if ke >= 0 else (t_new + grid_eps if t_new == t_bound else t_new)
            while filled < ng and grid[filled] <= lim:
                if ke < 0 and grid[filled] == t_new:  # a step ending on the point
                    for i in range(n):
                        rows[filled, i] = y_new[i]
                    filled += 1
                    continue
                if not have_dense:
                    _dense(rhs, p, mode, seg, t, h, y, y_new, K[NS], K, F, ytmp)
                    nfev += NSX - NS - 1
                    have_dense = True
                _eval(grid[filled], t, h, y, F, rows[filled])
                filled += 1
            if ke >= 0:
                _eval(te, t, h, y, F, ytmp)
                for i in range(n):
                    y[i] = ytmp[i]
                t = te
                nevents += 1
                mode = jump(te, y, p, mode, seg, ke)
                if mode == TERMINAL:
                    return filled, nfev, nsteps, nevents, STOPPED
                if nevents >= MAX_EVENTS:
                    return filled, nfev, nsteps, nevents, TOO_MANY
                restart = True
            else:
                t = t_new
                for i in range(n):
                    y[i] = y_new[i]
                    f[i] = K[NS, i]
                for k in range(ns):
                    g_old[k] = g_new[k]
    return filled, nfev, nsteps, nevents, FINISHED


# --------------------------------------------------------------------------- the models
# Each model: rhs(t, y, p, mode, seg, dy); surf(t, y, p, mode, seg, g, d) -> number of
# surfaces of the branch (g their values, d their directions as solve_ivp's); jump(t, y,
# p, mode, seg, k) -> the new branch after surface k (y changed in place; TERMINAL stops);
# at_segment(y, p, mode, seg) -> the branch entering TIME segment seg.

STICK = 0  # Exercise 4: slip +1, slip -1, stick 0 (W1 = 0 held)

# two-mass drive: p = U, R, L, KT, KE, MF, J1, JOBC, MOBC, C, B, CLUTCH (1: open in seg 0)


@njit(cache=False)
def _ex4_sw(p, seg):
    return 0.0 if p[11] > 0.5 and seg == 0 else 1.0


@njit(cache=False)
def ex4_rhs(t, y, p, mode, seg, dy):
    ia, th, w1, w2 = y[0], y[1], y[2], y[3]
    sw = _ex4_sw(p, seg)
    moving = 0.0 if mode == STICK else 1.0
    mc = sw * (p[9] * th + p[10] * (w1 - w2))
    dy[0] = (p[0] - p[1] * ia - p[4] * w1) / p[2]
    dy[1] = sw * (w1 - w2)
    dy[2] = moving * (p[3] * ia - mc - mode * p[5]) / p[6]
    dy[3] = sw * (mc - p[8]) / p[7]


@njit(cache=False)
def _ex4_net(y, p, seg):
    return p[3] * y[0] - _ex4_sw(p, seg) * (p[9] * y[1] + p[10] * (y[2] - y[3]))


@njit(cache=False)
def ex4_surf(t, y, p, mode, seg, g, d):
    if mode == STICK:  # |MNET| = MF: breakaway
        net = _ex4_net(y, p, seg)
        g[0], d[0] = net - p[5], 1.0
        g[1], d[1] = net + p[5], -1.0
        return 2
    g[0], d[0] = y[2], -float(mode)  # W1 = 0 ends a slip
    return 1


@njit(cache=False)
def ex4_jump(t, y, p, mode, seg, k):
    if mode == STICK:
        return 1 if k == 0 else -1
    y[2] = 0.0
    m = _ex4_net(y, p, seg)
    return STICK if abs(m) <= p[5] else (1 if m > 0.0 else -1)


@njit(cache=False)
def ex4_at_segment(y, p, mode, seg):
    m = _ex4_net(y, p, seg)
    if mode == STICK and abs(m) > p[5]:
        return 1 if m > 0.0 else -1
    return mode


# torque-meter stand: p = U, R, L, KT, KE, MF, J1, J2, JOBC, MOBC, C, B, CT, BT;
# y = IA, TH12, TH23, TH34, W1, W2, W3, W4


@njit(cache=False)
def meter_rhs(t, y, p, mode, seg, dy):
    ia, th12, th23, th34, w1, w2, w3, w4 = y[0], y[1], y[2], y[3], y[4], y[5], y[6], y[7]
    moving = 0.0 if mode == STICK else 1.0
    m12 = p[10] * th12 + p[11] * (w1 - w2)
    m23 = p[12] * th23 + p[13] * (w2 - w3)
    m34 = p[10] * th34 + p[11] * (w3 - w4)
    dy[0] = (p[0] - p[1] * ia - p[4] * w1) / p[2]
    dy[1] = w1 - w2
    dy[2] = w2 - w3
    dy[3] = w3 - w4
    dy[4] = moving * (p[3] * ia - m12 - mode * p[5]) / p[6]
    dy[5] = (m12 - m23) / p[7]
    dy[6] = (m23 - m34) / p[7]
    dy[7] = (m34 - p[9]) / p[8]


@njit(cache=False)
def _meter_net(y, p):
    return p[3] * y[0] - (p[10] * y[1] + p[11] * (y[4] - y[5]))


@njit(cache=False)
def meter_surf(t, y, p, mode, seg, g, d):
    if mode == STICK:
        net = _meter_net(y, p)
        g[0], d[0] = net - p[5], 1.0
        g[1], d[1] = net + p[5], -1.0
        return 2
    g[0], d[0] = y[4], -float(mode)
    return 1


@njit(cache=False)
def meter_jump(t, y, p, mode, seg, k):
    if mode == STICK:
        return 1 if k == 0 else -1
    y[4] = 0.0
    m = _meter_net(y, p)
    return STICK if abs(m) <= p[5] else (1 if m > 0.0 else -1)


@njit(cache=False)
def keep_branch(y, p, mode, seg):
    return mode


# hoist with backlash: p = I1, I2, I3, C1, C2, D1, D2, E (half gap), MN, M0, W;
# y = X1, Y, V1, V2, V3, PH; branches gap 0, contact +1, contact -1


@njit(cache=False)
def hoist_rhs(t, s, p, mode, seg, dy):
    x1, y, v1, v2, v3, ph = s[0], s[1], s[2], s[3], s[4], s[5]
    yd = v2 - v3
    t2 = 0.0 if mode == 0 else p[4] * (y - mode * p[7]) + p[6] * yd
    m1 = p[3] * x1 + p[5] * (v1 - v2)
    dy[0] = v1 - v2
    dy[1] = yd
    dy[2] = (p[8] - m1) / p[0]
    dy[3] = (m1 - t2 + p[9] * math.sin(ph)) / p[1]
    dy[4] = (t2 - p[8]) / p[2]
    dy[5] = p[10]


@njit(cache=False)
def hoist_surf(t, s, p, mode, seg, g, d):
    e = p[7]
    if mode == 0:  # |Y| = DELTA/2: contact
        g[0], d[0] = s[1] - e, 1.0
        g[1], d[1] = s[1] + e, -1.0
        return 2
    g[0], d[0] = s[1] - mode * e, -float(mode)  # back into the gap
    return 1


@njit(cache=False)
def hoist_jump(t, s, p, mode, seg, k):
    new = (1 if k == 0 else -1) if mode == 0 else 0
    s[1] = (new if new != 0 else mode) * p[7]
    return new


# crank-slider: p = M, L, M1, K2, G, I0, SQRT2, W_FINISH; y = PHI, W


@njit(cache=False)
def crank_rhs(t, s, p, mode, seg, dy):
    phi, w = s[0], s[1]
    q = p[2] - p[3] * w - p[0] * p[4] * p[1] * p[6] * math.sin(phi + math.pi / 4.0)
    di = 3.0 * p[5] * math.sin(2.0 * phi)
    dy[0] = w
    dy[1] = (q - 0.5 * di * w * w) / (p[5] * (1.0 + 3.0 * math.sin(phi) ** 2))


@njit(cache=False)
def crank_surf(t, s, p, mode, seg, g, d):
    g[0], d[0] = s[1] - p[7], 1.0  # FINISH W = 10
    return 1


@njit(cache=False)
def stop_jump(t, s, p, mode, seg, k):
    return TERMINAL


# machine unit: p = I0, I1, A, B, C0, C1, K; y = PHI, W, AW (no switches)


@njit(cache=False)
def machine_rhs(t, s, p, mode, seg, dy):
    phi, w = s[0], s[1]
    sp = math.sin(phi)
    i = p[0] + p[1] * sp ** 2
    di = p[1] * math.sin(2.0 * phi)
    torque = (p[2] - p[3] * w) - (p[4] + p[5] * sp + p[6] * w)
    dy[0] = w
    dy[1] = (torque - 0.5 * di * w * w) / i
    dy[2] = w * w


@njit(cache=False)
def no_surfaces(t, s, p, mode, seg, g, d):
    return 0


# --------------------------------------------------------------------------- per case

def _ex4_params(kind: str) -> np.ndarray:
    from tests.references import ex4

    if kind == "meter":
        return np.array([ex4.U, ex4.R, ex4.L, ex4.KT, ex4.KE, ex4.MF, ex4.J_ROTOR,
                         ex4.J_METER_HALF, ex4.J_OBC, ex4.M_OBC, ex4.C_COUPLING,
                         ex4.B_COUPLING, ex4.C_METER, ex4.B_METER])
    return np.array([ex4.U, ex4.R, ex4.L, ex4.KT, ex4.KE, ex4.MF, ex4.J_ROTOR, ex4.J_OBC,
                     ex4.M_OBC, ex4.C_COUPLING, ex4.B_COUPLING,
                     1.0 if kind == "clutch" else 0.0])


def _hoist_params() -> np.ndarray:
    from tests.references import hoist

    h = hoist.Hoist()
    return np.array([h.i1, h.i2, h.i3, h.c1, h.c2, h.beta * h.c1, h.beta * h.c2, h.half_gap,
                     h.mn, h.m0, 70.0])


def _crank_params() -> np.ndarray:
    from tests.references import crank_slider as cs

    return np.array([cs.M, cs.L, cs.M1, cs.K2, cs.G, cs.I0, math.sqrt(2.0), 10.0])


def _machine_params() -> np.ndarray:
    from tests.references import machine_unit as mu

    return np.array([mu.I0, mu.I1, mu.A, mu.B, mu.C0, mu.C1, mu.K])


# case name: (rhs, surf, jump, at_segment, parameters, first branch)
MODELS = {
    "ex4_elastic": (ex4_rhs, ex4_surf, ex4_jump, ex4_at_segment,
                    lambda: _ex4_params("elastic"), STICK),
    "ex4_clutch": (ex4_rhs, ex4_surf, ex4_jump, ex4_at_segment,
                   lambda: _ex4_params("clutch"), STICK),
    "ex4_torque_meter": (meter_rhs, meter_surf, meter_jump, keep_branch,
                         lambda: _ex4_params("meter"), STICK),
    "hoist_backlash": (hoist_rhs, hoist_surf, hoist_jump, keep_branch, _hoist_params, 0),
    "crank_slider_startup": (crank_rhs, crank_surf, stop_jump, keep_branch, _crank_params, 0),
    "machine_unit": (machine_rhs, no_surfaces, stop_jump, keep_branch, _machine_params, 0),
}


_ENTRIES: dict = {}


def _entry(rhs, surf, jump, at_segment):
    """`_solve` compiled for one model: a numba function with the model's functions
    bound in (calling `_solve` with them as arguments costs 20 us more per call)."""
    key = (rhs, surf, jump, at_segment)
    if key not in _ENTRIES:
        @njit(cache=False)
        def entry(p, y0, mode0, breaks, grid, grid_eps, rtol, atol, rows, land):
            return _solve(rhs, surf, jump, at_segment, p, y0, mode0, breaks, grid, grid_eps,
                          rtol, atol, rows, land)
        _ENTRIES[key] = entry
    return _ENTRIES[key]


class Ceiling:
    """One case's compiled solver: `run(rtol, atol)` -> (t, {state: values}, nfev, nsteps,
    events, status)."""

    def __init__(self, case: Case):
        self.case = case
        self.solve = _entry(*MODELS[case.name][:4])
        self.p = MODELS[case.name][4]()
        self.mode0 = MODELS[case.name][5]
        self.y0 = np.array(case.y0, dtype=float)
        self.grid = case.grid()
        # the TIME segments' ends, as the hand-written routes split (cases.segments)
        self.breaks = np.array([tb for tb, _ in case.segments()], dtype=float)
        self.grid_eps = 1e-9 * case.outdel

    def run(self, rtol: float, atol: float, land: bool = False):
        rows = np.empty((len(self.grid), len(self.y0)))
        filled, nfev, nsteps, nev, status = self.solve(
            self.p, self.y0, self.mode0, self.breaks, self.grid, self.grid_eps,
            rtol, atol, rows, land)
        return (self.grid[:filled], {n: rows[:filled, i] for i, n in enumerate(self.case.states)},
                nfev, nsteps, nev, status)

    def measured(self, res) -> dict:
        t, vals, nfev, nsteps, nev, status = res
        return dict(nfev=nfev, nsteps=nsteps, events=nev, status=STATUS[status],
                    error=error_on_grid(self.case, t, vals))


def prepare(case: Case) -> tuple[Ceiling, float]:
    """The case's solver and its compile time (the first call, seconds)."""
    c = Ceiling(case)
    t0 = time.perf_counter()
    c.run(1e-3, 1e-3 * case.atol_factor())
    return c, time.perf_counter() - t0


def main(names=None, tols=None, repeats: int = 5, land: bool = False) -> list[dict]:
    import statistics

    from cases import all_cases

    cases = all_cases()
    out = []
    for name in names or list(MODELS):
        case = cases[name]
        case.ref()
        c, compile_s = prepare(case)
        fac = case.atol_factor()
        print(f"{name}: compile (first call) {compile_s:.2f} s")
        for rtol in tols or [10.0**-k for k in range(3, 13)]:
            times = []
            for _ in range(repeats):
                t0 = time.perf_counter()
                res = c.run(rtol, rtol * fac, land)
                times.append(time.perf_counter() - t0)
            m = c.measured(res)
            row = dict(case=name, rtol=rtol, time=statistics.median(times), compile=compile_s,
                       **m)
            out.append(row)
            print(f"  rtol {rtol:.0e}: {row['time'] * 1e3:8.3f} ms  nfev {m['nfev']:>8} "
                  f"steps {m['nsteps']:>7} events {m['events']:>5} error {m['error']:.2e} "
                  f"{m['status']}")
    return out


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", nargs="*", help=f"case names (default: {list(MODELS)})")
    ap.add_argument("--land", action="store_true",
                    help="end a step on every output point instead of the dense output")
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    main(a.models or None, repeats=a.repeats, land=a.land)
