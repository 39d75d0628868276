"""The Fortran subroutines written after an FST listing's STOP (issue 23, a first
subset): `CALL LEAFGR(...)` in the listing's sorted code runs SUBROUTINE LEAFGR as a
PROCEDURAL, its outputs the arguments the body assigns. A leaf-area routine in the
crop modellers' manner against the Euler recurrence written here in Python; what the
subset does not run is refused at its line, by name."""

import math

import pytest

import amilpy
from amilpy.diagnostics import AmilError

# A leaf-area routine of our own in the manner of the Wageningen crop listings (LINTUL1's
# GLA computes the same quantity): exponential juvenile growth on the temperature sum,
# then growth from the leaf weight; driven by a temperature of our own, no weather file
LISTING = """DEFINE_CALL LEAFGR(INPUT,INPUT,INPUT,INPUT,INPUT,INPUT,INPUT,INPUT, ...
                   INPUT,INPUT,OUTPUT)
TITLE LEAF AREA BY A SUBROUTINE
INITIAL
INCON ZERO = 0.
DYNAMIC
      TEMP   = 10. + 5.*SIN(2.*3.14159265*TIME/365.)
      TEFF   = MAX(0., TEMP - TBASE)
      TSUM   = INTGRL(ZERO, TEFF)
      CALL LEAFGR(TIME, TEMERG, TEFF, TSUM, AINIT, RGR, DELT, SLA, AREA, ...
                  GLEAF, RAREA)
      GLEAF  = 0.01*AREA
      AREA   = INTGRL(ZERO, RAREA)
PARAM AINIT = 0.012; SLA = 0.022; TBASE = 0.; TEMERG = 60.; RGR = 0.009
TIMER STTIME = 58.; FINTIM = 400.; DELT = 1.; PRDEL = 1.
TRANSLATION_GENERAL DRIVER='EUDRIV'
PRINT AREA, TSUM, RAREA
END
STOP

C     LEAFGR: the rate of increase of the leaf area (m2 leaf / m2 ground / d)
      SUBROUTINE LEAFGR(T, TEMRG, TE, TS, A0, R, DT, SPECA, A, GW,
     &                  RATE)
      IMPLICIT REAL (A-Z)
      IF (T .LT. TEMRG) THEN
C        not emerged yet
         RATE = 0.
      ELSE IF (A .EQ. 0.) THEN
C        the day of emergence: the initial area at once
         RATE = A0 / DT
      ELSE IF (TS .LT. 330. .AND. A .LT. 0.75) THEN
C        young crop: exponential on the temperature sum
         GROWTH = EXP(R * TE * DT) - 1.
         RATE   = A * GROWTH / DT
      ELSE
         RATE = SPECA * GW
      END IF
      RETURN
      END
"""


def euler_reference():
    """FST's EUDRIV by hand: at each day the rates from the states, then one day on."""
    out, tsum, lai = [], 0.0, 0.0
    for day in range(58, 401):
        t = float(day)
        dteff = max(0.0, 10.0 + 5.0 * math.sin(2.0 * 3.14159265 * t / 365.0))
        glai = 0.022 * (0.01 * lai)
        if tsum < 330.0 and lai < 0.75:
            glai = lai * (math.exp(0.009 * dteff) - 1.0)
        if t >= 60.0 and lai == 0.0:
            glai = 0.012
        if t < 60.0:
            glai = 0.0
        out.append((t, lai, tsum, glai))
        tsum, lai = tsum + dteff, lai + glai
    return out


def test_a_subroutine_after_stop_runs_as_the_euler_recurrence():
    # every day's LAI, TSUM and GLAI the recurrence's to round-off (1e-12 relative:
    # the same operations, summed over 342 days); the juvenile branch, the emergence
    # day and the maturation branch (TSUM passes 330 on day 85) are all taken
    run, = amilpy.loads(LISTING, name="leaf.fst").run(advice=False)
    ref = euler_reference()
    assert len(run.times) == len(ref)
    for k, (t, lai, tsum, glai) in enumerate(ref):
        assert run.times[k] == t
        assert run.values["AREA"][k] == pytest.approx(lai, rel=1e-12, abs=1e-15)
        assert run.values["TSUM"][k] == pytest.approx(tsum, rel=1e-12)
        assert run.values["RAREA"][k] == pytest.approx(glai, rel=1e-12, abs=1e-15)
    # the routine's own name is each call's: LEAFGR#1.GROWTH
    assert "LEAFGR#1.GROWTH" in run.values
    assert any(r[2] > 330.0 for r in ref) and ref[2][3] == 0.012


def _fault(subroutine: str, call: str = "CALL F(X, Y)") -> str:
    text = ("TITLE T\nX = INTGRL(0., 1.)\n" + call + "\nTIMER FINTIM = 1., DELT = 0.5\n"
            "TRANSLATION_GENERAL DRIVER='EUDRIV'\nPRINT Y\nEND\nSTOP\n" + subroutine)
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, name="f.fst")
    return err.value.render()


def _run_f(after_stop: str, fintim: float = 2.0, start: float = 1.0, delt: float = 1.0):
    """The run of a listing that calls F(X, Y), X = start + t, a step of `delt` (a day by
    default; EUDRIV), with `after_stop` after its STOP."""
    text = (f"TITLE T\nX = INTGRL({start!r}, 1.)\nCALL F(X, Y)\n"
            f"TIMER FINTIM = {fintim!r}, DELT = {delt!r}\n"
            "TRANSLATION_GENERAL DRIVER='EUDRIV'\nPRINT Y\nEND\nSTOP\n" + after_stop)
    run, = amilpy.loads(text, name="f.fst").run(advice=False)
    return run


SUB = "      SUBROUTINE F(A, B)\n      IMPLICIT REAL (A-Z)\n{body}      RETURN\n      END\n"


