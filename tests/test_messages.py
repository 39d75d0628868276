"""Messages that misled a student (issue 28 point 6), each now located and saying
what to write. A short listing, what the checker says, and why."""

from __future__ import annotations

import pytest

import amilpy
from amilpy.cli import main
from amilpy.diagnostics import AmilError


def _errors(text: str) -> AmilError:
    with pytest.raises(AmilError) as caught:
        amilpy.loads(text, "m.amil")
    return caught.value


def test_pascal_assignment_is_named_not_a_label():
    """`JOBC := 2.0` was reported as an unsupported statement label (GO TO)."""
    err = _errors("JOBC := 2.0\nX = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0\nEND\n")
    (d,) = err.diagnostics
    assert d.message == "':=' is not this language's assignment"
    assert d.hint == "write JOBC = 2.0" and (d.span.line, d.span.column) == (1, 1)


def test_a_line_broken_without_continuation_says_how_to_continue():
    """A statement broken over two lines without `...` got only "missing closing
    parenthesis": the hint now says how a statement goes on to the next line."""
    err = _errors("X = INTGRL(1.0, -X +\n  2.0)\nTIMER FINTIM = 1.0\nEND\n")
    first = err.diagnostics[0]
    assert first.message.startswith("missing closing parenthesis")
    assert "continued on the next line ends its line with ..." in first.hint


def test_a_forgotten_dynamic_is_one_error_that_says_so():
    """Four INTGRL under INITIAL (the DYNAMIC line forgotten) gave four errors and a
    fifth for the PRINT; now one, with the others as notes and what to write."""
    err = _errors("INITIAL\nPARAM K = 1.0\nX = INTGRL(1.0, -K*X)\nV = INTGRL(0.0, X)\n"
                  "W = INTGRL(0.0, V)\nZ = INTGRL(0.0, W)\nTIMER FINTIM = 1.0\nPRINT X\nEND\n")
    (d,) = err.diagnostics
    assert d.message == "INTGRL cannot be used in INITIAL (nor can 3 more statements here)"
    assert [s.line for s, _ in d.related] == [4, 5, 6]
    assert d.hint.endswith("write DYNAMIC on a line before them (before line 3)")


def test_an_undefined_name_is_reported_once():
    """Q in an initial value was reported twice, at the same place."""
    err = _errors("X = INTGRL(Q*2.0, -X)\nTIMER FINTIM = 1.0\nEND\n")
    assert [d.message for d in err.diagnostics] == ["Q is used but never defined"]


def test_a_decimal_comma_on_the_command_line_gets_its_hint(tmp_path, capsys):
    path = tmp_path / "m.amil"
    path.write_text("PARAM B = 1.0\nX = INTGRL(1.0, -B*X)\nTIMER FINTIM = 1.0\nEND\n")
    assert main(["run", str(path), "--set", "B=1,5"]) == 2
    assert "the decimal separator is a point: 1.5" in capsys.readouterr().err


@pytest.mark.parametrize("text, name", [
    ("X = INTGRL(TIME + 1.0, 1.0)\nTIMER FINTIM = 1.0\nEND\n", "TIME"),
    ("PROGRAM P\n  DERIVATIVE\n    X = INTEG(1.0, T + 1.0)\n    TERMT(T .GE. 1.0)\n  END\n"
     "END\n", "T")])
def test_time_in_an_initial_value_is_named_as_the_listing_names_it(text, name):
    """An initial value that reads the time was refused as "t is not known before the
    run starts": the generated code's name, which no listing has."""
    with pytest.raises(AmilError) as caught:
        amilpy.loads(text, "m.csl" if name == "T" else "m.amil").run(advice=False)
    (d,) = caught.value.diagnostics
    assert d.message == f"{name} is not known before the run starts"
    assert "write the start's value" in d.hint
