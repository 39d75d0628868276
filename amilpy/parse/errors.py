"""What a syntax fault means, in the listing's words: lark's exceptions become
`Diagnostic`s with a friendly label (matched against small bad listings, lark's
`match_examples`), the token or character found, and a hint. A non-ASCII letter
or digit in code is named (`U+09EA BENGALI DIGIT FOUR`) with the ASCII one it
looks like. Grammar terminal names never reach a message.
"""

from __future__ import annotations

import unicodedata

from ..diagnostics import Diagnostic, Span

# Friendly labels for parser states, matched by lark's `match_examples` against
# small bad listings that end in the same parser state as the user's text.
EXAMPLES: dict[str, tuple[str, list[str]]] = {
    "missing closing parenthesis": (
        "every '(' needs a matching ')' before the end of the statement; a statement "
        "continued on the next line ends its line with ...",
        ["X = SIN(Y\n", "X = (A + B\n", "X = INTGRL(0.0, Y\n", "X = A*(B - C\n"],
    ),
    "missing value after the operator": (
        "an operator must be followed by a number, a name or '('; a statement "
        "continued on the next line ends its line with ...",
        ["X = A +\n", "X = A *\n", "X = A /\n", "X = A **\n", "X = -\n"],
    ),
    "missing expression after '='": (
        "write the value the variable takes, e.g. X = 2.0*Y",
        ["X =\n", "X = \n"],
    ),
    "two values with no operator between them": (
        "write the operator, e.g. 2.0*X; a decimal separator is a point, not a space",
        ["X = A B\n", "X = 2 3\n", "X = 2.0 A\n", "X = (A) B\n", "X = SIN(A) B\n"],
    ),
    "unmatched ')'": (
        "remove the ')' or add the '(' it closes",
        ["X = A)\n", "X = (A))\n"],
    ),
    "a statement must start with a name or a keyword": (
        "statements look like NAME = expression, or start with a keyword such as PARAM",
        ["= 3\n", "3 = X\n", "(X) = 3\n", "+X = 3\n"],
    ),
    "this statement needs '='": (
        "an assignment is NAME = expression",
        ["X\n", "X Y\n", "X + 1\n"],
    ),
    "an FST array's elements in a data statement (FST's ARRAY): not supported": (
        "write one scalar per element (X1, X2, ...); a table for AFGEN is FUNCTION "
        "T = x1,y1, x2,y2, ...",
        ["PARAM X(1:3) = 1., 2., 3.\n", "PARAM X(1) = 1.\n", "PARAM A = 1.; X(2:N) = 0.\n"],
    ),
    "a data statement takes NAME = number": (
        "PARAM, CONST and INCON take numbers only (in their lines `;` separates items "
        "like `,`); derived values belong in INITIAL",
        ["PARAM A\n", "PARAM A = 1 + 2\n", "PARAM\n", "PARAM A = 1, B = 2 + C\n"],
    ),
    "a decimal comma in a data statement": (
        "the decimal separator is a point: write 1.5, not 1,5",
        ["PARAM A = 1,5\n", "CONST A = 1,5, B = 2\n"],
    ),
    "TIMER takes NAME = number settings": (
        "e.g. TIMER FINTIM = 1.0, PRDEL = 0.01",
        ["TIMER FINTIM\n", "TIMER FINTIM = A\n", "TIMER 1.0\n"],
    ),
}

# what each terminal of the grammar is, for "expected ..." hints
_TERMINALS = {
    "NAME": "a name", "NUMBER": "a number", "INT": "a number", "_NL": "end of line",
    "LPAR": "'('", "RPAR": "')'", "COMMA": "','", "EQUAL": "'='", "PLUS": "'+'",
    "MINUS": "'-'", "STAR": "'*'", "SLASH": "'/'", "POW": "'**'", "SEMICOLON": "';'",
    "DOLLAR": "'$'", "$END": "end of file", "TEXT": "text", "DATA_KW": "PARAM/CONST/INCON",
    "TOL_KW": "RELERR/ABSERR", "REPORT_KW": "PRINT/OUTPUT/RANGE/PREPARE", "_VS": "VS",
    "INITIAL": "INITIAL", "DYNAMIC": "DYNAMIC", "TERMINAL": "TERMINAL", "_END": "END",
    "_STOP": "STOP", "_TITLE": "TITLE", "_LABEL": "LABEL", "_FUNCTION": "FUNCTION",
    "_TIMER": "TIMER", "_METHOD": "METHOD", "_FINISH": "FINISH", "_TERMT": "TERMT",
    "REL_OP": "a comparison (< <= > >= == /=)", "AND_OP": ".AND.", "OR_OP": ".OR.",
    "NOT_OP": ".NOT.", "EQV_OP": ".EQV.", "TRUTH": ".TRUE./.FALSE.", "STRING": "a string",
    "LSQB": "'['", "RSQB": "']'", "COLON": "':'", "SCHED_OP": ".AT./.XP./.XN./.XZ.",
    "CONTROL_KW": "ALGORITHM/NSTEPS/MAXTERVAL/...", "TYPE_KW": "LOGICAL/INTEGER/REAL",
    "DERIVATIVE": "DERIVATIVE", "REST": "text", "LABEL_NUM": "a label",
    "LABEL_NAME": "a label",
}
_LETTERS_HINT = "letters and digits outside A-Z, 0-9 are allowed only in comments and " \
    "TITLE/LABEL text"
# look-alikes with no compatibility decomposition to ASCII
_LOOKALIKE = {"\u2212": "-", "\u2013": "-", "\u2014": "-", "\u00d7": "*", "\u00b7": "*",
              "\u2215": "/", "\u2044": "/", "\u2018": "'", "\u2019": "'", "\u201c": '"',
              "\u201d": '"', "\u00a0": " ", "\u0131": "i", "\u0130": "I"}


