"""FST's ARRAY and ARRAY_SIZE, array arguments of the routines after STOP, and the
variables those routines change (issue 23): what LINGRA's MOWING does with its
mowing dates MNDAT(1:NH), its count of cuts INCUT (a PARAM it adds 1 to) and its
HARV and RDAHA (kept where no branch sets them), and PENMAN with VP = MIN(VP, SVP)
on a weather variable. Each against a recurrence written here, step point by step
point, as FSE's Euler loop runs the generated Fortran (every variable SAVEd)."""

import os

import pytest

import amilpy
from amilpy.diagnostics import AmilError

HERE = os.path.dirname(os.path.abspath(__file__))
WEATHER = os.path.join(HERE, "listings", "weather")

# the dates come from element data, a range given one value and a range given a list
DATES = """DEFINE_CALL CUTS(INPUT, INPUT_ARRAY, INTEGER_INPUT, INPUT, OUTPUT)
ARRAY D(1:N), W(1:3)
ARRAY_SIZE N=6
TITLE DATES
X = INTGRL(1., 1.)
CALL CUTS(TIME, D, N, X, Y)
PARAM D(1) = 2.; D(2)=4.; D(3:N) = 99.
PARAM W(1:3) = 10., 20., 30.
Z = W(1) + W(2)*W(3)
TIMER FINTIM = 8., DELT = 1.
TRANSLATION_GENERAL DRIVER='EUDRIV'
PRINT Y, Z
END
PARAM D(2) = 7.
END
STOP
      SUBROUTINE CUTS(T, DATES, NDATES, A, B)
      IMPLICIT NONE
      INTEGER NDATES, I
      REAL T, DATES(NDATES), A, B
      LOGICAL CUT
      CUT = .FALSE.
      DO 10 I = 1, NDATES
         IF (T .EQ. DATES(I)) CUT = .TRUE.
   10 CONTINUE
      IF (CUT) THEN
         B = A
      ELSE
         B = 0.
      END IF
      RETURN
      END
"""


@pytest.mark.parametrize("argument", ["DATES(NDATES)", "DATES(*)", "DATES(1)"])
def test_an_array_of_dates_from_element_data_passed_to_a_routine(argument):
    # Y = X = 1 + t on the listed days, 0 elsewhere; the rerun moves the second date to
    # 7 (one element of the data changed); the other elements keep 99: never a cut.
    # The argument's declared size is the caller's business (Fortran's X(*), X(1))
    text = DATES.replace("DATES(NDATES)", argument)
    first, second = amilpy.loads(text, name="dates.fst").run(advice=False)
    for run, days in ((first, (2.0, 4.0)), (second, (2.0, 7.0))):
        assert list(run.times) == [float(k) for k in range(9)]
        assert list(run["Y"]) == [1.0 + t if t in days else 0.0 for t in run.times]
        assert set(run["Z"]) == {10.0 + 20.0 * 30.0}


@pytest.mark.parametrize("change, words", [
    ("ARRAY D(1:N), W(1:3)", "ARRAY D(0:N), W(1:3)",),
    ("D(3:N) = 99.", "D(3:9) = 99."),
    ("W(1:3) = 10., 20., 30.", "W(1:3) = 10., 20."),
    ("PARAM D(1) = 2.;", "PARAM Q(1) = 2.;"),
    ("CALL CUTS(TIME, D, N, X, Y)", "CALL CUTS(TIME, X, N, X, Y)"),
    ("ARRAY_SIZE N=6\n", "ARRAY_SIZE N=6\nPARAM N = 4.\n"),
])
def test_array_faults_are_said_where_they_are(change, words):
    cases = {
        "ARRAY D(0:N), W(1:3)": ("dates.fst:2:1: error: ARRAY D(0:N): an array whose first "
                                 "subscript is not 1 is not supported"),
        "D(3:9) = 99.": "D(3:9) is not a range of D(1:6)",
        "W(1:3) = 10., 20.": "W(1:3) is given 2 values for 3 elements",
        "PARAM Q(1) = 2.;": "Q(...) = ...: Q is not an array of one subscript",
        "CALL CUTS(TIME, X, N, X, Y)": ("argument DATES of SUBROUTINE CUTS is an array: the "
                                        "CALL must give the name of an array"),
        "ARRAY_SIZE N=6\nPARAM N = 4.\n": ("dates.fst:4:7: error: N, a size of D, is given "
                                          "another value here (line 3 gave it one)"),
    }
    with pytest.raises(AmilError) as err:
        amilpy.loads(DATES.replace(change, words), name="dates.fst")
    assert cases[words] in err.value.render(), err.value.render()


