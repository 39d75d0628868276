"""DELAY, both forms, sampled from the integrator's dense output.

A DELAY keeps X at instants one spacing apart (CSMP's DELAY(N, P, X): P/N; ACSL's
DELAY(X, IC, TDL, NMX, DMIN): max(DMIN, TDL/NMX)) and reads X(t - delay) linearly
between them. The run loop takes X at every such instant inside an accepted step at
the state the stepper's dense output gives there (`Integrator.sample_memory`), so the
store holds X itself, whatever the step: the only error left is the linear reading,
spacing**2/8 * max|X''|, which for N = 1000 over P = 0.5 is 3.1e-8. Before, the
instants inside a step were filled on the straight line between the step's ends,
which is off by step**2/8 * |X''| (1.4e-4 with the default tolerances' long steps).

Tolerances: 1e-7, the issue's bound, is three times the reading's own error; the
integrals add the integrator's error at the default RELERR 1e-10 (BDF 1e-8). The
fixed-step TRAPZ, ADAMS and EULER are held to their own truncation error (said where
they are left out). Step-point mode (EULER by default) keeps the classic loop: memory
at the step points only, the instants between on the straight line (its own test).
"""

import math

import numpy as np
import pytest
from conftest import METHODS, run1
from scipy.integrate import quad
from scipy.optimize import brentq

import amilpy
from amilpy.codegen import Compiler
from amilpy.routes import route_for

P = 0.5
SINE = """TITLE DELAYED SINE
D = DELAY(1000, 0.5, SIN(TIME))
Y = INTGRL(0.0, D)
TIMER FINTIM = 3.0, OUTDEL = {outdel}
END
"""
READING = (P / 1000) ** 2 / 8  # the linear reading's error, |X''| <= 1
BOUND = 1e-7


def accurate(method: str) -> bool:
    """Routes whose own error at the default tolerances (or DELT) is far below 1e-7
    on these runs: every variable-step route, and RK4."""
    route = route_for(method)
    return route.uses_tolerances or method == "RK4"


def delayed_sine(t):
    return np.where(t < P, 0.0, np.sin(t - P))


@pytest.mark.parametrize("outdel", [0.01, 3.0 / 7.0])
@pytest.mark.parametrize("method", METHODS)
def test_the_delayed_sine_on_every_route(method, outdel):
    """D = X(t - 0.5), X(t0) = 0 before 0.5, within 1e-7 on every route (EULER taken
    out of step-point mode: located like the others). OUTDEL = 0.01 puts every row's
    t - 0.5 on a stored instant (the value sampled there, exact); OUTDEL = 3/7 is
    coarse and off the store's grid (the reading between two samples, 2.9e-8), and
    the steps are long (up to 3/7) while the store keeps 2000 points a second.
    Y = integral of D reads the store between samples at every stage:
    1 - cos(t - 0.5) after 0.5."""
    r = run1(SINE.format(outdel=repr(outdel)), method=method,
             step_point=False if method == "EULER" else None)
    assert r.ok
    assert np.max(np.abs(r["D"] - delayed_sine(r.t))) < BOUND
    if accurate(method):
        assert np.max(np.abs(r["Y"] - np.where(r.t < P, 0.0, 1 - np.cos(r.t - P)))) < BOUND
    if method == "COMPILED":  # the store is kept in Python: it runs as DOP853, and says so
        assert any("ran as DOP853" in w for w in r.warnings)


def test_step_point_mode_keeps_the_classic_store():
    """EULER in step-point mode (its default): memory changes only at the step points
    t0 + k*DELT, and the store's instants between two of them are on the straight
    line through X there, as the classic translators filled it: off by DELT**2/8 at
    most (DELT = OUTDEL/16), not by the reading's 3.1e-8."""
    r = run1(SINE.format(outdel=repr(3.0 / 7.0)), method="EULER")
    assert r.settings.endswith("step-point mode")
    delt = 3.0 / 7.0 / 16
    err = np.max(np.abs(r["D"] - delayed_sine(r.t)))
    assert 1e-6 < err <= delt**2 / 8


def test_the_value_before_t0_plus_p():
    """CSMP: X(t0) until t0 + P (2 here), then X(t - P); ACSL: IC until t0 + TDL,
    then X(t - TDL), where the run restarts (TIME - TDL is a breakpoint: the jump is
    at 0.5 exactly). X is linear in time, so the stored values read exactly."""
    r = run1("C = DELAY(100, 0.5, 2.0 + TIME)\nA = DELAY(2.0 + TIME, -1.0, 0.5, 100)\n"
             "Y = INTGRL(0.0, A)\nTIMER FINTIM = 2.0, OUTDEL = 0.25\nEND\n")
    t = r.t
    assert np.max(np.abs(r["C"] - np.where(t < P, 2.0, 1.5 + t))) < 1e-12
    assert np.max(np.abs(r["A"] - np.where(t < P, -1.0, 1.5 + t))) < 1e-12
    # -t before 0.5, then -0.5 + integral of 1.5 + u from 0.5: the jump located exactly
    # (what is left is the integrator's own error at RELERR 1e-10)
    expect = np.where(t < P, -t, -P + 1.5 * (t - P) + (t**2 - P**2) / 2)
    assert np.max(np.abs(r["Y"] - expect)) < 1e-9
    assert [(e.time, e.kind) for e in r.events] == [(P, "breakpoint")]


