"""Arrays in ACSL/Magnolia listings (issue 22): DIMENSION (brackets or parentheses,
typed), CONSTANT value lists in Fortran's order, subscripts known when the listing is
read and only as the run goes, loops written out over arrays, whole-array INTEG. Each
element is a variable of its own (`X(1)`); every test runs to a closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest

import amilpy
from amilpy.diagnostics import AmilError, UsageError

DECAYS = """PROGRAM three decays, one array
  DIMENSION X(3), XD(3), K(3), X0(3)
  CONSTANT K = 1.0, 2.0, 3.0, X0 = 3*1.0
  CINTERVAL CINT = 0.1
  DERIVATIVE
    PROCEDURAL (XD = X)
      DO I = 1, 3
        XD(I) = -K(I)*X[I]
      END DO
    END
    X = INTEG(XD, X0)
    TERMT(T >= 1.0)
  END
END
"""


def test_an_array_of_states_integrates_element_by_element():
    """X(i)' = -K(i) X(i), X(i)(0) = 1: exp(-K(i) t) at every row (ACSL default RELERR
    1e-11: 1e-9 holds with room)."""
    run = amilpy.loads(DECAYS, "decays.csl").run(advice=False)[0]
    for i, k in enumerate((1.0, 2.0, 3.0), start=1):
        assert np.max(np.abs(run[f"X({i})"] - np.exp(-k * run.t))) < 1e-9
    # (nothing reads I after the loop: it is no variable of the run, and the PROCEDURAL
    # says nothing of it)
    assert "I" not in run.final and not run.warnings


@pytest.mark.parametrize("method", ["AUTO", "RKS", "STIFF"])
def test_a_chain_written_as_a_loop_in_sorted_code(method):
    """N compartments in a row, X(1)(0) = 1, the loop in DERIVATIVE itself (written out
    element by element, then sorted): X(n) = (k t)^(n-1)/(n-1)! exp(-k t), Erlang's."""
    text = """PROGRAM chain
  CONSTANT N = 5, KT = 2.0
  DIMENSION X[N], XD[N], X0[N]
  CONSTANT X0 = 1.0, 4*0.0
  CINTERVAL CINT = 0.25
  DERIVATIVE
    XD[1] = -KT*X[1]
    for i = 2, N
      XD[i] = KT*(X[i - 1] - X[i])
    end
    X = INTEG(XD, X0)
    TERMT(T >= 3.0)
  END
END
"""
    run = amilpy.loads(text, "chain.csl").run(method=method, advice=False)[0]
    kt = 2.0 * run.t
    tol = 1e-8 if method == "AUTO" else 1e-5  # (RKS/STIFF at the same RELERR: looser)
    for n in range(1, 6):
        exact = kt ** (n - 1) / math.factorial(n - 1) * np.exp(-kt)
        assert np.max(np.abs(run[f"X({n})"] - exact)) < tol


def test_a_value_list_fills_a_two_dimensional_array_in_fortrans_order():
    """A(2,2) = 1, 2, 3, 4: the first subscript runs fastest, A(2,1) = 2, A(1,2) = 3."""
    text = """PROGRAM order
  DIMENSION A(2, 2)
  CONSTANT A = 1, 2, 3, 4
  CINTERVAL CINT = 0.5
  DERIVATIVE
    Y = INTEG(A(1,2) + 10.0*A[2,1], 0.0)
    TERMT(T >= 1.0)
  END
END
"""
    run = amilpy.loads(text, "order.csl").run(advice=False)[0]
    assert run.final["Y"] == pytest.approx(23.0, rel=1e-12)
    assert [run.final[f"A({i},{j})"] for j in (1, 2) for i in (1, 2)] == [1, 2, 3, 4]


REMDESIVIR_LIKE = """PROGRAM five infusions
INITIAL
  dimension real dose[5], tinf[5]
  constant dose = 200.0, 100.0, 100.0, 100.0, 100.0
  constant tinf = 2.0, 2.0, 2.0, 2.0, 2.0
  dimension integer day
  for day = 1, 5
    schedule start_infusion at 24.0*(day - 1)
    schedule end_infusion at 24.0*(day - 1) + tinf[day]
  end
  day = 1
  infrate = 0.0
  constant TSTOP = 120.0, KE = 0.1
  CINTERVAL CINT = 1.0
end
DERIVATIVE
  A = INTEG(infrate - KE*A, 0.0)
  TERMT(T >= TSTOP)
end
discrete start_infusion
  infrate = dose[day]/tinf[day]
  day = day + 1
end
discrete end_infusion
  infrate = 0.0
end
END
"""