@pytest.mark.parametrize("body, where, words", [
    ("      GO TO 10\n      B = A\n", "11:7", "GO TO 10: no label 10 where it can jump"),
    ("   10 B = A\n      GO TO 10\n", "12:7", "GO TO 10 jumps back (to line 11): a loop"),
    ("      GO TO (10, 20), K\n   10 B = A\n   20 CONTINUE\n", "11:7",
     "a computed GO TO (SUBROUTINE F, line 11): not supported"),
    ("   10 REAL Q\n      B = A\n", "11:7",
     "the statement label 10 on a declaration (in SUBROUTINE F)"),
    # Fortran's integers where they would give other numbers: a quotient cut, a value cut
    ("      INTEGER I\n      I = 3\n      B = A*(I/2)\n", "13:14",
     "a division of whole numbers (SUBROUTINE F): Fortran's integer division"),
    ("      INTEGER N\n      N = 2.5*A\n      B = N\n", "12:7",
     "N is an INTEGER (SUBROUTINE F): Fortran would cut this value"),
    # an array's DATA values the routine changes are memory from one CALL to the next
    # (a scalar's are kept: tests/test_fst_arrays.py)
    ("      REAL Q(2)\n      DATA Q /1., 2./\n      Q(1) = Q(1) + A\n      B = Q(1)\n",
     "13:7", "Q has its value from DATA and is assigned in SUBROUTINE F"),
    ("      INTEGER A(3)\n      B = 1.\n", "11:7", "A(3) in SUBROUTINE F: an INTEGER array"),
    ("      REAL A(2:5)\n      B = 1.\n", "11:7", "A(2:5) in SUBROUTINE F: an array argument "
     "of more than one subscript, or numbered from other than 1"),
    # (a review's cases: each ran with other numbers than Fortran's before)
    ("      INTEGER I\n      I = 4\n      B = MOD(I, 3)/2\n", "13:11",
     "a division of whole numbers"),
    ("      INTEGER I\n      I = 4\n      B = I**2/5\n", "13:11", "a division of whole numbers"),
    ("      B = INT(A + 1.)/2\n", "11:11", "a division of whole numbers"),
    ("      B = 2**(-1)\n", "11:11", "a power of whole numbers whose exponent may be"),
    ("      INTEGER K\n      DIMENSION K(2)\n      K(1) = 2.5\n      B = K(1)\n", "12:7",
     "K in SUBROUTINE F: an INTEGER array"),
    ("      INTEGER J\n      B = 0.\n      DO 10 J = A + 0.5, 4\n      B = B + J\n"
     "   10 CONTINUE\n", "13:7", "the bounds of DO J, an INTEGER, are no whole numbers"),
    ("      B = 0.\n      DO 10 I = 1, 3\n      I = I + 1\n      B = B + 1.\n"
     "   10 CONTINUE\n", "13:7", "I is assigned inside its own DO loop"),
    ("      B = 0.\n      DO 10 I = 1, 3, 0\n      B = B + 1.\n   10 CONTINUE\n", "12:23",
     "a DO loop with step 0 never ends"),
    ("      B = 0.\n      DO 20 I = 1, 3\n      B = B + 1.\n   10 CONTINUE\n", "12:7",
     "DO 20 (in SUBROUTINE F): no 20 CONTINUE in SUBROUTINE F ends it"),
    ("      CALL F(A, B)\n", "9:7", "SUBROUTINE F calls itself (through F -> F)"),
    ("      COMMON /W/ Q\n      B = A\n", "11:7", "Fortran's COMMON in a subroutine"),
    ("      B = A\n      RETURN\n      B = 2.*A\n", "12:7",
     "RETURN before the end of SUBROUTINE F"),
    ("      B = A + Q\n", "11:15", "Q is read in SUBROUTINE F before it has a value"),
])
def test_what_the_subset_does_not_run_is_refused_at_its_line(body, where, words):
    message = _fault(SUB.format(body=body))
    assert f"f.fst:{where}: error: " in message and words in message, message
    assert "follows STOP" not in message  # (the subroutine's fault only, not its CALL's)


def test_calls_that_cannot_be_run_say_what_to_write():
    missing = _fault("")
    assert "f.fst:3:1: error: CALL F (line 3): no SUBROUTINE F follows STOP" in missing
    count = _fault(SUB.format(body="      B = A\n"), call="CALL F(X)")
    assert "CALL F gives 1 argument(s); SUBROUTINE F (line 9) takes 2" in count
    expression = _fault(SUB.format(body="      B = A\n"), call="CALL F(X, 2.*Y)")
    assert "argument B of SUBROUTINE F is assigned in it" in expression
    # (LINTUL-banana's CALL INTERPOL('PCOTB', ...): FST's STRING arguments)
    text = _fault(SUB.format(body="      B = A\n"), call="CALL F('PCOTB', Y)")
    assert "f.fst:3:8: error: CALL F gives the string 'PCOTB': a string argument (FST's " \
           "STRING) is not supported" in text and text.count("error:") == 1, text
    # (an implicit INTEGER read as a value is the same number in real arithmetic; here it
    # has none)
    integer = _fault(SUB.format(body="      B = A\n").replace(
        "      IMPLICIT REAL (A-Z)\n", "").replace("B = A", "B = A + KQ"))
    assert "KQ is read in SUBROUTINE F before it has a value" in integer
    # (DIMENSION K(2) with no IMPLICIT REAL: K is an INTEGER array, as Fortran types it)
    implicit = _fault(SUB.format(body="      DIMENSION K(2)\n      K(1) = 2.5\n      B = K(1)\n"
                                 ).replace("      IMPLICIT REAL (A-Z)\n", ""))
    assert "f.fst:10:7: error: K in SUBROUTINE F: an INTEGER array (by Fortran's implicit " \
           "typing)" in implicit


