"""The ACSL form (contract section 9): a PROGRAM or MODEL of nested sections, END closing
the innermost block, sorted DERIVATIVE, written-order INITIAL/DYNAMIC/DISCRETE/TERMINAL,
T as time, CINTERVAL rows, all states printed when nothing is asked, the order of one
run. Numbers are checked against closed forms."""

import math

import numpy as np
import pytest

import amilpy
from amilpy.diagnostics import AmilError


def load(text: str) -> amilpy.Model:
    return amilpy.loads(text, name="p.csl")


def run(text: str, **kw):
    runs = load(text).run(**kw)
    assert len(runs) == 1
    return runs[0]


def fault(text: str) -> AmilError:
    with pytest.raises(AmilError) as err:
        load(text)
    return err.value


DECAY = """MODEL decay           ! X' = -K X, rows every CINT
  INITIAL
    CONSTANT K = 0.5, X0 = 2.0, TSTOP = 2.0
    CINTERVAL CINT = 0.25
  END
  DYNAMIC
    DERIVATIVE
      X = INTEG(-K*X, X0)
      TERMT(T >= TSTOP, 'time limit')
    END
  END
END
"""


def test_rows_every_cint_up_to_the_termt_instant():
    r = run(DECAY, rtol=1e-10, atol=1e-12)
    assert np.allclose(r.t, np.arange(9) * 0.25, rtol=0, atol=1e-15)
    assert np.max(np.abs(r["X"] - 2.0 * np.exp(-0.5 * r.t))) < 1e-9
    assert r.status == "stopped" and r.message.startswith("stopped at TIME = 2: time limit")


def test_no_print_statement_prints_t_and_every_state():
    m = load(DECAY.replace("X = INTEG(-K*X, X0)", "X = INTEG(-K*X, X0)\n      R = K*X"))
    from amilpy.output.printout import format_run

    out = format_run(m.run()[0])
    header = next(line for line in out.splitlines() if "TIME" in line)
    assert header.split() == ["TIME", "X"]  # R is not a state


def test_sections_nest_and_end_closes_the_innermost():
    # INITIAL inside DYNAMIC, CONSTANT inside DERIVATIVE, DISCRETE inside DERIVATIVE
    # (surprises 1 and 2 of tests/listings/SOURCES.md: accepted, as ACSL has them)
    r = run("""PROGRAM nested
  DYNAMIC
    INITIAL
      A0 = 3.0
    END
    DERIVATIVE
      CONSTANT RATE = 2.0, TSTOP = 1.0
      Y = INTEG(RATE, A0)
      DISCRETE never
        Y = 0.0
      END
      TERMT(T >= TSTOP)
    END
  END
END
""")
    assert r["Y"][-1] == pytest.approx(5.0, rel=1e-9)


def test_without_sections_everything_is_derivative():
    r = run("PROGRAM p\nCONSTANT TSTOP = 1.0\nX = INTEG(1.0, 0.0)\nTERMT(T >= TSTOP)\nEND\n")
    assert r["X"][-1] == pytest.approx(1.0)


def test_written_order_initial_allows_reassignment():
    r = run("""PROGRAM count
  INITIAL
    N = 1.0
    N = N + 1.0
    N = N*10.0
    CONSTANT TSTOP = 1.0
  END
  DERIVATIVE
    X = INTEG(N, 0.0)
    TERMT(T >= TSTOP)
  END
END
""")
    assert r.constants["N"] == 20.0 and r["X"][-1] == pytest.approx(20.0, rel=1e-9)


def test_reading_a_name_before_it_has_a_value_gives_zero_and_a_warning():
    m = load("""PROGRAM p
  INITIAL
    A = B + 1.0
    B = 5.0
  END
  DERIVATIVE
    X = INTEG(A + B, 0.0)
    TERMT(T >= 1.0)
  END
END
""")
    w, = m.ir.warnings
    assert w.severity == "warning" and w.span.line == 3
    assert "B is read at line 3 before it has a value (first assigned at line 4)" in w.message
    r, = m.run()
    assert r["X"][-1] == pytest.approx(6.0, rel=1e-9)  # A = 0 + 1, B = 5
    assert any("line 3: B is read" in n for n in r.warnings)


