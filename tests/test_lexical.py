"""Lexical additions of the contract's section 8, in both forms: strings, dotted
operators that win over decimal points, `!=` against `!` comments, `&&`/`||`, `;`
between the items of data, TIMER and FINISH lines, text after STOP."""

import pytest
from conftest import run1

import amilpy
from amilpy.diagnostics import AmilError
from amilpy.parse import parse
from amilpy.parse.lexical import prepare

END = "TIMER FINTIM = 1.0\nEND\n"


def fault(text: str, name: str = "m.amil") -> AmilError:
    with pytest.raises(AmilError) as err:
        amilpy.loads(text, name=name)
    return err.value


def test_semicolon_separates_the_items_of_a_data_line():
    # FST writes `PARAM LAII = 0.012; SLA = 0.022`: two items, never a PARAM and an
    # equation (which would be a silent wrong model)
    m = amilpy.loads("PARAM LAII = 0.012; SLA = 0.022\nINCON ZERO = 0.; ROOTDI = 0.1\n"
                     "X = INTGRL(ROOTDI, LAII*SLA)\nTIMER FINTIM = 2.0; PRDEL = 1.0\nEND\n")
    assert m.parameters == {"LAII": 0.012, "SLA": 0.022, "ZERO": 0.0, "ROOTDI": 0.1}
    run, = m.run()
    assert list(run.t) == [0.0, 1.0, 2.0]  # the TIMER line's items too
    assert run["X"][-1] == pytest.approx(0.1 + 2 * 0.012 * 0.022, rel=1e-9)


def test_an_item_list_never_turns_into_a_statement():
    err = fault("PARAM A = 1.0; X = 2.0*A\n" + END)
    d = err.diagnostics[0]
    assert d.message.startswith("a data statement takes NAME = number")
    assert d.span.line == 1


def test_semicolon_ending_a_data_line_ends_the_statement():
    m = amilpy.loads("PARAM A = 1.0;\nX = INTGRL(0.0, A); Y = 2.0*X\n" + END)
    run, = m.run()
    assert run["Y"][-1] == pytest.approx(2.0, rel=1e-9)


def test_finish_items_are_separated_by_semicolons():
    run = run1("Y = INTGRL(0.0, 1.0)\nZ = INTGRL(0.0, 2.0)\nFINISH Y = 5.0; Z = 1.0\n"
               "TIMER FINTIM = 10.0\nEND\n")
    assert run.t_end == pytest.approx(0.5, abs=1e-12)  # Z reaches 1 first


def test_strings_keep_bang_semicolon_and_doubled_quotes():
    program = parse("PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, 0.0)\n"
                    "TERMT(X >= 1.0, 'it''s done; really! ok')\nEND\nEND\n")
    termt = program.statements[0].body[1]
    assert termt.message == "it's done; really! ok"


def test_a_string_alone_is_a_comment():
    # ACSL's `END $ 'of derivative'`
    m = amilpy.loads("PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, 0.0)\nTERMT(X >= 1.0)\n"
                     "END $ 'of derivative'\nEND $ 'of program'\n")
    assert [s.name for s in m.ir.states] == ["X"]


def test_a_string_as_a_value_is_an_error_naming_it():
    err = fault("PROGRAM p\nCONSTANT B = 'text'\nDERIVATIVE\nX = INTEG('abc', 0.0)\n"
                "TERMT(X >= 1.0)\nEND\nEND\n", "p.csl")
    assert [(d.span.line, d.message) for d in err.diagnostics] == [
        (2, "the string 'text' cannot be a value of B"), (4, "the string 'abc' cannot be a value")]
    assert "TERMT message" in err.diagnostics[0].hint


def test_a_quote_inside_a_comment_is_plain():
    # A10: `CONSTANT k = 0.12 ; a = 1.0 ! simon's comment`
    m = amilpy.loads("PARAM K = 0.12 ; A = 1.0 ! simon's comment\nX = INTGRL(0.0, K*A)\n"
                     + END)
    assert m.parameters == {"K": 0.12, "A": 1.0}


@pytest.mark.parametrize("expr, value", [
    ("1.EQ.2", 0.0), ("1.EQ.1", 1.0), ("2.GE.0.", 1.0), ("1.5.LT.2.5", 1.0),
    ("1.E1.GT.9", 1.0),  # 1.E1 is still a number: ten
    ("A.EQ..TRUE.", 1.0), (".NOT.A", 0.0), ("A.AND..FALSE.", 0.0), ("A .OR. .FALSE.", 1.0),
    ("(1 != 2)", 1.0), ("(1 /= 1)", 0.0), ("(1 ~= 2)", 1.0), ("1 == 1", 1.0),
    ("(1 < 2) && (3 > 4)", 0.0), ("(1 < 2) || (3 > 4)", 1.0), ("~(1 > 2)", 1.0),
])
def test_dotted_and_symbolic_operators(expr, value):
    # in INITIAL every test is made on the spot: the value is the truth 1.0 or 0.0
    run = run1(f"CONST A = 1.0\nINITIAL\nV = {expr}\nDYNAMIC\nX = INTGRL(0.0, V)\n" + END)
    assert run.constants["V"] == value


def test_bang_starts_a_comment_outside_parentheses():
    # banner comments stay comments; `!=` is not-equal only inside parentheses
    m = amilpy.loads("!=======================\nX = INTGRL(0.0, 1.0) != not a test\n" + END)
    assert [s.name for s in m.ir.states] == ["X"]
    assert prepare("Y = (A != B) != c") == "Y = (A /= B) != c"


def test_ampersand_continues_and_double_ampersand_is_and():
    run = run1("INITIAL\nV = (1 < 2) && &\n    (2 < 3)\nDYNAMIC\nX = INTGRL(0.0, V)\n" + END)
    assert run.constants["V"] == 1.0


def test_text_after_stop_is_not_read():
    run = run1("X = INTGRL(0.0, 1.0)\nTIMER FINTIM = 1.0\nEND\nSTOP\n"
               "      SUBROUTINE GLA (TIME, X)\n      IF (X .GT. 0) GOTO 10\n 10   RETURN\n")
    assert run["X"][-1] == pytest.approx(1.0)


def test_prepare_keeps_lines_and_columns():
    text = "PARAM A = 1; B = 2 ! c; d\n* comment\nX = (A != B)\nSTOP\nanything 'here\n"
    out = prepare(text).split("\n")
    assert len(out) == len(text.split("\n"))  # same lines; kept lines keep their columns
    assert out[0] == "PARAM A = 1, B = 2 ! c; d"
    assert out[1] == "" and out[2] == "X = (A /= B)" and out[4] == ""


def test_an_unclosed_string_is_named():
    err = fault("PROGRAM p\nDERIVATIVE\nX = INTEG(1.0, 0.0)\nTERMT(T > 1.0, 'oops)\n"
                "END\nEND\n", "p.csl")
    d = err.diagnostics[0]
    assert d.message == "a string that is not closed" and d.span.line == 4
