"""Benchmark cases: each model as an amilpy listing, a reference solution on its output
grid checked against a second method, and the same equations hand-written as plain Python
functions (floats only, no NumPy in the right-hand side) for the SciPy baselines.

References. The Exercise 4 drives and the hoist are affine between switches: their
reference is exact there (`exact.py`, the matrix exponential, switches located on the
exact solution) and is checked against the hybrid DOP853 integration of
``tests/references`` at rtol 1e-13. The crank-slider and the machine unit are
nonlinear and smooth: DOP853 at rtol 1e-13, checked against Radau at its tightest
(rtol 2.3e-13). `Case.agreement` is the largest difference of the two on the grid, in
the error metric below. The core models have closed forms.

Hand-written functions come two ways, as a user would write them:

* ``segments``: one function per TIME segment (split at the switches on TIME, the
  clutch instant), integrating straight through the switches on states, as an
  ``odeint`` user would;
* ``hybrid``: one function per branch of the switches on states, each switch a
  terminal event of ``solve_ivp`` followed by a restart in the new branch (stiction,
  backlash; the crank-slider's ``FINISH W = 10`` as a terminal event).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass, field

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

ATOL_SCALE = 1e-12  # floor of the per-state scale in the error metric

from hybrids import Hybrid, crank_hybrid, ex4_hybrid, hoist_hybrid  # noqa: E402


@dataclass
class Case:
    name: str
    shipped: bool
    text: str  # the listing
    states: list[str]  # listing names of the states, in the order of the hand-written y
    y0: list[float]
    # hand-written right-hand sides: [(t_end, f)], f(t, y) -> list; t_end of the last = end
    segments: Callable[[], list[tuple[float, Callable]]]
    reference: Callable[[np.ndarray], dict[str, np.ndarray]]
    outdel: float
    fintim: float
    state_switches: bool  # has switches on states (hand-written code integrates through)
    end_time: Callable[[], float] | None = None  # e.g. FINISH: the reference's stop time
    # a second reference, by another method (None: the reference is a closed form)
    check: Callable[[np.ndarray], dict[str, np.ndarray]] | None = None
    reference_method: str = "closed form"
    check_method: str = ""
    hybrid: Callable[[], Hybrid] | None = None  # branches and events (hand-written)
    _ref_cache: dict = field(default_factory=dict)

    def grid(self) -> np.ndarray:
        end = self.end_time() if self.end_time else self.fintim
        n = int(math.floor(end / self.outdel * (1 + 1e-12) + 1e-9))
        return self.outdel * np.arange(n + 1)

    def ref(self) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        if "ref" not in self._ref_cache:
            g = self.grid()
            self._ref_cache["ref"] = (g, self.reference(g))
        return self._ref_cache["ref"]

    def agreement(self) -> tuple[float, str]:
        """The largest difference of the two references on the grid, in the error
        metric (each state relative to its maximum), and the state where it is."""
        if self.check is None:
            return 0.0, ""
        if "agreement" not in self._ref_cache:
            g, ref = self.ref()
            other = self.check(g)
            scales = self.scales()
            diffs = {n: float(np.max(np.abs(other[n] - ref[n])) / (ATOL_SCALE + scales[n]))
                     for n in self.states}
            worst = max(diffs, key=diffs.get)
            self._ref_cache["agreement"] = (diffs[worst], worst)
        return self._ref_cache["agreement"]

    def scales(self) -> dict[str, float]:
        _, r = self.ref()
        return {n: float(np.max(np.abs(r[n]))) for n in self.states}

    def atol_factor(self) -> float:
        """atol = rtol * this: the smallest state scale (so atol never dominates rtol)."""
        return max(min(self.scales().values()), 1e-12)


def error_on_grid(case: Case, t: np.ndarray, values: dict[str, np.ndarray]) -> float:
    """max over the OUTDEL grid and the states of |y - y_ref| / (ATOL_SCALE + max|y_ref|).

    ``t``: the instants of ``values``; only those matching the reference grid count.
    """
    g, ref = case.ref()
    t = np.asarray(t, dtype=float)
    idx = np.searchsorted(t, g - 1e-9 * case.outdel)
    idx = np.clip(idx, 0, len(t) - 1)
    ok = np.abs(t[idx] - g) <= 1e-7 * case.outdel
    if not np.any(ok):
        return math.inf
    if np.count_nonzero(ok) < 0.9 * len(g):
        return math.inf  # the run stopped early
    scales = case.scales()
    err = 0.0
    for n in case.states:
        y = np.asarray(values[n], dtype=float)[idx[ok]]
        e = np.max(np.abs(y - ref[n][ok])) / (ATOL_SCALE + scales[n])
        if not np.isfinite(e):
            return math.inf
        err = max(err, float(e))
    return err


def with_delt(text: str, delt: float) -> str:
    """The listing with DELT = delt added to its (first) TIMER statement."""
    out = []
    done = False
    for line in text.splitlines():
        if not done and line.strip().upper().startswith("TIMER"):
            line = f"{line.rstrip()}, DELT = {delt!r}"
            done = True
        out.append(line)
    assert done, "no TIMER statement"
    return "\n".join(out) + "\n"


def _read(name: str) -> str:
    with open(os.path.join(ROOT, "models", f"{name}.amil"), encoding="utf-8") as fh:
        return fh.read()


# ----------------------------------------------------------------- Exercise 4 (three models)


# The friction FSW is written out in each right-hand side below, as a hand-written
# one would be: a helper call makes it 13% slower (0.16 -> 0.18 us, measured) and
# would flatter amilpy in the ratios.


def _ex4_elastic_segments():
    from tests.references import ex4

    U, R, L, KT, KE, MF = ex4.U, ex4.R, ex4.L, ex4.KT, ex4.KE, ex4.MF
    J1, JOBC, MOBC, C, B = ex4.J_ROTOR, ex4.J_OBC, ex4.M_OBC, ex4.C_COUPLING, ex4.B_COUPLING

    def f(t, y):
        ia, th, w1, w2 = y
        mc = C * th + B * (w1 - w2)
        mnet = KT * ia - mc
        if w1 > 0.0:
            mfr = MF
        elif w1 < 0.0:
            mfr = -MF
        else:
            mfr = MF if mnet > MF else (-MF if mnet < -MF else mnet)
        return [(U - R * ia - KE * w1) / L, w1 - w2, (mnet - mfr) / J1, (mc - MOBC) / JOBC]

    return [(0.5, f)]


def _ex4_clutch_segments():
    from tests.references import ex4

    U, R, L, KT, KE, MF = ex4.U, ex4.R, ex4.L, ex4.KT, ex4.KE, ex4.MF
    J1, JOBC, MOBC, C, B = ex4.J_ROTOR, ex4.J_OBC, ex4.M_OBC, ex4.C_COUPLING, ex4.B_COUPLING

    def f_open(t, y):
        ia, th, w1, w2 = y
        mnet = KT * ia
        if w1 > 0.0:
            mfr = MF
        elif w1 < 0.0:
            mfr = -MF
        else:
            mfr = MF if mnet > MF else (-MF if mnet < -MF else mnet)
        return [(U - R * ia - KE * w1) / L, 0.0, (mnet - mfr) / J1, 0.0]

    def f_engaged(t, y):
        ia, th, w1, w2 = y
        mc = C * th + B * (w1 - w2)
        mnet = KT * ia - mc
        if w1 > 0.0:
            mfr = MF
        elif w1 < 0.0:
            mfr = -MF
        else:
            mfr = MF if mnet > MF else (-MF if mnet < -MF else mnet)
        return [(U - R * ia - KE * w1) / L, w1 - w2, (mnet - mfr) / J1, (mc - MOBC) / JOBC]

    return [(ex4.clutch_time(), f_open), (0.5, f_engaged)]


def _ex4_meter_segments():
    from tests.references import ex4

    U, R, L, KT, KE, MF = ex4.U, ex4.R, ex4.L, ex4.KT, ex4.KE, ex4.MF
    J1, J2, J4, MOBC = ex4.J_ROTOR, ex4.J_METER_HALF, ex4.J_OBC, ex4.M_OBC
    C12, B12, CT, BT = ex4.C_COUPLING, ex4.B_COUPLING, ex4.C_METER, ex4.B_METER

    def f(t, y):
        ia, th12, th23, th34, w1, w2, w3, w4 = y
        m12 = C12 * th12 + B12 * (w1 - w2)
        m23 = CT * th23 + BT * (w2 - w3)
        m34 = C12 * th34 + B12 * (w3 - w4)
        mnet = KT * ia - m12
        if w1 > 0.0:
            mfr = MF
        elif w1 < 0.0:
            mfr = -MF
        else:
            mfr = MF if mnet > MF else (-MF if mnet < -MF else mnet)
        return [(U - R * ia - KE * w1) / L, w1 - w2, w2 - w3, w3 - w4,
                (mnet - mfr) / J1, (m12 - m23) / J2, (m23 - m34) / J2, (m34 - MOBC) / J4]

    return [(2.5, f)]


def _ex4_names(chain) -> list[str]:
    n = chain.n
    return ["IA"] + [f"W{k + 1}" for k in range(n)] + [f"TH{k + 1}" for k in range(n - 1)]


def _ex4_reference(chain_name: str, t_end: float, rename: dict[str, str]):
    """Exact between switches (exact.py)."""
    def ref(grid):
        import exact

        from tests.references import ex4

        chain = getattr(ex4, chain_name)()
        y = exact.ex4_exact(chain, grid)
        return {rename.get(k, k): y[:, i] for i, k in enumerate(_ex4_names(chain))}

    return ref


def _ex4_check(chain_name: str, t_end: float, rename: dict[str, str]):
    """The hybrid DOP853 integration of tests/references at rtol 1e-13."""
    def ref(grid):
        from tests.references import ex4

        chain = getattr(ex4, chain_name)()
        tr = ex4.simulate(chain, t_end, rtol=1e-13, atol=1e-20)
        s = tr.sample(grid)
        return {rename.get(k, k): v for k, v in s.items()}

    return ref


# ----------------------------------------------------------------- hoist with backlash


def _hoist_segments():
    from tests.references import hoist

    h = hoist.Hoist()
    i1, i2, i3, c1, c2 = h.i1, h.i2, h.i3, h.c1, h.c2
    d1, d2, e = h.beta * h.c1, h.beta * h.c2, h.half_gap
    mn, m0, w = h.mn, h.m0, 70.0
    sin = math.sin

    def f(t, s):
        x1, y, v1, v2, v3, ph = s
        yd = v2 - v3
        if y > e:
            t2 = c2 * (y - e) + d2 * yd
        elif y < -e:
            t2 = c2 * (y + e) + d2 * yd
        else:
            t2 = 0.0
        m1 = c1 * x1 + d1 * (v1 - v2)
        return [v1 - v2, yd, (mn - m1) / i1, (m1 - t2 + m0 * sin(ph)) / i2, (t2 - mn) / i3, w]

    return [(5.0, f)]


def _hoist_reference(grid):
    """Exact between contact edges (exact.py)."""
    import exact

    from tests.references import hoist

    y = exact.hoist_exact(hoist.Hoist(), 70.0, grid)
    return dict(zip(["X1", "Y", "V1", "V2", "V3", "PH"], y.T, strict=True))


def _hoist_check(grid):
    """The hybrid DOP853 integration of tests/references at rtol 1e-13."""
    from tests.references import hoist

    r = hoist.simulate(hoist.Hoist(), 70.0, (0.0, 5.0), t_eval=grid, rtol=1e-13, atol=1e-15)
    return dict(zip(["X1", "Y", "V1", "V2", "V3", "PH"], r.y, strict=True))


# ----------------------------------------------------------------- crank-slider, machine unit


def _crank_segments():
    from tests.references import crank_slider

    # without events a user integrates to FINTIM and keeps the rows before W = 10
    return [(3.0, crank_slider.rhs)]  # already a plain float function


_SMOOTH: dict[str, object] = {}


def _smooth(name: str, method: str = "DOP853"):
    """A smooth reference solution: DOP853 at rtol 1e-13, or Radau at its tightest."""
    key = f"{name}/{method}"
    if key not in _SMOOTH:
        from scipy.integrate import solve_ivp

        from tests.references import crank_slider, machine_unit

        rtol = 1e-13 if method == "DOP853" else 2.3e-13  # Radau's floor is 1000 eps
        if name == "crank":
            def finish(t, s):
                return s[1] - 10.0
            finish.terminal, finish.direction = True, 1.0
            _SMOOTH[key] = solve_ivp(crank_slider.rhs, (0.0, 3.0), [0.0, 0.0], method=method,
                                     rtol=rtol, atol=1e-14, events=[finish],
                                     dense_output=True)
        else:
            _SMOOTH[key] = solve_ivp(machine_unit.rhs, (0.0, 10.0), [0.0] * 3, method=method,
                                     rtol=rtol, atol=1e-14, dense_output=True)
    return _SMOOTH[key]


def _crank_end() -> float:
    return float(_smooth("crank").t[-1])  # W = 10 reached (the listing's FINISH)


def _crank_reference(grid, method="DOP853"):
    y = _smooth("crank", method).sol(grid)
    return {"PHI": y[0], "W": y[1]}


def _machine_segments():
    from tests.references import machine_unit

    return [(10.0, machine_unit.rhs)]  # already a plain float function


def _machine_reference(grid, method="DOP853"):
    y = _smooth("machine", method).sol(grid)
    return {"PHI": y[0], "W": y[1], "AW": y[2]}


# ----------------------------------------------------------------- core test models

DECAY = """TITLE EXPONENTIAL DECAY
PARAM K = 2.0
INCON X0 = 1.0
DYNAMIC
   X = INTGRL(X0, -K*X)
