"""Arithmetic faults in the model: a branch that is not selected is never what
stops a run, and a fault is reported as the statement that failed, on every
route, never as a later symptom in another state."""

import numpy as np
import pytest
from conftest import METHODS, run1

import amilpy
from amilpy.routes import route_for

# The NOTNUL idiom: divide by P unless P is zero. P = 0 at the start, where FCNSW
# selects its X = 0 branch (1.0); after that P > 0 and X' = P/P = 1, so X = 1 + TIME.
NOTNUL = """P = INTGRL(0.0, 1.0)
X = INTGRL(1.0, P/FCNSW(P, P, 1., P))
Y = X/FCNSW(P, P, 1., P)
TIMER FINTIM = 1.0, OUTDEL = 0.25
END
"""


@pytest.mark.parametrize("method", METHODS)
def test_unselected_branch_is_not_evaluated_at_the_start(method):
    r = run1(NOTNUL, method=method, advice=False)
    assert r.ok, r.message
    # X' is 0 at TIME = 0 exactly (the X = 0 branch) and 1 after: a method that
    # samples the start (a fixed step's first stage) is off by a part of one step
    tol = 2e-2 if route_for(method).fixed else 2e-4
    assert r["X"][-1] == pytest.approx(2.0, abs=tol)
    assert r["Y"][0] == 1.0  # X/1 at the start, as FCNSW is defined there
    assert r["Y"][1] == pytest.approx(r["X"][1] / 0.25, rel=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_a_fault_at_the_start_names_its_statement(method):
    # A = 1/P faults; X's derivative is the constant 1.0 and must not be blamed
    r = run1("PARAM P = 0.0\nX = INTGRL(0.0, 1.0)\nY = INTGRL(0.0, A)\nA = 1.0/P\n"
             "TIMER FINTIM = 1.0\nEND\n", method=method, advice=False)
    assert r.status == "failed"
    assert r.message == "integration failed at TIME = 0: A (line 4): division by zero: P = 0"
    # the row at the fault: the states as they start, what cannot be computed NaN
    assert r["X"][0] == 0.0 and r["Y"][0] == 0.0 and np.isnan(r["A"][0])


@pytest.mark.parametrize("method", METHODS)
def test_a_fault_inside_the_run_names_its_statement(method):
    # ASIN(X - 0.5) has no value once X > 1.5 (TIME > 1.5): every route, AUTO's
    # odeint chunks and the implicit methods' Jacobians included, reports that
    # statement rather than the NaN it left in a state or SciPy's complaint
    r = run1("X = INTGRL(0.0, 1.0)\nY = INTGRL(0.0, B)\nZ = INTGRL(0.0, 1.0)\n"
             "B = ASIN(X - 0.5)\nTIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n",
             method=method, advice=False)
    assert r.status == "failed"
    assert "B (line 4): math domain error: ASIN(X - 0.5) with X - 0.5 = 1.00" in r.message, \
        r.message
    fault_time = float(r.message.split("TIME = ")[1].split(":")[0])
    assert 1.49 < fault_time < 1.51
    assert np.isclose(r.t, 1.4).any() and r.t[-1] < 1.51  # the rows up to the fault


def test_a_fault_in_a_derivative_blames_no_other_state():
    # The student's clutch: the load inertia is 0 before T1. The fault is in W2's
    # derivative; the message must name W2, its line and the zero divisor, not FI1
    # (the first state) nor line 1 (the TITLE), as it used to.
    r = run1("TITLE A LOAD INERTIA THAT IS ZERO BEFORE T1\nPARAM T1 = 0.5, MC = 1.0\n"
             "JL = FSW(TIME - T1, 0.0, 2.0, 2.0)\nFI1 = INTGRL(0.0, 1.0)\n"
             "W2 = INTGRL(0.0, MC/JL)\nTIMER FINTIM = 1.0\nEND\n", advice=False)
    assert r.status == "failed"
    assert r.message == ("integration failed at TIME = 0: W2 (line 5): division by zero: "
                         "JL = 0"), r.message


@pytest.mark.parametrize("method", ["RKS", "DOP853", "RADAU", "AUTO"])
def test_a_blow_up_prints_no_numpy_warning(method):
    # X' = 1E300*X**2 overflows in the first step: the run fails with its message,
    # and NumPy's overflow warnings from inside SciPy's step (with a SciPy source line
    # on the user's screen) are not printed
    import warnings

    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        r = run1("X = INTGRL(1.0, 1.0E300*X*X)\nTIMER FINTIM = 2.0\nEND\n", method=method,
                 advice=False)
    assert r.status == "failed"
    assert not [w for w in seen if issubclass(w.category, RuntimeWarning)], \
        [str(w.message) for w in seen]


def test_a_step_at_the_spacing_of_floats_is_a_step_size_underflow():
    # DOP853 on X' = 1E300*X**2 from X = 1: SciPy gives up with "Required step size is
    # less than spacing between numbers"; the run says what that is, and where
    r = run1("X = INTGRL(1.0, 1.0E300*X*X)\nTIMER FINTIM = 2.0\nEND\n", method="DOP853",
             advice=False)
    assert r.status == "failed"
    assert "step size underflow: the step fell to the spacing of the floats" in r.message
    assert "X = 1 (a finite-time singularity?)" in r.message, r.message


def test_an_overflow_inside_radaus_step_names_the_state():
    # RADAU's Newton matrix overflows on X' = 1E300*X**2 and SciPy refuses it ("array
    # must not contain infs or NaNs"): the run names the state, as every route does
    r = run1("X = INTGRL(1.0, 1.0E300*X*X)\nTIMER FINTIM = 2.0\nEND\n", method="RADAU",
             advice=False)
    assert r.status == "failed"
    assert r.message.startswith("integration failed at TIME = 0: X is no longer finite"), \
        r.message


@pytest.mark.parametrize("method", ["AUTO", "RKS", "STIFF"])
def test_a_fault_is_reported_where_the_model_stops_having_values(method):
    """ASIN(T) has no value past T = 1: the failure is said at T = 1 (within LSODA's
    last steps), not at the furthest point a failing solver tried (AUTO said TIME = 5,
    the run's end), and its operands as plain numbers (RKS said np.float64(...))."""
    text = ("PROGRAM h\n  CINTERVAL CINT = 0.5\nDERIVATIVE\nXD = ASIN(T)\n"
            "X = INTEG(XD, 1.0)\nTERMT(T >= 5)\nEND\nEND\n")
    run = amilpy.loads(text, "h.csl").run(method=method, advice=False)[0]
    assert not run.ok and "ASIN(TIME)" in run.message and "np." not in run.message
    said = float(run.message.split("TIME = ")[1].split(":")[0])
    assert 1.0 <= said < 1.0 + 1e-5
