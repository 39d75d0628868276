"""CSMP III's additions (contract section 13): MACRO expansion, IMPL loops, NOSORT
regions and FIXED, each against a closed form or a root found separately."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import amilpy
from amilpy.diagnostics import AmilError

LAGS = """TITLE TWO SECOND-ORDER LAGS BY ONE MACRO
MACRO Y = LAG2(T, X)
   Y1 = REALPL(0., T, X)
   Y  = REALPL(0., T, Y1)
ENDMAC
PARAM TA = 0.5, TB = 0.2
U  = STEP(0.)
A  = LAG2(TA, U)
B  = LAG2(TB, 2.*U)
TIMER FINTIM = 3., PRDEL = 0.5
PRINT A, B
END
STOP
"""


def _lag2(t: float, tau: float) -> float:
    """Two first-order lags of time constant tau in series, unit step at 0."""
    return 1.0 - (1.0 + t / tau) * math.exp(-t / tau)


def test_a_macro_called_twice_gives_each_call_its_own_states():
    # each call expands to two REALPLs of its own (LAG2#1.Y1, LAG2#2.Y1): the step
    # response of two lags in series, 1 - (1 + t/T) exp(-t/T), for each T; at the
    # tolerances given, to 1e-7
    model = amilpy.loads(LAGS)
    run, = model.run(rtol=1e-9, atol=1e-12, advice=False)
    for t, a, b in zip(run.times, run.values["A"], run.values["B"], strict=True):
        assert a == pytest.approx(_lag2(t, 0.5), abs=1e-7)
        assert b == pytest.approx(2.0 * _lag2(t, 0.2), abs=1e-7)
    assert {s.name for s in model.ir.states} == {"A", "B", "LAG2#1.Y1", "LAG2#2.Y1"}


def test_macros_call_macros_and_give_two_outputs():
    text = """TITLE NESTED MACROS
MACRO Y = LAG(T, X)
   Y = REALPL(0., T, X)
ENDMAC
MACRO P, Q = PAIR(T, X)
   P = LAG(T, X)
   Q = LAG(T, P)
ENDMAC
A, B = PAIR(0.5, STEP(0.))
TIMER FINTIM = 2., PRDEL = 0.5
PRINT A, B
END
"""
    run, = amilpy.loads(text).run(rtol=1e-9, atol=1e-12, advice=False)
    for t, a, b in zip(run.times, run.values["A"], run.values["B"], strict=True):
        assert a == pytest.approx(1.0 - math.exp(-t / 0.5), abs=1e-7)
        assert b == pytest.approx(_lag2(t, 0.5), abs=1e-7)


@pytest.mark.parametrize("text, message, hint", [
    (LAGS.replace("A  = LAG2(TA, U)", "A  = LAG2(TA)"),
     "LAG2 takes 2 argument(s) and gives 1 value(s): MACRO Y = LAG2(T, X) (line 2)",
     "write Y = LAG2(T, X)"),
    (LAGS.replace("A  = LAG2(TA, U)", "A  = 2.*LAG2(TA, U)"),
     "MACRO LAG2 is called inside an expression", "call it as a statement"),
    (LAGS.replace("   Y1 = REALPL(0., T, X)", "   Y1 = LAG2(T, X)"),
     "MACRO LAG2 calls itself", "not itself"),
    (LAGS.replace("   Y1 = REALPL(0., T, X)", "   T = 1.\n   Y1 = REALPL(0., T, X)"),
     "MACRO LAG2 assigns its parameter T", "another name"),
    (LAGS.replace("ENDMAC\n", ""), "MACRO opened at line 2 is never closed", "ENDMAC"),
])
def test_macro_faults_are_located_and_say_what_to_write(text, message, hint):
    with pytest.raises(AmilError) as err:
        amilpy.loads(text)
    rendered = err.value.render()
    assert message in rendered and hint in rendered, rendered


def test_an_acsl_macro_left_open_says_how_it_ends():
    # (ACSL's MACRO is expanded: tests/test_acsl_macro.py; its END is MACRO END)
    text = "PROGRAM P\nMACRO MYLAG(Y, X, T)\nEND\n"
    with pytest.raises(AmilError) as err:
        amilpy.loads(text)
    assert "END inside the MACRO of line 2" in err.value.render()
    assert "a MACRO ends with MACRO END" in err.value.render()


def test_impl_solves_the_dottie_number():
    # Y = cos(Y): 0.7390851332..., by fixed-point iteration (rate |sin Y| = 0.67) to
    # |F - Y| <= 1e-8, so Y is within 1e-8/(1 - 0.67) of the root found by brentq
    text = """TITLE DOTTIE
