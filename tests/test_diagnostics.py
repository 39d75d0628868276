"""Every fault kind of the checker: where it points (line:column), what it says, the hint.

All faults of a stage are reported together, so a student fixes them in one go.
"""

import pytest

import amilpy


def faults(text: str):
    with pytest.raises(amilpy.AmilError) as info:
        amilpy.loads(text, name="m.amil")
    return info.value


def only(text: str):
    err = faults(text)
    assert len(err.diagnostics) == 1, err.render()
    return err.diagnostics[0], err


TIMER = "TIMER FINTIM = 1.0\n"


def test_undefined_name_suggests_the_nearest():
    d, err = only("PARAM OMEGA = 2.0\nX = INTGRL(0.0, OMEGAA*X)\n" + TIMER)
    assert (d.span.line, d.span.column) == (2, 17)
    assert "OMEGAA is used but never defined" in d.message
    assert "did you mean OMEGA?" in d.hint
    assert (err.path, err.line, err.column) == ("m.amil", 2, 17)


def test_defined_twice_points_at_both():
    d, _ = only("X = 1.0\nY = 2.0\nX = 3.0\n" + TIMER)
    assert (d.span.line, d.span.column) == (3, 1)
    assert "defined twice" in d.message and "line 1" in d.hint


def test_algebraic_loop_names_every_variable_with_its_line():
    d, err = only("A = B + 1.0\nB = C*2.0\nC = A - 3.0\nD = 1.0\n" + TIMER)
    assert "algebraic loop" in d.message
    for name in "ABC":
        assert name in d.message
    assert sorted(span.line for span, _ in d.related) == [2, 3]
    assert "INTGRL" in d.hint
    text = err.render()
    assert "m.amil:1:1: error: algebraic loop" in text and "m.amil:3:1: note" in text


def test_a_state_breaks_a_cycle():
    amilpy.loads("A = X + 1.0\nX = INTGRL(0.0, -A)\n" + TIMER)


def test_unknown_function_suggests():
    d, _ = only("X = INTGRAL(0.0, 1.0)\n" + TIMER)
    assert "unknown function INTGRAL" in d.message and "INTGRL" in d.hint


def test_decimal_comma_in_a_call():
    d, _ = only("X = INTGRL(0,5, 1.0)\n" + TIMER)
    assert "INTGRL takes 2 arguments, got 3" in d.message
    assert "0,5" in d.hint and "0.5" in d.hint


def test_decimal_comma_in_data():
    d, _ = only("PARAM K = 1,5\nX = K\n" + TIMER)
    assert "decimal comma" in d.message and "1.5" in d.hint


def test_assignment_to_reserved_name():
    d, _ = only("TIME = 2.0\n" + TIMER)
    assert "TIME is a reserved name" in d.message
    d, _ = only("PARAM DELT = 0.1\nX = 1.0\n" + TIMER)
    assert "DELT is a reserved name" in d.message


@pytest.mark.parametrize("timer, message", [
    ("", "FINTIM is not given"),
    ("TIMER FINTIM = 0.0\n", "FINTIM must be positive"),
    ("TIMER FINTIM = -1.0\n", "FINTIM must be positive"),
])
def test_fintim_missing_or_not_positive(timer, message):
    d, _ = only("X = INTGRL(0.0, 1.0)\n" + timer)
    assert message in d.message


def test_unknown_timer_setting():
    d, _ = only("X = 1.0\nTIMER FINTIM = 1.0, OUTDEL = 0.1, PRDLE = 0.1\n")
    assert "unknown TIMER setting PRDLE" in d.message and "PRDEL" in d.hint


def test_function_table_must_increase():
    d, _ = only("FUNCTION F = 0.0,1.0, 2.0,3.0, 1.0,4.0\nY = AFGEN(F, TIME)\n" + TIMER)
    assert "x values must increase" in d.message and d.span.line == 1


def test_function_table_odd_count_mentions_the_comma():
    d, _ = only("FUNCTION F = 0.0,1.0, 2.0\nY = AFGEN(F, TIME)\n" + TIMER)
    assert "odd number" in d.message and "1,5" in d.hint