@pytest.mark.parametrize("call, body, words", [
    ("CALL F(Y, Y)", "      B = A + 1.\n", "both as a value it reads and as an argument it "
     "assigns"),
    ("CALL F(X, Y)", "      CALL G(A, B)\n      END\n      SUBROUTINE G(A, B)\n"
     "      IF (A .LT. 0.5) B = A\n", "f.fst:11:7: error: argument B of SUBROUTINE G is not "
     "assigned on every path"),
])
def test_calls_whose_fortran_meaning_differs_are_refused(call, body, words):
    # (Fortran would read Y's value before the CALL, or keep B's from before a routine's
    # CALL: refused, not run with other numbers; a CALL of the listing's keeps B from
    # the last step point, tests/test_fst_arrays.py)
    message = _fault(SUB.format(body=body), call=call)
    assert ("f.fst:" in words or "f.fst:3:1: error: " in message) and words in message, \
        message


def test_only_the_called_subroutines_are_read_and_other_text_is_left():
    # notes, a routine nothing calls (with INTEGER and DO, outside the subset) and a
    # FUNCTION after STOP: not read; F runs, Y = 2 X at every row (X = 1 + t)
    after = ("Notes: this text is no Fortran, and has a mark in column 6\n"
             "      REAL FUNCTION G(A)\n      G = A\n      END\n"
             "      SUBROUTINE UNUSED(N)\n      INTEGER N\n      DO 10 I = 1, N\n"
             "   10 CONTINUE\n      END\n"
             + SUB.format(body="      B = 2.*A\n") + "Data after the routine: 1 2 3\n")
    run = _run_f(after)
    assert list(run.values["Y"]) == [2.0, 4.0, 6.0]


def test_a_call_under_a_one_line_if_and_one_in_initial():
    # IF (c) CALL F(...) is the IF block with the CALL in it (Y = 2 X where X > 0, which
    # is every row here); INITIAL, sorted in the CSMP form, takes no CALL: said so
    sub = SUB.format(body="      B = 2.*A\n")
    text = ("TITLE T\nX = INTGRL(1., 1.)\nIF (X > 0.) CALL F(X, Y)\nTIMER FINTIM = 2., "
            "DELT = 1.\nTRANSLATION_GENERAL DRIVER='EUDRIV'\nPRINT Y\nEND\nSTOP\n" + sub)
    run, = amilpy.loads(text, name="f.fst").run(advice=False)
    assert list(run.values["Y"]) == [2.0, 4.0, 6.0]
    with pytest.raises(AmilError) as err:
        amilpy.loads(text.replace("IF (X > 0.) CALL F(X, Y)", "INITIAL\nCALL F(2., Y)\n"
                                  "DYNAMIC"), name="f.fst")
    assert "f.fst:4:1: error: a PROCEDURE block (or a CALL of a subroutine, or a reference " \
           "to a FUNCTION written after STOP) cannot stand in INITIAL" in err.value.render()


def test_implicit_none_and_a_call_with_no_arguments():
    # IMPLICIT NONE: a name not declared is said so (not called an implicit INTEGER);
    # declared REAL, the routine runs; CALL G with no parentheses calls G() (a routine
    # with no arguments changes nothing the listing sees: it runs, Y = 2 X)
    none = SUB.format(body="      REAL A, B\n      B = 2.*A + KQ\n").replace(
        "IMPLICIT REAL (A-Z)", "IMPLICIT NONE")
    message = _fault(none)
    assert "f.fst:12:18: error: KQ is not declared (IMPLICIT NONE in SUBROUTINE F)" in message
    ok = SUB.format(body="      REAL A, B\n      B = 2.*A\n").replace(
        "IMPLICIT REAL (A-Z)", "IMPLICIT NONE")
    text = ("TITLE T\nX = INTGRL(1., 1.)\nCALL F(X, Y)\nCALL G\nTIMER FINTIM = 2., "
            "DELT = 1.\nTRANSLATION_GENERAL DRIVER='EUDRIV'\nPRINT Y\nEND\nSTOP\n" + ok
            + "      SUBROUTINE G\n      END\n")
    run, = amilpy.loads(text, name="f.fst").run(advice=False)
    assert list(run.values["Y"]) == [2.0, 4.0, 6.0]


GAUSS = """TITLE THE AREA UNDER X**P BY THREE-POINT GAUSS, IN A SUBROUTINE
INCON ZERO = 0.
PARAM P = 2.
      B    = 1. + TIME
      CALL GAUSS3(0., B, P, AREA)
      W    = INTGRL(ZERO, AREA)
TIMER FINTIM = 6., DELT = 1., PRDEL = 1.
TRANSLATION_GENERAL DRIVER='EUDRIV'
PRINT AREA, W
END
STOP

C     GAUSS3: the integral of SHAPE from A to B by Gauss-Legendre on three points
      SUBROUTINE GAUSS3(A, B, P, AREA)
      IMPLICIT REAL (A-Z)
      INTEGER I
      REAL XG(3), WG(3)
      DATA XG /0.1127016653792583, 0.5, 0.8872983346207417/
      DATA WG /0.2777777777777778, 0.4444444444444444,
     &         0.2777777777777778/
      AREA = 0.
      DO 10 I = 1, 3
         X = A + (B - A)*XG(I)
         IF (X .GE. 0.) THEN
            CALL SHAPE(X, P, Y)
         ELSE
            Y = 0.
         END IF
         AREA = AREA + Y*WG(I)
   10 CONTINUE
      AREA = AREA*(B - A)
      RETURN
      END

C     SHAPE: X**P, by way of an array of its own
      SUBROUTINE SHAPE(X, P, Y)
      IMPLICIT REAL (A-Z)
      REAL Q(2)
      DATA Q /2*1./
      Y = Q(1)*X**P/Q(2)
      RETURN
      END
"""


