"""What amilpy does not run (contract section 14): every keyword of these dialects it
does not implement is an error that names the construct, its line and what to write
instead, never a bare "unexpected token"; no parser token name reaches a user (the
conftest fixture scans every diagnostic any test makes)."""

import pytest
from conftest import leaked_token

import amilpy
from amilpy.diagnostics import AmilError

PROGRAM = "PROGRAM p\n{line}\nDERIVATIVE\nX = INTEG(1.0, 0.0)\nTERMT(T >= 1.0)\nEND\nEND\n"
DERIV = "PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, 0.0)\n{line}\nTERMT(T >= 1.0)\nEND\nEND\n"
CSMP = "{line}\nX = INTGRL(0.0, 1.0)\nTIMER FINTIM = 1.0\nEND\n"

# (listing, its line, what the message names, what the hint tells to write)
CASES = [
    (DERIV, "Y = X(2)", 4, "X is a variable, not a function or an array",
     "DIMENSION X(n)"),
    # (FST's ARRAY X(1:N) and ARRAY_SIZE N = 10 run: tests/test_fst_arrays.py)
    (CSMP, "ARRAY MNDAT (NH)", 1, "an ARRAY statement not of FST's form X(1:N)",
     "ARRAY X(1:N), Y(1:3) with ARRAY_SIZE N = 10"),
    (CSMP, "ARRAY_SIZE NH=N2", 1, "an ARRAY_SIZE statement not of the form N = 10",
     "ARRAY_SIZE N = 10"),
    (CSMP, "STORAGE IC(5)", 1, "CSMP's STORAGE (arrays)", "one scalar per element"),
    (CSMP, "TABLE IC(1-5) = 1., 2., 3., 4., 5.", 1, "the TABLE statement", "FUNCTION F ="),
    (PROGRAM, "TABLE F, 4, 2, 2, 2, 2 / 0., 1., 0., 1., 0., 1., 0., 1., 16*0. /", 2,
     "TABLE F, 4, 2, 2, 2, 2: a table of 1, 2 or 3 variables", "TABLE F, 2, 3, 2 /"),
    (CSMP, "      SUBROUTINE GLA (TIME, X)", 1, "a Fortran subroutine", "PROCEDURE"),
    (CSMP, "CALL TOTASS(DOY, LAT, DTR)", 1,
     "CALL TOTASS (line 1): no SUBROUTINE TOTASS follows STOP",
     "rewrite it as statements or a PROCEDURE"),
    # GO TO runs in written-order code (a PROCEDURAL's), not in DERIVATIVE's sorted code
    (DERIV, "IF( T.LE.1.0E-6) GO TO P\nP: CONTINUE", 4, "GO TO in DERIVATIVE's sorted code",
     "inside a PROCEDURAL block"),
    (DERIV, "GOTO 10\n10 CONTINUE", 4, "GO TO in DERIVATIVE's sorted code",
     "inside a PROCEDURAL block"),
    (DERIV, "10 CONTINUE", 4, "10 CONTINUE ends no DO loop labelled 10", "DO 10 I = a, b"),
    (CSMP, "GO TO 10", 1, "GO TO outside the ACSL form", "IF (c) THEN"),
    (PROGRAM, "GO TO (10, 20), K", 2, "a computed GO TO", "IF (K .EQ. 1) GO TO 10"),
    (CSMP, " 10   X = 1.0", 1, "the statement label 10", "IF (c) THEN"),
    (DERIV, "PROCEDURAL\nDO L I = 1, 2\nY = 1.0\nAnotherLoop: Continue\nEND", 7,
     "ANOTHERLOOP CONTINUE ends no DO loop labelled", "ends at ANOTHERLOOP CONTINUE"),
    (DERIV, "CONTINUE", 4, "CONTINUE (the end of a labelled DO)", "END DO"),
    (PROGRAM, "MACRO first(y, x)\nMACRO RELABEL L1\ny = x\nMACRO END", 3,
     "ACSL's MACRO RELABEL", "MACRO STANDVAL and MACRO REDEFINE"),
    (PROGRAM, "SUBMODEL tank(h, q)", 2, "ACSL's SUBMODEL", "write the statements out"),
    (DERIV, "Y = IMPLC(X - Y, 0.0)", 4, "ACSL's IMPLC (implicit algebraic loop)", "REALPL"),
    (DERIV, "Y = IMPVC(X, 0.0)", 4, "ACSL's IMPVC", "one state per element"),
    (DERIV, "Y = INTVC(X, 0.0)", 4, "ACSL's INTVC", "one INTEG per element"),
    (DERIV, "Y = TRAN(1, 2, N, D, X)", 4, "ACSL's TRAN (transfer function)", "LEDLAG"),
    (DERIV, "Y = DBLINT(X, 0.0, 0.0, -1.0, 1.0)", 4, "ACSL's DBLINT", "two INTEGs"),
    (PROGRAM, "Constant bufferslp = 'RumPartSizeSlp is positive'", 2,
     "the string 'RumPartSizeSlp is positive' cannot be a value", "TERMT message"),
    (CSMP, "STORAGE X(10)", 1, "CSMP's STORAGE (arrays)", "one scalar per element"),
    (CSMP, "COMMON /BLK/ A, B", 1, "Fortran COMMON", "global"),
    (PROGRAM, "DERIVATIVE one\nALGORITHM IALG = 2\nY = INTEG(1.0, 0.)\nEND\n"
     "DERIVATIVE two\nALGORITHM IALG = 5\nZ = INTEG(1.0, 0.)\nEND", 7,
     "a per-section ALGORITHM (line 7)",
     "one ALGORITHM statement"),
]


