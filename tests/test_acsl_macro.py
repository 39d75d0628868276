"""ACSL's MACRO (contract: moved from refused to required): MACRO NAME(A1, A2, ...) ...
MACRO END, defined before the PROGRAM or inside it, called as a statement NAME(e1, ...)
or with its first arguments before '=' (A1 = NAME(e2, ...)); MACRO STANDVAL gives the
arguments left out at the end, MACRO REDEFINE the names each call keeps to itself; every
other name of the body is the program's. Each listing's numbers are checked against
closed forms; the faults against their located messages."""

import math

import numpy as np
import pytest

import amilpy
from amilpy.diagnostics import AmilError


def run(text: str, **kw):
    runs = amilpy.loads(text, name="m.csl").run(**kw)
    assert len(runs) == 1
    return runs[0]


def fault(text: str) -> str:
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, name="m.csl")
    return err.value.render()


# a first-order lag: Y' = (X - Y)/TAU, Y(0) = Y0 (Y0 = 0 when the call leaves it out);
# RATE is each call's own (REDEFINE), so two calls do not define it twice
LAG = """MACRO LAG(Y, X, TAU, Y0)
   MACRO STANDVAL Y0 = 0.0
   MACRO REDEFINE RATE
   RATE = (X - Y)/TAU
   Y = INTEG(RATE, Y0)
MACRO END
"""

LAGS = LAG + """PROGRAM lags
MACRO LAG2(Y, X, TAU)
   MACRO REDEFINE MID
   LAG(MID, X, TAU)
   Y = LAG(MID, TAU)
MACRO END
INITIAL
  CONSTANT TAU = 2.0, U = 1.0, TF = 4.0
END
DYNAMIC
  CINTERVAL CINT = 0.5
  DERIVATIVE
    Z = LAG(U, TAU)               ! LAG(Z, U, TAU) with Y0 = 0
    LAG2(W, U + 0.0*Z, TAU)       ! an expression where the body only reads
    LAG(V, U, 0.5*TAU, 3.0)       ! Y0 given, and a second RATE of its own
  END
  TERMT(T >= TF)
END
END
"""


def test_a_macro_called_three_ways_matches_the_closed_forms():
    # the unit step through one lag: 1 - e^(-t/tau); through two: 1 - e^(-t/tau)(1 + t/tau);
    # from 3 with tau/2: 1 + 2 e^(-2t/tau). RELERR 1e-11 (the form's default): 1e-9
    r = run(LAGS)
    t = r.t
    assert np.allclose(t, np.arange(9) * 0.5, rtol=0, atol=1e-14)
    assert np.max(np.abs(r["Z"] - (1 - np.exp(-t / 2)))) < 1e-9
    assert np.max(np.abs(r["W"] - (1 - np.exp(-t / 2) * (1 + t / 2)))) < 1e-9
    assert np.max(np.abs(r["V"] - (1 + 2 * np.exp(-t)))) < 1e-9


def test_each_call_keeps_its_redefined_names_apart():
    # four LAG calls (Z's, the two inside LAG2, V's), each RATE its own; LAG2's MID a
    # state of that call alone; RATE of the first call is (U - Z)/TAU
    r = run(LAGS)
    assert sorted(n for n in r.values if "#" in n) == [
        "LAG#1.RATE", "LAG#2.RATE", "LAG#3.RATE", "LAG#4.RATE", "LAG2#1.MID"]
    assert np.max(np.abs(r["LAG#1.RATE"] - (1 - r["Z"]) / 2)) < 1e-12
    assert np.max(np.abs(r["LAG#4.RATE"] - (1 - r["V"]))) < 1e-12


def test_a_name_the_body_assigns_without_redefine_is_the_programs():
    # ACSL's rule: without REDEFINE the body's names are the program's, so a second
    # call defines RATE again: said at the MACRO's line, with the calls as places
    message = fault(LAGS.replace("   MACRO REDEFINE RATE\n", ""))
    assert "RATE is defined twice" in message and "in MACRO LAG, called here" in message


