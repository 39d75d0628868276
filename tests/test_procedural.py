"""Expressions, conditions and procedural code (contract section 10): precedence,
.TRUE./.FALSE., LOGICAL/INTEGER, relational tests as located switching surfaces (on
time alone, breakpoints), IF/ELSE IF/ELSE in three spellings and on one line,
PROCEDURAL as one sorting unit, FOR/DO loops, ACSL FUNCTION definitions."""

import math

import numpy as np
import pytest
from conftest import run1
from scipy.integrate import solve_ivp

import amilpy
from amilpy.diagnostics import AmilError

END = "TIMER FINTIM = 1.0\nEND\n"


def initial_value(expr: str, form: str = "CSMP") -> float:
    """The value of `expr` computed once in INITIAL."""
    if form == "CSMP":
        return run1(f"CONST A = 1.0, B = 0.0\nINITIAL\nV = {expr}\nDYNAMIC\n"
                    "X = INTGRL(0.0, V)\n" + END).constants["V"]
    m = amilpy.loads(f"PROGRAM p\nCONSTANT A = 1.0, B = 0.0\nINITIAL\nV = {expr}\nEND\n"
                     "DERIVATIVE\nX = INTEG(V, 0.0)\nTERMT(T >= 1.0)\nEND\nEND\n", "p.csl")
    run, = m.run()
    return run.constants["V"]


@pytest.mark.parametrize("expr, value", [
    # .OR. binds looser than .AND., which binds looser than .NOT.
    ("A .OR. B .AND. B", 1.0), ("(A .OR. B) .AND. B", 0.0), (".NOT. B .AND. A", 1.0),
    # relational below arithmetic: -1 + 2 > 0
    ("-1.0 + 2.0 > 0.0", 1.0), ("2.0*3.0 == 6.0", 1.0), ("-2.0**2 < -3.0", 1.0),
    # .EQV. and .NEQV. lowest
    ("A > 0.5 .EQV. B < 0.5", 1.0), ("A .NEQV. A", 0.0),
    # a number used as a condition is true when > 0; a truth used as a number is 1 or 0
    ("(A > B) + (A > B)", 2.0), ("-3.0 .OR. B", 0.0), (".TRUE. .AND. .FALSE.", 0.0),
])
def test_operators_and_their_precedence(expr, value):
    assert initial_value(expr) == value


def test_relational_chains_are_not_associative():
    with pytest.raises(AmilError) as err:
        amilpy.loads("INITIAL\nV = 1 < 2 < 3\nDYNAMIC\nX = INTGRL(0.0, V)\n" + END)
    assert err.value.diagnostics[0].span.line == 2


def test_acsl_true_false_and_logical_constants():
    assert initial_value("true .AND. .NOT. false", "ACSL") == 1.0
    # A11: CONSTANT abson = .false.; IF (abson.eq..true.) ...
    run, = amilpy.loads("""PROGRAM p
  LOGICAL ABSON
  CONSTANT ABSON = .FALSE.
  DERIVATIVE
    PROCEDURAL (R = ABSON)
      IF (ABSON.EQ..TRUE.) THEN
        R = 5.0
      ELSE
        R = 2.0*ABSON + 1.0
      ENDIF
    END
    X = INTEG(R, 0.0)
    TERMT(T >= 1.0)
  END
END
""", "p.csl").run()
    assert run["X"][-1] == pytest.approx(1.0)


def test_integer_truncates_toward_zero_and_logical_stores_one_or_zero():
    run, = amilpy.loads("""PROGRAM p
  INTEGER I, J
  LOGICAL L
  INITIAL
    I = 7.9
    J = -7.9
    L = -3.0
    M = 2.5
  END
  DERIVATIVE
    X = INTEG(I + J + L, 0.0)
    TERMT(T >= 1.0)
  END
END
""", "p.csl").run()
    assert (run.constants["I"], run.constants["J"], run.constants["L"]) == (7.0, -7.0, 0.0)


def test_a_division_of_whole_numbers_is_real_with_a_warning():
    m = amilpy.loads("INITIAL\nV = 1/2\nDYNAMIC\nX = INTGRL(0.0, V)\n" + END)
    w, = m.ir.warnings
    assert "1/2 is a division of whole numbers: it is 0.5 here (Fortran would give 0)" \
        == w.message
    assert m.run()[0].constants["V"] == 0.5