TIMER FINTIM = 2.0, OUTDEL = 0.01
END
"""

OSC_W = 2.0 * math.pi
OSC = f"""TITLE UNDAMPED OSCILLATOR
PARAM W = {OSC_W!r}
INCON X0 = 1.0
DYNAMIC
   X = INTGRL(X0, V)
   V = INTGRL(0.0, -W**2*X)
TIMER FINTIM = 20.0, OUTDEL = 0.01
END
"""

GAP_D, GAP_A0 = 0.5, 1.0
GAP_W = (2 * math.pi + 4 * GAP_D / GAP_A0) / 1.5  # period exactly 1.5
GAP = f"""TITLE MASS BETWEEN TWO SPRINGS WITH A GAP
PARAM M = 1.0, K = {GAP_W**2!r}, D = 0.5
INCON X0 = 1.5
DYNAMIC
   X = INTGRL(X0, V)
   V = INTGRL(0.0, -K*DEADSP(-D, D, X)/M)
TIMER FINTIM = 12.0, OUTDEL = 0.01
END
"""

SW_T1, SW_K1, SW_XE, SW_K2 = 0.3711, 2.0, 1.0, 3.0
FSWT = """TITLE FIRST-ORDER LAG, SWITCHED TO DECAY AT T1
PARAM T1 = 0.3711, K1 = 2.0, XE = 1.0, K2 = 3.0
DYNAMIC
   RATE = FSW(TIME - T1, K1*(XE - X), 0.0, -K2*X)
   X    = INTGRL(0.0, RATE)
