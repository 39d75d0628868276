"""Source text -> abstract syntax (`syntax.Program`).

The only module that sees lark: the grammar is `grammar/amil.lark` (shipped as
`amilpy.grammar`), the parser is LALR with lark's cache so a start does not
rebuild the tables, and the tree is turned into `syntax` dataclasses here.
"""

from __future__ import annotations

import sys
from functools import lru_cache
from importlib import resources

from . import syntax as ast
from .diagnostics import AmilError, Diagnostic, Span
from .language import DATA_KEYWORDS, REPORT_KEYWORDS, SECTIONS

# Friendly labels for parser states, matched by lark's `match_examples` against
# small bad listings that end in the same parser state as the user's text.
_EXAMPLES: dict[str, tuple[str, list[str]]] = {
    "missing closing parenthesis": (
        "every '(' needs a matching ')' before the end of the statement",
        ["X = SIN(Y\n", "X = (A + B\n", "X = INTGRL(0.0, Y\n", "X = A*(B - C\n"],
    ),
    "missing value after the operator": (
        "an operator must be followed by a number, a name or '('",
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
    "a data statement takes NAME = number": (
        "PARAM, CONST and INCON take numbers only; derived values belong in INITIAL",
        ["PARAM A\n", "PARAM A = B\n", "PARAM A = 1 + 2\n", "CONST A = 2*B\n", "PARAM\n"],
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


@lru_cache(maxsize=1)
def _parser():
    from lark import Lark

    grammar = resources.files("amilpy.grammar").joinpath("amil.lark").read_text("utf-8")
    return Lark(
        grammar,
        parser="lalr",
        lexer="contextual",
        propagate_positions=True,
        maybe_placeholders=True,
        cache=True,
    )


def blank_comment_lines(text: str) -> str:
    """Blank every `*` comment line, keeping line and column numbers intact.

    A line that follows a continuation mark is part of an expression even when
    it starts with `*`, so it is kept.
    """
    out = []
    continued = False
    for line in text.split("\n"):
        stripped = line.strip()
        if not continued and stripped.startswith("*"):
            out.append("")
            continue
        out.append(line)
        code = stripped.split("!", 1)[0].rstrip()
        continued = code.endswith("...") or code.endswith("&")
    return "\n".join(out)


def parse(text: str, path: str | None = None) -> ast.Program:
    """Parse a listing. Raises `AmilError` (with every syntax fault located)."""
    from lark.exceptions import UnexpectedInput

    if text.startswith("\ufeff"):
        text = text[1:]
    prepared = blank_comment_lines(text.replace("\r\n", "\n").replace("\r", "\n"))
    if not prepared.endswith("\n"):
        prepared += "\n"
    parser = _parser()
    try:
        tree = parser.parse(prepared)
    except UnexpectedInput as exc:
        raise AmilError([_syntax_diagnostic(exc, prepared, parser)], path, text) from None
    except RecursionError:
        raise AmilError("the listing is nested too deeply to read", path, text) from None
    try:
        statements = _Builder(text, path).statements(tree)
    except RecursionError:
        raise AmilError(
            [Diagnostic("expression nested too deeply", None,
                        "split it into several assignments")], path, text) from None
    return ast.Program(tuple(statements), path, text)


def _syntax_diagnostic(exc, text: str, parser) -> Diagnostic:
    from lark.exceptions import UnexpectedCharacters, UnexpectedToken

    line = getattr(exc, "line", None) or 1
    column = getattr(exc, "column", None) or 1
    if not isinstance(line, int) or line < 1:
        lines = text.split("\n")
        line, column = len(lines), 1
    span = Span(line, column, line, column + 1)
    label = None
    try:
        label = exc.match_examples(
            parser.parse, {k: v[1] for k, v in _EXAMPLES.items()}, use_accepts=True
        )
    except Exception:  # noqa: BLE001 - a failed guess just means no label
        label = None
    if isinstance(exc, UnexpectedCharacters):
        ch = text[exc.pos_in_stream] if exc.pos_in_stream < len(text) else ""
        if ch and not ch.isascii():
            return Diagnostic(
                f"character {ch!r} is not allowed here",
                span,
                "letters outside A-Z are allowed only in comments and TITLE/LABEL text",
            )
        if label:
            msg, hint = label, _EXAMPLES[label][0]
        else:
            msg, hint = f"unexpected character {ch!r}", None
        if ch == ",":
            hint = "a decimal separator is a point: write 1.5, not 1,5"
        return Diagnostic(msg, span, hint)
    token = getattr(exc, "token", None)
    shown = _describe_token(token)
    if token is not None and str(token) and not str(token)[:1].isascii():
        return Diagnostic(
            f"character {str(token)[0]!r} is not allowed here",
            span,
            "letters outside A-Z are allowed only in comments and TITLE/LABEL text",
        )
    if isinstance(exc, UnexpectedToken) and token is not None and token.end_column:
        span = Span(line, column, token.end_line or line, token.end_column)
    if label is None and token is not None:
        label = _fallback_label(token, text)
    if label:
        return Diagnostic(f"{label} (found {shown})", span, _EXAMPLES[label][0])
    expected = sorted(getattr(exc, "expected", None) or getattr(exc, "allowed", ()) or ())
    pretty = ", ".join(_TERMINAL_NAMES.get(e, e) for e in expected[:8])
    hint = f"expected {pretty}" if pretty else None
    if token is not None and str(token) == ",":
        hint = (hint + "; " if hint else "") + "a decimal separator is a point, not a comma"
    return Diagnostic(f"unexpected {shown}", span, hint)


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


_TERMINAL_NAMES = {
    "NAME": "a name", "NUMBER": "a number", "_NL": "end of line", "LPAR": "'('",
    "RPAR": "')'", "COMMA": "','", "EQUAL": "'='", "PLUS": "'+'", "MINUS": "'-'",
    "STAR": "'*'", "SLASH": "'/'", "POW": "'**'", "SEMICOLON": "';'", "$END": "end of file",
}


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


# -------------------------------------------------------------- tree -> syntax

MAX_RUNS = 10_000  # value-list runs in one group: beyond this, a typo or a sweep

_BINOPS = {"add": "+", "sub": "-", "mul": "*", "div": "/", "pow": "**"}


def _number(text: str) -> float:
    return float(text.replace("D", "E").replace("d", "e"))


class _Builder:
    """Turns lark trees into `syntax` nodes; iterative over statements."""

    def __init__(self, source: str, path: str | None) -> None:
        self.source = source
        self.path = path

    @staticmethod
    def span(node) -> Span:
        meta = getattr(node, "meta", None)
        if meta is not None and not getattr(meta, "empty", True):
            return Span(meta.line, meta.column, meta.end_line, meta.end_column)
        return Span(node.line, node.column, node.end_line, node.end_column)

    def statements(self, tree) -> list[ast.Statement]:
        out: list[ast.Statement] = []
        for node in tree.children:
            built = getattr(self, "st_" + node.data)(node)
            out.append(built)
        return out

    # statements ------------------------------------------------------------
    def st_title(self, node) -> ast.Title:
        text = str(node.children[0]).strip() if node.children and node.children[0] else ""
        return ast.Title(text, self.span(node))

    def st_label(self, node) -> ast.Label:
        text = str(node.children[0]).strip() if node.children and node.children[0] else ""
        return ast.Label(text, self.span(node))

    def st_section(self, node) -> ast.Section:
        return ast.Section(SECTIONS[str(node.children[0]).upper()], self.span(node))

    def st_end(self, node) -> ast.End:
        return ast.End(self.span(node))

    def st_stop(self, node) -> ast.Stop:
        return ast.Stop(self.span(node))

    def st_assign(self, node) -> ast.Assign:
        *targets, expr = node.children
        return ast.Assign(
            tuple(str(t).upper() for t in targets),
            tuple(self.span(t) for t in targets),
            self.expr(expr),
            self.span(node),
        )

    def value(self, node) -> float:
        if node.data == "negative":
            return -_number(str(node.children[0]))
        return _number(str(node.children[0]))

    def st_data(self, node) -> ast.Data:
        keyword = DATA_KEYWORDS[str(node.children[0]).upper()]
        items = []
        for item in node.children[1:]:
            name = str(item.children[0]).upper()
            if item.data == "data_list":
                values: list[float] = []
                for entry in item.children[1:]:
                    count = int(str(entry.children[0])) if entry.data == "repeat" else 1
                    if len(values) + count > MAX_RUNS:
                        raise AmilError([Diagnostic(
                            f"the value list of {name} gives more than {MAX_RUNS} runs",
                            self.span(item), "a sweep of many values is `amilpy sweep`")],
                            self.path, self.source)
                    value = self.value(entry.children[1] if entry.data == "repeat" else entry)
                    values.extend([value] * count)
                items.append(ast.DataItem(name, tuple(values), self.span(item), True))
            else:
                items.append(ast.DataItem(name, (self.value(item.children[1]),), self.span(item)))
        return ast.Data(keyword, tuple(items), self.span(node))

    def st_table(self, node) -> ast.Table:
        name = str(node.children[0]).upper()
        points = node.children[1]
        numbers: list[float] = []
        for child in points.children:
            if child.data == "pair":
                numbers.extend(self.value(v) for v in child.children)
            else:
                numbers.append(self.value(child))
        odd = len(numbers) % 2 == 1
        return ast.Table(name, tuple(numbers[0::2]), tuple(numbers[1::2]), self.span(node), odd)

    def settings(self, nodes) -> tuple[ast.Setting, ...]:
        return tuple(
            ast.Setting(str(s.children[0]).upper(), self.value(s.children[1]), self.span(s))
            for s in nodes
        )

    def st_timer(self, node) -> ast.Timer:
        return ast.Timer(self.settings(node.children), self.span(node))

    def st_method(self, node) -> ast.Method:
        return ast.Method(str(node.children[0]).upper(), self.span(node))

    def st_tolerance_all(self, node) -> ast.Tolerance:
        kind = str(node.children[0]).upper()
        return ast.Tolerance(kind, self.value(node.children[1]), (), self.span(node))

    def st_tolerance_each(self, node) -> ast.Tolerance:
        kind = str(node.children[0]).upper()
        return ast.Tolerance(kind, None, self.settings(node.children[1:]), self.span(node))

    def st_finish(self, node) -> ast.Finish:
        return ast.Finish(self.settings(node.children), self.span(node))

    def st_termt(self, node) -> ast.Termt:
        return ast.Termt(self.expr(node.children[0]), self.span(node))

    def st_report(self, node) -> ast.Report:
        kind = REPORT_KEYWORDS[str(node.children[0]).upper()]
        names = node.children[1:]
        return ast.Report(
            kind,
            tuple(str(n).upper() for n in names),
            tuple(self.span(n) for n in names),
            self.span(node),
        )

    # expressions -----------------------------------------------------------
    def expr(self, node) -> ast.Expr:
        from lark import Token

        if isinstance(node, Token):  # a bare NUMBER/NAME never reaches here, kept for safety
            return ast.Name(str(node).upper(), self.span(node))
        kind = node.data
        if kind == "number":
            tok = node.children[0]
            return ast.Num(_number(str(tok)), self.span(node), str(tok))
        if kind == "name":
            return ast.Name(str(node.children[0]).upper(), self.span(node))
        if kind == "call":
            func, *args = node.children
            real = [a for a in args if a is not None]
            return ast.Call(
                str(func).upper(),
                tuple(self.expr(a) for a in real),
                self.span(node),
                tuple(self.span(a) for a in real),
            )
        if kind in _BINOPS:
            left, *rest = node.children
            right = rest[-1]
            return ast.BinOp(_BINOPS[kind], self.expr(left), self.expr(right), self.span(node))
        if kind == "neg":
            return ast.Neg(self.expr(node.children[0]), self.span(node))
        if kind == "pos":
            return self.expr(node.children[0])
        raise AssertionError(f"unknown expression node {kind}")


def _raise_recursion_limit() -> None:
    # Deeply nested expressions are legal; give the tree walk room for them.
    if sys.getrecursionlimit() < 10000:
        sys.setrecursionlimit(10000)