BILINEAR = """TITLE BILINEAR SPRING: STIFFNESS K1 FOR X > 0, K2 FOR X < 0
PARAM K1 = 1.0, K2 = 4.0
X = INTGRL(1.0, V)
V = INTGRL(0.0, F)
IF (X > 0.0) THEN
   F = -K1*X
ELSE
   F = -K2*X
END IF
TIMER FINTIM = 20.0, PRDEL = 0.1
RELERR 1.0E-10
ABSERR 1.0E-12
END
"""


def test_if_else_on_a_state_is_a_located_switch_bilinear_spring_period():
    # half a period at each stiffness: T = pi/sqrt(K1) + pi/sqrt(K2) = 1.5 pi
    run = run1(BILINEAR)
    down = [e.time for e in run.events if e.new < 0]
    up = [e.time for e in run.events if e.new > 0]
    period = 0.5 * math.pi * (1.0 + 0.5)  # pi/2/sqrt(K1) + pi/2/sqrt(K2), the first down
    assert down[0] == pytest.approx(math.pi / 2, abs=1e-9)
    assert np.allclose(np.diff(down), 1.5 * math.pi, atol=1e-8)
    assert np.allclose(np.array(up) - np.array(down[:len(up)]), math.pi / 2, atol=1e-8)
    assert period == pytest.approx(0.75 * math.pi)
    # the energy K(x) x^2 + v^2 is kept across the switch: the stiff side's amplitude
    # is halved (K2 x^2 = K1 * 1)
    k = np.where(run["X"] > 0, 1.0, 4.0)
    assert np.max(np.abs(k * run["X"] ** 2 + run["V"] ** 2 - 1.0)) < 1e-8


@pytest.mark.parametrize("spelling", [
    "IF (X > 0.0) THEN\n F = -K1*X\nELSE\n F = -K2*X\nEND IF",
    "IF (X .GT. 0.0) THEN\n F = -K1*X\nELSE IF (X .LE. 0.0) THEN\n F = -K2*X\nENDIF",
    "IF (X > 0.0)\n F = -K1*X\nELSE\n F = -K2*X\nEND",  # Magnolia, ACSL form
])
def test_three_spellings_of_if_give_the_same_run(spelling):
    text = f"""PROGRAM p
  CONSTANT K1 = 1.0, K2 = 4.0
  CINTERVAL CINT = 0.1
  DERIVATIVE
    X = INTEG(V, 1.0)
    V = INTEG(F, 0.0)
    {spelling}
    TERMT(T >= 5.0)
  END
END
"""
    run, = amilpy.loads(text, "p.csl").run(rtol=1e-10, atol=1e-12)
    ref = run1(BILINEAR.replace("FINTIM = 20.0", "FINTIM = 5.0"))
    assert np.max(np.abs(run["X"] - ref["X"])) < 1e-8


def test_one_line_if():
    run = run1("X = INTGRL(0.0, R)\nIF (TIME > 0.5) R = 3.0\n" + END)
    # where the IF does not assign R it keeps its value from before the block (a
    # warning says so): 0, as nothing else gives it one
    assert run["X"][-1] == pytest.approx(1.5, rel=1e-9)


def test_if_on_time_alone_is_a_breakpoint():
    # A2 (flow_limited_fat): IF (T >= TCHNG) CIN0 = 0.0 ... END on a name INITIAL gave
    run, = amilpy.loads("""MODEL p
  INITIAL
    CONSTANT TCHNG = 1.2345
    CIN0 = 1.0
  END
  DERIVATIVE
    IF (T >= TCHNG)
      CIN0 = 0.0
    END
    X = INTEG(CIN0, 0.0)
    TERMT(T >= 2.0)
  END
END
""", "p.csl").run()
    ev, = [e for e in run.events if e.kind == "breakpoint"]
    assert ev.time == 1.2345
    assert run["X"][-1] == pytest.approx(1.2345, rel=1e-12)


def test_an_if_without_else_warns_that_the_name_keeps_its_value():
    m = amilpy.loads("X = INTGRL(0.0, R)\nIF (X > 0.5) THEN\nR = 3.0\nEND IF\n" + END)
    w, = m.ir.warnings
    assert "R is not assigned on every path of this IF" in w.message


