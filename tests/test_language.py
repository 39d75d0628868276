"""The lexical and expression rules of the contract, section 1, shown by running them."""

import math

import pytest
from conftest import run1


def value(expr: str, **data) -> float:
    """The value of an expression in DYNAMIC, at TIME = 0."""
    params = "".join(f"PARAM {k} = {v}\n" for k, v in data.items())
    r = run1(f"{params}Y = {expr}\nTIMER FINTIM = 1.0\nEND\n")
    return float(r["Y"][0])


@pytest.mark.parametrize("expr, expected", [
    ("-2.0**2", -4.0),          # ** binds tighter than unary minus
    ("2**3**2", 512.0),         # and is right associative
    ("2^3", 8.0),               # ^ is accepted for **
    ("-3 - -2", -1.0),
    ("2*-3", -6.0),
    ("1.5D-3*1000", 1.5),       # D exponent reads as E
    ("12. + .5", 12.5),
    ("1.5e+3", 1500.0),
    ("10/4", 2.5),              # real division, never integer
    ("SIN(PI/2)", 1.0),
    ("AMAX1(1.0, 3.0, 2.0)", 3.0),
    ("MIN(4.0, -1.0)", -1.0),
    ("AMOD(-7.0, 3.0)", -1.0),  # Fortran MOD keeps the sign of the dividend
    ("SIGN(3.0, -0.5)", -3.0),
    ("AINT(-2.7)", -2.0),
    ("INT(2.7)", 2.0),
    ("ALOG(EXP(2.0))", 2.0),
    ("LOG10(1000.0)", 3.0),
    ("ATAN2(1.0, -1.0)", 3 * math.pi / 4),
])
def test_expressions(expr, expected):
    assert value(expr) == pytest.approx(expected, rel=1e-15)


def test_case_insensitive_names_and_keywords():
    r = run1("param k = 2.0\ndynamic\n  x = intgrl(1.0, -K*X)\ntimer fintim = 1.0\nend\n")
    assert r["X"][-1] == pytest.approx(math.exp(-2.0), rel=1e-5)
    assert r["x"][-1] == r["X"][-1]


def test_comments_continuation_and_separators():
    text = (
        "* a comment line, even with = and ( in it\n"
        "   * an indented comment line\n"
        "PARAM A = 1.0 ! a trailing comment\n"
        "Y = A ...\n"
        "* 2.0\n"          # a continued line may start with *: it is not a comment
        "Z = A + &\n"
        "    3.0; W = 4.0 $ V = 5.0\n"
        "TIMER FINTIM = 1.0\n"
        "END\nSTOP\n"
    )
    r = run1(text)
    assert (r["Y"][0], r["Z"][0], r["W"][0], r["V"][0]) == (2.0, 4.0, 4.0, 5.0)


def test_title_and_label_keep_polish_text():
    r = run1("TITLE Napęd z mikrosilnikiem — sprzęgło\nY = 1.0\nOUTPUT Y\n"
             "LABEL Prędkość kątowa\nTIMER FINTIM = 1.0\nEND\n")
    assert r.titles == ["Napęd z mikrosilnikiem — sprzęgło"]
    assert r.reports[0].label == "Prędkość kątowa"


def test_without_section_keyword_everything_is_dynamic():
    r = run1("X = INTGRL(0.0, 1.0)\nTIMER FINTIM = 2.0\nEND\n")
    assert r["X"][-1] == pytest.approx(2.0)


def test_derivative_is_an_alias_of_dynamic_and_integ_reverses_arguments():
    r = run1("DERIVATIVE\n X = INTEG(1.0, 0.5)\nTIMER FINTIM = 2.0\nEND\n")
    assert r["X"][-1] == pytest.approx(2.5)


def test_initial_section_is_sorted_and_feeds_dynamic():
    r = run1("PARAM R = 2.0\nINITIAL\n B = 2*A\n A = R + 1\nDYNAMIC\n"
             " X = INTGRL(B, 0.0)\nTIMER FINTIM = 1.0\nEND\n")
    assert r["X"][0] == 6.0
    assert r.constants["A"] == 3.0


def test_terminal_runs_once_at_the_end_in_written_order():
    # each statement sees the constants, the final states and DYNAMIC values, TIME
    # at the end and the TERMINAL values above it: X(1) = 2, V = 4, Y = 8, Z = 9
    r = run1("PARAM K = 2.0\nX = INTGRL(0.0, K)\nV = X*X\nTERMINAL\n Y = 2.0*X + V\n"
             " Z = Y + TIME\n W = FSW(Y - 5.0, -1.0, 0.0, 1.0)\nTIMER FINTIM = 1.0\n"
             "PRINT X, Y\nEND\n")
    assert r.ok
    assert list(r.terminal) == ["Y", "Z", "W"]
    assert r.terminal == pytest.approx({"Y": 8.0, "Z": 9.0, "W": 1.0}, rel=1e-6)
    assert r.final["Y"] == r.terminal["Y"] and r.final["Z"] == r.terminal["Z"]


def test_terminal_follows_a_stopped_run_and_its_fault_is_reported():
    # FINISH stops at X = 0.5 (TIME 0.25): TERMINAL sees that instant
    r = run1("X = INTGRL(0.0, 2.0)\nTERMINAL\n T = TIME\nTIMER FINTIM = 1.0\n"
             "FINISH X = 0.5\nEND\n")
    assert r.status == "stopped" and r.terminal["T"] == pytest.approx(0.25, rel=1e-12)
    r = run1("PARAM K = 0.0\nX = INTGRL(0.0, 1.0)\nTERMINAL\n Y = 1.0/K\n"
             "TIMER FINTIM = 1.0\nEND\n")
    assert r.status == "failed" and "TERMINAL" in r.message and "line 4" in r.message
    assert r.t[-1] == 1.0  # the rows are all there


def test_reserved_names_are_readable():
    r = run1("Y = FINTIM + 0.0*TIME\nTIMER FINTIM = 3.0, OUTDEL = 0.5\nEND\n")
    assert r["Y"][0] == 3.0
    assert list(r.t) == [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0]


@pytest.mark.parametrize("timer, outdel, prdel", [
    ("FINTIM = 2.0", 0.02, 0.02),                  # neither: FINTIM/100 for both
    ("FINTIM = 2.0, PRDEL = 0.5", 0.5, 0.5),       # one given: the other takes it
    ("FINTIM = 2.0, OUTDEL = 0.25", 0.25, 0.25),
    ("FINTIM = 2.0, OUTDEL = 0.1, PRDEL = 0.5", 0.1, 0.5),
])
def test_timer_defaults(timer, outdel, prdel):
    r = run1(f"X = INTGRL(0.0, 1.0)\nTIMER {timer}\nEND\n")
    assert r.t[1] == pytest.approx(outdel)
    assert r.printout.t[1] == pytest.approx(prdel)
    assert r.t[0] == 0.0 and r.t[-1] == 2.0 and r.printout.t[-1] == 2.0


def test_output_grid_includes_fintim_when_not_a_multiple():
    r = run1("X = INTGRL(0.0, 1.0)\nTIMER FINTIM = 1.0, OUTDEL = 0.3\nEND\n")
    assert list(r.t) == pytest.approx([0.0, 0.3, 0.6, 0.9, 1.0])
