"""Magnolia's everyday syntax in ACSL programs, seen in published listings: pow(),
typed constants, TRUE/FALSE without dots, IF without parentheses, a CONSTANT
repeated with its value. Each runs to a closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest

import amilpy
from amilpy.diagnostics import AmilError


def _program(constants: str, derivative: str) -> str:
    return ("PROGRAM probe\n" + constants + "  CINTERVAL CINT = 0.5\n  DERIVATIVE\n"
            + derivative + "    TERMT(T >= 2.0)\n  END\nEND\n")


def test_pow_is_the_power():
    """Y = pow(X, 2) with X = exp(-K t): exp(-2 K t) at every row (RELERR 1e-11 for the
    ACSL form: 1e-9 is safe)."""
    run = amilpy.loads(_program("  CONSTANT K = 0.5\n",
                                "    X = INTEG(-K*X, 1.0)\n    Y = pow(X, 2.0)\n"),
                       "p.csl").run(advice=False)[0]
    assert np.max(np.abs(run["Y"] - np.exp(-run.t))) < 1e-9


@pytest.mark.parametrize("line, value", [
    ("constant integer N = 3", 3.0), ("CONSTANT INTEGER N = 2.7", 2.0),
    ("CONSTANT REAL N = 1.5", 1.5), ("CONSTANT DOUBLE PRECISION N = 1.5", 1.5),
    ("CONSTANT DOUBLEPRECISION N = 1.5", 1.5), ("CONSTANT LOGICAL N = .TRUE.", 1.0),
    ("CONSTANT N = false", 0.0), ("CONSTANT N = TRUE", 1.0), ("constant n = False", 0.0),
])
def test_typed_constants_and_bare_truth_values(line, value):
    """Magnolia's typed constants (an INTEGER one truncated as Fortran assigns it)
    and TRUE/FALSE without dots: X' = N from 0, so X(2) = 2 N."""
    run = amilpy.loads(_program(f"  {line}\n", "    X = INTEG(N, 0.0)\n"), "p.csl").run(
        advice=False)[0]
    assert run["X"][-1] == pytest.approx(2.0 * value, abs=1e-12)


def test_a_constant_of_no_type_is_refused_where_it_stands():
    with pytest.raises(AmilError, match="DIMENSION is no type of a constant"):
        amilpy.loads(_program("  CONSTANT DIMENSION N = 3\n", "    X = INTEG(N, 0.0)\n"),
                     "p.csl")


@pytest.mark.parametrize("block", [
    "    IF T < 1.0 THEN\n      R = 1.0\n    ELSE\n      R = 2.0\n    END IF\n",
    "    if t < tchng\n      R = 1.0\n    else\n      R = 2.0\n    end\n",
    "    IF (T < 1.0) THEN\n      R = 1.0\n    ELSE IF T >= 1.0 THEN  ! bare\n      R = 2.0\n"
    "    END IF\n",
])
def test_if_without_parentheses(block):
    """Magnolia writes `IF t < tchng` (with or without THEN, closed by END): the
    condition is put in parentheses before the grammar reads it, columns kept. R = 1
    before TIME 1, 2 after: X(2) = 3, and the switch is located at TIME 1."""
    run = amilpy.loads(_program("  CONSTANT TCHNG = 1.0\n", block + "    X = INTEG(R, 0.0)\n"),
                       "p.csl").run(advice=False)[0]
    assert run["X"][-1] == pytest.approx(3.0, abs=1e-9)
    assert any(abs(e.time - 1.0) < 1e-12 for e in run.events)


def test_a_constant_given_twice_with_its_value_is_one_constant():
    """Published listings repeat a CONSTANT (in another section, after an INCLUDE):
    with the same value it is the same constant; with another it is an error still."""
    same = _program("  CONSTANT K = 0.5\n  CONSTANT K = 0.5\n", "    X = INTEG(-K*X, 1.0)\n")
    run = amilpy.loads(same, "p.csl").run(advice=False)[0]
    assert run["X"][-1] == pytest.approx(math.exp(-1.0), rel=1e-9)
    with pytest.raises(AmilError, match="K is given a value twice"):
        amilpy.loads(same.replace("  CONSTANT K = 0.5\n  CONSTANT K = 0.5",
                                  "  CONSTANT K = 0.5\n  CONSTANT K = 0.7"), "p.csl")