def test_procedural_is_one_sorting_unit_with_written_order_inside():
    # the unit reads Y, computed after it in the listing: sorted as one unit
    run, = amilpy.loads("""PROGRAM p
  CINTERVAL CINT = 0.5
  DERIVATIVE
    PROCEDURAL (A, B = Y)
      A = Y*2.0
      A = A + 1.0       ! reassigned in written order inside
      B = A*A
    END
    Y = INTEG(1.0, 0.0)
    Z = INTEG(B, 0.0)
    TERMT(T >= 1.0)
  END
END
""", "p.csl").run(rtol=1e-10, atol=1e-12)
    # Z = integral of (2t + 1)^2 = ((2t+1)^3 - 1)/6
    assert run["Z"][-1] == pytest.approx((27.0 - 1.0) / 6.0, rel=1e-9)


def test_numbers_among_a_procedurals_inputs_order_nothing():
    """The EPA lead model (O'Flaherty form) writes `PROCEDURAL (A, B = 1, 1)`: a
    number in the input list depends on nothing, so it orders nothing; the unit's
    names are sorted by what its body reads (Y here, computed after it). Z =
    integral of (2t + 1)^2, as in the test above."""
    run, = amilpy.loads("""PROGRAM p
  CINTERVAL CINT = 0.5
  DERIVATIVE
    PROCEDURAL (A, B = 1, 1.0, Y)
      A = Y*2.0 + 1.0
      B = A*A
    END
    Y = INTEG(1.0, 0.0)
    Z = INTEG(B, 0.0)
    TERMT(T >= 1.0)
  END
END
""", "p.csl").run(rtol=1e-10, atol=1e-12)
    assert run["Z"][-1] == pytest.approx((27.0 - 1.0) / 6.0, rel=1e-9)


def test_procedural_lists_that_disagree_with_the_body_warn():
    m = amilpy.loads("PROGRAM p\nDERIVATIVE\nPROCEDURAL (A = )\nA = T\nB = 2.0\nEND\n"
                     "X = INTEG(A + B, 0.0)\nTERMT(T >= 1.0)\nEND\nEND\n", "p.csl")
    assert any("the PROCEDURAL assigns B, not in its list" in w.message
               for w in m.ir.warnings)


def test_a_condition_inside_a_unit_reads_the_straight_line_values():
    # Y is assigned before the IF in the same unit: its surface is 2*X - 1, located
    run, = amilpy.loads("""PROGRAM p
  CINTERVAL CINT = 0.25
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    PROCEDURAL (R = X)
      Y = 2.0*X
      IF (Y > 1.0) THEN
        R = 1.0
      ELSE
        R = 0.0
      END IF
    END
    Z = INTEG(R, 0.0)
    TERMT(T >= 1.0)
  END
END
""", "p.csl").run(rtol=1e-10, atol=1e-12)
    ev, = [e for e in run.events if e.kind == "switch"]
    assert ev.time == pytest.approx(0.5, abs=1e-9)
    assert run["Z"][-1] == pytest.approx(0.5, abs=1e-9)


def test_loops_in_written_order_code_and_in_procedural():
    run, = amilpy.loads("""PROGRAM p
  INITIAL
    S = 0.0
    FOR I = 1, 10
      S = S + I
    END
    P = 1.0
    DO J = 1, 5, 2
      P = P*J
    END DO
  END
  DERIVATIVE
    PROCEDURAL (Q = X)
      Q = 0.0
      DO K = 1, 3
        Q = Q + X**K
      ENDDO
    END
    X = INTEG(1.0, 0.0)
    Z = INTEG(Q, 0.0)
    TERMT(T >= 1.0)
  END
END
""", "p.csl").run(rtol=1e-10, atol=1e-12)
    assert run.constants["S"] == 55.0 and run.constants["P"] == 15.0  # 1*3*5
    assert run.constants["I"] == 11.0  # one step past the last value, as in Fortran
    assert run["Z"][-1] == pytest.approx(1 / 2 + 1 / 3 + 1 / 4, rel=1e-9)