# a count the routine keeps in a PARAM (MOWING's INCUT), and a value it sets only on
# some paths (MOWING's HARV)
COUNT = """TITLE COUNT
X = INTGRL(1., 1.)
CALL F(X, N, B, H)
PARAM N = 0.
TIMER FINTIM = 7., DELT = 1.
TRANSLATION_GENERAL DRIVER='EUDRIV'
PRINT B, H
END
PARAM N = 10.
END
STOP
      SUBROUTINE F(A, N, B, H)
      IMPLICIT REAL (A-Z)
      IF (A .GT. 2.5) N = N + 1.
      B = N
      IF (A .LT. 3.5 .OR. A .GT. 6.5) H = A
      RETURN
      END
"""


def fse_count(n0: float):
    """The generated Fortran in FSE's Euler loop: one rate calculation per step point,
    N and H kept from one to the next (H is 0 before it is first set)."""
    rows, n, h = [], n0, 0.0
    for k in range(8):
        a = 1.0 + k
        if a > 2.5:
            n += 1.0
        if a < 3.5 or a > 6.5:
            h = a
        rows.append((n, h))
    return rows


def test_a_param_a_routine_counts_in_and_a_value_it_keeps_where_no_branch_sets_it():
    # once per step point, whatever else evaluates the rates there (the rows, the Euler
    # step, the switches' reading); a rerun starts the count again from its PARAM
    first, second = amilpy.loads(COUNT, name="count.fst").run(advice=False)
    for run, n0 in ((first, 0.0), (second, 10.0)):
        assert list(zip(run["B"], run["H"], strict=True)) == fse_count(n0)


def test_kept_values_need_step_points_and_a_changed_param_is_read_changed_everywhere():
    for run in amilpy.loads(COUNT, name="count.fst").run(method="RKS", advice=False):
        assert not run.ok and "a routine after STOP changes N from the value it left " \
            "before" in run.message and "DRIVER = 'EUDRIV', or --method RECT" in \
            run.message, run.message
    # (as FSE's generated code has it: the listing's N is the count from then on, in
    # an equation, a FINISH and the rows; the PARAM its first value, set as N)
    text = COUNT.replace("PRINT B, H", "PRINT B, H, N\nZ = 2.*N\nFINISH N > 11.5")
    first, second = amilpy.loads(text, name="count.fst").run(advice=False)
    assert list(first["N"]) == list(first["B"]) == [n for n, _ in fse_count(0.0)]
    assert list(first["Z"]) == [2.0 * b for b in first["B"]]
    assert second.status == "stopped" and list(second["N"]) == [10.0, 10.0, 11.0, 12.0]
    # the PARAM is set from outside by its own name
    run, _ = amilpy.loads(text, name="count.fst").run(advice=False, N=5.0)
    assert list(run["N"])[:3] == [5.0, 5.0, 6.0]