def test_afgen_needs_a_table():
    d, _ = only("FUNCTION FT = 0.0,1.0, 2.0,3.0\nY = AFGEN(F, TIME)\n" + TIMER)
    assert "needs a FUNCTION table" in d.message and "FT" in d.hint


@pytest.mark.parametrize("late, column", [("PARAM T1 = 0.5", 7),
                                           ("FUNCTION T1 = 0.0, 0.0, 1.0, 2.0", 1)])
def test_value_first_given_after_end(late, column):
    """Found by fuzzing (a line moved below END): the first run has no T1 at all, which
    reached the generated code as a NameError."""
    use = "AFGEN(T1, TIME)" if late.startswith("FUNCTION") else "FSW(TIME - T1, 0.0, 1.0, 1.0)"
    d, _ = only(f"SW = {use}\nX = INTGRL(0.0, SW)\n" + TIMER + f"END\n{late}\nEND\n")
    assert (d.span.line, d.span.column) == (5, column)
    assert "T1 has no value in the first run" in d.message
    assert "before the first END" in d.hint


def test_a_value_changed_after_end_is_fine():
    m = amilpy.loads("PARAM T1 = 0.2\nX = INTGRL(0.0, FSW(TIME - T1, 0.0, 1.0, 1.0))\n"
                     + TIMER + "END\nPARAM T1 = 0.5\nEND\n")
    a, b = m.run()
    assert a["X"][-1] == pytest.approx(0.8) and b["X"][-1] == pytest.approx(0.5)


def test_unknown_method():
    d, _ = only("X = 1.0\nMETHOD RUNGE\n" + TIMER)
    assert "unknown integration method RUNGE" in d.message


def test_print_of_unknown_variable():
    d, _ = only("X = INTGRL(0.0, 1.0)\nPRINT X, XX1\n" + TIMER)
    assert "PRINT names XX1" in d.message and (d.span.line, d.span.column) == (2, 10)


def test_initial_cannot_read_dynamic_values():
    d, _ = only("INITIAL\n A = X*2.0\nDYNAMIC\n X = INTGRL(0.0, 1.0)\n" + TIMER)
    assert "computed in DYNAMIC" in d.message


def test_state_function_outside_dynamic():
    d, _ = only("INITIAL\n A = INTGRL(0.0, 1.0)\nDYNAMIC\n X = A\n" + TIMER)
    assert "INTGRL cannot be used in INITIAL" in d.message


def test_all_faults_of_the_stage_at_once():
    err = faults("X = INTGRL(0.0, Y)\nZ = SIN(1,5)\nW = FOO(X)\nTIME = 3\n"
                 "A = B + 1\nB = A*2\nTIMER FINTIM = 0\n")
    lines = [d.span.line for d in err.diagnostics]
    assert lines == [1, 2, 3, 4, 5, 7]
    assert err.render().endswith("6 errors")


@pytest.mark.parametrize("text, message, line, column", [
    ("X = SIN(Y\n", "missing closing parenthesis", 1, 10),
    ("X = A +\n", "missing value after the operator", 1, 8),
    ("X = A B\n", "two values with no operator", 1, 7),
    ("X = A)\n", "unmatched ')'", 1, 6),
    ("PARAM K\n", "a data statement takes NAME = number", 1, 8),
    ("X = 1.0\nY = 2.0 $\n Z = = 3\n", "missing expression after '='", 3, 6),
    ("X = Ł\n", "character 'Ł' is not allowed here", 1, 5),
])
def test_syntax_errors(text, message, line, column):
    d, _ = only(text)
    assert message in d.message
    assert (d.span.line, d.span.column) == (line, column)


def test_render_shows_the_line_and_a_caret():
    err = faults("PARAM K = 2.0\nX = INTGRL(0.0, -KK*X)\n" + TIMER)
    text = err.render().splitlines()
    assert text[0] == "m.amil:2:18: error: KK is used but never defined"
    assert text[1].endswith("X = INTGRL(0.0, -KK*X)")
    assert text[2].index("^") == text[1].index("KK")
    assert "did you mean K?" in text[3]