def test_time_is_t_and_time_too_and_variable_renames_it():
    r = run("PROGRAM p\nDERIVATIVE\nX = INTEG(T + TIME, 0.0)\nTERMT(T >= 2.0)\nEND\nEND\n")
    assert r["X"][-1] == pytest.approx(4.0, rel=1e-9)  # 2 * t^2/2 at t = 2
    r = run("PROGRAM p\nVARIABLE S = 1.0\nCINTERVAL CI = 0.5\nDERIVATIVE\n"
            "X = INTEG(S, 0.0)\nTERMT(S >= 2.0)\nEND\nEND\n")
    assert list(r.t) == [1.0, 1.5, 2.0]  # time starts at 1 and is called S
    assert r["X"][-1] == pytest.approx((4.0 - 1.0) / 2.0, rel=1e-9)


def test_a_listing_may_name_a_variable_time():
    # A10 (spring.csl): `time = INTEG(1.0, 0.0)`; ACSL's time is T, so this TIME is a
    # state of its own (surprise 3: accepted), kept as TIME_
    r = run("PROGRAM p\nDERIVATIVE\ntime = INTEG(2.0, 0.0)\nTERMT(T >= 1.0)\nEND\nEND\n")
    assert r["TIME_"][-1] == pytest.approx(2.0) and r.t[-1] == pytest.approx(1.0)


def test_an_acsl_program_that_defines_pi_computes_with_its_own():
    """ACSL has no PI of its own, and its listings define one (the EPA lead model's
    CONSTANT PI = 3.141592): the listing's value is used, as a CONSTANT or assigned
    in INITIAL. X = PI*W*t. A program that defines none reads pi."""
    text = ("PROGRAM p\n  CONSTANT {pi}W = 2.0\n  INITIAL\n    {init}\n  END\n"
            "  DERIVATIVE\n    X = INTEG(PI*W, 0.0)\n    TERMT(T >= 1.0)\n  END\n"
            "  CINTERVAL CINT = 0.5\nEND\n")
    for pi, init, value in (("PI = 3.0, ", "V = 1.0", 3.0), ("", "PI = 3.5", 3.5),
                            ("", "V = 1.0", math.pi)):
        run, = amilpy.loads(text.format(pi=pi, init=init), "pi.csl").run(advice=False)
        assert run["X"][-1] == pytest.approx(2.0 * value, rel=1e-9)
    # a CONSTANT PI is data like any other: set from outside
    run, = amilpy.loads(text.format(pi="PI = 3.0, ", init="V = 1.0"), "pi.csl").run(
        advice=False, PI=4.0)
    assert run["X"][-1] == pytest.approx(8.0, rel=1e-9)


def test_an_empty_unnamed_discrete_section_is_read_and_a_full_one_needs_a_name():
    """The EPA lead model keeps an empty `DISCRETE ... END` from its template: it runs
    nothing, so it needs no name. One with statements does: nothing could run it."""
    text = ("PROGRAM p\n  DYNAMIC\n    DERIVATIVE\n      X = INTEG(1.0, 0.0)\n    END\n"
            "    DISCRETE   ! START OF DISCRETE SECTION\n{body}    END\n"
            "    TERMT(T >= 1.0)\n  END\n  CINTERVAL CINT = 0.5\nEND\n")
    run, = amilpy.loads(text.format(body="\n"), "d.csl").run(advice=False)
    assert run["X"][-1] == pytest.approx(1.0, rel=1e-12)
    with pytest.raises(AmilError) as err:
        amilpy.loads(text.format(body="      X = 0.0\n"), "d.csl")
    assert "a DISCRETE section needs a name" in err.value.render()
    assert err.value.diagnostics[0].span.line == 6


