#!/usr/bin/env python
"""The long stress runs of issue 5, by hand:

    OPENBLAS_NUM_THREADS=1 python benchmarks/stress.py [--quick] [--only NAME]

Prints one table: case, method, wall time, steps, events, status and the
error or drift against the closed form / exact solution. The CI-sized versions
are tests/stress/.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                "tests"))
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from stress import cases as C  # noqa: E402

import amilpy  # noqa: E402

ROWS: list[tuple] = []


def row(case, method, r, seconds, measure):
    ROWS.append((case, method, seconds, r.stats.get("nsteps", 0), len(r.events), str(r.status),
                 measure, r.message if not r.ok else ""))
    c, m, s, n, e, st, meas, msg = ROWS[-1]
    print(f"{c:28s} {m:7s} {s:8.2f} {n:9d} {e:7d} {st:8s} {meas:>14s}  {msg[:90]}",
          flush=True)


def _two_mass_run(model, k: float, method: str, quick: bool, **tolerances):
    """One run of the two-mass drive: the run, its seconds, and its error in
    tolerance units against the matrix exponential ("-" if it did not finish)."""
    t0 = time.perf_counter()
    r, = model.run(method=method, K=k, max_steps=200_000 if quick else 5_000_000,
                   max_time=120, **tolerances)
    dt = time.perf_counter() - t0
    meas = "-"
    if r.ok:
        err = C.scaled_error(r, C.two_mass_reference(k, r.t), r.rtol, r.atol)
        meas = f"{err:.3g} tol"
    return r, dt, meas


def stiffness(quick):
    model = amilpy.loads(C.TWO_MASS.format(fintim="1.0", outdel="0.01"))
    for k in [1e0, 1e2, 1e4, 1e6, 1e8]:
        for method in C.METHODS:
            r, dt, meas = _two_mass_run(model, k, method, quick)
            row(f"stiff K={k:.0e} (ratio {C.stiffness_ratio(k):.0e})", method, r, dt, meas)


def tolerance_ladder(quick):
    """The stiffness sweep again at RELERR 1E-3 ... 1E-9 (ABSERR = RELERR/1000): where
    the error per step that the variable-step methods control adds up to more than
    10 tolerance units."""
    model = amilpy.loads(C.TWO_MASS.format(fintim="1.0", outdel="0.01"))
    ks = [1e0, 1e2, 1e4, 1e6] if quick else [1e0, 1e1, 3e1, 1e2, 3e2, 1e3, 1e4, 1e6, 1e8]
    for k in ks:
        for method in C.VARIABLE:
            for rtol in [1e-3, 1e-6, 1e-9] if quick else [10.0 ** -e for e in range(3, 10)]:
                r, dt, meas = _two_mass_run(model, k, method, quick, rtol=rtol,
                                            atol=rtol * 1e-3)
                row(f"K={k:.0e} RELERR={rtol:.0e}", method, r, dt, meas)


def backlash(quick):
    fintim = 20.0 if quick else 200.0
    model = amilpy.loads(C.DEAD_ZONE.format(fintim=fintim))
    for gap in [1e-9, 1e-6, 1e-3, 1e-1, 1.0]:
        for method in C.METHODS:
            t0 = time.perf_counter()
            r, = model.run(method=method, GAP=gap)
            dt = time.perf_counter() - t0
            first = r.events[0].surface if r.events else None
            same = [e.time for e in r.events if e.surface == first and e.old > 0 > e.new]
            per = np.diff(same)
            err = np.max(np.abs(per / C.dead_zone_period(gap) - 1)) if len(per) else math.nan
            n_exp = len(C.dead_zone_events(gap, fintim))
            row(f"backlash gap={gap:.0e}", method, r, dt,
                f"T {err:.1e} ev{len(r.events)}/{n_exp}")


def chatter(quick):
    model = amilpy.loads(C.STICK_SLIP.format(fintim="40.0" if quick else "200.0"))
    for method in C.METHODS:
        t0 = time.perf_counter()
        r, = model.run(method=method)
        dt = time.perf_counter() - t0
        x, _, _, _ = C.stick_slip_exact(r.t)
        row("stick-slip", method, r, dt, f"x {np.max(np.abs(r['X'] - x)):.1e}")
    for name, text in [("relay/integrator", C.RELAY_INTEGRATOR),
                       ("relay/sliding line", C.RELAY_SLIDING), ("relay/lag (Zeno)", C.RELAY_LAG)]:
        model = amilpy.loads(text)
        for method in C.METHODS:
            t0 = time.perf_counter()
            r, = model.run(method=method, max_time=120,
                           max_events=20_000 if quick else None)
            dt = time.perf_counter() - t0
            row(name, method, r, dt, f"X {r['X'][-1]:.1e}")


def blow_up(quick):
    model = amilpy.loads(C.BLOW_UP)
    for method in C.METHODS:
        t0 = time.perf_counter()
        r, = model.run(method=method)
        dt = time.perf_counter() - t0
        row("blow-up X'=X^2", method, r, dt, f"stop {r.t_end:.6f}")


def long_horizon(quick):
    periods = 1000 if quick else 10_000
    model = amilpy.loads(C.OSCILLATOR.format(periods=f"{periods}.0"))
    for method in C.METHODS:
        t0 = time.perf_counter()
        r, = model.run(method=method, max_time=600)
        dt = time.perf_counter() - t0
        row(f"oscillator {periods} periods", method, r, dt,
            f"drift {C.amplitude_drift(r):.2e}")


def extremes(quick):
    for name, text, scale in [
        ("FINTIM 1E-9", "PARAM A = 1.0E9\nX = INTGRL(1.0, -A*X)\nTIMER FINTIM = 1.0E-9\nEND\n",
         1.0),
        ("FINTIM 1E9", "PARAM A = 1.0E-9\nX = INTGRL(1.0, -A*X)\nTIMER FINTIM = 1.0E9\nEND\n",
         1.0),
        ("X ~ 1E300", "X = INTGRL(1.0E300, -X)\nTIMER FINTIM = 1.0\nEND\n", 1e300),
        ("X ~ 1E-300", "ABSERR 1.0E-310\nX = INTGRL(1.0E-300, -X)\nTIMER FINTIM = 1.0\nEND\n",
         1e-300),
        ("overflow 1E300*e^t", "X = INTGRL(1.0E300, X)\nTIMER FINTIM = 20.0\nEND\n", None),
    ]:
        model = amilpy.loads(text)
        for method in C.METHODS:
            t0 = time.perf_counter()
            try:
                r, = model.run(method=method)
            except Exception as exc:  # noqa: BLE001 - a core bug; shown in the table
                print(f"{name:28s} {method:7s} CRASH {type(exc).__name__}: {exc}")
                ROWS.append((name, method, 0, 0, 0, "CRASH", type(exc).__name__, str(exc)))
                continue
            dt = time.perf_counter() - t0
            meas = "-" if scale is None else f"err {abs(r['X'][-1] / scale - math.exp(-1)):.1e}"
            row(name, method, r, dt, meas)


GROUPS = {"stiffness": stiffness, "ladder": tolerance_ladder, "backlash": backlash,
          "chatter": chatter, "blowup": blow_up, "long": long_horizon, "extremes": extremes}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="amilpy stress runs")
    ap.add_argument("--quick", action="store_true", help="shorter runs (minutes, not tens)")
    ap.add_argument("--only", choices=sorted(GROUPS), action="append")
    a = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    print(f"{'case':28s} {'method':7s} {'seconds':>8s} {'steps':>9s} {'events':>7s} "
          f"{'status':8s} {'error/drift':>14s}  message")
    started = time.perf_counter()
    for name in a.only or list(GROUPS):
        GROUPS[name](a.quick)
    print(f"{len(ROWS)} runs in {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