def test_a_do_loop_over_the_routines_own_arrays_calling_another_routine():
    """SUCROS's TOTASS integrates over the day the same way: a labelled DO over
    Gauss's points and weights (local arrays given by DATA), calling another routine
    (ASSIM) at each point. Three points integrate a polynomial of degree 5 exactly:
    AREA = (1 + t)^3/3 at every day, to the weights' rounding (1e-15 relative), and W
    (Euler, a day a step) the sum of the days before. The loop's I and the routines'
    own names are each CALL's (GAUSS3#1.I, ...), not the listing's."""
    run, = amilpy.loads(GAUSS, name="gauss.fst").run(advice=False)
    t = run.t.tolist()
    assert t == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    for k, tk in enumerate(t):
        assert run.values["AREA"][k] == pytest.approx((1.0 + tk) ** 3 / 3.0, rel=1e-14)
        assert run.values["W"][k] == pytest.approx(
            sum((1.0 + d) ** 3 / 3.0 for d in range(k)), rel=1e-14, abs=1e-300)
    assert "I" not in run.final and "GAUSS3#1.I" in run.final
    # written with DO ... END DO and P = 4: still exact (degree 4)
    block = GAUSS.replace("      DO 10 I = 1, 3", "      DO I = 1, 3").replace(
        "   10 CONTINUE", "      END DO").replace("P = 2.", "P = 4.")
    run, = amilpy.loads(block, name="gauss.fst").run(advice=False)
    assert run.values["AREA"][-1] == pytest.approx(7.0 ** 5 / 5.0, rel=1e-14)


ASTRO = """TITLE DAY LENGTH BY SUCROS'S ASTRONOMY, IN A SUBROUTINE
PARAM LAT = 52.
      CALL ASTRO(TIME, LAT, DAYL, SINLD, COSLD)
      HOURS = INTGRL(0., DAYL)
TIMER STTIME = 1., FINTIM = 365., DELT = 1., PRDEL = 1.
TRANSLATION_GENERAL DRIVER='EUDRIV'
PRINT DAYL, SINLD, COSLD, HOURS
END
STOP

*     ASTRO: day length (h) and the sine and cosine parts of the sun's elevation
      SUBROUTINE ASTRO (DAY, LAT, DAYL, SINLD, COSLD)
      IMPLICIT REAL (A-Z)
      SAVE
      PARAMETER (PI = 3.141592654, RAD = PI/180.)
      DEC   = -ASIN(SIN(23.45*RAD)*COS(2.*PI*(DAY+10.)/365.))
      SINLD = SIN(RAD*LAT)*SIN(DEC)
      COSLD = COS(RAD*LAT)*COS(DEC)
      AOB   = SINLD/COSLD
      DAYL  = 12.0*(1.+2.*ASIN(AOB)/PI)
      RETURN
      END
"""


def test_parameter_and_save_as_an_astronomy_routine_has_them():
    """PARAMETER's named constants (one read in the next), and a SAVE that keeps
    nothing the routine reads before assigning it (so it changes nothing): the day
    length at 52 N every day of a year, against the same formula in Python (1e-13
    relative: the same operations), 16.5 h at midsummer, and its Euler sum."""
    run, = amilpy.loads(ASTRO, name="astro.fst").run(advice=False)
    pi = 3.141592654
    rad = pi / 180.0
    total = 0.0
    for k, day in enumerate(run.t.tolist()):
        dec = -math.asin(math.sin(23.45 * rad) * math.cos(2.0 * pi * (day + 10.0) / 365.0))
        sinld = math.sin(rad * 52.0) * math.sin(dec)
        cosld = math.cos(rad * 52.0) * math.cos(dec)
        dayl = 12.0 * (1.0 + 2.0 * math.asin(sinld / cosld) / pi)
        assert run.values["DAYL"][k] == pytest.approx(dayl, rel=1e-13)
        assert run.values["HOURS"][k] == pytest.approx(total, rel=1e-12, abs=1e-300)
        total += dayl
    assert max(run.values["DAYL"]) == pytest.approx(16.5, abs=0.1)


@pytest.mark.parametrize("body, where, words", [
    ("      PARAMETER (C = 2.)\n      C = A\n      B = C\n", "12:7",
     "C is a PARAMETER of SUBROUTINE F: Fortran does not let the routine assign it"),
    ("      SAVE\n      CALL G(A, B)\n      END\n      SUBROUTINE G(A, B)\n"
     "      B = B + A\n", "12:7", "argument B of SUBROUTINE G is read before"),
])
def test_parameter_assigned_and_what_save_would_keep_are_refused(body, where, words):
    # (SAVE matters only for a value read before the routine gives it one: refused in a
    # routine's CALL of another; a CALL of the listing's keeps it from the last step
    # point, as FSE's generated code does: tests/test_fst_arrays.py)
    message = _fault(SUB.format(body=body))
    assert words in message, message


def test_real_of_a_loop_index_and_integers_given_whole_numbers():
    """REAL(I - 1) (the listing's FLOAT) spaces five points k A/4 over [0, A]; N =
    INT(4.5) and MOD of INTEGERs are whole numbers, as Fortran computes them: the mean
    of X**2 over the points is 0.375 A**2 (0 + 1 + 4 + 9 + 16 over 5, in quarters of
    A), and the sum at odd k 0.625 A**2 (1 + 9 over 16)."""
    sub = ("      SUBROUTINE F(A, B)\n      IMPLICIT REAL (A-Z)\n      INTEGER I, N, J\n"
           "      N = INT(4.5)\n      S = 0.\n      B = 0.\n      DO 10 I = 1, N + 1\n"
           "         X = A*REAL(I - 1)/4.\n         S = S + X**2/5.\n"
           "         J = MOD(I, 2)\n         IF (J .EQ. 0) B = B + X**2\n"
           "   10 CONTINUE\n      B = B + S\n      RETURN\n      END\n")
    run = _run_f(sub)
    for x, y in zip(run.values["X"], run.values["Y"], strict=True):
        assert y == pytest.approx(0.375 * x * x + 0.625 * x * x, rel=1e-14)