def character_name(ch: str) -> str:
    """'U+09EA BENGALI DIGIT FOUR'."""
    return f"U+{ord(ch):04X} {unicodedata.name(ch, 'UNNAMED CHARACTER')}"


def ascii_for(ch: str) -> str | None:
    """The ASCII character a non-ASCII one stands for, if there is one."""
    if ch in _LOOKALIKE:
        return _LOOKALIKE[ch]
    digit = unicodedata.digit(ch, None)
    if digit is not None:
        return str(digit)
    base = "".join(c for c in unicodedata.normalize("NFKD", ch) if c.isascii())
    return base if len(base) == 1 and base.isprintable() else None


def not_ascii(ch: str, span: Span) -> Diagnostic:
    """A non-ASCII character where code stands."""
    ascii_ = ascii_for(ch)
    hint = (f"write {ascii_!r}; " if ascii_ else "") + _LETTERS_HINT
    return Diagnostic(f"character {ch!r} is not allowed here: {character_name(ch)}", span, hint)


def syntax_diagnostic(exc, text: str, parser) -> Diagnostic:
    """The diagnostic of one lark UnexpectedInput raised on `text`."""
    from lark.exceptions import UnexpectedCharacters, UnexpectedToken

    line = getattr(exc, "line", None) or 1
    column = getattr(exc, "column", None) or 1
    if not isinstance(line, int) or line < 1:
        line, column = text.count("\n") + 1, 1
    span = Span(line, column, line, column + 1)
    if isinstance(exc, UnexpectedCharacters):
        ch = text[exc.pos_in_stream] if exc.pos_in_stream < len(text) else ""
        if ch and not ch.isascii():
            return not_ascii(ch, span)
        if ch == "'":
            return _unclosed(span)
        label = _label(exc, parser)
        if label:
            msg, hint = label, EXAMPLES[label][0]
        else:
            msg, hint = f"unexpected character {ch!r}", None
            if ch and not ch.isprintable():
                msg = f"unexpected character {ch!r} ({character_name(ch)})"
        if ch == "," and _between_digits(text, exc.pos_in_stream):
            hint = "a decimal separator is a point: write 1.5, not 1,5"
        return Diagnostic(msg, span, hint)
    token = getattr(exc, "token", None)
    first = str(token)[:1] if token is not None else ""
    if first and not first.isascii():
        return not_ascii(first, span)
    if first and not first.isprintable() and token.type not in ("_NL", "$END"):
        # a control character (\v, \x1c, ...) that only free text could take
        return Diagnostic(f"unexpected character {first!r} ({character_name(first)})", span,
                          "remove it: code is ASCII letters, digits, operators and blanks")
    if isinstance(exc, UnexpectedToken) and token is not None and token.end_column:
        span = Span(line, column, token.end_line or line, token.end_column)
    if first == "'" and "'" not in str(token)[1:]:
        return _unclosed(span)
    label = _label(exc, parser)
    if label is None and token is not None:
        label = _fallback_label(token, text)
    shown = _describe_token(token)
    if label:
        return Diagnostic(f"{label} (found {shown})", span, EXAMPLES[label][0])
    expected = sorted(getattr(exc, "expected", None) or getattr(exc, "allowed", ()) or ())
    names = list(dict.fromkeys(_TERMINALS.get(e, e[1:] if e.startswith("_") and
                                               e[1:].isalpha() else "a keyword")
                               for e in expected))
    hint = f"expected {', '.join(names[:8])}" if names else None
    if token is not None and str(token) == "," and \
            _between_digits(text, getattr(token, "start_pos", None)):
        hint = (hint + "; " if hint else "") + "a decimal separator is a point, not a comma"
    return Diagnostic(f"unexpected {shown}", span, hint)


def _between_digits(text: str, pos: int | None) -> bool:
    """A comma with a digit on both sides: a decimal comma is plausible there."""
    return pos is not None and 0 < pos < len(text) - 1 and text[pos - 1].isdigit() \
        and text[pos + 1].isdigit()


def _unclosed(span: Span) -> Diagnostic:
    return Diagnostic("a string that is not closed", span,
                      "end it with a quote on the same line ('text'; '' is one quote inside)")


def _label(exc, parser) -> str | None:
    try:
        return exc.match_examples(parser.parse, {k: v[1] for k, v in EXAMPLES.items()},
                                  use_accepts=True)
    except Exception:  # noqa: BLE001 - a failed guess just means no label
        return None


def _fallback_label(token, text: str) -> str | None:
    """Recognise the two commonest slips where no example state matched."""
    pos = getattr(token, "start_pos", None)
    if token.type in ("_NL", "$END"):
        end = len(text) if pos is None else pos
        start = text.rfind("\n", 0, end) + 1
        line = text[start:end].split("!", 1)[0]
        if line.count("(") > line.count(")"):
            return "missing closing parenthesis"
    if pos is not None and pos >= 2 and text[pos - 1] == "," and text[pos - 2].isdigit() \
            and str(token)[:1].isdigit():
        return "a decimal comma in a data statement"
    return None


def _describe_token(token) -> str:
    if token is None:
        return "end of input"
    if token.type == "$END":
        return "end of file"
    if token.type == "_NL":
        return "end of line"
    value = str(token)
    if token.type == "TEXT":
        # free text is only read after TITLE/LABEL; elsewhere show what starts it
        stripped = value.strip()
        value = stripped[:1] if not stripped[:1].isalnum() else stripped.split()[0]
    if len(value) > 30:
        value = value[:27] + "..."
    return repr(value)