def _infused(t: float, ke: float = 0.1) -> float:
    """The amount after five zero-order infusions (dose D over 2 h each day), by
    superposition of each infusion's closed form."""
    total = 0.0
    for d, dose in enumerate((200.0, 100.0, 100.0, 100.0, 100.0)):
        t0 = 24.0 * d
        if t > t0:
            te = min(t, t0 + 2.0)
            total += dose / 2.0 / ke * (1 - math.exp(-ke * (te - t0))) * math.exp(-ke * (t - te))
    return total


def test_subscripts_known_only_as_the_run_goes():
    """The remdesivir listing's dosing (magnoliasci/PBPK): SCHEDULEs in a FOR loop over
    an array, and dose[day] in a DISCRETE section where DAY counts the doses. Against
    superposed infusions: 1e-7 of the peak (ACSL default tolerances)."""
    run = amilpy.loads(REMDESIVIR_LIKE, "dosing.csl").run(advice=False)[0]
    exact = np.array([_infused(t) for t in run.t])
    assert np.max(np.abs(run["A"] - exact)) < 1e-7 * exact.max()
    assert run.final["DAY"] == 6.0
    assert [e.time for e in run.events if e.kind == "discrete"] == [
        24.0 * d + h for d in range(5) for h in (0.0, 2.0)]


def test_a_subscript_outside_the_array_while_running_is_named():
    """Six infusions scheduled over an array of five: the sixth reads DOSE[6]."""
    text = REMDESIVIR_LIKE.replace("for day = 1, 5", "for day = 1, 6").replace(
        "tinf[day]\n  end", "2.0\n  end")
    run = amilpy.loads(text, "dosing.csl").run(advice=False)[0]
    assert not run.ok
    assert "a subscript 6 outside 1..5" in run.message
    assert run.t[-1] == pytest.approx(120.0)  # (the sixth dose is due at 120)


def test_whole_array_statements_and_print():
    """V = 2*W + C for arrays V, W and a scalar C: element by element; PRINT V lists
    the elements."""
    text = """PROGRAM whole
  DIMENSION V(3), W(3)
  CONSTANT W = 1.0, 2.0, 3.0, C = 0.5
  CINTERVAL CINT = 0.5
  DERIVATIVE
    V = 2.0*W + C
    Y = INTEG(V(3), 0.0)
    TERMT(T >= 1.0)
  END
  PRINT V
END
"""
    run = amilpy.loads(text, "whole.csl").run(advice=False)[0]
    assert [run.final[f"V({i})"] for i in (1, 2, 3)] == [2.5, 4.5, 6.5]
    assert [c for c in run.printout.columns if c.startswith("V")] == ["V(1)", "V(2)", "V(3)"]


def test_a_size_is_fixed_when_the_listing_is_read():
    """N sizes the arrays and bounds the loop: a run may not change it."""
    text = DECAYS.replace("DIMENSION X(3), XD(3), K(3), X0(3)",
                          "CONSTANT N = 3\n  DIMENSION X(N), XD(N), K(N), X0(N)")
    model = amilpy.loads(text, "decays.csl")
    with pytest.raises(UsageError, match="N sizes an array"):
        model.run(N=4)
    # an element's value is a value like any other
    run = model.run(advice=False, **{"K(2)": 0.5})[0]
    assert np.max(np.abs(run["X(2)"] - np.exp(-0.5 * run.t))) < 1e-9


