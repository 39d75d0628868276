"""Extreme scales: FINTIM 1E-9 and 1E9, values near 1E+-300, overflow."""

import math

import numpy as np
import pytest

import amilpy
from stress import cases as C

ERR = {"AUTO": 2e-6, "RKS": 1e-6, "DOP853": 1e-6, "COMPILED": 1e-6, "LSODA": 1e-6,
       "RADAU": 1e-6, "BDF": 2e-6, "RK4": 1e-8, "EULER": 2e-4, "TRAPZ": 1e-7, "ADAMS": 1e-7}


@pytest.mark.parametrize("method", C.METHODS)
@pytest.mark.parametrize("text,scale", [
    ("PARAM A = 1.0E9\nX = INTGRL(1.0, -A*X)\nTIMER FINTIM = 1.0E-9\nPRINT X\nEND\n", 1.0),
    ("PARAM A = 1.0E-9\nX = INTGRL(1.0, -A*X)\nTIMER FINTIM = 1.0E9\nPRINT X\nEND\n", 1.0),
    ("X = INTGRL(1.0E300, -X)\nTIMER FINTIM = 1.0\nPRINT X\nEND\n", 1e300),
    # (RELERR 1E-6: RELERR*X must stay a normal float for LSODA's error weights, and
    # 1E-10 * 1E-300 is a subnormal one)
    ("RELERR 1.0E-6\nABSERR 1.0E-310\nX = INTGRL(1.0E-300, -X)\nTIMER FINTIM = 1.0\nPRINT X\n"
     "END\n", 1e-300),
], ids=["fintim1e-9", "fintim1e9", "x1e300", "x1e-300"])
def test_decay_at_extreme_scales(text, scale, method):
    r, = amilpy.loads(text).run(method=method)
    assert r.status == "finished", r.message
    assert len(r.t) == 101
    assert abs(r["X"][-1] / scale - math.exp(-1.0)) <= ERR[method]
    assert r.t[-1] == pytest.approx(r.t[1] * 100, rel=1e-12)


@pytest.mark.parametrize("method", C.METHODS)
def test_denormal_underflow_is_harmless(method):
    r, = amilpy.loads("X = INTGRL(1.0E-300, -X)\nTIMER FINTIM = 100.0\nEND\n").run(
        method=method)
    assert r.status == "finished" and abs(r["X"][-1]) < 1e-300


# Fixed: overflow inside SciPy's Radau/BDF Newton solve raised ValueError out of
# Model.run (a traceback from the CLI); DOP853 left NaN rows (its dense output
# overflows inside before the state does).
@pytest.mark.parametrize("method", C.METHODS)
def test_overflow_stops_with_message(method):
    r, = amilpy.loads("X = INTGRL(1.0E300, X)\nTIMER FINTIM = 20.0\nPRINT X\nEND\n").run(
        method=method)
    assert r.status == "failed" and "TIME =" in r.message
    assert 14.0 < r.t_end < 20.0
    assert len(r.times) > 50 and np.all(np.isfinite(r.values["X"]))


def test_no_nan_row_after_overflow():
    # RKS kept a NaN row when the state overflowed in one step
    r, = amilpy.loads("PARAM A = 1.0E308\nX = INTGRL(A, A)\nTIMER FINTIM = 1.0\nEND\n").run(
        method="RKS")
    assert r.status == "failed"
    assert np.all(np.isfinite(r.values["X"]))


def test_algebraic_overflow_is_shown_not_hidden():
    """An output (not a state) that overflows is printed as inf; the run finishes."""
    r, = amilpy.loads("X = INTGRL(1.0E300, 0.0)\nY = X*X\nTIMER FINTIM = 1.0\nEND\n").run()
    assert r.status == "finished" and math.isinf(r["Y"][-1])