def test_an_acsl_delay_from_a_later_start_reads_ic_until_t0_plus_tdl():
    """A program from T = 1 (VARIABLE T = 1.0): XD = DELAY(X, -3, 0.5, 20) is IC
    until 1.5, then X(t - 0.5) = 2 + (t - 1.5), X = 2 + (t - 1). (A read a little
    before the store's start extends its first segment, for a tangent's difference
    step; a change of 2026-12-01 extended it from any distance, and XD was 2.0
    .. 1.9 from 1.0 to 1.4, the review of that day.) To 1e-9."""
    run, = amilpy.loads("PROGRAM d\n  VARIABLE T = 1.0\n  CONSTANT TDL = 0.5, IC = -3.0\n"
                        "  DERIVATIVE\n    XD = DELAY(X, IC, TDL, 20)\n    X = INTEG(1.0, 2.0)\n"
                        "    TERMT(T >= 2.2)\n  END\n  CINTERVAL CINT = 0.1\nEND\n",
                        "later.csl").run(advice=False, rtol=1e-10, atol=1e-12)
    t = np.asarray(run.times)
    expect = np.where(t < 1.5 - 1e-12, -3.0, 2.0 + (t - 1.5))
    assert np.asarray(run["XD"]) == pytest.approx(expect, abs=1e-9)


def test_an_acsl_delay_from_a_later_start_turns_where_it_is_located():
    """The same program, Y = INTEG(XD): XD jumps from IC = -3 to X(1) = 2 at t0 + TDL
    = 1.5, and the run restarts there (its switch is TIME - TDL - t0, a breakpoint).
    Y = -3 (t - 1) until 1.5, then -1.5 + 2 (t - 1.5) + (t - 1.5)**2 / 2. When the
    switch was TIME - TDL, it had turned before the start and the jump was stepped
    over: Y was 7.5e-4 off at any tolerance (a read just before the store's start
    extends its first segment). To 1e-8 at RELERR 1e-10 (measured 2e-10)."""
    run, = amilpy.loads("PROGRAM d\n  VARIABLE T = 1.0\n  CONSTANT TDL = 0.5, IC = -3.0\n"
                        "  DERIVATIVE\n    XD = DELAY(X, IC, TDL, 20)\n    X = INTEG(1.0, 2.0)\n"
                        "    Y = INTEG(XD, 0.0)\n    TERMT(T >= 2.2)\n  END\n"
                        "  CINTERVAL CINT = 0.1\nEND\n",
                        "later.csl").run(advice=False, rtol=1e-10, atol=1e-12)
    t = np.asarray(run.times)
    expect = np.where(t < 1.5, -3.0 * (t - 1.0), -1.5 + 2.0 * (t - 1.5) + (t - 1.5) ** 2 / 2)
    assert np.asarray(run["Y"]) == pytest.approx(expect, abs=1e-8)
    assert [(e.time, e.kind) for e in run.events][:1] == [(1.5, "breakpoint")]


def method_of_steps(t):
    """y' = -y(t - 1), y = 1 on [-1, 0]: integrated one delay at a time."""
    return np.where(t <= 1, 1 - t, np.where(t <= 2, 1 - t + (t - 1) ** 2 / 2,
                                            1 - t + (t - 1) ** 2 / 2 - (t - 2) ** 3 / 6))


@pytest.mark.parametrize("method", [m for m in METHODS if accurate(m)])
@pytest.mark.parametrize("call", ["DELAY(2000, 1.0, Y)", "DELAY(Y, 1.0, 1.0, 2000)"])
def test_delayed_feedback_against_the_method_of_steps(method, call):
    """The classic DDE y' = -y(t - 1) with y = 1 before 0 (CSMP: X(t0) = 1 before
    t0 + P; ACSL: IC = 1 before TDL) on [0, 3], against its closed form. The
    derivatives read the store at every stage: no step is longer than the delay
    (each reads a past that is stored), and the store's reading error, (1/2000)**2/8
    * |y''| <= 3.1e-8, integrates to at most 1e-7 over the three delays."""
    r = run1(f"Y = INTGRL(1.0, -{call})\nTIMER FINTIM = 3.0, OUTDEL = 0.1\nEND\n",
             method=method)
    assert r.ok
    assert np.max(np.abs(r["Y"] - method_of_steps(r.t))) < BOUND