@pytest.mark.parametrize("line, message, hint", [
    ("  DIMENSION Z(3)\n  Y = Z(4)", "the subscript 4 of Z is outside 1..3", "line 4"),
    ("  Y = Z[4] + 1.0", "Z[...]: Z is not an array", "DIMENSION Z(10)"),
    ("  DIMENSION Z(2)\n  CONSTANT Z = 1.0, 2.0, 3.0", "Z is given 3 value(s) for 2",
     "2*0.0"),
    ("  CONSTANT Z = 1.0, 2.0", "Z is given 2 values, but it is no array",
     "DIMENSION Z(2)"),
    ("  DIMENSION Z(2)\n  CONSTANT Z = 1.0, 2.0\n  Y = Z + 1.0",
     "the array Z stands here without a subscript", "Z[i]"),
    ("  DIMENSION Z(2, 2)\n  Y = Z(1)", "Z has 2 subscript(s), not 1", "Z[i, j]"),
    ("  DimensionZ = 1.0\n  DoublePrecision Z(NZ)", "the size of Z is not known", "CONSTANT"),
    ("  DIMENSION Z(2)\n  Z(J) = 1.0\n  J = 1.0", "a subscript known only as the run goes",
     "PROCEDURAL"),
    # (an array named SIN would silently turn every SIN(X) into a subscript)
    ("  DIMENSION SIN(3)\n  Y = SIN(2)", "SIN is a function: an array cannot take its name",
     "another name"),
    ("  DIMENSION T(3)\n  Y = T(2)", "T is reserved: an array cannot take its name",
     "another name"),
])
def test_array_faults_are_located_with_what_to_write(line, message, hint):
    text = ("PROGRAM faults\n  CINTERVAL CINT = 0.5\n  DERIVATIVE\n"
            f"{line}\n  X = INTEG(1.0, 0.0)\n  TERMT(T >= 1.0)\n  END\nEND\n")
    text = text.replace("DERIVATIVE\n  DIMENSION", "DERIVATIVE\n  DIMENSION")
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, "faults.csl")
    d = err.value.diagnostics[0]
    assert message in d.message and hint in (d.hint or "")
    assert d.span is not None and d.span.line >= 4


NAMED = """PROGRAM values named by PARAMETERs, as Molly writes them
  PARAMETER (NH = 3, IA = 2)
  DIMENSION F(NH), G(4), H(2, 3)
  CONSTANT F = NH*1.5
  CONSTANT G = IA, 7.0, 2*IA
  CONSTANT H = 1.0, 2.0
  CINTERVAL CINT = 0.5
  DERIVATIVE
    PROCEDURAL (R = )
      CONSTANT S = IA
      R = F(1) + F(3) + G(1) + G(4) + H(1,1) + H(2,1) + H(1,2) + H(2,3) + S
    END
    X = INTEG(R, 0.0)
    TERMT(T >= 1.0)
  END
END
"""


def test_a_value_list_reads_parameter_names_and_zero_fills():
    """A count or a value of a CONSTANT list may name a PARAMETER (Fortran's DATA
    takes named constants): NH*1.5 is three 1.5s, G = (2, 7, 2, 2). H gets its first
    two elements, the rest 0 (the zero of static storage; Molly relies on it), with a
    warning; a CONSTANT inside a PROCEDURAL is a declaration like any other. So
    R = 1.5 + 1.5 + 2 + 2 + 1 + 2 + 0 + 0 + 2 = 12 and X(t) = 12 t, exact at every
    row to rounding."""
    model = amilpy.loads(NAMED, "named.csl")
    run = model.run(advice=False)[0]
    assert np.max(np.abs(run["X"] - 12.0 * run.t)) < 1e-12
    assert any("H is given 2 value(s) for 6 elements: the other 4 are 0" in w
               for w in run.warnings)
    # the PARAMETERs the lists read are fixed when the listing is read
    with pytest.raises(UsageError, match="NH sizes an array"):
        model.run(NH=4)


@pytest.mark.parametrize("line, message", [
    ("  DIMENSION Z(2)\n  CONSTANT Z = NZ*0.0", "Z's values name NZ, which has no value"),
    ("  DIMENSION Z(2)\n  CONSTANT Z = 1.0, W", "Z's values name W, which has no value"),
    ("  PARAMETER (NZ = 1.5)\n  DIMENSION Z(2)\n  CONSTANT Z = NZ*0.0",
     "the repeat count NZ is 1.5"),
])
def test_a_named_value_that_is_not_known_is_located(line, message):
    text = ("PROGRAM faults\n  CINTERVAL CINT = 0.5\n  DERIVATIVE\n"
            f"{line}\n  X = INTEG(1.0, 0.0)\n  TERMT(T >= 1.0)\n  END\nEND\n")
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, "faults.csl")
    d = err.value.diagnostics[0]
    assert message in d.message and d.span is not None and d.span.line >= 4


def test_csmp_data_statements_still_take_numbers_only():
    """In CSMP form PARAM A = B or CONST A = 2*B is a derived value written in the
    wrong place: refused as before, with where it belongs."""
    for line in ("PARAM A = B", "CONST A = 2*B", "PARAM A = 1, B = C"):
        text = f"TITLE t\n{line}\nX = INTGRL(0.0, 1.0)\nTIMER FINTIM = 1.0, OUTDEL = 0.5\nEND\n"
        with pytest.raises(AmilError) as err:
            amilpy.loads(text, "t.amil")
        d = err.value.diagnostics[0]
        assert "a data statement takes NAME = number" in d.message, line
        assert "INITIAL" in d.hint and d.span.line == 2