TIMER FINTIM = 2.0, OUTDEL = 0.01
END
"""


def _gap_exact(grid):
    w, d, a0 = GAP_W, GAP_D, GAP_A0
    t1 = math.pi / (2 * w)
    fl = 2 * d / (a0 * w)
    t2 = t1 + fl
    t3 = t2 + math.pi / w
    t4 = t3 + fl
    period = t4 + math.pi / (2 * w)
    s = np.mod(grid, period)
    x = np.empty_like(s)
    v = np.empty_like(s)
    for k, si in enumerate(s):
        if si <= t1:
            x[k], v[k] = d + a0 * math.cos(w * si), -a0 * w * math.sin(w * si)
        elif si <= t2:
            x[k], v[k] = d - a0 * w * (si - t1), -a0 * w
        elif si <= t3:
            x[k], v[k] = -d - a0 * math.sin(w * (si - t2)), -a0 * w * math.cos(w * (si - t2))
        elif si <= t4:
            x[k], v[k] = -d + a0 * w * (si - t3), a0 * w
        else:
            x[k], v[k] = d + a0 * math.sin(w * (si - t4)), a0 * w * math.cos(w * (si - t4))
    return {"X": x, "V": v}


def _gap_segments():
    k, d = GAP_W**2, GAP_D

    def f(t, y):
        x, v = y
        if x > d:
            dz = x - d
        elif x < -d:
            dz = x + d
        else:
            dz = 0.0
        return [v, -k * dz]

    return [(12.0, f)]


def _gap_hybrid() -> Hybrid:
    """The dead zone's three branches, |X| = D ending each."""
    k, d = GAP_W**2, GAP_D

    def field(mode, seg):
        off = mode * d
        if mode == 0:
            return lambda t, y: [y[1], 0.0]
        return lambda t, y: [y[1], -k * (y[0] - off)]

    def events(mode):
        if mode == 0:
            return [(lambda t, y: y[0] - d, 1.0), (lambda t, y: y[0] + d, -1.0)]
        return [(lambda t, y, off=mode * d: y[0] - off, -float(mode))]

    def jump(mode, j, t, y):
        new = (1 if j == 0 else -1) if mode == 0 else 0
        return new, y

    return Hybrid(1, field, events, jump)