Y = IMPL(1., 1.E-8, F)
F = COS(Y)
X = INTGRL(0., Y)
TIMER FINTIM = 1., PRDEL = 0.5
PRINT Y, X
END
"""
    root = brentq(lambda y: math.cos(y) - y, 0.0, 1.0)
    run, = amilpy.loads(text).run(advice=False)
    assert np.allclose(run.values["Y"], root, atol=4e-8)
    assert run.values["X"][-1] == pytest.approx(root, rel=1e-6)


def test_impl_follows_a_state_from_the_last_accepted_value():
    # Y = (Y + X)/2 is solved by Y = X; with X' = -Y, X = exp(-t). Each solve starts
    # from the Y of the last accepted step (IC = 5 at first, far from X(0) = 1)
    text = """TITLE IMPL WITH A STATE
Y = IMPL(5., 1.E-12, F)
F = 0.5*Y + 0.5*X
X = INTGRL(1., -Y)
TIMER FINTIM = 2., PRDEL = 0.25
PRINT X, Y
END
"""
    run, = amilpy.loads(text).run(rtol=1e-10, atol=1e-12, advice=False)
    assert np.allclose(run.values["X"], np.exp(-run.times), rtol=1e-8)
    assert np.allclose(run.values["Y"], run.values["X"], rtol=1e-11)


def test_impl_that_does_not_converge_names_y_the_time_and_the_residual():
    text = """TITLE DIVERGES
Y = IMPL(1., 1.E-8, F)
F = COS(2.*Y)
X = INTGRL(0., Y)
TIMER FINTIM = 1.
PRINT X
END
"""
    run, = amilpy.loads(text).run(advice=False)
    assert not run.ok
    assert "IMPL for Y did not converge in 50 iterations at TIME = 0" in run.message
    assert "|FOFY - Y|" in run.message


def test_impl_without_its_closing_statement_is_an_error():
    with pytest.raises(AmilError) as err:
        amilpy.loads("TITLE T\nY = IMPL(1., 1.E-8, F)\nX = INTGRL(0., Y)\n"
                     "TIMER FINTIM = 1.\nPRINT X\nEND\n")
    assert "IMPL for Y: no statement F = ... follows" in err.value.render()


def test_nosort_runs_a_region_in_written_order():
    # S is assigned three times in written order: S = X*X + 1 with X = exp(-2t)
    text = """TITLE NOSORT
PARAM K = 2.0
DYNAMIC
Y = S - 1.
X = INTGRL(1., -K*X)
NOSORT
   S = X
   S = S*S
   S = S + 1.
SORT
TIMER FINTIM = 1., PRDEL = 0.5
PRINT X, S, Y
END
"""
    run, = amilpy.loads(text).run(rtol=1e-10, atol=1e-12, advice=False)
    x = np.exp(-2.0 * run.times)
    assert np.allclose(run.values["S"], x * x + 1.0, rtol=1e-9)
    assert np.allclose(run.values["Y"], x * x, rtol=1e-8)


def test_fixed_declares_integer_names():
    # FIXED N: an assignment to N keeps the whole part (Fortran's truncation)
    text = "TITLE FIXED\nFIXED N\nPARAM A = 2.7\nN = A\nX = INTGRL(0., N)\n" \
           "TIMER FINTIM = 1.\nPRINT X, N\nEND\n"
    run, = amilpy.loads(text).run(advice=False)
    assert set(run.values["N"]) == {2.0}
    assert run.values["X"][-1] == pytest.approx(2.0, rel=1e-9)


def test_procedure_is_a_sorted_unit_with_its_lists():
    # PROCEDURE Y, Z = P(X) ... ENDPRO: written order inside, sorted as one unit
    # (it stands before X's statement); with X = exp(-t), Y = 2X and Z = Y + 1
    text = """TITLE PROCEDURE