def test_a_constant_given_a_new_value_in_initial():
    """Magnolia lets INITIAL give a CONSTANT a new value: the assignment wins from there
    on (KB read before it is 0.5, KA after it 0.25, and the derivatives and TERMINAL
    see 0.25: X = exp(-0.25 t)); elsewhere (DERIVATIVE) it is still refused."""
    text = ("PROGRAM probe\n  CONSTANT K = 0.5\n  CINTERVAL CINT = 0.5\n  INITIAL\n"
            "    KB = K\n    K = 0.25\n    KA = K\n  END\n  DERIVATIVE\n"
            "    X = INTEG(-K*X, 1.0)\n    TERMT(T >= 2.0)\n  END\n  TERMINAL\n    KT = K\n"
            "  END\n  PRINT X, KB, KA\nEND\n")
    run = amilpy.loads(text, "p.csl").run(advice=False)[0]
    assert (run["KB"][-1], run["KA"][-1], run.terminal["KT"]) == (0.5, 0.25, 0.25)
    assert np.max(np.abs(run["X"] - np.exp(-0.25 * run.t))) < 1e-9
    with pytest.raises(AmilError, match="K is both a data value and computed"):
        amilpy.loads(text.replace("    TERMT(T >= 2.0)\n", "    TERMT(T >= 2.0)\n    K = 0.3\n"),
                     "p.csl")


def test_a_bare_if_with_a_not_equal_keeps_its_condition():
    """`IF C != 2.0 THEN` without parentheses: the `!` is not-equal's, not a comment's
    (it became `IF (C)` and a comment, and ran the wrong branch: X(2) = 2)."""
    block = "    IF C != 2.0 THEN\n      R = 1.0\n    ELSE\n      R = 0.0\n    END IF\n"
    run = amilpy.loads(_program("  CONSTANT C = 2.0\n", block + "    X = INTEG(R, 0.0)\n"),
                       "p.csl").run(advice=False)[0]
    assert run["X"][-1] == 0.0


def test_the_new_keywords_leave_names_that_look_like_them_alone():
    """SET (FST, refused by name) as the first output of a two-output call, a
    variable named FALSE in a RELERR setting, and a PARAM given twice (refused in
    the CSMP form, where only a repeated CONST is the same constant)."""
    run = amilpy.loads("X = INTGRL(0.0, 1.0)\nSET, Z = OUTSW(X - 0.5, 1.0)\n"
                       "FALSE = INTGRL(1.0, -FALSE)\nRELERR FALSE = 1.0E-8\n"
                       "TIMER FINTIM = 1.0, OUTDEL = 0.5\nPRINT SET, Z, FALSE\nEND\n").run(
                           advice=False)[0]
    assert run.ok and run["FALSE"][-1] == pytest.approx(math.exp(-1.0), rel=1e-6)
    with pytest.raises(AmilError, match="K is given a value twice"):
        amilpy.loads("PARAM K = 1.0\nPARAM K = 1.0\nX = INTGRL(0.0, K)\nEND\n")


def test_cinterval_cannot_read_a_constant_initial_changes():
    """CINTERVAL CINT = TS is computed before INITIAL runs: with TS given a new value
    in INITIAL it used the old one (rows every 0.5 for 0.1). Said now, with what to
    write (and that, CINT = TS in INITIAL, gives rows every 0.1)."""
    text = ("PROGRAM p\n  CONSTANT TS = 0.5\n  CINTERVAL CINT = TS\n  INITIAL\n    TS = 0.1\n"
            "  END\n  DERIVATIVE\n    X = INTEG(1.0, 0.0)\n    TERMT(T >= 1.0)\n  END\nEND\n")
    with pytest.raises(AmilError, match="CINTERVAL uses TS, which INITIAL gives a new value"):
        amilpy.loads(text, "p.csl")
    run = amilpy.loads(text.replace("CINTERVAL CINT = TS", "CINTERVAL CINT = 0.5").replace(
        "    TS = 0.1\n", "    TS = 0.1\n    CINT = TS\n"), "p.csl").run(advice=False)[0]
    assert np.allclose(run.t, np.linspace(0.0, 1.0, 11))


def test_an_initial_value_computed_in_derivative_from_constants():
    """AALD (magnoliasci/PBPK) gives INTEG an initial value DERIVATIVE computes from
    constants only (HT0DO1 = HFREE0*(1 + ATOTAL/(KA + HFREE0)), HFREE0 = 10**(-PHINIT)):
    one value for the whole run, computed before it. X = X0 exp(-t), X0 = 2*10^-P."""
    run = amilpy.loads(_program("  CONSTANT P = 2.0\n",
                                "    X = INTEG(-X, X0)\n    X0 = 2.0*H\n    H = 10**(-P)\n"),
                       "p.csl").run(advice=False)[0]
    assert np.max(np.abs(run["X"] - 0.02 * np.exp(-run.t))) < 1e-12
    assert run.final["X0"] == 0.02


def test_an_initial_value_that_changes_in_time_is_still_refused():
    """X0 reads a state: no value before the run (a located error, as before)."""
    with pytest.raises(AmilError, match="the initial value uses X0, which changes in time"):
        amilpy.loads(_program("", "    X = INTEG(-X, X0)\n    Y = INTEG(1.0, 0.0)\n"
                                  "    X0 = 2.0 + Y\n"), "p.csl")
