"""RANGE: each variable's minimum and maximum, with their times, located between
the output instants on the integrator's dense output, so they are right whatever
OUTDEL is (issue 13 item 1)."""

import math
import os

import numpy as np
import pytest
from conftest import METHODS, ROOT, run1

import amilpy
from amilpy.routes import route_for

W, Z = 2.0, 0.1  # X'' + 2 Z W X' + W^2 X = 0, X(0) = 1, X'(0) = 0
DAMPED = f"""PARAM W = {W}, Z = {Z}
X = INTGRL(1.0, V)
V = INTGRL(0.0, -2.0*Z*W*V - W*W*X)
TIMER FINTIM = 10.0, OUTDEL = 0.37
RANGE X, V
END
"""
WD = W * math.sqrt(1.0 - Z * Z)
T_MIN = math.pi / WD  # the first (and lowest) minimum, where V = 0
X_MIN = -math.exp(-Z * W * T_MIN)


@pytest.mark.parametrize("method", METHODS)
def test_damped_oscillator_first_minimum_with_a_coarse_outdel(method):
    # OUTDEL = 0.37 puts no row near T_MIN = 1.5787: the rows' minimum is -0.7149,
    # the true one -0.72925
    r = run1(DAMPED, method=method, advice=False)
    lo, t_lo, hi, t_hi = r.range["X"]
    rows = float(np.min(r["X"]))
    assert (hi, t_hi) == (1.0, 0.0)  # the start, where X turns down at once
    if route_for(method).uses_tolerances or method == "RK4":
        assert rows > X_MIN + 0.01
        # RELERR 1E-6 (RK4: DELT = OUTDEL/16 gives 1E-7): 1E-5 relative is ten
        # tolerance units; the time of an extremum is a square root less sharp
        # than its value, but the turn of the rate is solved directly
        assert lo == pytest.approx(X_MIN, rel=1e-5)
        assert t_lo == pytest.approx(T_MIN, rel=1e-5)
    else:
        # a low-order method's own trajectory has its own minimum: located between
        # the rows, it is below them, within the output interval around the lowest
        i = int(np.argmin(r["X"]))
        assert lo <= rows and r.t[i - 1] < t_lo < r.t[i + 1]


def test_range_only_locates_what_the_rows_cannot_show():
    # a fine OUTDEL: the parabola through the rows is already within 1E-9, so the
    # vertex is taken (no integration again); the minimum still to RELERR
    r = run1(DAMPED.replace("OUTDEL = 0.37", "OUTDEL = 0.001"), advice=False)
    lo, t_lo, _, _ = r.range["X"]
    assert lo == pytest.approx(X_MIN, rel=1e-5) and t_lo == pytest.approx(T_MIN, rel=1e-4)


def test_clutch_peaks_are_the_located_ones():
    # issue 13: RANGE said W1 min -142.29 and MC max 0.2681 off the OUTDEL grid; the
    # located values are -147.92 and 0.2717 (docs/models.md says about -148)
    model = amilpy.load(os.path.join(ROOT, "models", "ex4_clutch.amil"))
    run, = model.run(advice=False)
    assert run.range["W1"][0] == pytest.approx(-147.92, abs=0.01)
    assert run.range["MC"][2] == pytest.approx(0.2717, abs=1e-4)


BOUNCES_ON_ROWS = """PROGRAM ball whose impacts fall on output instants
  CONSTANT G = 9.81, E = 0.5, H0 = 4.905
  CINTERVAL CINT = 0.5
  DERIVATIVE
    V = INTEG(-G, 0.0)
    H = INTEG(V, H0)
    SCHEDULE BOUNCE .XN. H
    TERMT(T >= 2.1)
  END
  DISCRETE BOUNCE
    V = -E*V
  END
  RANGE V
END
"""