def test_a_real_do_loop_counts_as_fortran_and_do_label_comma():
    """DO T = 0., 0.7, 0.1 makes Fortran's MAX(INT((0.7 - 0 + 0.1)/0.1), 0) = 7 passes,
    whether its body reads an array (the loop written out when it is read) or not (a
    loop as the run goes): it made 8 and 7 before. `DO 10, I = 1, 4` (a comma after
    the label, legal Fortran 77) sums 1 to 4; a labelled CONTINUE no DO ends does
    nothing (no GO TO may reach it)."""
    sub = ("      SUBROUTINE F(A, B)\n      IMPLICIT REAL (A-Z)\n      REAL W(1)\n"
           "      DATA W /1./\n      B = 0.\n      DO T = 0., 0.7, 0.1\n"
           "         B = B + W(1)\n      END DO\n      DO T = 0., 0.7, 0.1\n"
           "         B = B + 100.\n      END DO\n      DO 10, I = 1, 4\n"
           "         B = B + 10000.*I\n   10 CONTINUE\n   20 CONTINUE\n"
           "      B = B + 0.*A\n      RETURN\n      END\n")
    run = _run_f(sub, fintim=1.0)
    assert list(run.values["Y"]) == [100707.0, 100707.0]


@pytest.mark.parametrize("body", ["      B = FOO(A) + 1.\n",
                                  "      I = 1\n      B = FOO(A) + I\n"])
def test_a_fault_in_a_routine_is_said_once_not_again_where_its_outputs_are_read(body):
    # the CALL's outputs and the routine's own names are still defined: no "PRINT names
    # Y, which the model never defines", no "F#1.I is used but never defined" (a name
    # the user never wrote) after the one fault
    with pytest.raises(AmilError) as err:
        _run_f(SUB.format(body=body))
    messages = [d.message for d in err.value.diagnostics]
    assert messages == ["unknown function FOO"]


FUNCTIONS = """TITLE FUNCTIONS AFTER STOP
X = INTGRL(1., RATE(X, K))
Y = 2.*SQ(X) + CUBE(X)
PARAM K = 0.5
TIMER FINTIM = 6., DELT = 1.
TRANSLATION_GENERAL DRIVER='EUDRIV'
PRINT X, Y
END
STOP
      REAL FUNCTION RATE(A, B)
      IMPLICIT REAL (A-Z)
      RATE = -B*A
      RETURN
      END
      FUNCTION SQ(A)
      SQ = A*A
      RETURN
      END
      FUNCTION CUBE(A)
      CUBE = A*SQ(A)
      END
"""


def test_function_subprograms_run_where_the_listing_refers_to_them():
    # X' = RATE(X, K) = -K X a day at a time (EUDRIV): X = 0.5**t exactly in binary;
    # Y = 2 SQ(X) + CUBE(X) = 2 X^2 + X^3, CUBE referring to SQ in turn
    run, = amilpy.loads(FUNCTIONS, name="fn.fst").run(advice=False)
    assert list(run.times) == [0., 1., 2., 3., 4., 5., 6.]
    for k, t in enumerate(run.times):
        x = 0.5 ** t
        assert run["X"][k] == x and run["Y"][k] == 2 * x * x + x ** 3


def test_define_function_declares_a_function_subprogram_as_define_call_a_routine():
    """LINTUL-banana declares its FUNCTIONs after STOP as DEFINE_CALL declares
    routines: DEFINE_FUNCTION RATE(INPUT, INPUT). It said "this statement needs '='"."""
    text = "DEFINE_FUNCTION RATE(INPUT, INPUT)\n" + FUNCTIONS
    run, = amilpy.loads(text, name="fn.fst").run(advice=False)
    assert list(run["X"]) == [0.5 ** t for t in run.times]


def test_a_function_in_a_subroutine_an_if_condition_and_a_loop_bound():
    # SQ(A) in the IF's condition and its branch, TWO(A) in a DO loop's bound: the
    # references are written out before the IF and the loop, in the routine's order;
    # X = 1 + t: B = sum over I = 1..NINT(2X) of X**2 where X**2 > 2, else -X**2
    run = _run_f(SUB.format(body="      IF (SQ(A) .GT. 2.) THEN\n      B = 0.\n"
                            "      DO 10 I = 1, NINT(TWO(A))\n      B = B + SQ(A)\n"
                            "   10 CONTINUE\n      ELSE\n      B = -SQ(A)\n      END IF\n")
                 + "      FUNCTION SQ(Z)\n      SQ = Z*Z\n      END\n"
                 "      REAL FUNCTION TWO(Z)\n      TWO = 2.*Z\n      END\n", fintim=3.0)
    for k, t in enumerate(run.times):
        x = 1.0 + t
        want = -x * x if x * x <= 2.0 else round(2 * x) * x * x
        assert run["Y"][k] == want