def test_a_delay_the_derivatives_read_limits_the_step():
    """A step longer than a delay the derivatives read would read the store where it
    has nothing yet: the plan's largest step is the delay (0.3, under OUTDEL = 1)."""
    m = amilpy.loads("Y = INTGRL(1.0, -DELAY(100, 0.3, Y))\nD = DELAY(100, 0.1, SIN(TIME))\n"
                     "TIMER FINTIM = 3.0, OUTDEL = 1.0\nEND\n")
    c = Compiler(m.ir, {}, {}, {}).build()
    # (the delay of 0.1 feeds only an output: its rows sample the store up to them)
    assert c.step_limit == 0.3


VARYING = """PROGRAM VARYING DELAY
INITIAL
  CONSTANT TMX = 4.0
  CINTERVAL CINT = 0.1
END
DERIVATIVE
  TAU = 0.5 + 0.25*SIN(T)
  D = DELAY(SIN(T), 0.0, TAU, 2000, 5.0E-4)
  Y = INTEG(D, 0.0)
  TERMT(T .GE. TMX)
END
END
"""


def tau(t):
    return 0.5 + 0.25 * np.sin(t)


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU", "RK4"])
def test_acsl_delay_with_a_tdl_that_changes_in_time(method):
    """ACSL: IC until T - TDL(T) reaches t0, then X(T - TDL(T)), TDL = 0.5 + 0.25 sin T.
    2000 points at least 5E-4 apart cover 1 s, more than the longest delay (0.75), so
    the store holds every past read; the reading is off by (5E-4)**2/8 = 3.1e-8. The
    start, where T - TDL(T) = 0 (T* = 0.6516...), is located (an event), and Y, the
    integral of D, matches the quadrature of the closed form from T*."""
    r = run1(VARYING, method=method)
    assert r.status == "stopped" and r.t[-1] == pytest.approx(4.0)
    t = r.t
    s = t - tau(t)
    assert np.max(np.abs(r["D"] - np.where(s < 0, 0.0, np.sin(s)))) < BOUND
    start = brentq(lambda u: u - tau(u), 0.0, 1.0, xtol=1e-15)
    assert abs(r.events[0].time - start) < 1e-9
    expect = [quad(lambda u: math.sin(u - tau(u)), start, v, epsabs=1e-13)[0] if v > start
              else 0.0 for v in t]
    assert np.max(np.abs(r["Y"] - np.array(expect))) < 2 * BOUND


@pytest.mark.parametrize("fed_back", [False, True])
def test_a_past_the_store_no_longer_holds_stops_the_run(fed_back):
    """A TDL that grows (0.2 + 0.5*TIME) with NMX = 50 and no DMIN: the 50 points are
    spaced TDL/50 and span the delay as it was, not as it is: at TIME = 0.4 the read
    reaches back to 0, which the ring no longer holds. The run stops there with the
    statement and what to write, whether the value feeds the derivatives or only an
    output; with DMIN = 0.05 (50 points over 2.5 s, more than the longest delay, 1.7)
    the same listing runs to the end."""
    x = "Y" if fed_back else "SIN(TIME)"
    body = f"D = DELAY({x}, 1.0, 0.2 + 0.5*TIME, 50{{dmin}})\nY = INTGRL(1.0, -D)\n" \
        "TIMER FINTIM = 3.0, OUTDEL = 0.1\nEND\n"
    r = run1(body.format(dmin=""), method="RKS")
    assert r.status == "failed"
    assert "D (line 1): at TIME = 0.4 it reads TIME - delay = 0, older than the 50 " \
        "points of its store keep" in r.message
    assert "give DMIN so that NMX*DMIN covers the longest delay" in r.message
    # the rows before are kept; at 0.4 itself the value has no past to come from
    assert r.t[-1] == pytest.approx(0.4) and np.isfinite(r["D"][:-1]).all()
    assert run1(body.format(dmin=", 0.05"), method="RKS").ok


def test_a_negative_tdl_is_a_fault_at_its_statement():
    r = run1("Y = INTGRL(1.0, -D)\nD = DELAY(Y, 1.0, 0.5 - TIME, 50)\n"
             "TIMER FINTIM = 3.0, OUTDEL = 0.1\nEND\n", method="RKS")
    assert r.status == "failed"
    assert "D (line 2): the delay must not be negative" in r.message