def fault(template: str, line: str) -> AmilError:
    text = template.format(line=line)
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, name="m.csl" if text.startswith("PROGRAM") else "m.amil")
    return err.value


@pytest.mark.parametrize("template, line, where, construct, instead", CASES,
                         ids=[c[1].split("(")[0].strip()[:24] for c in CASES])
def test_refused_constructs_are_named_with_line_and_alternative(template, line, where,
                                                                 construct, instead):
    err = fault(template, line)
    d = next((d for d in err.diagnostics if construct in d.message), None)
    assert d is not None, err.render()
    assert d.span.line == where and instead in (d.hint or "")
    assert not d.message.startswith("unexpected")


def test_a_message_with_a_token_name_would_be_caught():
    # the scan the conftest fixture makes on every diagnostic of the suite
    assert leaked_token("unexpected '$' / expected DOLLAR") == "DOLLAR"
    assert leaked_token("expected _NL or __ANON_3") == "_NL"
    assert leaked_token("expected DATA_KW") == "DATA_KW"
    assert leaked_token("write X = 1.0; character U+2212 MINUS SIGN") is None


def test_an_unknown_statement_word_gets_a_label_not_tokens():
    # the issue: every unknown keyword gave "unexpected 'X' / expected ',', '='"
    with pytest.raises(AmilError) as err:
        amilpy.loads("FROBNICATE X, Y\nX = INTGRL(0.0, 1.0)\nTIMER FINTIM = 1.0\nEND\n")
    d = err.value.diagnostics[0]
    assert d.message.startswith("this statement needs '='")


def test_molly_style_listing_stops_with_refusals_only(tmp_path):
    # the constructs of A12 (molly3.csl) that amilpy does not run, each named
    text = """PROGRAM molly
  INITIAL
    Integer MaxEvents
    Parameter (MaxHerds=1)
    Constant InitCond = 1.0, 550, 3.5
    CHARACTER bufferslp*80;
  END
  DERIVATIVE
    IF( T.LE.1.0E-6) GO TO P
    X = INTEG(1.0, 0.0)
    TERMT(T >= 1.0)
  END
END
"""
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, "molly.csl")
    messages = [d.message for d in err.value.diagnostics]
    # (the reader goes on past the value list, an array's, now that arrays are read)
    # (CHARACTER is read since: its texts are set aside, `parse.texts`)
    assert messages == ["INITCOND is given 3 values, but it is no array",
                        "GO TO in DERIVATIVE's sorted code, whose order is not the written "
                        "one"]


@pytest.mark.parametrize("call, hint", [
    # the signature, with what trips readers (INTGRL's order is not INTEG's)
    ("INTGRL(1.0)", "write it as INTGRL(IC, X): the initial value comes first"),
    ("INTGRL(A, B, C)", "write it as INTGRL(IC, X): the initial value comes first"),
    ("INTEG(1.0)", "INTEG(X, IC): the derivative comes first"),
    # a decimal comma only where a number stands on both sides of the comma
    ("INTGRL(0.0, 1,5)", "'1,5' reads as two arguments; the decimal separator is a point"),
])
def test_argument_count_errors_show_the_signature(call, hint):
    with pytest.raises(AmilError) as err:
        amilpy.loads(f"CONST A = 1.0, B = 2.0, C = 3.0\nX = {call}\nTIMER FINTIM = 1.0\n"
                     "END\n")
    d = err.value.diagnostics[0]
    assert hint in d.hint and (("decimal" in d.hint) == ("1,5" in call))