@pytest.mark.parametrize("functions, words", [
    ("      FUNCTION SQ(Z)\n      SQ = SQ(Z - 1.)\n      END\n",
     "FUNCTION SQ calls itself (through F -> SQ -> SQ)"),
    ("      FUNCTION SQ(Z, W)\n      SQ = Z*W\n      END\n",
     "SQ gives 1 argument(s); FUNCTION SQ (line 14) takes 2"),
    ("      FUNCTION SQ(Z)\n      Z = Z*Z\n      SQ = Z\n      END\n",
     "argument Z of FUNCTION SQ is read before it is assigned"),
    ("      FUNCTION SQ(Z)\n      IF (Z .GT. 0.) SQ = Z*Z\n      END\n",
     "argument SQ of FUNCTION SQ is not assigned on every path"),
    # Fortran's INTEGER results: cut to a whole number, or divided as whole numbers
    ("      INTEGER FUNCTION SQ(Z)\n      SQ = Z*Z\n      END\n",
     "SQ is an INTEGER (FUNCTION SQ): Fortran would cut this value"),
    ("      FUNCTION ISQ(Z)\n      ISQ = Z*Z\n      END\n",
     "ISQ is an INTEGER (FUNCTION ISQ): Fortran would cut this value"),
])
def test_functions_whose_fortran_meaning_differs_are_refused(functions, words):
    body = "      B = ISQ(A)\n" if "ISQ" in functions else "      B = SQ(A)\n"
    message = _fault(SUB.format(body=body) + functions)
    assert words in message, message


def test_an_integer_function_divided_in_a_routine_that_types_it_integer_is_refused():
    # IHALF(A) is INTEGER in F (no IMPLICIT there): IHALF(A)/2 is Fortran's integer
    # division there
    message = _fault("      SUBROUTINE F(A, B)\n      B = IHALF(A)/2\n      END\n"
                     "      INTEGER FUNCTION IHALF(Z)\n      IHALF = 2\n      END\n")
    assert "a division of whole numbers (SUBROUTINE F)" in message, message


def test_go_to_forward_in_a_routine_the_cycle_idiom_and_a_skip():
    # Fortran's GO TO 10 to a CONTINUE before the loop's own (the rest of the pass
    # skipped: I = 3 left out) and a jump over B = -B: written out as IF blocks
    # (parse/jumps.py); X = 1 + t: B = 12 X, negated where X <= 2.5
    run = _run_f(SUB.format(body="      B = 0.\n      DO 20 I = 1, 5\n"
                            "      IF (I .EQ. 3) GO TO 10\n      B = B + I*A\n"
                            "   10 CONTINUE\n   20 CONTINUE\n"
                            "      IF (A .GT. 2.5) GO TO 30\n      B = -B\n"
                            "   30 CONTINUE\n"), fintim=3.0)
    assert list(run["Y"]) == [-12.0, -24.0, 36.0, 48.0]


@pytest.mark.parametrize("body, want", [
    # the search idiom: I where the jump leaves the loop (X = 1 + t: the first I >= X)
    ("      DO 10 I = 1, 10\n      IF (I .GE. A) GO TO 20\n   10 CONTINUE\n"
     "   20 B = I\n", [1.0, 2.0, 3.0]),
    # GO TO the loop's own CONTINUE: the pass's rest skipped (B counts I <= X)
    ("      B = 0.\n      DO 10 I = 1, 5\n      IF (I .GT. A) GO TO 10\n      B = B + 1.\n"
     "   10 CONTINUE\n", [1.0, 2.0, 3.0]),
    # to a labelled RETURN, and to a labelled END
    ("      B = 1.\n      IF (A .GT. 1.5) GO TO 99\n      B = 2.\n   99 RETURN\n",
     [2.0, 1.0, 1.0]),
])
def test_go_to_a_routines_usual_targets(body, want):
    run = _run_f(SUB.format(body=body).replace("      RETURN\n      RETURN\n",
                                               "      RETURN\n"))
    assert list(run["Y"]) == want
    assert not run.warnings  # (the flags' tests, which no one wrote, say nothing)


def test_go_to_a_labelled_end_and_a_function_in_termt():
    run = _run_f("      SUBROUTINE F(A, B)\n      IMPLICIT REAL (A-Z)\n      B = 1.\n"
                 "      IF (A .GT. 1.5) GO TO 99\n      B = 2.\n   99 END\n")
    assert list(run["Y"]) == [2.0, 1.0, 1.0]
    text = ("TITLE T\nX = INTGRL(1., 1.)\nTERMT (G(X) .GT. 0.)\nTIMER FINTIM = 9., DELT = 1.\n"
            "TRANSLATION_GENERAL DRIVER='EUDRIV'\nPRINT X\nEND\nSTOP\n"
            "      REAL FUNCTION G(A)\n      G = A - 3.5\n      END\n")
    run, = amilpy.loads(text, name="g.fst").run(advice=False)
    assert run.times[-1] == 3.0 and run["X"][-1] == 4.0


def test_a_call_refused_in_initial_is_the_only_error():
    # Y is assigned by the CALL that was refused: "PRINT names Y, which the model never
    # defines" would follow that fault and point at the PRINT
    with pytest.raises(AmilError) as err:
        amilpy.loads("TITLE T\nINITIAL\nCALL F(2., Y)\nDYNAMIC\nX = INTGRL(0., 1.)\n"
                     "TIMER FINTIM = 1., DELT = 0.5\nTRANSLATION_GENERAL DRIVER='EUDRIV'\n"
                     "PRINT Y\nEND\nSTOP\n" + SUB.format(body="      B = A\n"), name="f.fst")
    assert [d.span.line for d in err.value.diagnostics] == [3]


