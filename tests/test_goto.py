"""GO TO in the ACSL form's written-order code (a PROCEDURAL's, INITIAL's, a
DISCRETE section's): a jump forward, out of IF blocks and DO loops, written out as IF
blocks (parse/jumps.py), with the numbers the jumps give; the rest refused at the GO
TO with what to write."""

from __future__ import annotations

import math

import pytest

import amilpy
from amilpy.diagnostics import AmilError

# Molly's way of choosing a set of coefficients (molly3.csl, its FORSET/MIXSET/CONSET)
CHOOSE = """PROGRAM CHOOSE
INITIAL
CONSTANT FORSET = {f}, MIXSET = {m}, CONSET = {c}
END
DERIVATIVE
PROCEDURAL (A, B = FORSET, MIXSET, CONSET)
   IF(FORSET.EQ.1.0) GO TO 10
   IF(MIXSET.EQ.1.0) GO TO 11
   IF(CONSET.EQ.1.0) GO TO 12
10: A = 1.0
    B = 10.0
    GO TO 13
11: A = 2.0
    B = 20.0
    GO TO 13
12: A = 3.0
    B = 30.0
13: CONTINUE
END
X = INTEG(-A*X, 1.0)
TERMT (T .GE. 1.0)
END
END
"""


@pytest.mark.parametrize("f, m, c, a, b", [(1, 0, 0, 1, 10), (0, 1, 0, 2, 20),
                                           (0, 0, 1, 3, 30), (0, 1, 1, 2, 20),
                                           (0, 0, 0, 1, 10)])
def test_a_chain_of_jumps_chooses_one_set_as_fortran_would(f, m, c, a, b):
    # the first set whose switch is 1 (none: the first, which the jumps fall into);
    # X = exp(-A t), the rate the jumps chose (RELERR 1e-10: 1e-9 relative)
    run, = amilpy.loads(CHOOSE.format(f=f, m=m, c=c), "choose.csl").run(
        advice=False, rtol=1e-10, atol=1e-12)
    assert set(run["A"]) == {a} and set(run["B"]) == {b}
    assert run["X"][-1] == pytest.approx(math.exp(-a), rel=1e-9)


def test_a_jump_on_a_state_is_a_located_switch():
    # X' = -X while X > 0.5, then -2X: X = exp(-t) to t1 = ln 2, then 0.5 exp(-2(t - t1));
    # the condition of the GO TO is watched like an IF's, its crossing located
    run, = amilpy.loads("""PROGRAM P
DERIVATIVE
PROCEDURAL (R = X)
   R = -X
   IF (X .GT. 0.5) GO TO 20
   R = -2.0*X
20: CONTINUE
END
X = INTEG(R, 1.0)
TERMT (T .GE. 1.5)
END
END
""", "p.csl").run(advice=False, rtol=1e-10, atol=1e-12)
    t1 = math.log(2.0)
    assert any(abs(e.time - t1) < 1e-9 for e in run.events)
    # (the flags' own tests -- set where the located X > 0.5 is -- are no news: no NOTE
    # that they are never located)
    assert not any("never located" in w for w in run.warnings), run.warnings
    assert run["X"][-1] == pytest.approx(0.5 * math.exp(-2.0 * (1.5 - t1)), rel=1e-8)


def test_jumps_out_of_a_loop_and_out_of_nested_ifs_in_initial():
    # K: the last I with I*I <= 10 (the loop left at I = 4); the nested IF's jump skips
    # C2 and lands on D's label; E after the label runs on every path
    run, = amilpy.loads("""PROGRAM P
INITIAL
   CONSTANT A = 1.0, B = 1.0
   K = 0.0
   DO 5 I = 1, 10
      IF (I*I .GT. 10.0) GO TO 20
      K = I
 5 CONTINUE
20: CONTINUE
   C = 0.0
   C2 = 0.0
   IF (A .GT. 0.0) THEN
      IF (B .GT. 0.0) GO TO 30
      C = 1.0
   END IF
   C2 = 2.0
30: D = 3.0
   E = K + C + C2 + D
END
DERIVATIVE
X = INTEG(E, 0.0)
TERMT (T .GE. 1.0)
END
END
""", "p.csl").run(advice=False)
    assert run.constants["K"] == 3.0
    assert (run.constants["C"], run.constants["C2"], run.constants["D"]) == (0.0, 0.0, 3.0)
    assert run["X"][-1] == pytest.approx(6.0, rel=1e-12)


