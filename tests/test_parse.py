"""The reader: every syntax fault of a file at once, ASCII-only code, one definition of
a line, any nesting read without recursion, OUTPUT ... VS X."""

import pytest

import amilpy
from amilpy.diagnostics import AmilError
from amilpy.parse import MAX_DEPTH, MAX_ERRORS, parse

TIMER = "TIMER FINTIM = 1.0\nEND\n"


def fault(text: str) -> AmilError:
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, name="m.amil")
    return err.value


def test_every_syntax_fault_is_reported():
    err = fault("X = SIN(Y\nZ = 2 3\nA = 1.0\nPARAM K\nB = (A))\n" + TIMER)
    assert [(d.span.line, d.message.split(" (")[0]) for d in err.diagnostics] == [
        (1, "missing closing parenthesis"), (2, "two values with no operator between them"),
        (4, "a data statement takes NAME = number"), (5, "unmatched ')'")]
    assert err.render().endswith("4 errors")


def test_a_continued_statement_is_skipped_whole():
    err = fault("X = A + ...\n  B B ...\n  + C\nY = = 1\n" + TIMER)
    assert [d.span.line for d in err.diagnostics] == [2, 4]


def test_syntax_faults_are_capped():
    err = fault("X = = 1\n" * 50 + TIMER)
    assert len([d for d in err.diagnostics if d.severity == "error"]) == MAX_ERRORS
    assert err.diagnostics[-1].message == f"stopped reading after {MAX_ERRORS} syntax errors"


def test_a_fault_on_the_last_line_ends_the_reading():
    err = fault("X = INTGRL(0.0, 1.0)\nTIMER FINTIM = 1.0\nY = (")
    assert [d.span.line for d in err.diagnostics] == [3]


@pytest.mark.parametrize("text, char, name, ascii_", [
    ("PARAM K = \u09ea\n", "\u09ea", "U+09EA BENGALI DIGIT FOUR", "'4'"),
    ("CON\u017fT K = 1.0\n", "\u017f", "U+017F LATIN SMALL LETTER LONG S", "'s'"),
    ("\u017fTOP\n", "\u017f", "U+017F LATIN SMALL LETTER LONG S", "'s'"),
    ("DYNAM\u0130C\n", "\u0130", "U+0130 LATIN CAPITAL LETTER I WITH DOT ABOVE", "'I'"),
    ("X = \uff21 + 1.0\n", "\uff21", "U+FF21 FULLWIDTH LATIN CAPITAL LETTER A", "'A'"),
    ("X = 2.0 \u2212 1.0\n", "\u2212", "U+2212 MINUS SIGN", "'-'"),
    ("X = \u0141\n", "\u0141", "U+0141 LATIN CAPITAL LETTER L WITH STROKE", None),
])
def test_non_ascii_in_code_is_named(text, char, name, ascii_):
    err = fault(text + "X = INTGRL(0.0, 1.0)\n" + TIMER)
    d = err.diagnostics[0]
    assert d.message == f"character {char!r} is not allowed here: {name}"
    assert d.span.line == 1 and text[d.span.column - 1] == char
    if ascii_:
        assert d.hint.startswith(f"write {ascii_};")
    else:
        assert not d.hint.startswith("write")


def test_keywords_are_ascii_case_insensitive_only():
    m = amilpy.loads("param k = 2.0\ndynamic\n x = intgrl(0.0, k)\ntimer fintim = 1.0\nend\n")
    assert m.parameters == {"K": 2.0}


def test_non_ascii_is_fine_in_comments_titles_and_labels():
    m = amilpy.loads("TITLE Napęd dwumasowy \u09ea\n* komentarz ſ\nX = INTGRL(0.0, 1.0) ! ৪\n"
                     "OUTPUT X\nLABEL prędkość\n" + TIMER)
    run, = m.run()
    assert run.titles == ["Napęd dwumasowy \u09ea"]


@pytest.mark.parametrize("brk", ["\u2028", "\u0085", "\f", "\x0b", "\u2029"])
def test_messages_count_lines_like_the_reader(brk):
    # a line break only str.splitlines knows must not shift the excerpt
    err = fault(f"TITLE A{brk}B\nX = INTGRL(0.0, KK)\n" + TIMER)
    d = err.diagnostics[0]
    assert d.span.line == 2 and "KK is used" in d.message
    assert "    2 | X = INTGRL(0.0, KK)" in err.render()


def test_code_after_a_form_feed_or_vertical_tab():
    # \f is blank in code; \v is no character of the language (and the place is exact)
    assert amilpy.loads("X = INTGRL(0.0,\f1.0)\n" + TIMER)
    err = fault("X = INTGRL(0.0,\x0b1.0)\n" + TIMER)
    assert (err.line, err.column) == (1, 16) and "U+000B" in err.render()


def test_a_sum_of_999_terms_checks_and_runs():
    terms = "+".join(["1.0"] * 999)
    run, = amilpy.loads(f"X = INTGRL(0.0, {terms})\nTIMER FINTIM = 1.0\nEND\n").run()
    assert run.ok and run["X"][-1] == pytest.approx(999.0, rel=1e-12)