@pytest.mark.parametrize("method", ["RECT", "RKS"])
def test_a_stop_in_a_routine_ends_the_run_there_with_its_words(method):
    """SUCROS's ASTRO checks its input as Fortran does, `IF (LAT.GT.67.) STOP 'ERROR IN
    ASTRO: LAT> 67'`: the run ends where the STOP is reached (here where X = TIME
    reaches 1.5, located on RKS; at the step point t = 1.5 on RECT, DELT 0.5), saying
    the routine's words; the rows before it are kept. (STOP was refused, and SUCROS1
    and SUCROS2 with it.)"""
    sub = SUB.format(body="      IF (A .GT. 1.5)  STOP 'ERROR IN F: A> 1.5'\n      B = 2.*A\n")
    text = ("TITLE T\nX = INTGRL(0., 1.)\nCALL F(X, Y)\nTIMER FINTIM = 3., DELT = 0.5, "
            "OUTDEL = 0.5\nPRINT Y\nEND\nSTOP\n" + sub)
    run, = amilpy.loads(text, name="f.fst").run(method=method, advice=False)
    assert run.status == "stopped" and "ERROR IN F: A> 1.5 (STOP in SUBROUTINE F at line 10)" in \
        run.message, run.message
    assert run.t_end == pytest.approx(2.0 if method == "RECT" else 1.5, abs=1e-9)
    assert list(run["Y"][:4]) == pytest.approx([0.0, 1.0, 2.0, 3.0])