def test_macros_in_written_order_code_a_dose_each_interval():
    # DISCRETE code calling a MACRO: A += AMT every 1.0, and A decays at K in between:
    # just after the n-th dose (n = 0, 1, ...) A = AMT (1 - q^(n+1))/(1 - q), q = e^(-K)
    text = """PROGRAM doses
MACRO DOSE(A, AMT)
   A = A + AMT
MACRO END
INITIAL
  CONSTANT K = 0.3, AMT = 2.0, A0 = 0.0
  CINTERVAL CINT = 0.5
END
DYNAMIC
  DERIVATIVE
    A = INTEG(-K*A, A0)
  END
  DISCRETE dosing
    INTERVAL DT = 1.0
    DOSE(A, AMT)
  END
  TERMT(T >= 4.75)
END
END
"""
    r = run(text, rtol=1e-12, atol=1e-14)
    q = math.exp(-0.3)
    for k, t in enumerate(r.t):
        n = math.floor(t + 1e-12)  # doses given at 0, 1, ..., n
        after = 2.0 * (1 - q ** (n + 1)) / (1 - q)
        assert r["A"][k] == pytest.approx(after * math.exp(-0.3 * (t - n)), rel=1e-9)


def test_a_macro_with_an_if_block_in_its_body():
    # SAT(Y, X, LO, HI) clamps X; Y integrated from the ramp T: the integral of
    # clamp(t, 0.5, 1.5) over [0, 2] is 0.5*0.5 + (1.5^2 - 0.5^2)/2 + 1.5*0.5 = 2.0
    text = """PROGRAM clamp
MACRO SAT(Y, X, LO, HI)
   IF (X < LO) THEN
      Y = LO
   ELSE IF (X > HI) THEN
      Y = HI
   ELSE
      Y = X
   END IF
MACRO END
DERIVATIVE
  SAT(C, T, 0.5, 1.5)
  S = INTEG(C, 0.0)
  TERMT(T >= 2.0)
END
END
"""
    r = run(text, rtol=1e-12, atol=1e-14)
    assert r.t[-1] == pytest.approx(2.0, abs=1e-12)
    assert r["S"][-1] == pytest.approx(2.0, abs=1e-9)


@pytest.mark.parametrize("call, where, words", [
    ("LAG(Z, 1.0)", "12:3", "LAG takes 4 argument(s), and TAU has no MACRO STANDVAL value"),
    ("LAG(Z, 1.0, 1.0, 0.0, 5.0)", "12:3", "LAG takes 4 argument(s), 5 given"),
    ("LAG(2.0*Z, 1.0, 1.0)", "12:3", "argument Y of MACRO LAG is assigned in it"),
    ("NOSUCH(Z, 1.0)", "12:3", "no MACRO NOSUCH is defined"),
    ("LOOP(Z)", "3:4", "MACRO LOOP calls itself"),  # (at the body's call, LOOP's line)
    ("X = 1.0 + LAG(1.0, 2.0)", "12:13", "MACRO LAG is called inside an expression"),
])
def test_a_wrong_call_is_located_and_says_what_to_write(call, where, words):
    # LOOP's three lines after PROGRAM, then LAG's six: the call is on line 12
    text = ("PROGRAM p\nMACRO LOOP(Y)\n   LOOP(Y)\nMACRO END\n" + LAG + "DERIVATIVE\n  "
            + call + "\n  TERMT(T >= 1.0)\nEND\nEND\n")
    message = fault(text)
    assert f"m.csl:{where}: error: " in message and words in message, message


def test_macro_directives_and_blocks_out_of_place():
    relabel = fault("PROGRAM p\nMACRO M(Y, X)\nMACRO RELABEL L1\nY = X\nMACRO END\n"
                    "DERIVATIVE\nM(A, 1.0)\nEND\nEND\n")
    assert "m.csl:3:1:" in relabel and "ACSL's MACRO RELABEL" in relabel
    stray = fault("PROGRAM p\nMACRO STANDVAL X = 1.0\nDERIVATIVE\nA = 1.0\nEND\nEND\n")
    assert "m.csl:2:1:" in stray and "MACRO STANDVAL stands inside a MACRO" in stray
    unclosed = fault("PROGRAM p\nMACRO M(Y, X)\nY = X\nDERIVATIVE\nM(A, 1.0)\nEND\nEND\n")
    assert "MACRO opened at line 2 is never closed" in unclosed and "MACRO END" in unclosed
    with pytest.raises(AmilError) as err:  # ACSL's MACRO in a CSMP-form listing
        amilpy.loads("MACRO M(Y, X)\nY = X\nMACRO END\nA = INTGRL(0.0, 1.0)\n"
                     "TIMER FINTIM = 1.0\nEND\n", name="m.amil")
    assert "belongs to the ACSL form" in err.value.render()