def test_a_decimal_comma_is_still_one_in_csmp_form():
    """PARAM K = 1,5 in CSMP form is a slip for 1.5 (arrays are the ACSL form's)."""
    with pytest.raises(AmilError) as err:
        amilpy.loads("PARAM K = 1,5\nX = INTGRL(0.0, K)\nTIMER FINTIM = 1.0\nEND\n")
    d = err.value.diagnostics[0]
    assert "decimal comma" in d.message and "1.5" in d.hint


def test_an_acsl_table_is_read_as_its_function():
    """TABLE F, 1, 4 / x..., y... / (the Loccisano and Verner listings' form, with a
    repeat and a continuation line): F(X) interpolates linearly and holds the end
    values outside, as AFGEN. Y' = F(T) from 0 to 4: the area under the polyline,
    0..1: T, 1..2: 1, 2..3: 1 + 2(T - 2), then 3 held -> 0.5 + 1 + 2 + 3 = 6.5."""
    text = """PROGRAM table
  TABLE F, 1, 4 / 0.0, 1.0, 2.0, 3.0, &
                  0.0, 2*1.0, 3.0 /   ! breakpoints, then values
  CINTERVAL CINT = 0.5
  DERIVATIVE
    Y = INTEG(F(T), 0.0)
    TERMT(T >= 4.0)
  END
END
"""
    run = amilpy.loads(text, "table.csl").run(advice=False)[0]
    assert run.final["Y"] == pytest.approx(6.5, rel=1e-9)
    i = int(np.argmin(np.abs(run.t - 2.5)))
    assert run["Y"][i] == pytest.approx(0.5 + 1.0 + 0.5 + 0.25, rel=1e-9)


@pytest.mark.parametrize("line, message", [
    ("TABLE F, 1, 3 / 0.0, 1.0, 2.0, 0.0, 1.0 /", "TABLE F has 5 values for 3 breakpoints"),
    ("TABLE F, 1, 2 / 0.0, 1.0, 0.0, Q /", "TABLE F: 'Q' is not a number"),
    # (said of the TABLE, not of the 1-variable tables it is written out as)
    ("TABLE F, 1, 3 / 0.0, 2.0, 1.0, 0.0, 1.0, 2.0 /",
     "TABLE F: its breakpoints must increase strictly (2, then 1)"),
    ("TABLE F, 2, 2, 2 / 0.0, 1.0, 5.0, 5.0, 1.0, 2.0, 3.0, 4.0 /",
     "TABLE F: its second variable's breakpoints must increase strictly (5, then 5)"),
])
def test_table_faults_are_located(line, message):
    text = (f"PROGRAM t\n  {line}\n  CINTERVAL CINT = 0.5\n  DERIVATIVE\n"
            "    Y = INTEG(F(T), 0.0)\n    TERMT(T >= 1.0)\n  END\nEND\n")
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, "t.csl")
    d = err.value.diagnostics[0]
    assert message in d.message and d.span.line == 2


def test_labelled_do_loops_and_array_as_dimension():
    """Fortran's DO 10 J ... DO 10 I ... 10 CONTINUE (one label ends both loops), a
    named label (`do l1 k = ...` / `l1: continue`, acslX), and ARRAY X(n) as DIMENSION
    (acslX): A(I, J) = 10 I + J, S = A(1,2) + A(2,2) + A(3,2) = 66."""
    text = """PROGRAM labelled loops
  ARRAY A(3, 2)
  CINTERVAL CINT = 0.5
  INITIAL
    DO 10 J = 1, 2
    DO 10 I = 1, 3
      A(I, J) = 10*I + J
 10 CONTINUE
    S = 0.0
    do l1 k = 1, 3
      S = S + A(k, 2)
l1: continue
    N = 100*I + 10*J + K
  END
  DERIVATIVE
    Y = INTEG(S, 0.0)
    TERMT(T >= 1.0)
  END
END
"""
    run = amilpy.loads(text, "loops.csl").run(advice=False)[0]
    assert [run.final[f"A({i},{j})"] for j in (1, 2) for i in (1, 2, 3)] == [
        11, 21, 31, 12, 22, 32]
    assert run.final["S"] == 66.0 and run.final["Y"] == pytest.approx(66.0, rel=1e-12)
    # the loops' variables after them, as Fortran leaves them, where something reads them
    assert run.final["N"] == 434.0