def test_a_loop_of_more_than_a_million_iterations_is_an_error():
    with pytest.raises(AmilError) as err:
        amilpy.loads("PROGRAM p\nINITIAL\nS = 0.0\nFOR I = 1, 2000000\nS = S + 1\nEND\nEND\n"
                     "DERIVATIVE\nX = INTEG(S, 0.0)\nTERMT(T >= 1.0)\nEND\nEND\n",
                     "p.csl").run()
    d = err.value.diagnostics[0]
    assert "a FOR/DO loop of 2000000 iterations (at most 1000000)" in d.message
    assert d.span.line == 4


def test_a_loop_whose_step_is_0_when_it_runs_stops_the_run_with_a_located_message():
    # a step that is a CONSTANT is known only when the run starts: the loop's line,
    # its bounds and what to write, with the rows before it kept (a TypeError from the
    # copy of the code that makes a fault's values NaN was a traceback)
    from amilpy.result import Status

    run = amilpy.loads("""PROGRAM P
INITIAL
CONSTANT S = 0.0, N = 3.0
END
DERIVATIVE
PROCEDURAL (Y = X)
Y = 0.0
DO 10 I = 1, N, S
Y = Y + X
10 CONTINUE
END
X = INTEG(-X, 1.0)
TERMT (T .GE. 1.0)
END
END
""", "p.csl").run(advice=False)[0]
    assert run.status is Status.FAILED
    assert "(line 8): a FOR/DO loop from 1 to 3 with step 0 never ends: give its step " \
        "a value that is not 0" in run.message
    assert len(run.t) == 1 and run["X"][0] == 1.0


def test_a_loop_in_derivative_outside_procedural_is_refused():
    with pytest.raises(AmilError) as err:
        amilpy.loads("PROGRAM p\nDERIVATIVE\nDO I = 1, 3\nX = 1.0\nEND DO\nY = INTEG(1., 0.)"
                     "\nTERMT(T >= 1.0)\nEND\nEND\n", "p.csl")
    assert "inside a PROCEDURAL" in err.value.diagnostics[0].hint


def test_acsl_function_definitions():
    # Magnolia's docetaxel: function Cv_x = calc_cven(C_x, P_x, STB_x), with locals
    run, = amilpy.loads("""PROGRAM p
  CONSTANT KD = 2.0
  FUNCTION ROOT = QROOT(A, B, C)
    DIMENSION A, B, C
    D = B*B - 4.0*A*C
    IF (D < 0.0) THEN
      ROOT = 0.0
    ELSE
      ROOT = (-B + SQRT(D))/(2.0*A)
    END IF
  END
  DERIVATIVE
    X = INTEG(QROOT(1.0, KD, -T), 0.0)   ! the positive root of x^2 + 2x - t
    TERMT(T >= 3.0)
  END
END
""", "p.csl").run(rtol=1e-10, atol=1e-12)
    sol = solve_ivp(lambda t, y: [-1 + math.sqrt(1 + t)], (0, 3), [0.0], rtol=1e-12,
                    atol=1e-14)
    assert run["X"][-1] == pytest.approx(sol.y[0, -1], abs=1e-9)


@pytest.mark.parametrize("body, message", [
    ("FUNCTION F = G(A)\nF = H(A)\nEND\nFUNCTION R = H(B)\nR = G(B)\nEND\n",
     "FUNCTION G calls itself through other FUNCTIONs"),
    ("FUNCTION F = G(A)\nF = A + Q\nEND\n", "FUNCTION G reads Q"),
    ("FUNCTION F = G(A)\nF = G(A)\nEND\n", "FUNCTION G calls itself"),
    ("FUNCTION F = G(A)\nY = A\nEND\n", "FUNCTION G never assigns its result F"),
])
def test_function_definition_faults(body, message):
    with pytest.raises(AmilError) as err:
        amilpy.loads(f"PROGRAM p\n{body}DERIVATIVE\nX = INTEG(G(1.0), 0.0)\n"
                     "TERMT(T >= 1.0)\nEND\nEND\n", "p.csl")
    assert any(message in d.message for d in err.value.diagnostics)