def test_deep_nesting_up_to_the_limit_runs():
    depth = MAX_DEPTH - 10
    expr = "-" * depth + "1.0"  # each unary minus one level
    run, = amilpy.loads(f"X = INTGRL(0.0, {expr})\n" + TIMER).run()
    assert run.ok and run["X"][-1] == pytest.approx(1.0)


def test_deeper_nesting_is_a_located_error():
    expr = "(" * 20 + "-" * (MAX_DEPTH + 5) + "1.0" + ")" * 20
    err = fault(f"TITLE T\nX = INTGRL(0.0, {expr})\n" + TIMER)
    d = err.diagnostics[0]
    assert d.span.line == 2 and f"nested too deeply (more than {MAX_DEPTH} levels)" in d.message


def test_parse_raises_only_amil_errors_for_bad_bytes():
    # (NULs only after the last line are padding, not read: test_acsl_form.py)
    for text in ["\x00X = 1.0\n", "X = 1.0\x00\n", "\udcff", "X = (" * 5000]:
        with pytest.raises(AmilError):
            parse(text)


def test_output_vs_another_variable():
    m = amilpy.loads("X = INTGRL(1.0, V)\nV = INTGRL(0.0, -X)\nOUTPUT V VS X\n"
                     "PLOT X, V vs TIME\nVS = 2*X\nOUTPUT VS\n" + TIMER)
    assert [(r.names, r.x) for r in m.ir.runs[0].reports] == [
        (("V",), "X"), (("X", "V"), None), (("VS",), None)]


@pytest.mark.parametrize("statement, message, column", [
    ("PRINT X VS V", "PRINT has no horizontal axis: VS V belongs to a figure", 12),
    ("OUTPUT X VS Q", "OUTPUT names Q, which the model never defines", 13),
])
def test_output_vs_is_checked(statement, message, column):
    err = fault(f"X = INTGRL(1.0, V)\nV = INTGRL(0.0, -X)\n{statement}\n" + TIMER)
    assert err.diagnostics[0].message == message
    assert (err.line, err.column) == (3, column)


# ------------------------------------------------------------ property-based
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

LOOKALIKES = ["\u017f", "\u0131", "\u0130", "\u0410", "\u0415", "\u041e", "\u0440", "\uff21",
              "\uff10", "\u09ea", "\u0665", "\u2212", "\u212a", "\u00b5", "\u00e9", "\u03bf"]
VALID = ("PARAM K = 2.0, D = 0.5\nINITIAL\nA = 2*K\nDYNAMIC\nX = INTGRL(1.0, -K*X + D)\n"
         "Y = LIMIT(-1.0, 1.0, X)\nTIMER FINTIM = 1.0, PRDEL = 0.1\nPRINT X, Y\nEND\n")


@settings(max_examples=150, deadline=None, derandomize=True)
@given(st.integers(0, len(VALID) - 1), st.sampled_from(LOOKALIKES))
def test_a_lookalike_anywhere_in_code_is_named_where_it_stands(pos, char):
    if not VALID[pos].isalnum():
        return
    text = VALID[:pos] + char + VALID[pos + 1:]
    with pytest.raises(AmilError) as err:
        amilpy.loads(text)
    d = err.value.diagnostics[0]
    line = VALID.count("\n", 0, pos) + 1
    column = pos - (VALID.rfind("\n", 0, pos) + 1) + 1
    assert (d.span.line, d.span.column) == (line, column)
    assert d.message.startswith(f"character {char!r} is not allowed here: U+")


NESTED = ["LIMIT(-1.0, 1.0, {})", "DEADSP(-0.1, 0.1, {})", "FSW({}, 0.0, 1.0, X)",
          "ZHOLD(X - 0.5, {})", "INSW({}, -1.0, {})", "QNTZR(0.5, {})", "REALPL(0.0, 0.1, {})",
          "DELAY(10, 0.1, {})", "({} + {})", "SIN({})", "AFGEN(F, {})"]


@settings(max_examples=80, deadline=None, derandomize=True)
@given(st.lists(st.sampled_from(NESTED), min_size=1, max_size=12), st.booleans())
def test_nested_functions_check_and_compile(wraps, initial):
    """Any nesting of switches, memory, states and tables checks and compiles, or
    is a model error (never another exception)."""
    expr = "X"
    for w in wraps:
        expr = w.format(*([expr] * w.count("{}")))
    section = f"INITIAL\nB = {expr.replace('X', '0.3')}\nDYNAMIC\n" if initial else ""
    text = (f"FUNCTION F = 0.0, 0.0, 1.0, 2.0\n{section}X = INTGRL(1.0, -X)\nY = {expr}\n"
            "TIMER FINTIM = 1.0\nEND\n")
    try:
        source = amilpy.loads(text).python_source()
    except AmilError as exc:
        assert exc.render()
        return
    assert "def rhs" in source