def test_acsl_tables_of_two_and_three_variables():
    """TABLE G, 2, 3, 2 (x = 0, 1, 2; y = 0, 10): bilinear between the breakpoints and
    the end values held, as for one variable: G(0.5, 5) = 3.25, G(1.5, 12) = 10 (y held
    at 10), G(-1, -3) = G(0, 0) = 0; along x = t, y = 10 t it is 6 t + t^2, whose
    integral to 1 is 10/3. A table of three variables whose values are 1 + x + 2y + 4z
    at the corners gives that, trilinear, inside: H(0.25, 0.5, 0.75) = 5.25."""
    text = """PROGRAM two-variable table
  TABLE G, 2, 3, 2 / 0.0, 1.0, 2.0,  0.0, 10.0, &
                     0.0, 1.0, 4.0,  5.0, 7.0, 13.0 /
  TABLE H, 3, 2, 2, 2 / 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, &
                        1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0 /
  CINTERVAL CINT = 0.5
  DERIVATIVE
    A = G(0.5, 5.0)
    B = G(1.5, 12.0)
    C = G(-1.0, -3.0)
    D = H(0.25, 0.5, 0.75)
    X = INTEG(G(T, 10.0*T), 0.0)
    TERMT(T >= 1.0)
  END
END
"""
    f = amilpy.loads(text, "tables.csl").run(advice=False)[0].final
    assert (f["A"], f["B"], f["C"], f["D"]) == (3.25, 10.0, 0.0, 5.25)
    assert f["X"] == pytest.approx(10.0 / 3.0, rel=1e-10)
    with pytest.raises(AmilError, match="the table G takes 2 argument"):
        amilpy.loads(text.replace("G(0.5, 5.0)", "G(0.5)"), "tables.csl")


def test_an_element_is_named_on_the_command_line(tmp_path):
    """`--set K(2)=0.5` and a sweep over `K(2)=0.5:1:0.5` with `--measure X(2)`: an
    element is a data value like any other (the sweep said "'K(2)' is not a name").
    X(2) = exp(-K(2) t) falls to exp(-K(2)) at t = 1."""
    from amilpy.batch.sweep import parse_range
    from amilpy.cli import main

    assert parse_range("k( 2 )=0.5:1:0.5") == ("K(2)", [0.5, 1.0])
    path = tmp_path / "decays.csl"
    path.write_text(DECAYS)
    csv = tmp_path / "sweep.csv"
    assert main(["sweep", str(path), "K(2)=0.5:1:0.5", "--measure", "X(2)", "--csv",
                 str(csv), "--quiet"]) == 0
    rows = csv.read_text().splitlines()
    assert rows[0].split(",")[1:3] == ["K(2)", "MIN_X(2)"]
    assert [float(r.split(",")[2]) for r in rows[1:]] == pytest.approx(
        [math.exp(-0.5), math.exp(-1.0)], rel=1e-8)


def test_character_names_keep_their_texts_aside():
    """Molly declares text for messages only routines amilpy does not run would print:
    CHARACTER bufferslp*80 and CONSTANT bufferslp = '...' are read and set aside (a
    length, CHARACTER*40 or REAL*8, is read and left). X' = K = 2: X(1) = 2."""
    text = """PROGRAM texts
  INITIAL
    CHARACTER bufferslp*80;
    Character*40 other
    REAL*8 K
    Constant bufferslp = 'RumPartSizeSlp is positive - it''s likely non-biological'
    CONSTANT other = 'x', K = 2.0
  END
  DERIVATIVE
    X = INTEG(K, 0.0)
    TERMT(T >= 1.0)
  END
END
"""
    run = amilpy.loads(text, "texts.csl").run(advice=False)[0]
    assert abs(run.final["X"] - 2.0) < 1e-12 and "BUFFERSLP" not in run.final
    # read in a computation: said where it is read, not "used but never defined"
    with pytest.raises(AmilError) as err:
        amilpy.loads(text.replace("INTEG(K, 0.0)", "INTEG(K + bufferslp, 0.0)"), "t.csl")
    d = err.value.diagnostics[0]
    assert d.message == "BUFFERSLP is CHARACTER text: a run computes with numbers only"
    assert (d.span.line, d.span.column) == (10, 19)
    # a text for a name that is no CHARACTER
    with pytest.raises(AmilError) as err:
        amilpy.loads(text.replace("CHARACTER bufferslp*80;", ""), "t.csl")
    d = err.value.diagnostics[0]
    assert d.message.startswith("the string 'RumPartSizeSlp is positive - it's likely")
    assert "CHARACTER BUFFERSLP*80" in d.hint and d.span.line == 6