def test_cinterval_reassigned_in_initial_and_later():
    r = run("""PROGRAM p
  INITIAL
    CONSTANT TSTOP = 3.0, POINTS = 6.0
    CINT = TSTOP/POINTS
    SCHEDULE FINER .AT. 1.0
  END
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    TERMT(T >= TSTOP)
  END
  DISCRETE FINER
    CINT = 0.25        ! from the next instant on
  END
END
""")
    assert np.allclose(r.t, [0, 0.5, 1.0, 1.25, 1.5, 1.75, 2.0, 2.25, 2.5, 2.75, 3.0])


def test_constant_cint_is_the_output_interval():
    # A11, A12: `CONSTANT CINT = 1.0` with no CINTERVAL (surprise 4: accepted)
    r = run("PROGRAM p\nCONSTANT CINT = 0.5\nDERIVATIVE\nX = INTEG(1.0, 0.0)\n"
            "TERMT(T >= 1.0)\nEND\nEND\n")
    assert list(r.t) == [0.0, 0.5, 1.0]


def test_dynamic_statements_run_at_every_cint_instant_in_written_order():
    # the DYNAMIC block's own statements see the state at the instant; N counts them
    r = run("""PROGRAM p
  INITIAL
    CINTERVAL CINT = 0.5
    N = 0.0
  END
  DYNAMIC
    DERIVATIVE
      X = INTEG(1.0, 0.0)
      TERMT(T >= 2.0)
    END
    N = N + 1.0
    SEEN = X
  END
END
""")
    assert list(r["N"]) == [1.0, 2.0, 3.0, 4.0, 5.0]
    assert np.allclose(r["SEEN"], r.t, atol=1e-12)


def test_order_of_one_run_events_at_t0_before_the_first_row():
    # constants -> INITIAL -> states -> events due at t0 -> DYNAMIC -> row: the row at
    # t0 shows what the DISCRETE due at t0 set, and DYNAMIC saw it
    r = run("""PROGRAM p
  INITIAL
    CINTERVAL CINT = 1.0
    RATE = 1.0
    SCHEDULE DOUBLE .AT. 0.0
  END
  DYNAMIC
    DERIVATIVE
      X = INTEG(RATE, 0.0)
      TERMT(T >= 2.0)
    END
    SEENRATE = RATE
  END
  DISCRETE DOUBLE
    RATE = 2.0*RATE
  END
END
""")
    assert list(r["RATE"]) == [2.0, 2.0, 2.0] and r["SEENRATE"][0] == 2.0
    assert r["X"][-1] == pytest.approx(4.0)


def test_terminal_runs_after_the_last_row_in_written_order():
    r = run("""PROGRAM p
  DERIVATIVE
    X = INTEG(1.0, 0.0)
    TERMT(T >= 2.0)
  END
  TERMINAL
    Y = X*10.0
    Y = Y + 1.0
  END
END
""")
    assert r.terminal == {"Y": pytest.approx(21.0)}


def test_a_run_must_be_bounded():
    err = fault("PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, 0.0)\nEND\nEND\n")
    assert "nothing ends the run" in err.diagnostics[0].message
    assert "TERMT" in err.diagnostics[0].hint


def test_timer_fintim_bounds_a_run_without_termt():
    r = run("PROGRAM p\nTIMER FINTIM = 1.0\nCINTERVAL CINT = 0.5\nDERIVATIVE\n"
            "X = INTEG(1.0, 0.0)\nEND\nEND\n")
    assert list(r.t) == [0.0, 0.5, 1.0] and r.status == "finished"