def test_macros_before_the_program_leave_it_in_the_acsl_form():
    # (the file's first statement is a MACRO: CONSTANT TAUS = 2.0, 4.0 still fills the
    # array, as in any ACSL program) and array elements are arguments like any value
    text = LAG + """PROGRAM arrays
INITIAL
  DIMENSION TAUS(2)
  CONSTANT TAUS = 2.0, 4.0
  CINTERVAL CINT = 1.0
END
DERIVATIVE
  LAG(Z1, 1.0, TAUS(1))
  LAG(Z2, 1.0, TAUS(2))
  TERMT(T >= 4.0)
END
END
"""
    r = run(text)
    assert np.max(np.abs(r["Z1"] - (1 - np.exp(-r.t / 2)))) < 1e-9
    assert np.max(np.abs(r["Z2"] - (1 - np.exp(-r.t / 4)))) < 1e-9


# Arguments that are no plain values: an array read by subscript, a table read as a
# function, a DISCRETE section a SCHEDULE names, an INTERVAL's name; and REDEFINE'd
# names that are a CONSTANT or an array of each call. (what a run gives, by hand)
VSUM = """PROGRAM arr
MACRO VSUM(S, V, N)
   MACRO REDEFINE I
   PROCEDURAL(S = V)
   S = 0.0
   DO I = 1, N
      S = S + V(I) + V[I]
   END DO
   END
MACRO END
DIMENSION A(3)
CONSTANT A = 1.0, 2.0, 3.0
DERIVATIVE
  VSUM(Q, A, 3)                   ! Q = 2 (1 + 2 + 3) = 12
  Z = INTEG(Q, 0.0)
  TERMT(T >= 1.0)
END
END
"""
LOOKUP = """PROGRAM tab
MACRO LOOKUP(Y, F, X)
   Y = F(X)
MACRO END
TABLE GAIN, 1, 3 / 0.0, 1.0, 2.0, 0.0, 1.0, 4.0 /
DERIVATIVE
  LOOKUP(G, GAIN, 1.5)            ! G = 2.5, halfway from 1 to 4
  Z = INTEG(G, 0.0)
  TERMT(T >= 1.0)
END
END
"""
LOCALS = """PROGRAM arr
MACRO TWO(S, X)
   MACRO REDEFINE W, K
   DIMENSION W(2)
   CONSTANT K = 2.0
   W(1) = X
   W(2) = K*X
   S = W(1) + W(2)
MACRO END
DERIVATIVE
  TWO(P, 1.0)                     ! 3
  TWO(Q, 2.0)                     ! 6
  Z = INTEG(P + Q, 0.0)
  TERMT(T >= 1.0)
END
END
"""
SECTIONS = """PROGRAM sp
MACRO AFTER(SEC, D)
   SCHEDULE SEC .AT. T + D
MACRO END
MACRO EVERY(DTN, DT)
   INTERVAL DTN = DT
MACRO END
INITIAL
  AFTER(bump, 0.25)
END
DYNAMIC
  DERIVATIVE
    C = INTEG(0.0, 0.0)
    D = INTEG(0.0, 0.0)
  END
  DISCRETE bump                   ! C = 10 from 0.25 on
    C = C + 10.0
  END
  DISCRETE tick                   ! D + 1 at 0, 0.5 and 1.0
    EVERY(DTA, 0.5)
    D = D + 1.0
  END
  TERMT(T >= 1.0)
END
END
"""


@pytest.mark.parametrize("text, name, final", [
    (VSUM, "Z", 12.0), (LOOKUP, "Z", 2.5), (LOCALS, "Z", 9.0), (SECTIONS, "C", 10.0),
    (SECTIONS, "D", 3.0),
])
def test_arguments_that_name_arrays_tables_sections_and_local_declarations(text, name, final):
    r = run(text, rtol=1e-12, atol=1e-14)
    assert r.t[-1] == pytest.approx(1.0, abs=1e-12)
    assert r[name][-1] == pytest.approx(final, rel=1e-10)