# PENMAN's VP = MIN(VP, SVP): a weather variable the routine changes; after the CALL the
# listing's VP is the changed one (printed so by FSE), before it the day's
CAPPED = f"""DEFINE_CALL CAP(INPUT, INPUT, OUTPUT)
TITLE CAPPED
WEATHER WTRDIR = '{WEATHER}{os.sep}'; CNTR = 'TZ'; ISTN = 2; ...
        IYEAR = 2018
CALL CAP(VP, VPMAX, E)
VPX = 10.*VP
PARAM VPMAX = 1.40
TIMER STTIME = 5.; FINTIM = 14.; DELT = 1.
TRANSLATION_GENERAL DRIVER='EUDRIV'
PRINT VP, VPX, E
END
STOP
      SUBROUTINE CAP(VP, VPMAX, E)
      IMPLICIT REAL (A-Z)
      E = VP
      VP = MIN(VP, VPMAX)
      RETURN
      END
"""


def test_a_weather_variable_a_routine_changes_is_the_changed_one_after_the_call():
    from pathlib import Path

    from listings.references.water_stress import read_cabo

    day = read_cabo(Path(WEATHER, "TZ2.018"))
    run, = amilpy.loads(CAPPED, name="capped.fst").run(advice=False)
    assert list(run.times) == [float(k) for k in range(5, 15)]
    vp = [day[int(t)]["VP"] for t in run.times]
    assert list(run["E"]) == vp  # (what the routine read: the day's)
    assert list(run["VP"]) == [min(v, 1.40) for v in vp]
    assert list(run["VPX"]) == [10.0 * min(v, 1.40) for v in vp]
    assert any(v > 1.40 for v in vp) and any(v < 1.40 for v in vp)


def test_an_fst_listing_that_sets_pi_computes_with_its_own():
    # LINGRA writes PI = 3.1416 and reads it in its day length: FST has no PI of its
    # own; an AMIL listing may not assign PI (the contract's reserved names)
    text = ("TITLE PI\nPI = 3.1416\nY = PI*TIME\nTIMER FINTIM = 1., DELT = 1.\n"
            "TRANSLATION_GENERAL DRIVER='EUDRIV'\nPRINT Y, PI\nEND\n")
    run, = amilpy.loads(text, name="pi.fst").run(advice=False)
    assert list(run["Y"]) == [0.0, 3.1416] and list(run["PI"]) == [3.1416, 3.1416]
    from amilpy.output.printout import format_runs

    assert "  PI\n" in format_runs([run])  # (its column, by its own name)
    # a routine's output PI too
    by_call = text.replace("PI = 3.1416", "CALL F(2., PI)") + \
        "STOP\n      SUBROUTINE F(A, B)\n      B = 1.5*A\n      END\n"
    run, = amilpy.loads(by_call, name="pi.fst").run(advice=False)
    assert list(run["Y"]) == [0.0, 3.0]
    # a PARAM PI is the listing's, set from outside as any other
    given = text.replace("PI = 3.1416", "PARAM PI = 3.1416")
    run, = amilpy.loads(given, name="pi.fst").run(advice=False, PI=3.0)
    assert list(run["Y"]) == [0.0, 3.0]
    with pytest.raises(AmilError) as err:
        amilpy.loads(text.replace("TRANSLATION_GENERAL DRIVER='EUDRIV'\n", ""),
                     name="pi.amil")
    assert "PI is a reserved name and cannot be assigned" in err.value.render()


# a routine's own names kept from one CALL to the next: a running total under SAVE, and
# a FIRST flag and a start value under DATA, which the routine changes
SAVED = """TITLE SAVED
X = INTGRL(1., 1.)
CALL F(X, Y)
CALL G(X, Z)
TIMER FINTIM = 4., DELT = 1.
TRANSLATION_GENERAL DRIVER='EUDRIV'
PRINT Y, Z
END
STOP
      SUBROUTINE F(A, B)
      IMPLICIT REAL (A-Z)
      SAVE
      TOTAL = TOTAL + A
      B = TOTAL
      RETURN
      END
      SUBROUTINE G(A, B)
      IMPLICIT REAL (A-Z)
      LOGICAL FIRST
      DATA FIRST /.TRUE./, START /0./
      IF (FIRST) THEN
         START = A
         FIRST = .FALSE.
      END IF
      B = A - START
      RETURN
      END
"""