@pytest.mark.parametrize("text, message", [
    ("PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, 0.0)\nTERMT(T >= 1.0)\n",
     "DERIVATIVE opened at line 2 is never closed"),
    ("PROGRAM p\nDERIVATIVE\nIF (T > 1.0) THEN\nX = 1.0\nEND DO\nEND\nEND\n",
     "END DO closes a DO loop, but the innermost open block is the IF of line 3"),
    ("PROGRAM p\nY = 1.0\nDERIVATIVE\nX = INTEG(Y, 0.0)\nTERMT(T >= 1.0)\nEND\nEND\n",
     "outside the sections only declarations may stand"),
    ("PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, 0.0)\nX = 2.0\nTERMT(T >= 1.0)\nEND\nEND\n",
     "X is defined twice"),
    # (in INITIAL a CONSTANT may be given a new value, as Magnolia allows:
    # test_magnolia.py; in a DISCRETE section it may not)
    ("PROGRAM p\nCONSTANT A = 1.0\nDERIVATIVE\nX = INTEG(A, 0.)\n"
     "TERMT(T >= 1.0)\nEND\nDISCRETE D\nINTERVAL DT = 0.5\nA = 2.0\nEND\nEND\n",
     "A is a CONSTANT and cannot be assigned"),
    ("PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, Y)\nY = X\nTERMT(T >= 1.0)\nEND\nEND\n",
     "the initial value uses Y, which changes in time"),
    ("PROGRAM p\nINITIAL\nSCHEDULE NOPE .AT. 1.0\nEND\nDERIVATIVE\nX = INTEG(1.0, 0.)\n"
     "TERMT(T >= 1.0)\nEND\nDISCRETE NOPF\nEND\nEND\n",
     "SCHEDULE names NOPE, which is no DISCRETE section"),
])
def test_structure_faults_name_the_block_and_its_line(text, message):
    err = fault(text)
    assert any(message in d.message for d in err.diagnostics), err.render()


@pytest.mark.parametrize("after", ["Y = 2.0\n", "END\n", "  TERMT(T >= 5.0)\nEND ! PROGRAM\n"])
def test_text_after_the_programs_end_is_not_read_and_said(after):
    """ACSL's translator reads a program up to its END (published listings leave a
    second TERMT/END block there): not read, with a warning that says where."""
    text = "PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, 0.0)\nTERMT(T >= 1.0)\nEND\nEND\n" + after
    model = amilpy.loads(text, "p.csl")
    assert any("the text after the program's END (line 6) is not read" in str(w)
               for w in model.ir.warnings)
    assert run(text)["X"][-1] == pytest.approx(1.0)


def test_integ_initial_value_is_evaluated_after_initial():
    r = run("PROGRAM p\nINITIAL\nX0 = 4.0\nX0 = X0*2.0\nEND\nDERIVATIVE\n"
            "X = INTEG(0.0, X0)\nTERMT(T >= 1.0)\nEND\nEND\n")
    assert r["X"][0] == 8.0


def test_a_csmp_form_t_hints_time():
    with pytest.raises(AmilError) as err:
        amilpy.loads("X = INTGRL(0.0, T)\nTIMER FINTIM = 1.0\nEND\n")
    d = err.value.diagnostics[0]
    assert d.message == "T is used but never defined" and "time is TIME" in d.hint


def test_acsl_statements_in_csmp_form_say_which_form_they_belong_to():
    with pytest.raises(AmilError) as err:
        amilpy.loads("X = INTGRL(0.0, 1.0)\nSCHEDULE A .AT. 1.0\nTIMER FINTIM = 1.0\nEND\n")
    d = err.value.diagnostics[0]
    assert "belongs to the ACSL form" in d.message and "PROGRAM or MODEL" in d.hint


def test_exact_exponential_on_a_finer_check():
    # the TERMT instant is exact on time alone (a breakpoint), whatever CINT is
    r = run(DECAY.replace("TSTOP = 2.0", "TSTOP = 1.9"))
    assert r.t[-1] == 1.9 and r.t[-2] == 1.75
    assert r["X"][-1] == pytest.approx(2.0 * math.exp(-0.95), rel=1e-6)