PROCEDURE Y, Z = P(X)
  Y = 2.*X
  Z = Y + 1.
ENDPRO
X = INTGRL(1., -X)
TIMER FINTIM = 1., PRDEL = 0.5
PRINT Y, Z
END
"""
    run, = amilpy.loads(text).run(rtol=1e-10, atol=1e-12, advice=False)
    x = np.exp(-run.times)
    assert np.allclose(run.values["Y"], 2.0 * x, rtol=1e-9)
    assert np.allclose(run.values["Z"], 2.0 * x + 1.0, rtol=1e-9)
    with pytest.raises(AmilError) as err:
        amilpy.loads(text.replace("ENDPRO", "ENDMAC"))
    assert "ENDMAC closes a MACRO, but the innermost open block is the PROCEDURE of line 2" \
        in err.value.render()


def test_lint2_is_lint_with_fst_arguments():
    # LINT2('RDTB', RDTB, 4, TIME) = 1 + 0.2 t, extended past the table's end at 10:
    # X = t + 0.1 t^2; the name in the string must be the table's
    text = """TITLE LINT2
FUNCTION RDTB = 0., 1., 10., 3.
X = INTGRL(0., LINT2('RDTB', RDTB, 4, TIME))
TIMER FINTIM = 12., PRDEL = 2.
PRINT X
END
"""
    run, = amilpy.loads(text).run(rtol=1e-10, atol=1e-12, advice=False)
    assert np.allclose(run.values["X"], run.times + 0.1 * run.times ** 2, rtol=1e-9)
    assert any("outside its x range [0, 10]" in w for w in run.warnings)
    with pytest.raises(AmilError) as err:
        amilpy.loads(text.replace("LINT2('RDTB'", "LINT2('XX'"))
    assert err.value.render().count("LINT2 names the table 'XX' but reads another") == 1


def test_procedure_in_initial_is_refused_and_in_terminal_runs_in_order():
    initial = """TITLE P
INITIAL
PROCEDURE Y = P(A)
  Y = 2.*A
ENDPRO
PARAM A = 1.
DYNAMIC
X = INTGRL(1., -X)
TIMER FINTIM = 1.
PRINT X
END
"""
    with pytest.raises(AmilError) as err:
        amilpy.loads(initial)
    assert "a PROCEDURE block (or a CALL of a subroutine, or a reference to a FUNCTION " \
        "written after STOP) cannot stand in INITIAL" in err.value.render()
    terminal = """TITLE P
X = INTGRL(1., -X)
TERMINAL
PROCEDURE Z = P(X)
  Z = 2.*X
ENDPRO
TIMER FINTIM = 1.
PRINT X
END
"""
    run, = amilpy.loads(terminal).run(rtol=1e-10, atol=1e-12, advice=False)
    assert run.terminal["Z"] == pytest.approx(2.0 * math.exp(-1.0), rel=1e-9)


def test_a_fault_in_a_macro_body_is_said_once_with_the_calls_it_came_through():
    text = LAGS.replace("   Y  = REALPL(0., T, Y1)", "   Y  = REALPL(0., T, Y1) + FOO(1.)")
    with pytest.raises(AmilError) as err:
        amilpy.loads(text)
    faults = [d for d in err.value.diagnostics if "unknown function FOO" in d.message]
    assert len(faults) == 1 and faults[0].span.line == 4  # the body's line
    assert [span.line for span, _ in faults[0].related] == [8, 9]  # both calls
    assert "in MACRO LAG2, called here" in err.value.render()


def test_endjob_ends_the_runs_as_stop_does():
    # CSMP III's and FST's job ends with ENDJOB, after STOP or in its place: the runs
    # before it run (X = t), and what follows it is not read (the Fortran below would
    # be a syntax error)
    body = "TITLE T\nX = INTGRL(0.0, 1.0)\nTIMER FINTIM = 1.0, PRDEL = 0.5\nEND\n"
    for ending in ("ENDJOB\n", "STOP\nENDJOB\n"):
        runs = amilpy.loads(body + ending + "      SUBROUTINE F(A)\n      A = 1\n"
                            "      RETURN\n      END\n", name="m.amil").run()
        assert len(runs) == 1 and runs[0]["X"][-1] == pytest.approx(1.0, abs=1e-12)