@pytest.mark.parametrize("definition, where, words", [
    ("MACRO M(Y, X, X)\n   Y = X", "2:1", "MACRO M names its argument X twice"),
    ("MACRO M(Y, X)\n   MACRO STANDVAL B = 1.0\n   Y = X", "2:1",
     "MACRO STANDVAL B: no argument of MACRO M (Y, X)"),
    ("MACRO M(Y, X)\n   MACRO STANDVAL X = 1.2.3\n   Y = X", "3:4",
     "MACRO STANDVAL takes NAME = number items"),
    ("MACRO ABS(Y, X)\n   Y = 2.0*X", "2:1",
     "MACRO ABS: ABS is a function, which a MACRO of that name would hide"),
    ("MACRO SET(Y, X)\n   Y = X", "2:1", "MACRO SET: SET is a keyword"),
    ("MACRO M(Y, X)\n   IF (X > 0.0) THEN\n      MACRO REDEFINE Q\n   END IF\n   Y = X",
     "4:7", "MACRO REDEFINE stands in the MACRO's own body, not inside a block of it"),
])
def test_a_faulty_definition_is_said_once_and_its_calls_are_not(definition, where, words):
    name = definition.split()[1].split("(")[0]
    text = ("PROGRAM p\n" + definition + f"\nMACRO END\nDERIVATIVE\n  {name}(Z, 1.0)\n"
            "  W = INTEG(1.0, 0.0)\n  TERMT(T >= 1.0)\nEND\nEND\n")
    message = fault(text)
    assert f"m.csl:{where}: error: {words}" in message, message
    assert "is defined" not in message  # (the definition's fault only, not its calls')


def test_a_macro_call_in_a_condition_and_misplaced_calls_say_what_to_write():
    text = ("PROGRAM p\nMACRO TWICE(Y, X)\n   Y = 2.0*X\nMACRO END\nDIMENSION B(2)\n"
            "DERIVATIVE\n  W = INTEG(1.0, 0.0)\n  IF (TWICE(T) > 1.0) Q = 1.0\n"
            "  TERMT(TWICE(T) >= 2.0)\n  B(1) = TWICE(1.0)\nEND\nEND\n")
    message = fault(text)
    assert "m.csl:8:7: error: MACRO TWICE is called inside an expression" in message
    assert "m.csl:9:9: error: MACRO TWICE is called inside an expression" in message
    assert "m.csl:10:3: error: MACRO TWICE gives its values to names, not to an array's " \
           "element" in message
    with pytest.raises(AmilError) as err:  # a statement NAME(...) in the CSMP form
        amilpy.loads("A = INTGRL(0.0, 1.0)\nDEBUG(1)\nTIMER FINTIM = 1.0\nEND\n",
                     name="m.amil")
    assert "m.amil:2:1: error: DEBUG(...) is no statement of the CSMP form" in \
        err.value.render()
    with pytest.raises(AmilError) as err:  # CSMP III's MACRO called ACSL's way
        amilpy.loads("MACRO Y = LAG1(T1, X)\nY = REALPL(0.0, T1, X)\nENDMAC\n"
                     "LAG1(2.0, 1.0)\nTIMER FINTIM = 1.0\nEND\n", name="m.amil")
    assert "MACRO LAG1 is CSMP III's: it is called Y = LAG1(T1, X)" in err.value.render()


def test_a_fault_inside_a_block_of_a_macro_names_the_call():
    text = ("PROGRAM p\nMACRO SAT(Y, X)\n   IF (X > 1.0) THEN\n      Y = 1.0\n   ELSE\n"
            "      Y = X + UNDEFINEDNAME\n   END IF\nMACRO END\nDERIVATIVE\n  SAT(Z, T)\n"
            "  W = INTEG(Z, 0.0)\n  TERMT(T >= 1.0)\nEND\nEND\n")
    message = fault(text)
    assert "m.csl:6:15: error: UNDEFINEDNAME is used but never defined" in message
    assert "m.csl:10:3: note: in MACRO SAT, called here" in message