def test_molly_style_punctuation_and_blocks_are_read():
    # A12: `END; !OF DERIVATIVE`, `Discrete NewDay $!comment`, INCLUDED ... END (the
    # text an ACSL INCLUDE brought in), Fortran's PARAMETER (N = v), `dimension integer i`
    # and `Procedural()` with empty lists (SOURCES.md surprises 6, 9, 11: accepted)
    r = run("""PROGRAM molly style
  INITIAL
    INCLUDED ! INCLUDE 'constants.csl'
      Parameter (NFEED = 2)
    END ! INCLUDE
    dimension integer I
    CINTERVAL CINT = 0.5
  END
  DERIVATIVE
    Procedural()
      Q = 1.0
    END
    Procedural(=X)
      R = X
    END
    X = INTEG(Q*NFEED, 0.0)
    Y = INTEG(R, 0.0)
    TERMT(T >= 1.0)
  END; !OF DERIVATIVE
  Discrete NewDay                $!Schedules nothing
    I = 1.9
  END
END
""")
    assert r["X"][-1] == pytest.approx(2.0) and r["Y"][-1] == pytest.approx(1.0)


def test_pi_may_be_assigned_in_acsl_form():
    # PI is no reserved name of ACSL (SOURCES.md surprise 10, in ACSL form)
    r = run("PROGRAM p\nINITIAL\nPI = 3.0\nEND\nDERIVATIVE\nX = INTEG(PI, 0.0)\n"
            "TERMT(T >= 1.0)\nEND\nEND\n")
    assert r["X"][-1] == pytest.approx(3.0)


def test_program_colon_and_padding_after_the_last_line():
    """`PROGRAM: name` (acslX listings of the EPA lead model open so) is the program,
    not a statement label; NULs and ^Z after the last line (an old editor's padding,
    DOS's end-of-file mark) are not read."""
    text = ("PROGRAM: demo\nDERIVATIVE\nX = INTEG(1.0, 0.0)\nTERMT(T >= 1.0)\nEND\nEND\r\n"
            "\x00\x00\x1a")
    model = amilpy.loads(text, "p.csl")
    assert model.ir.name == "demo" or model.ir.name.endswith("p.csl")
    assert run(text)["X"][-1] == pytest.approx(1.0)


def ticking(cint: str, fintim: str, interval: str, extra: str = "") -> str:
    """A state driven by N, the count of the ticks of a DISCRETE section every
    `interval` (`extra`: more statements of that section)."""
    return f"""PROGRAM p
  CINTERVAL CINT = {cint}
  TIMER FINTIM = {fintim}
  INITIAL
    N = 0.0
  END
  DERIVATIVE
    X = INTEG(-X + N, 1.0)
  END
  DISCRETE TICK
    INTERVAL DT = {interval}
    N = N + 1.0{extra}
  END
  PRINT X, N
END
"""


def test_a_termt_of_code_at_an_instant_off_the_grid_ends_there_with_its_row():
    """TERMT inside DISCRETE at T = 1.125 (ticks every 0.375, rows every 0.5): the run
    stops there and its last row is that instant, after the tick (N = 4): the final
    values were the 1.0 row's (N = 3), and TERMINAL read them."""
    run, = amilpy.loads(ticking("0.5", "5.0", "0.375",
                                "\n    TERMT(T >= 1.1, 'ticked enough')"),
                        "p.csl").run(advice=False)
    assert run.status == "stopped" and "ticked enough" in run.message
    assert list(run.t) == [0.0, 0.5, 1.0, 1.125]
    assert run["N"][-1] == 4.0 and run.final["N"] == 4.0


def test_fintim_a_float_after_the_last_event_finishes():
    """INTERVAL 0.7 three times is 2.0999999999999996, a float before FINTIM = 2.1:
    the run went on to integrate that one float and LSODA refused it ("Unexpected
    istate"); it finishes at 2.1 after the third tick."""
    run, = amilpy.loads(ticking("0.25", "2.1", "0.7"), "p.csl").run(advice=False)
    assert run.status == "finished" and run.t_end == 2.1 and run.final["N"] == 4.0