@pytest.mark.parametrize("body, where, words", [
    ("10: X0 = 1.0\n   GO TO 10", "5:4", "GO TO 10 jumps back (to line 4): a loop"),
    ("GO TO 20\nIF (X0 .GT. 0.0) THEN\n20: X0 = 1.0\nEND IF",
     "4:1", "GO TO 20 jumps into an IF or DO block"),
    ("GO TO 99\nX0 = 1.0", "4:1", "GO TO 99: no label 99 where it can jump"),
    ("GO TO 7\n7: X0 = 1.0\n7: X0 = 2.0", "6:1", "the label 7 is written twice"),
])
def test_jumps_that_cannot_be_written_out_are_refused_at_the_go_to(body, where, words):
    text = f"PROGRAM P\nINITIAL\nX0 = 0.0\n{body}\nEND\nDERIVATIVE\nX = INTEG(X0, 0.0)\n" \
           "TERMT (T .GE. 1.0)\nEND\nEND\n"
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, "p.csl")
    rendered = err.value.render()
    assert f"p.csl:{where}: error: " in rendered and words in rendered, rendered


def test_a_loop_left_by_a_jump_keeps_its_variable_and_a_jump_to_its_own_continue():
    # Fortran's search idiom: I is 3 where the jump leaves the loop, not the count's end
    # (11); GO TO 5, the loop's own CONTINUE, skips the rest of the pass (2 and 4 left
    # out of S); J, K where a jump leaves two loops at once
    run, = amilpy.loads("""PROGRAM P
INITIAL
   J0 = 0.0
   DO 5 I = 1, 10
      IF (I .GE. 3) GO TO 20
 5 CONTINUE
20: J0 = I
   S = 0.0
   DO 6 M = 1, 5
      IF (M .EQ. 2 .OR. M .EQ. 4) GO TO 6
      S = S + M
 6 CONTINUE
   DO J = 1, 3
      DO K = 1, 3
         IF (J*K .GE. 4) GO TO 50
      END DO
   END DO
50: CONTINUE
END
DERIVATIVE
X = INTEG(J0 + S + 10.0*J + 100.0*K, 0.0)
TERMT (T .GE. 1.0)
END
END
""", "p.csl").run(advice=False)
    c = run.constants
    assert (c["J0"], c["I"], c["S"], c["M"], c["J"], c["K"]) == (3.0, 3.0, 9.0, 6.0, 2.0, 2.0)
    assert run["X"][-1] == pytest.approx(3 + 9 + 20 + 200, rel=1e-12)


def test_labels_in_a_macro_are_each_calls_own():
    # CLIP called twice in one section: each call's label 9 its own (MACRO RELABEL's
    # work), each jump within its call
    run, = amilpy.loads("""PROGRAM P
MACRO CLIP(Y, U)
   Y = U
   IF (U .LT. 10.0) GO TO 9
   Y = 10.0
9: CONTINUE
MACRO END
INITIAL
   CLIP(A, 5.0)
   CLIP(B, 50.0)
END
DERIVATIVE
X = INTEG(A + B, 0.0)
TERMT (T .GE. 1.0)
END
END
""", "p.csl").run(advice=False)
    assert (run.constants["A"], run.constants["B"]) == (5.0, 10.0)


@pytest.mark.parametrize("text, where, words", [
    # an ACSL program without section keywords: its statements are DERIVATIVE's, sorted
    ("PROGRAM P\nCONSTANT A = 1.0\nR = -X\nIF (A .GT. 0.5) GO TO 20\nR = -2.0*X\n"
     "20: CONTINUE\nX = INTEG(R, 1.0)\nTERMT (T .GE. 1.0)\nEND\n", "4:17",
     "GO TO in DERIVATIVE's sorted code"),
    # back on one line is back, not into a block
    ("PROGRAM P\nINITIAL\nB = 0.0\n10: B = 1.0; GO TO 10\nEND\nDERIVATIVE\n"
     "X = INTEG(B, 0.0)\nTERMT (T .GE. 1.0)\nEND\nEND\n", "4:14", "GO TO 10 jumps back"),
])
def test_more_jumps_refused_where_they_stand(text, where, words):
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, "p.csl")
    rendered = err.value.render()
    assert f"p.csl:{where}: error: " in rendered and words in rendered, rendered
    assert rendered.count("error:") == 1