def test_a_function_reads_the_programs_variables_where_it_is_called():
    """Magnolia's FUNCTIONs see the program's variables (Peters 2008's Kpu functions
    read Dvow, which INITIAL computes): here G reads K, computed in INITIAL, and the
    state X, so X' = K + X from 0 with K = 2: X = 2 (e^t - 1), and H, called in
    INITIAL, reads K there."""
    run, = amilpy.loads("""PROGRAM p
FUNCTION F = G(A)
  F = A*K + X
END
FUNCTION R = H(B)
  R = B + G(0.0) + K
END
INITIAL
  K = 2.0
  C = H(1.0)
END
DERIVATIVE
  X = INTEG(G(1.0), 0.0)
  TERMT(T >= 1.0)
END
END
""", "p.csl").run(advice=False)
    assert np.max(np.abs(run["X"] - 2.0 * np.expm1(run.t))) < 1e-9
    assert run.final["C"] == 3.0  # 1 + (0*2 + X(0) = 0) + 2


def test_a_function_reads_the_runs_own_data_values():
    """A FUNCTION reading a CONSTANT: runs of one model given other values of it
    share a build, and each call must read its own run's value (it read the first
    run's, folded into the FUNCTION). A' = -K A: A(2) = exp(-2K) for each K."""
    model = amilpy.loads("""PROGRAM p
  CONSTANT K = 1.0
  CINTERVAL CINT = 0.5
  FUNCTION R = RATE(X)
    R = K*X
  END
  DERIVATIVE
    A = INTEG(-RATE(A), 1.0)
    TERMT(T >= 2.0)
  END
END
""", "p.csl")
    for k in (1.0, 0.5, 1.7):
        run, = model.run(advice=False, K=k)
        assert run.final["A"] == pytest.approx(math.exp(-2.0 * k), rel=1e-9)


def test_equality_on_a_state_is_tested_pointwise_with_a_warning():
    m = amilpy.loads("X = INTGRL(0.0, 1.0)\nY = X == 0.5\n" + END)
    w, = m.ir.warnings
    assert "X == 0.5 is tested where it is evaluated, never located" in w.message


def test_integ_inside_if_is_refused():
    with pytest.raises(AmilError) as err:
        amilpy.loads("PROGRAM p\nDERIVATIVE\nIF (T > 1.0) THEN\nX = INTEG(1.0, 0.0)\n"
                     "END IF\nTERMT(T >= 2.0)\nEND\nEND\n", "p.csl")
    d = err.value.diagnostics[0]
    assert "INTEG cannot be used in an IF or PROCEDURAL block" in d.message
    assert "outside" in d.hint


def test_csmp_terminal_with_a_do_loop():
    run = run1("X = INTGRL(0.0, 1.0)\nTERMINAL\nS = 0.0\nDO I = 1, 4\nS = S + X*I\nEND DO\n"
               + END)
    assert run.terminal["S"] == pytest.approx(10.0)


def test_a_test_on_a_value_an_if_selected_is_located():
    # W = |S| (S = sin t) by an IF on every path; the test W > 0.5 after it reads W as
    # the IF selects it, RSW(S > 0, S, -S), a surface of what the block reads: located
    # where |sin t| = 0.5, on both signs of S (it was made where it stood, with a
    # warning). Z is the time |sin t| > 0.5 has held: 2(pi - 2 asin 0.5) by t = 6
    text = """PROGRAM p
  CINTERVAL CINT = 0.1
  DERIVATIVE
    S = INTEG(C, 0.0)
    C = INTEG(-S, 1.0)
    PROCEDURAL (F, W = S)
      IF (S > 0.0) THEN
        W = S
      ELSE
        W = -S
      END IF
      IF (W > 0.5) THEN
        F = 1.0
      ELSE
        F = 0.0
      END IF
    END
    Z = INTEG(F, 0.0)
    TERMT(T >= 6.0)
  END
END
"""
    model = amilpy.loads(text, "p.csl")
    assert not model.ir.warnings
    run, = model.run(rtol=1e-10, atol=1e-12, advice=False)
    a = math.asin(0.5)
    crossings = [e.time for e in run.events if e.switch == "W > 0.5 at line 12"]
    assert crossings == pytest.approx([a, math.pi - a, math.pi + a, 2 * math.pi - a],
                                      abs=1e-9)
    assert run["Z"][-1] == pytest.approx(2 * (math.pi - 2 * a), abs=1e-8)