def test_save_and_data_keep_a_routines_own_names_from_one_step_point_to_the_next():
    # X = 1 + t: F's total is 1, 3, 6, 10, 15 (SAVE'd, 0 at first, as static storage
    # is); G takes X's first value as its start (DATA FIRST /.TRUE./ given once, not at
    # every CALL), then B = X - 1
    run, = amilpy.loads(SAVED, name="saved.fst").run(advice=False)
    assert list(run["Y"]) == [1.0, 3.0, 6.0, 10.0, 15.0]
    assert list(run["Z"]) == [0.0, 1.0, 2.0, 3.0, 4.0]


def test_save_in_a_routine_another_calls_is_refused_with_why():
    text = SAVED.replace("CALL F(X, Y)\n", "CALL H(X, Y)\n").replace(
        "      SUBROUTINE G(A, B)", "      SUBROUTINE H(A, B)\n      CALL F(A, B)\n"
        "      RETURN\n      END\n      SUBROUTINE G(A, B)")
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, name="saved.fst")
    said = err.value.render()
    assert "saved.fst:13:15: error: TOTAL is read in SUBROUTINE F before it has a value" \
        in said and "SAVE keeps TOTAL only where the listing CALLs F" in said, said


def test_the_command_runs_a_count_in_step_point_mode_asked_for_and_refuses_others(
        tmp_path, capsys):
    # (a listing with no DRIVER: `--method RECT` is what the refusal tells to write; the
    # command compiled the listing for its default route first and refused there)
    from amilpy.cli import main

    listing = tmp_path / "count.fst"
    listing.write_text(COUNT.replace("TRANSLATION_GENERAL DRIVER='EUDRIV'\n", ""))
    assert main(["run", str(listing), "--method", "RECT", "--quiet", "--csv",
                 str(tmp_path / "c.csv")]) == 0
    rows = (tmp_path / "c.csv").read_text().splitlines()
    # (N#PARAM: the PARAM's value, which the runs change; N is the count)
    assert rows[0].startswith("RUN,N#PARAM,TIME,B,H") and len(rows) == 1 + 2 * 8
    assert main(["run", str(listing), "--method", "RKS", "--quiet"]) != 0
    assert "and METHOD RKS has none" in capsys.readouterr().err


def test_a_kept_name_in_a_routine_called_twice_and_a_routines_array_read_first_are_refused():
    # Fortran keeps one TOTAL for both CALLs (which one runs first would decide the
    # numbers); a routine's own array read before any element of it is given a value
    # is read before it has one (it read as its own new value, twice A, before)
    twice = SAVED.replace("CALL G(X, Z)", "CALL F(2.*X, Z)")
    with pytest.raises(AmilError) as err:
        amilpy.loads(twice, name="saved.fst")
    assert "saved.fst:4:1: error: SUBROUTINE F keeps TOTAL from CALL to CALL (SAVE or " \
        "DATA) and is CALLed 2 times" in err.value.render()
    branch = SAVED.replace("      SAVE\n      TOTAL = TOTAL + A\n      B = TOTAL\n",
                           "      REAL H(3)\n      SAVE H\n      H(1) = 0.\n"
                           "      IF (A .GT. 2.5) H(2) = A\n      B = H(1)\n")
    with pytest.raises(AmilError) as err:
        amilpy.loads(branch, name="saved.fst")
    assert "H, an array SAVE keeps, is set in an IF in SUBROUTINE F" in err.value.render()
    array = SAVED.replace("      SAVE\n      TOTAL = TOTAL + A\n      B = TOTAL\n",
                          "      REAL H(3)\n      SAVE H\n      H(1) = H(1) + A\n"
                          "      B = H(1)\n")
    with pytest.raises(AmilError) as err:
        amilpy.loads(array, name="saved.fst")
    said = err.value.render()
    assert "saved.fst:14:14: error: H is read in SUBROUTINE F before it has a value" in \
        said and "SAVE keeps no array here" in said, said