@pytest.mark.parametrize("method", ["AUTO", "BDF", "LSODA", "RKS"])
def test_range_across_impacts_on_the_rows(method):
    """H = H0 - G t^2/2 reaches 0 at t = 1, a row; V jumps from -9.81 to 4.905 there,
    and again at 2 (-4.905 to 2.4525). RANGE's search over a span of a few ulps
    between the row and the located impact divided by a rate step rounded to 0: a
    ZeroDivisionError traceback (hunt 53). V's minimum -9.81 and maximum 4.905, both
    at 1, to 1e-8."""
    run, = amilpy.loads(BOUNCES_ON_ROWS, "ball.csl").run(method=method, advice=False)
    lo, t_lo, hi, t_hi = run.range["V"]
    assert lo == pytest.approx(-9.81, abs=1e-8) and hi == pytest.approx(4.905, abs=1e-8)
    assert t_lo == pytest.approx(1.0, abs=1e-8) and t_hi == pytest.approx(1.0, abs=1e-8)


DOSES = """PROGRAM bolus doses at 0, 2, 4, 6
  CONSTANT KE = 0.3, DOSE = 1.0, TAU = 2.0
  CINTERVAL CINT = 5.0
  INITIAL
    SCHEDULE DOSING .AT. 0.0
  END
  DERIVATIVE
    A = INTEG(-KE*A, 0.0)
    TERMT(T >= 7.0)
  END
  DISCRETE DOSING
    A = A + DOSE
    SCHEDULE DOSING .AT. T + TAU
  END
  RANGE A
END
"""


@pytest.mark.parametrize("method", ["AUTO", "DOP853", "RKS", "BDF"])
def test_range_holds_the_peak_a_dose_between_rows_makes(method):
    """Doses at 0, 2, 4, 6 between rows 5 apart: the peak is right after the last,
    A(6+) = sum of exp(-0.3 (6 - 2k)), k = 0..3 = 2.015305, and the trough right
    before the first repeat, A(2-) = exp(-0.6) (the state before the dose at 0 is no
    part of the run: its first row is after it). RANGE read the first step's end
    after each dose (DOP853: 1.998707 at 6.0276, hunt 53). To 1e-7 (the states' own
    error at the default tolerances is below that), the times to 1e-9."""
    run, = amilpy.loads(DOSES, "doses.csl").run(method=method, advice=False)
    lo, t_lo, hi, t_hi = run.range["A"]
    peak = sum(math.exp(-0.3 * (6.0 - 2.0 * k)) for k in range(4))
    assert hi == pytest.approx(peak, abs=1e-7) and t_hi == pytest.approx(6.0, abs=1e-9)
    assert lo == pytest.approx(math.exp(-0.6), abs=1e-7) and t_lo == pytest.approx(2.0, abs=1e-9)


ABS_ONLY_READ = """PROGRAM range of abs(sin(3 t) - 0.2)
  CINTERVAL CINT = 1.0
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    Q = ABS(SIN(3.0*T) - 0.2)
    TERMT(T >= 4.0)
  END
  RANGE Q
END
"""


@pytest.mark.parametrize("method", [
    "AUTO", "RKS", "LSODA", "DOP853", "RADAU"])
def test_range_of_a_switch_only_printed_reads_it_as_it_stands(method):
    """Q = ABS(SIN(3T) - 0.2) feeds no state: the loop follows its sign at step ends,
    and RANGE, reading Q inside a step, took the branch from before the sign change
    (-1.2e-3 on RKS, hunt 53; AUTO's step-end samples read it in their batch's branch,
    -0.799). Its minimum is 0 where SIN(3T) = 0.2, its maximum 1.2
    where SIN(3T) = -1; to 1e-9."""
    run, = amilpy.loads(ABS_ONLY_READ, "q.csl").run(method=method, advice=False)
    lo, t_lo, hi, t_hi = run.range["Q"]
    assert lo == pytest.approx(0.0, abs=1e-9)
    assert abs(math.sin(3.0 * t_lo) - 0.2) < 1e-8
    assert hi == pytest.approx(1.2, abs=1e-9)