@pytest.mark.parametrize("text", [
    "PROGRAM P\nDERIVATIVE\nPROCEDURAL (Y, W = X)\nW = 2.0\nY = FOO(X) + W\nEND\n"
    "Z = Y + 1.0\nX = INTEG(-X, 1.0)\nTERMT (T .GE. 1.0)\nEND\nEND\n",
    "PROGRAM P\nDERIVATIVE\nIF (X .GT. 0.5) THEN\nY = FOO(X)\nELSE\nY = 1.0\nEND IF\n"
    "Z = Y + 1.0\nX = INTEG(-X, 1.0)\nTERMT (T .GE. 1.0)\nEND\nEND\n"])
def test_a_fault_inside_a_block_is_said_once_not_again_where_its_outputs_are_read(text):
    # what the block assigns is still defined: "W/Y is used but never defined" after
    # the one fault sent the reader to the wrong line
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, "p.csl")
    assert [d.message for d in err.value.diagnostics] == ["unknown function FOO"]


GUARDED = """PROGRAM tests read only where their branch is taken
  CINTERVAL CINT = 0.25
  DERIVATIVE
    PROCEDURAL (Y, W = X)
      IF (X .LE. 0.5) THEN
        Y = 0.0
      ELSE IF (LOG(X - 0.5) .LT. -1.0) THEN
        Y = 1.0
      ELSE
        Y = 2.0
      END IF
      W = 0.0
      IF (X .GT. 0.5) THEN
        IF (SQRT(X - 0.5) .GT. 0.3) W = 1.0
      END IF
    END
    X = INTEG(1.0, 0.0)
    Z = INTEG(Y + W, 0.0)
    TERMT(T >= 1.5)
  END
END
"""


@pytest.mark.parametrize("method", ["AUTO", "RKS", "STIFF", "LSODA", "DOP853", "RK4"])
def test_a_test_is_read_only_where_its_branch_is_taken(method):
    """Fortran reads an ELSE IF's test only where the tests before it are false, and
    a test inside a THEN only where the THEN's is true: LOG(X - 0.5) and
    SQRT(X - 0.5) have no value for X < 0.5, where neither is read. (They were read
    at every step, and the run stopped at TIME 0 on a math domain error.) With
    X = t: Y is 0, then 1 from 0.5 to 0.5 + 1/e, then 2; W is 1 from X = 0.59 on. So
    Z(1.5) = 1/e + 2 (1 - 1/e) + (1.5 - 0.59) = 2.542120558828558; the crossings
    are located (1e-9: RELERR 1e-11, a fixed-step route's step points on its grid
    DELT = CINT/10 are exact for X = t)."""
    run = amilpy.loads(GUARDED, "guarded.csl").run(method=method, advice=False)[0]
    assert run.ok, run.message
    assert abs(run.final["Z"] - (2.0 - math.exp(-1.0) + 0.91)) < 1e-9
    turns = [e.time for e in run.events if "LOG" in e.switch]
    assert turns and abs(turns[-1] - (0.5 + math.exp(-1.0))) < 1e-9


def test_the_rows_before_a_fault_in_a_test_are_kept():
    """1/(X - 1) < 0 read at every step, X = t: the test has no value at TIME 1, a row
    instant. The rows before it are printed (they were lost with the batch of rows
    the fault fell in) and the run stops at TIME 1, where the test was evaluated
    (it said TIME 0, where the step began), with the operand that was 0 and the
    test's line once."""
    text = ("PROGRAM pole\n  CINTERVAL CINT = 0.5\n  DERIVATIVE\n    PROCEDURAL (Y = X)\n"
            "      IF (1.0/(X - 1.0) .LT. 0.0) THEN\n        Y = 1.0\n      ELSE\n"
            "        Y = 2.0\n      END IF\n    END\n    X = INTEG(1.0, 0.0)\n"
            "    Z = INTEG(Y, 0.0)\n    TERMT(T >= 2.0)\n  END\nEND\n")
    run = amilpy.loads(text, "pole.csl").run(advice=False)[0]
    assert not run.ok and "TIME = 1:" in run.message
    assert "division by zero: X - 1.0 = 0" in run.message
    assert "at line 5" in run.message and "(line 5)" not in run.message
    assert list(run.t[:2]) == [0.0, 0.5] and abs(run["Z"][1] - 0.5) < 1e-12