MEMORY = """X = INTGRL(0.0, COS(3.0*TIME))
H = HSTRSS(0.0, -0.1, 0.1, X)
R = DERIV(0.0, X)
Z = ZHOLD(X - 0.2, X)
F = RST(X - 0.3, X + 0.3, 0.0)
{delay}TIMER FINTIM = 4.0, OUTDEL = 0.05
END
"""


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RK4"])
def test_the_other_memory_functions_are_not_sampled(method):
    """Only the stores are sampled inside a step: HSTRSS, DERIV, ZHOLD and RST are
    updated at the step ends, as without a DELAY beside them (DERIV's second-order
    difference and RST's flip-flop both depend on how many points they see; updating
    them at a DELAY's instants too would change what they give). A DELAY that feeds
    only an output changes neither the steps nor any other column, bit for bit."""
    plain = run1(MEMORY.format(delay=""), method=method)
    delayed = run1(MEMORY.format(delay="D = DELAY(500, 0.25, X)\n"), method=method)
    for name in ("X", "H", "R", "Z", "F"):
        assert np.array_equal(plain[name], delayed[name]), name
    assert plain.events == delayed.events


def test_no_change_without_delay():
    """A listing without DELAY samples nothing and its steps are bounded by the
    output interval alone, as before."""
    m = amilpy.loads(MEMORY.format(delay=""))
    c = Compiler(m.ir, {}, {}, {}).build()
    assert c.sample is None and c.next_sample is None and c.step_limit == math.inf
    assert "def smp" not in c.source


def test_the_vector_form_reads_the_store_as_the_scalar_one():
    """The output function over NumPy columns (RANGE's samples, AUTO's blocks) reads
    the same store as the scalar one, row by row, both forms."""
    m = amilpy.loads("Y = INTGRL(0.0, COS(TIME))\nD = DELAY(200, 0.5, Y)\n"
                     "A = DELAY(Y, -1.0, 0.5 + 0.1*TIME, 200, 0.005)\n"
                     "TIMER FINTIM = 2.0, OUTDEL = 0.1\nEND\n")
    z = m.run()[0].final_state["z"]
    c = Compiler(m.ir, {}, {}, {}).build()
    # instants from the store's newest point on (what the next step reads), each row
    # with its own state
    t = np.linspace(2.0, 2.04, 7)
    y = np.sin(t)
    modes = [1.0] * len(c.watched)
    columns = c.out_v(t, [y], modes, z)
    names = c.out_names
    for i in range(len(t)):
        row = c.out(float(t[i]), [float(y[i])], modes, z)
        for name in ("D", "A"):
            k = names.index(name)
            assert columns[k][i] == row[k], name


@pytest.mark.parametrize("call", ["DELAY(7, 0.5, X)", "DELAY(X, 0.0, 0.5, 7)",
                                  "DELAY(X, 0.0, 0.5, 7, 0.1)"])
def test_the_store_has_the_slots_its_entry_gives(call):
    """One layout: the entry's slot count is what the store's helpers fill (7 points
    and one to spare, as (t, X) pairs, after the header)."""
    m = amilpy.loads(f"X = INTGRL(0.0, 1.0)\nD = {call}\nTIMER FINTIM = 1.0\nEND\n")
    mem, = m.ir.memories
    c = Compiler(m.ir, {}, {}, {}).build()
    assert mem.nslots == len(c.z0) == 2 * 7 + 13
    z = c.mem(0.0, [0.0], [1.0] * len(c.watched), [1.0] * len(c.watched), c.z0)
    assert len(z) == len(c.z0) and c.next_sample(z) > 0.0


def test_a_short_delay_over_a_long_run_keeps_its_history_right():
    """A delay of 0.01 over 2,000 of its lengths (FINTIM 20): the history the delay
    reads is the integrator's own, step by step, however long the run; D = sin(t -
    0.01) and its integral 1 - cos(t - 0.01) to 1e-9 (RELERR 1e-10's global error)."""
    run = amilpy.loads("X = SIN(TIME)\nD = DELAY(100, 0.01, X)\nZ = INTGRL(0.0, D)\n"
                       "TIMER FINTIM = 20.0, OUTDEL = 0.1\nPRINT D, Z\nEND\n").run(
                           advice=False)[0]
    t = run.t
    assert run.ok
    assert np.max(np.abs(run["D"] - np.where(t >= 0.01, np.sin(t - 0.01), 0.0))) < 1e-9
    assert np.max(np.abs(run["Z"] - np.where(t >= 0.01, 1 - np.cos(t - 0.01), 0.0))) < 1e-9


def test_a_zero_csmp_delay_is_the_value_itself():
    """DELAY(N, 0.0, X) in the CSMP form: no delay, D = X at every row (it hung
    once; the ACSL form's zero TDL is its own test)."""
    run = amilpy.loads("X = INTGRL(1.0, -X)\nD = DELAY(10, 0.0, X)\n"
                       "TIMER FINTIM = 1.0, OUTDEL = 0.1\nPRINT D, X\nEND\n").run(advice=False)[0]
    assert run.ok and list(run["D"]) == list(run["X"])