def test_a_logical_flag_set_in_a_loop_over_a_routines_own_dates():
    """LINGRA's MOWING sets a LOGICAL flag in a loop over its mowing dates, then tests
    it with .AND.: here Y = 1 on the listed days (A = 1 + t = 2, 4 or 5) after A > 3,
    else 0. LOGICAL variables were refused in routines."""
    run = _run_f("""      SUBROUTINE F(A, B)
      IMPLICIT NONE
      REAL A, B, D(3)
      INTEGER I
      LOGICAL DAY
      DATA D /2., 4., 5./
      DAY = .FALSE.
      DO 10 I = 1, 3
         IF (A .EQ. D(I)) DAY = .TRUE.
   10 CONTINUE
      IF (DAY .AND. A .GT. 3.) THEN
         B = 1.
      ELSE
         B = 0.
      END IF
      RETURN
      END
""", fintim=6.0)
    assert [(t, y) for t, y in zip(run.times, run["Y"], strict=True)] == [
        (0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (3.0, 1.0), (4.0, 1.0), (5.0, 0.0), (6.0, 0.0)]


def test_an_arithmetic_if_jumps_by_the_sign_of_its_expression():
    # IF (e) l1, l2, l3: to l1 where e < 0, l2 where e = 0, l3 where e > 0 (X = 1 + t:
    # A - 2 is -1, 0, 1, 2); the switches it makes are named by their condition
    run = _run_f("""      SUBROUTINE F(A, B)
      IMPLICIT REAL (A-Z)
      IF (A - 2.) 10, 20, 30
   10 B = -1.
      GO TO 40
   20 B = 0.
      GO TO 40
   30 B = 1.
   40 CONTINUE
      RETURN
      END
""", fintim=3.0)
    assert list(run["Y"]) == [-1.0, 0.0, 1.0, 1.0]
    assert run.events[0].switch.startswith("X - 2. < 0. at line 11")


def test_fatalerr_stops_the_run_saying_its_module_and_message():
    # TTUTIL's FATALERR(MODULE, MESSAGE) says both and stops the program: here where
    # X = TIME passes 1.2 (the step point 1.5, DELT 0.5), the text from a CHARACTER name
    # given once and a literal with a doubled quote; the rows before it are kept
    sub = SUB.format(body="      CHARACTER*20 MODULE\n      MODULE = 'F'\n"
                          "      IF (A .GT. 1.2) CALL FATALERR (MODULE, 'A > 1.2: it''s "
                          "too large')\n      B = 2.*A\n")
    run = _run_f(sub, fintim=3.0, start=0.0, delt=0.5)
    assert run.status == "stopped" and "FATALERR in F: A > 1.2: it's too large (CALL " \
        "FATALERR in SUBROUTINE F at line 13)" in run.message, run.message
    assert list(run.t) == [0.0, 0.5, 1.0, 1.5] and list(run["Y"]) == [0.0, 1.0, 2.0, 3.0]


@pytest.mark.parametrize("body, where, words", [
    ("      CHARACTER*8 A\n      B = 1.\n", "11:7",
     "A in SUBROUTINE F: a CHARACTER argument is not supported"),
    ("      CHARACTER(LEN=*) :: M\n      B = A\n", "11:7",
     "a CHARACTER declaration of Fortran 90's form"),
    ("      CHARACTER M*8\n      M = 'X'\n      Q = M\n      B = A\n", "13:11",
     "M is CHARACTER (a text) in SUBROUTINE F"),
    ("      CALL FATALERR('F', M)\n      B = A\n", "11:7",
     "FATALERR's M (in SUBROUTINE F): not a text given before"),
])
def test_texts_other_than_fatalerrs_messages_are_refused(body, where, words):
    message = _fault(SUB.format(body=body))
    assert f"f.fst:{where}: error: " in message and words in message, message


@pytest.mark.parametrize("method", ["RECT", "RKS"])
@pytest.mark.parametrize("body, stop_at", [
    # an ELSE's FATALERR: where the test before it is false (A = 1 + t > 3.5 first at
    # t = 2.5: the step point 3 on RECT, located on RKS)
    ("      IF (A .LT. 3.5) THEN\n         B = A\n      ELSE\n         B = 0.\n"
     "         CALL FATALERR ('F', 'A too large')\n      END IF\n", {"RECT": 3.0, "RKS": 2.5}),
    # an ELSE IF's: never, the test before it holds wherever its own does
    ("      IF (A .GT. 0.) THEN\n         B = A\n      ELSE IF (A .GT. 2.5) THEN\n"
     "         B = 0.\n         STOP 'never'\n      ELSE\n         B = -A\n      END IF\n",
     {"RECT": None, "RKS": None}),
    # a STOP on a value known from the start (a PARAM checked): at t0, on every route
    ("      B = A\n      IF (Q .GT. 0.5) STOP 'Q too large'\n", {"RECT": 0.0, "RKS": 0.0}),
    # (a second review's cases) the test read where the IF stands, not after the
    # branch changes what it reads
    ("      C = A\n      B = A\n      IF (C .LT. 2.5) THEN\n         B = 1.\n      ELSE\n"
     "         C = 100.\n         STOP 'big'\n      END IF\n", {"RECT": 2.0, "RKS": 1.5}),
    # in a DO loop, at the pass that reaches it (I = 1: A < 3 fails at A = 3)
    ("      B = 0.\n      DO 10 I = 1, 3\n         IF (A .LT. I + 2.) THEN\n"
     "            B = B + 1.\n         ELSE\n            CALL FATALERR ('F', 'loop')\n"
     "         END IF\n   10 CONTINUE\n", {"RECT": 2.0, "RKS": 2.0}),
    # .GE. at equality (A = 4 at t = 3), and after a GO TO that jumps past it
    ("      B = A\n      IF (A .GE. 4.) STOP 'ge'\n", {"RECT": 3.0, "RKS": 3.0}),
    ("      B = A\n      IF (A .LT. 3.5) GO TO 20\n      STOP 'after goto'\n"
     "   20 CONTINUE\n", {"RECT": 3.0, "RKS": 2.5}),
])
def test_a_stop_is_reached_where_its_branch_is_taken(body, stop_at, method):
    """A STOP or FATALERR in an IF's branch stops the run where that branch is taken:
    its own test true and those before it false (an ELSE's FATALERR never stopped the
    run, and an ELSE IF's ignored the tests before it); one that holds from the start
    stops it at t0 on the located routes too."""
    sub = SUB.format(body=body).replace("(A, B)", "(A, B, Q)")
    text = ("TITLE T\nX = INTGRL(1., 1.)\nCALL F(X, Y, Q)\nPARAM Q = 1.\n"
            "TIMER FINTIM = 4., DELT = 1., OUTDEL = 1.\nPRINT Y\nEND\nSTOP\n" + sub)
    run, = amilpy.loads(text, name="f.fst").run(method=method, advice=False)
    want = stop_at[method]
    if want is None:
        assert run.status == "finished" and run.t_end == 4.0
    else:
        assert run.status == "stopped" and run.t_end == pytest.approx(want, abs=1e-9), \
            (run.status, run.t_end, run.message)


@pytest.mark.parametrize("body, where, words", [
    ("      IF (A .GT. 3.) 10, 20, 20\n   10 B = 1.\n   20 B = A\n", "11:7",
     "an arithmetic IF takes a number, not a test"),
    ("      CALL FATALERR ('F', 'A', 'B')\n      B = A\n", "11:7",
     "CALL FATALERR takes two texts"),
    ("      PARAMETER (M = 'F')\n      B = A\n", "11:7",
     "a text for a name not declared CHARACTER"),
    # (a line read in other words: its column is the statement's, not one past its end)
    ("      IF (A - 2.) 10, 20, 30\n   10 B = -1.\n   20 B = 0.\n", "11:7",
     "GO TO 30: no label 30"),
])
def test_what_the_reader_rewrites_is_refused_at_the_statement(body, where, words):
    message = _fault(SUB.format(body=body))
    assert f"f.fst:{where}: error: " in message and words in message, message


def test_a_fatalerr_text_from_parameter():
    sub = SUB.format(body="      CHARACTER*8 M\n      PARAMETER (M = 'F')\n"
                          "      IF (A .GT. 1.5) CALL FATALERR (M, 'too large')\n"
                          "      B = A\n")
    run = _run_f(sub, fintim=3.0, start=0.0)
    assert run.status == "stopped" and run.t_end == 2.0 and "FATALERR in F: too large" in \
        run.message


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RECT"])
def test_a_termt_that_holds_where_the_run_starts_stops_it_there(method):
    # X starts at 1 and falls: TERMT(X .GE. 1.) holds at t0 (at zero, closed) though the
    # motion leaves it at once; TERMT(Y .GT. 0.5) with Y = 1 holds outright
    for termt in ("TERMT(X .GE. 1.)", "TERMT(Y .GT. 0.5)"):
        text = (f"TITLE T0\nX = INTGRL(1., -1.)\nY = 1.0 + 0.*X\n{termt}\n"
                "TIMER FINTIM = 2., DELT = 0.5\nPRINT X\nEND\n")
        run, = amilpy.loads(text, name="t0.amil").run(method=method, advice=False)
        assert run.status == "stopped" and run.t_end == 0.0, (termt, run.message)


def test_a_routines_stop_ends_the_job_and_a_termt_only_its_run():
    # Fortran's STOP ends the program: the rerun after the run it stopped is not made
    # (said on that run); a TERMT of the listing ends its own run, and the next is made
    sub = SUB.format(body="      B = A\n      IF (A .GT. Q) STOP 'A passed Q'\n").replace(
        "(A, B)", "(A, Q, B)")
    text = ("TITLE T\nX = INTGRL(1., 1.)\nCALL F(X, Q, Y)\nPARAM Q = 2.5\n"
            "TIMER FINTIM = 4., DELT = 1.\nTRANSLATION_GENERAL DRIVER='EUDRIV'\nPRINT Y\n"
            "END\nPARAM Q = 10.\nEND\nSTOP\n" + sub)
    runs = amilpy.loads(text, name="f.fst").run(advice=False)
    assert len(runs) == 1 and runs[0].t_end == 2.0
    assert "the 1 later run is not made" in runs[0].warnings[-1]
    termt = text.replace("CALL F(X, Q, Y)", "Y = X\nTERMT(X .GT. Q)")
    assert [r.t_end for r in amilpy.loads(termt, name="f.fst").run(advice=False)] == \
        [2.0, 4.0]