ACOS_TEST = """PROGRAM a test with no value past its branch
  CINTERVAL CINT = 0.25
  INITIAL
    SCHEDULE UP .AT. TUP
  END
  DERIVATIVE
    CONSTANT X0 = 0.0, V = 1.0, TUP = 9.0, JUMP = 0.0
    PROCEDURAL (Y = X)
      IF (X .GT. 1.0) THEN
        Y = 0.0
      ELSE IF (ACOS(X) .GT. 1.0) THEN
        Y = 1.0
      ELSE
        Y = 2.0
      END IF
    END
    X = INTEG(V, X0)
    Z = INTEG(Y, 0.0)
    TERMT(T >= 1.5)
  END
  DISCRETE UP
    X = X + JUMP
  END
END
"""


@pytest.mark.parametrize("values, expected", [
    # X = t leaves the ELSE IF's branch inside a step: ACOS(X) is not read past X = 1
    # (the step's end was read with the branch it began in: math domain error)
    ({}, math.cos(1.0) + 2.0 * (1.0 - math.cos(1.0))),
    # X = 1.5 - t starts where the ELSE IF is not read (the first modes are zeros: it
    # was read, and the run could not start)
    ({"X0": 1.5, "V": -1.0}, math.cos(1.0) + 2.0 * (1.0 - math.cos(1.0))),
    # a DISCRETE section moves X from 0.4 to 1.1 past the branch: the restart reads
    # the test after it, where the program does (it was read at X = 1.1). Y = 1 up to
    # TIME 0.4 (X < cos 1), 0 after (X > 1)
    ({"TUP": 0.4, "JUMP": 0.7}, 0.4),
])
@pytest.mark.parametrize("method", ["AUTO", "RKS", "DOP853", "RK4"])
def test_a_test_past_its_branch_is_not_read(values, expected, method):
    """ACOS(X) has no value for X > 1, where the IF before it takes its own branch.
    Y = 2 while ACOS(X) <= 1 (X >= cos 1), 1 below, 0 above X = 1; Z = int Y dt,
    exact at the located crossings (1e-9)."""
    run = amilpy.loads(ACOS_TEST, "acos.csl").run(method=method, advice=False,
                                                  **values)[0]
    assert run.ok, run.message
    assert abs(run.final["Z"] - expected) < 1e-9


IF_READS_WHAT_IT_ASSIGNS = """PROGRAM p
DERIVATIVE
X = INTEG(1.0, 1.0)
PROCEDURAL (Y, Z = X)
  F = X - 1.5
  IF (F .GT. 0.0) THEN
     F = 0.0
     Z = X
  ELSE
     Z = -X
  END IF
  Y = Z + F
END
CINTERVAL CINT = 0.25
TERMT (T .GE. 1.0)
END
END
"""


@pytest.mark.parametrize("seed", ["0", "1"])
def test_an_if_that_assigns_a_name_its_test_reads_selects_by_the_test_before(seed, tmp_path):
    """After IF (F > 0) THEN F = 0; Z = X ..., Z is X where F was positive before the
    IF: each name the IF assigns is selected by its tests as they read before it. The
    selection of Z once read F's value after the IF where F came first in a set's
    order, which Python's hash seed decides: Y = Z + F was -X at T = 1 under seed 1
    (a run in a process of each seed here, as a user's would be)."""
    import json
    import os
    import subprocess
    import sys

    (tmp_path / "p.csl").write_text(IF_READS_WHAT_IT_ASSIGNS)
    code = ("import json, amilpy; r, = amilpy.load('p.csl').run(advice=False, "
            "outputs=['Y', 'Z']); print(json.dumps([list(map(float, r.t)), "
            "list(map(float, r['Y']))]))")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, env={**os.environ, "PYTHONHASHSEED": seed}, check=True)
    t, y = json.loads(out.stdout)
    x = [1.0 + s for s in t]
    # F = X - 1.5 where X <= 1.5 (Z = -X), else F = 0 and Z = X
    assert y == pytest.approx([-1.5 if xi <= 1.5 else xi for xi in x], abs=1e-12)