def _fswt_segments():
    k1, xe, k2 = SW_K1, SW_XE, SW_K2

    def f1(t, y):
        return [k1 * (xe - y[0])]

    def f2(t, y):
        return [-k2 * y[0]]

    return [(SW_T1, f1), (2.0, f2)]


def _fswt_reference(grid):
    x1 = SW_XE * (1 - math.exp(-SW_K1 * SW_T1))
    return {"X": np.where(grid <= SW_T1, SW_XE * (1 - np.exp(-SW_K1 * grid)),
                          x1 * np.exp(-SW_K2 * (grid - SW_T1)))}


def _decay_segments():
    def f(t, y):
        return [-2.0 * y[0]]

    return [(2.0, f)]


def _osc_segments():
    w2 = OSC_W**2

    def f(t, y):
        x, v = y
        return [v, -w2 * x]

    return [(20.0, f)]


def all_cases() -> dict[str, Case]:
    exact = "exact between switches (matrix exponential)"
    dop = "hybrid DOP853, rtol 1e-13"
    ex4_ref = dict(reference_method=exact, check_method=dop)
    smooth = dict(reference_method="DOP853, rtol 1e-13", check_method="Radau, rtol 2.3e-13")
    meter = {"TH1": "TH12", "TH2": "TH23", "TH3": "TH34"}
    cases = [
        Case("ex4_elastic", True, _read("ex4_elastic"), ["IA", "TH", "W1", "W2"],
             [0.0] * 4, _ex4_elastic_segments,
             _ex4_reference("elastic_chain", 0.5, {"TH1": "TH"}), 5e-5, 0.5, True,
             check=_ex4_check("elastic_chain", 0.5, {"TH1": "TH"}),
             hybrid=ex4_hybrid("elastic"), **ex4_ref),
        Case("ex4_clutch", True, _read("ex4_clutch"), ["IA", "TH", "W1", "W2"],
             [0.0] * 4, _ex4_clutch_segments,
             _ex4_reference("clutch_chain", 0.5, {"TH1": "TH"}), 5e-5, 0.5, True,
             check=_ex4_check("clutch_chain", 0.5, {"TH1": "TH"}),
             hybrid=ex4_hybrid("clutch"), **ex4_ref),
        Case("ex4_torque_meter", True, _read("ex4_torque_meter"),
             ["IA", "TH12", "TH23", "TH34", "W1", "W2", "W3", "W4"], [0.0] * 8,
             _ex4_meter_segments, _ex4_reference("meter_chain", 2.5, meter), 2.5e-4, 2.5, True,
             check=_ex4_check("meter_chain", 2.5, meter), hybrid=ex4_hybrid("meter"),
             **ex4_ref),
        Case("hoist_backlash", True, _read("hoist_backlash"),
             ["X1", "Y", "V1", "V2", "V3", "PH"], [0.0] * 6, _hoist_segments,
             _hoist_reference, 1e-3, 5.0, True, check=_hoist_check, hybrid=hoist_hybrid,
             **ex4_ref),
        Case("crank_slider_startup", True, _read("crank_slider_startup"), ["PHI", "W"],
             [0.0, 0.0], _crank_segments, _crank_reference, 1e-3, 3.0, False,
             end_time=_crank_end, check=lambda g: _crank_reference(g, "Radau"),
             hybrid=crank_hybrid, **smooth),
        Case("machine_unit", True, _read("machine_unit"), ["PHI", "W", "AW"], [0.0] * 3,
             _machine_segments, _machine_reference, 1e-3, 10.0, False,
             check=lambda g: _machine_reference(g, "Radau"), **smooth),
        Case("exp_decay", False, DECAY, ["X"], [1.0], _decay_segments,
             lambda g: {"X": np.exp(-2.0 * g)}, 0.01, 2.0, False),
        Case("oscillator", False, OSC, ["X", "V"], [1.0, 0.0], _osc_segments,
             lambda g: {"X": np.cos(OSC_W * g), "V": -OSC_W * np.sin(OSC_W * g)},
             0.01, 20.0, False),
        Case("deadzone_osc", False, GAP, ["X", "V"], [1.5, 0.0], _gap_segments, _gap_exact,
             0.01, 12.0, True, hybrid=_gap_hybrid),
        Case("fsw_on_time", False, FSWT, ["X"], [0.0], _fswt_segments, _fswt_reference,
             0.01, 2.0, False),
    ]
    return {c.name: c for c in cases}