def test_a_function_faulting_at_a_row_gives_nan_there_and_says_so():
    """1/(T - 1) at the row T = 1: NaN in that row with a warning, as before FUNCTIONs
    ran on NumPy columns (where 1/0 is inf, silently)."""
    run, = amilpy.loads("""PROGRAM p
  CINTERVAL CINT = 0.25
  FUNCTION R = INV(V)
    R = 1.0/V
  END
  DERIVATIVE
    X = INTEG(-X, 1.0)
    Y = INV(T - 1.0)*X
    TERMT(T >= 2.0)
  END
  PRINT X, Y
END
""", "p.csl").run(advice=False)
    assert math.isnan(run["Y"][4]) and math.isfinite(run["Y"][3])
    assert any("division by zero at TIME = 1" in w for w in run.warnings)


@pytest.mark.parametrize("cint", ["0.3", "0.5"])  # (1.0 off the grid, and on it)
def test_a_termt_a_float_after_an_event_stops_there(cint):
    """Ten ticks of 0.1 reach 0.9999999999999999, a float before TERMT(T >= 1.0): the
    integration loop took the TERMT's instant, that close, as passed, and the run went
    on to the next tick (stopped at 1.1). It stops at 1.0, its last row there (one
    row: with a grid instant at 1.0, the row after the tick is that row)."""
    run, = amilpy.loads(f"""PROGRAM p
  CINTERVAL CINT = {cint}
  DERIVATIVE
    X = INTEG(-2.0*X, 1.0)
    TERMT(T >= 1.0)
  END
  DISCRETE DOSE
    INTERVAL DT = 0.1
    X = X + 1.0
  END
  PRINT X
END
""", "p.csl").run(advice=False)
    assert run.status == "stopped" and run.t_end == 1.0 and run.t[-1] == 1.0
    assert np.all(np.diff(run.t) > 0)
    # eleven doses at 0, 0.1, ..., 0.9999999999999999 (the last a float before the
    # TERMT), each decaying at rate 2 to T = 1
    x = math.exp(-2.0) + sum(math.exp(-2.0 * (1.0 - 0.1 * k)) for k in range(11))
    assert run.final["X"] == pytest.approx(x, rel=1e-9)


def test_a_stop_a_float_from_a_grid_instant_is_one_row():
    """The grid's fourth instant is 3 x 0.1 = 0.30000000000000004, a float after
    TERMT(T >= 0.3): the run printed the state there twice, the second row (the
    stop's, at 0.3) a float before the first. One row now, and TIME increases."""
    run, = amilpy.loads("""PROGRAM p
  CINTERVAL CINT = 0.1
  DERIVATIVE
    X = INTEG(-X, 1.0)
    TERMT(T >= 0.3)
  END
  PRINT X
END
""", "p.csl").run(advice=False)
    assert len(run.t) == 4 and np.all(np.diff(run.t) > 0) and run.t_end == 0.3
    assert run.final["X"] == pytest.approx(math.exp(-0.3), rel=1e-9)


def test_a_dynamic_block_on_the_euler_route_keeps_every_cint_row():
    """METHOD EULER runs step point by step point; DYNAMIC's code at each CINT instant
    restarts it there, and the next call's last step point is the next CINT instant
    (0.09 + 10*0.001 is not 0.1 in floats): every row is kept. The rows stopped
    after TIME = 0.09 (11 rows, the next at 20), found by a review. Euler exactly:
    X = t, Y = (1 - DELT)^(t/DELT) (1e-12 relative: the same products)."""
    text = """PROGRAM dynamic statements at each CINT instant
  INITIAL
    CINTERVAL CINT = 0.01
    N = 0.0
  END
  DYNAMIC
    DERIVATIVE
      X = INTEG(1.0, 0.0)
      Y = INTEG(-Y, 1.0)
      TERMT(T >= 2.0)
    END
    N = N + 1.0
  END
END
"""
    run = amilpy.loads(text, "dyn.csl").run(method="EULER", advice=False)[0]
    assert len(run.t) == 201 and run.t[-1] == pytest.approx(2.0)
    np.testing.assert_allclose(run.values["X"], run.t, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(run.values["Y"], (1.0 - 1e-3) ** np.rint(run.t / 1e-3),
                               rtol=1e-12)
