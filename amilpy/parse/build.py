"""lark parse tree -> `syntax` nodes (lark trees never leave the `parse` package).

Expressions are built bottom-up with an explicit stack, so any nesting is read
without recursion; one nested deeper than `syntax.MAX_DEPTH` is a located error
(every later stage walks expressions recursively, with room for that depth).
"""

from __future__ import annotations

import math
import re
from dataclasses import replace

from ..diagnostics import AmilError, Diagnostic, Span
from ..language import (
    DATA_KEYWORDS,
    MAX_ELEMENTS,
    REFUSED,
    REPORT_KEYWORDS,
    SECTIONS,
    TYPE_KEYWORDS,
    fortran_float,
    split_lines,
)
from . import syntax as ast
from .blocks import Close, ElseHead, Head
from .lexical import code_end
from .syntax import MAX_DEPTH
from .tree import Node, read, relation

# -------------------------------------------------------------- tree -> syntax

# ACSL's TABLE NAME, n, i1[, i2, i3] / values / (the text after TABLE)
_ACSL_TABLE = re.compile(r"^\s*([A-Za-z][A-Za-z0-9_]*)\s*,\s*([0-9]+(?:\s*,\s*[0-9]+)+)\s*/"
                         r"([^/]*)/\s*$")
# ACSL's ARRAY X(220), A(N, 3): sizes that are numbers or names
_ACSL_ARRAY = re.compile(r"([A-Za-z][A-Za-z0-9_]*)\s*\(\s*((?:[0-9]+|[A-Za-z][A-Za-z0-9_]*)"
                         r"(?:\s*,\s*(?:[0-9]+|[A-Za-z][A-Za-z0-9_]*))*)\s*\)")
_ACSL_ARRAYS = re.compile(rf"{_ACSL_ARRAY.pattern}(?:\s*,\s*{_ACSL_ARRAY.pattern})*")
# FST's ARRAY X(1:N), Y(1:3) and ARRAY_SIZE N = 10
_FST_ARRAY = re.compile(r"([A-Za-z][A-Za-z0-9_]*)\s*\(\s*([0-9]+)\s*:\s*([0-9]+|[A-Za-z]"
                        r"[A-Za-z0-9_]*)\s*\)")
_FST_ARRAYS = re.compile(rf"{_FST_ARRAY.pattern}(?:\s*,\s*{_FST_ARRAY.pattern})*")
_FST_SIZE = re.compile(r"([A-Za-z][A-Za-z0-9_]*)\s*=\s*([0-9]+)")
_FST_SIZES = re.compile(rf"{_FST_SIZE.pattern}(?:\s*,\s*{_FST_SIZE.pattern})*")
MAX_RUNS = 10_000  # value-list runs in one group: beyond this, a typo or a sweep


def _rest_code(node) -> str:
    """The code of a refused statement's text (REST), on one line: comments dropped,
    continuation marks taken out."""
    return _code(str(node.children[1]))


def _code(text: str) -> str:
    """Statement text on one line: comments dropped, continuation marks taken out."""
    return " ".join(line[:code_end(line)].rstrip().removesuffix("&").removesuffix("...")
                    for line in text.split("\n")).strip()


# ACSL's MACRO directives, besides STANDVAL, REDEFINE and END (MACRO NAME(...) with one
# of these words is the directive, not a MACRO of that name)
ACSL_MACRO_WORDS = frozenset({"RELABEL", "IF", "GO", "GOTO", "CONTINUE", "EXIT",
                              "DECREMENT", "INCREMENT", "ASSIGN", "PRINT", "REDEFINE",
                              "STANDVAL", "END", "ENDMACRO"})


def _label(text: str) -> str:
    """A statement label as a loop names it: 10 and 010 are one label, names folded."""
    text = text.strip()
    return str(int(text)) if text.isdigit() else text.upper()


_BINOPS = {"add": "+", "sub": "-", "mul": "*", "div": "/", "pow": "**"}
# relational and logical operators (the token's spelling decides: rel, land, ...)
_OPERATORS = {".EQ.": "==", "==": "==", ".NE.": "/=", "/=": "/=", "~=": "/=",
              ".LT.": "<", "<": "<", ".LE.": "<=", "<=": "<=", ".GT.": ">", ">": ">",
              ".GE.": ">=", ">=": ">=", ".AND.": "AND", "&&": "AND", ".OR.": "OR",
              "||": "OR", ".EQV.": "EQV", ".NEQV.": "NEQV"}
_LOGIC = ("rel", "land", "lor", "eqv")


def string_value(token: str) -> str:
    """The text of a string as written ('it''s' -> it's; a `...` continuation inside
    joins the lines)."""
    import re

    inner = token[1:-1]
    inner = re.sub(r"\.\.\.[ \t]*\r?\n[ \t]*", "", inner)
    return inner.replace("''", "'")


class Builder:
    """Turns lark trees into `syntax` nodes; iterative over statements and expressions."""

    def __init__(self, source: str, path: str | None, parser=None) -> None:
        self.source = source
        self.path = path
        self.errors: list[Diagnostic] = []  # refusals and misplaced strings
        self.acsl = False  # the ACSL form (where CONSTANT X = 1, 2 fills an array)
        self.parser = parser  # the listing's (a labelled statement's text is read again)
        self.calls = False  # a CALL of a subroutine made (parse._subroutines_called)

    def refuse(self, construct: str, span: Span, hint: str) -> None:
        """A construct amilpy does not run (contract section 14)."""
        self.errors.append(Diagnostic(f"{construct} (line {span.line}): not supported",
                                      span, hint))

    @staticmethod
    def span(node) -> Span:
        """Where a node (`tree.Node`) or a token stands."""
        span = getattr(node, "span", None)  # (an expression node's, made as it reduced)
        if span is not None:
            return span
        return Span(node.line, node.column, node.end_line, node.end_column)

    def statements(self, tree) -> list:
        """The statements read one by one; block openers and closers as `blocks`
        heads (nested by `blocks.Nester`), comments left out."""
        out: list = []
        for node in tree.children:
            built = self.statement(node)
            if isinstance(built, list):  # (a labelled statement: the label, then it)
                out.extend(built)
            elif built is not None:
                out.append(built)
        return out

    def statement(self, node):
        return getattr(self, "st_" + node.data)(node)

    # statements ------------------------------------------------------------
    def st_title(self, node) -> ast.Title:
        text = str(node.children[0]).strip() if node.children and node.children[0] else ""
        return ast.Title(text, self.span(node))

    def st_label(self, node) -> ast.Label:
        text = str(node.children[0]).strip() if node.children and node.children[0] else ""
        return ast.Label(text, self.span(node))

    def st_section(self, node) -> ast.Section:
        written = str(node.children[0]).upper()
        return ast.Section(SECTIONS[written], self.span(node), written)

    def st_end(self, node) -> ast.End:
        return ast.End(self.span(node))

    def st_end_if(self, node) -> Close:
        return Close("ENDIF", self.span(node))

    def st_end_do(self, node) -> Close:
        return Close("ENDDO", self.span(node))

    def st_comment(self, node) -> None:
        return None  # a string alone: ACSL's END $ 'of derivative'

    # blocks (nested by blocks.Nester) --------------------------------------
    def st_program(self, node) -> Head:
        text = str(node.children[0]).strip() if node.children and node.children[0] else ""
        return Head("PROGRAM", self.span(node), text.removeprefix(":").strip())

    def st_discrete(self, node) -> Head:
        name = node.children[0] if node.children else None
        return Head("DISCRETE", self.span(node), str(name).upper() if name else None)

    def st_included(self, node) -> Head:
        return Head("INCLUDED", self.span(node))

    def st_procedural(self, node) -> Head:
        outputs: tuple[str, ...] = ()
        inputs: tuple[str, ...] = ()
        for lists in node.children:
            for part in lists.children:
                if part.data == "outputs":
                    outputs = tuple(str(n).upper() for n in part.children)
                elif part.children:  # proc_inputs: "=" inputs?
                    inputs = tuple(str(n).upper() for n in part.children[0].children
                                   if n.type == "NAME")
        return Head("PROCEDURAL", self.span(node), data=(outputs, inputs))

    def st_if_head(self, node) -> Head:
        return Head("IF", self.span(node), data=self.expr(node.children[0]))

    def st_if_one(self, node) -> ast.If | None:
        cond, inner = node.children
        built = self.statement(inner)
        if built is None:
            return None
        if not isinstance(built, (ast.Assign, ast.Termt, ast.Schedule, ast.If, ast.MacroCall,
                                  ast.SubroutineCall, ast.GoTo)):
            return None
        span = self.span(node)
        return ast.If((ast.Branch(self.expr(cond), (built,), span),), span)

    def st_else_if(self, node) -> ElseHead:
        return ElseHead(self.expr(node.children[0]), self.span(node))

    def st_else_(self, node) -> ElseHead:
        return ElseHead(None, self.span(node))

    def loop(self, kind: str, node) -> Head:
        var, start, stop, step = node.children
        return Head(kind, self.span(node), data=(
            str(var).upper(), self.expr(start), self.expr(stop),
            self.expr(step) if step is not None else None))

    def st_for_head(self, node) -> Head:
        return self.loop("FOR", node)

    def st_do_head(self, node) -> Head:
        return self.loop("DO", node)

    def st_do_labelled(self, node) -> Head:
        label, var, start, stop, step = node.children
        return Head("DO", self.span(node), data=(
            str(var).upper(), self.expr(start), self.expr(stop),
            self.expr(step) if step is not None else None), label=_label(str(label)))

    def st_func_def(self, node) -> Head:
        name, func, params = node.children
        names = tuple(str(n).upper() for n in params.children) if params is not None else ()
        return Head("FUNCTION", self.span(node), str(func).upper(),
                    data=(str(name).upper(), names))

    # statements of the ACSL form ---------------------------------------------
    def st_schedule(self, node) -> ast.Schedule:
        name, op, expr = node.children
        kind = str(op).strip(".").upper()
        return ast.Schedule(str(name).upper(), kind, self.expr(expr), self.span(node))

    def st_interval(self, node) -> ast.Interval:
        return ast.Interval(str(node.children[0]).upper(), self.expr(node.children[1]),
                            self.span(node))

    def st_cinterval(self, node) -> ast.Cinterval:
        return ast.Cinterval(str(node.children[0]).upper(), self.expr(node.children[1]),
                             self.span(node))

    def st_variable(self, node) -> ast.Variable:
        name, value = node.children
        return ast.Variable(str(name).upper(), self.value(value) if value is not None else None,
                            self.span(node))

    def st_control(self, node) -> ast.Control:
        return ast.Control(str(node.children[0]).upper(), self.settings(node.children[1:]),
                           self.span(node))

    def st_declare(self, node) -> ast.Declare | None:
        words = [str(c).upper().replace(" ", "").replace("\t", "") for c in node.children
                 if not hasattr(c, "data")]
        items = [c for c in node.children if getattr(c, "data", "length") != "length"]
        kind = TYPE_KEYWORDS[words[-1]]
        names = [c.children[0] for c in items]
        sizes = tuple(tuple(self.expr(e) for e in c.children[1:]
                            if getattr(e, "data", None) != "length") for c in items)
        return ast.Declare(kind, tuple(str(n).upper() for n in names),
                           tuple(self.span(n) for n in names), self.span(node),
                           sizes if any(sizes) else ())

    def st_refused(self, node) -> ast.Table | ast.Declare | None:
        word = " ".join(str(node.children[0]).upper().split())
        if word == "TABLE" and len(node.children) > 1 and node.children[1]:
            table = self.acsl_table(node)
            if table is not None:
                return table
        if word == "ARRAY" and len(node.children) > 1 and node.children[1]:
            declared = self.acsl_array(node) if self.acsl else self.fst_array(node)
            if declared is not None:
                return declared
        if word == "ARRAY_SIZE" and not self.acsl and len(node.children) > 1 and \
                node.children[1]:
            sizes = self.fst_array_size(node)
            if sizes is not None:
                return sizes
        what, hint = REFUSED[word.replace(" ", "")]
        self.refuse(what, self.span(node), hint)
        return None

    def acsl_array(self, node) -> ast.Declare | None:
        """ARRAY X(220), A(N, 3) in ACSL form: DIMENSION's synonym (acslX). None if the
        text is not of that form (FST's ARRAY X(1:N), refused)."""
        span = self.span(node)
        code = _rest_code(node)
        if _ACSL_ARRAYS.fullmatch(code) is None:
            return None
        names, sizes = [], []
        for m in _ACSL_ARRAY.finditer(code):
            names.append(m.group(1).upper())
            sizes.append(tuple(
                ast.Num(float(d), span, d) if d.isdigit() else ast.Name(d.upper(), span)
                for d in (k.strip() for k in m.group(2).split(","))))
        return ast.Declare("REAL", tuple(names), (span,) * len(names), span, tuple(sizes))

    def fst_array(self, node) -> ast.Declare | None:
        """FST's ARRAY X(1:N), Y(1:3): arrays of one subscript from 1 (N an ARRAY_SIZE
        name or a number). None if the text is not of that form (said by the caller)."""
        span = self.span(node)
        code = _rest_code(node)
        if _FST_ARRAYS.fullmatch(code) is None:
            return None
        names, sizes = [], []
        for m in _FST_ARRAY.finditer(code):
            first, last = m.group(2), m.group(3)
            if first != "1" and first.lstrip("0") != "1":
                self.errors.append(Diagnostic(
                    f"ARRAY {m.group(1).upper()}({first}:{last}): an array whose first "
                    "subscript is not 1 is not supported", span,
                    f"number its elements from 1: ARRAY {m.group(1).upper()}(1:N)"))
                return ast.Declare("REAL", (), (), span, ())
            names.append(m.group(1).upper())
            sizes.append((ast.Num(float(last), span, last) if last.isdigit()
                          else ast.Name(last.upper(), span),))
        return ast.Declare("REAL", tuple(names), (span,) * len(names), span, tuple(sizes))

    def fst_array_size(self, node) -> ast.Data | None:
        """FST's ARRAY_SIZE N = 10, M = 3: the sizes the ARRAYs are declared with,
        constants of the listing (a rerun may not change them)."""
        span = self.span(node)
        code = _rest_code(node)
        if _FST_SIZES.fullmatch(code) is None:
            return None
        return ast.Data("CONST", tuple(
            ast.DataItem(m.group(1).upper(), (float(m.group(2)),), span)
            for m in _FST_SIZE.finditer(code)), span)

    def acsl_table(self, node) -> ast.Table | None:
        """ACSL's TABLE NAME, n, N1[, N2, N3] / breakpoints of each variable, then the
        values (the first variable's index fastest) / (n*v repeats v): a function
        table like FUNCTION NAME = x1,y1, ... for n = 1, with the other variables'
        breakpoints in `grid` for n = 2, 3 (`parse.arrays` writes those out); None if
        the text is not of that form (CSMP's TABLE, which is refused)."""
        span = self.span(node)
        m = _ACSL_TABLE.match(_rest_code(node))
        if m is None:
            return None
        name, sizes, body = m.group(1).upper(), [int(k) for k in m.group(2).split(",")], \
            m.group(3)
        empty = ast.Table(name, (0.0, 1.0), (0.0, 0.0), span)
        if not 1 <= sizes[0] <= 3 or len(sizes) != sizes[0] + 1 or min(sizes[1:]) < 1:
            self.errors.append(Diagnostic(
                f"TABLE {name}, {m.group(2)}: a table of 1, 2 or 3 variables gives their "
                "number, then each one's count of breakpoints", span,
                "e.g. TABLE F, 2, 3, 2 / x1, x2, x3, y1, y2, f11, f21, f31, f12, f22, f32 /"))
            return empty
        values: list[float] = []
        for item in body.split(","):
            count, _, value = item.strip().rpartition("*")
            try:
                number = fortran_float(value.strip())
                times = int(count) if count else 1
            except ValueError:
                self.errors.append(Diagnostic(
                    f"TABLE {name}: {item.strip()!r} is not a number", span,
                    "the values between the slashes are numbers (n*v repeats v)"))
                return empty
            if times > MAX_ELEMENTS:
                self.errors.append(Diagnostic(f"TABLE {name}: {times}*... is too long", span,
                                              f"a table has at most {MAX_ELEMENTS:,} points"))
                return empty
            values.extend([number] * times)
        counts = sizes[1:]
        points = math.prod(counts)
        if len(values) != sum(counts) + points or points > MAX_ELEMENTS:
            self.errors.append(Diagnostic(
                f"TABLE {name} has {len(values)} values for {' x '.join(map(str, counts))} "
                "breakpoints", span,
                f"give the {' + '.join(map(str, counts))} breakpoints, then the {points} "
                f"function values ({sum(counts) + points} in all)"))
            return empty
        axes, at = [], 0
        for n in counts:
            axes.append(tuple(values[at:at + n]))
            at += n
        for k, axis in enumerate(axes):
            for i in range(1, len(axis)):
                if not axis[i] > axis[i - 1]:
                    which = f"its {('first', 'second', 'third')[k]} variable's" \
                        if len(axes) > 1 else "its"
                    self.errors.append(Diagnostic(
                        f"TABLE {name}: {which} breakpoints must increase strictly "
                        f"({axis[i - 1]:g}, then {axis[i]:g})", span,
                        "write each variable's breakpoints in increasing order"))
                    return empty
        return ast.Table(name, axes[0], tuple(values[at:]), span, grid=tuple(axes[1:]))

    def st_labelled(self, node) -> Close | None:
        label = str(node.children[0]).strip()
        span = self.span(node)
        lines = split_lines(self.source)
        line = lines[span.line - 1] if 0 < span.line <= len(lines) else ""
        rest = line[span.column - 1:].lstrip()[len(label):].lstrip()
        if rest.startswith(":="):  # (Pascal's and Algol's assignment, not a label)
            self.errors.append(Diagnostic(
                "':=' is not this language's assignment", span,
                f"write {label} = {rest[2:].split('!')[0].strip() or '...'}"))
            return
        statement = rest.removeprefix(":").split("!")[0].strip().rstrip(";$").strip()
        if statement.upper() == "CONTINUE":
            # the end of the DO loops with this label, else a place a GO TO jumps to
            return Close("ENDDO", span, label=_label(label))
        if not self.acsl:
            self.refuse(f"the statement label {label}", self.span(node),
                        "remove it: GO TO is the ACSL form's; write IF (c) THEN ... END IF "
                        "or DO i = a, b ... END DO")
            return None
        # `10: X = 1.0`: the place a GO TO jumps to, then the statement, read as if the
        # label were not written (at its own line and column)
        rest_token = node.children[-1] if len(node.children) > 1 else None
        if rest_token is None or not str(rest_token).strip().removeprefix(":").strip():
            return [ast.Target(_label(label), span)]
        return [ast.Target(_label(label), span), *self.labelled_statement(rest_token)]

    def labelled_statement(self, token) -> list:
        """The statements of the text after a label (a REST token), read by the
        listing's grammar where they stand."""
        from lark.exceptions import UnexpectedInput

        from .errors import syntax_diagnostic
        from .lexical import prepare

        text = str(token)
        colon = len(text) - len(text.lstrip())
        if text.lstrip().startswith(":"):
            colon += 1 + len(text.lstrip()[1:]) - len(text.lstrip()[1:].lstrip())
        source = "\n" * (token.line - 1) + " " * (token.column - 1 + colon) + \
            text[colon:] + "\n"
        try:
            tree = read(self.parser, prepare(source))
        except UnexpectedInput as exc:
            self.errors.append(syntax_diagnostic(exc, prepare(source), self.parser))
            return []
        return self.statements(tree)

    def st_goto_computed(self, node) -> None:
        self.refuse("a computed GO TO", self.span(node),
                    "write one IF (K .EQ. 1) GO TO 10 per label, or IF ... ELSE IF blocks")

    def st_goto(self, node) -> ast.GoTo | None:
        label = _label(str(node.children[0]))
        if not self.acsl:
            what, hint = REFUSED["GOTO"]
            self.refuse(what, self.span(node), hint)
            return None
        return ast.GoTo(label, self.span(node))

    def st_assign_subscript(self, node) -> ast.Assign:
        name, *subscripts, expr = node.children
        return ast.Assign((str(name).upper(),), (self.span(name),), self.expr(expr),
                          self.span(node), tuple(self.expr(e) for e in subscripts))

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
            return -fortran_float(str(node.children[0]))
        if node.data == "truth":
            return 1.0 if str(node.children[0]).upper().strip(".") == "TRUE" else 0.0
        if node.data == "string":
            self.errors.append(Diagnostic(
                f"the string {node.children[0]} cannot be a value", self.span(node),
                "strings are TERMT messages, WEATHER/TRANSLATION values and comments; put "
                "the text in a TERMT message or a comment"))
            return 0.0
        return fortran_float(str(node.children[0]))

    def st_data(self, node) -> ast.Data:
        keyword = DATA_KEYWORDS[str(node.children[0]).upper()]
        items = []
        children = node.children[1:]
        whole = False  # an INTEGER constant: Fortran truncates what it is given
        if children and getattr(children[0], "type", None) == "TYPE_KW":
            kind = "".join(str(children[0]).upper().split())
            if kind not in ("INTEGER", "REAL", "DOUBLEPRECISION", "LOGICAL"):
                self.errors.append(Diagnostic(
                    f"{kind} is no type of a constant", self.span(children[0]),
                    "write CONSTANT INTEGER, REAL, DOUBLE PRECISION or LOGICAL, or none"))
            whole, children = kind == "INTEGER", children[1:]
        for item in children:
            if item.data in ("more_value", "more_repeat"):
                # ACSL's CONSTANT X = 1, 2, 3 (FST's X(1:3) = 1, 2, 3): the value belongs
                # to the name before it
                if not self.acsl and not (items and items[-1].element):
                    self.errors.append(Diagnostic(
                        "a decimal comma in a data statement", self.span(item),
                        "the decimal separator is a point: write 1.5, not 1,5"))
                    continue
                if not items:  # (a fault in the item before it, said there)
                    continue
                last = items[-1]
                piece = self.piece(item, item.children[0] if item.data == "more_repeat"
                                   else None, item.children[-1])
                if piece is None:
                    continue
                if last.pieces or not isinstance(piece[0], int) or \
                        not isinstance(piece[1], float):
                    pieces = last.pieces or tuple((1, v, last.span) for v in last.values)
                    items[-1] = replace(last, values=(), pieces=(*pieces, piece),
                                        is_array=True)
                    continue
                count, value = piece[0], piece[1]
                if whole and math.isfinite(value):
                    value = float(math.trunc(value))
                items[-1] = replace(last, values=last.values + (value,) * count,
                                    is_array=True)
                continue
            name = str(item.children[0]).upper()
            if item.data == "data_item" and self.acsl and \
                    getattr(item.children[-1], "data", None) == "string":
                # (a CHARACTER name's text: `texts` keeps it aside, or says it is none)
                items.append(ast.DataItem(name, (), self.span(item), text=string_value(
                    str(item.children[-1].children[0]))))
                continue
            if item.data in ("data_element", "data_element_repeat"):
                element = tuple(self.bound(b) for b in item.children[1:3])
                piece = self.piece(item, item.children[3] if len(item.children) > 4
                                   else None, item.children[-1])
                if piece is not None:
                    items.append(ast.DataItem(name, (), self.span(item), pieces=(piece,),
                                              element=element))
                continue
            if item.data in ("data_item", "data_repeat"):
                piece = self.piece(item, item.children[1] if item.data == "data_repeat"
                                   else None, item.children[-1])
                if piece is None:
                    continue
                count, value, _ = piece
                array = item.data == "data_repeat"
                if isinstance(count, int) and isinstance(value, float):
                    items.append(ast.DataItem(name, (value,) * count, self.span(item),
                                              is_array=array))
                else:
                    items.append(ast.DataItem(name, (), self.span(item), is_array=array,
                                              pieces=(piece,)))
            elif item.data == "data_list":
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
            if whole and items:
                items[-1] = replace(items[-1], values=tuple(
                    float(math.trunc(v)) if math.isfinite(v) else v for v in items[-1].values))
        return ast.Data(keyword, tuple(items), self.span(node))

    def bound(self, token) -> float | str | None:
        """A subscript of FST's X(k) = v or X(i:j) = ...: a number or a name (None: no
        second one)."""
        if token is None:
            return None
        return str(token).upper() if token.type == "NAME" else fortran_float(str(token))

    def piece(self, item, count, datum) -> tuple | None:
        """(n, v, span) of a data value `n*v` (n = 1 without a count): a number, or in
        the ACSL form the name of a constant given a value before (kept as its name,
        for `arrays` to read when the constants are known); None when it cannot be."""
        named = [t for t in (count, datum) if getattr(t, "type", None) == "NAME"]
        if named and not self.acsl:
            found = "*".join(str(t) for t in (count, datum) if t is not None)
            self.errors.append(Diagnostic(
                f"a data statement takes NAME = number (found {found!r})", self.span(item),
                "PARAM, CONST and INCON take numbers only (in their lines `;` separates "
                "items like `,`); derived values belong in INITIAL"))
            return None
        n = 1 if count is None else str(count).upper() if count in named else \
            self.count(count)
        v = str(datum).upper() if datum in named else self.value(datum)
        return n, v, self.span(item)

    def count(self, token) -> int:
        """n of an array's n*v (at most language.MAX_ELEMENTS)."""
        n = int(str(token))
        if n > MAX_ELEMENTS:
            self.errors.append(Diagnostic(
                f"{n}*... repeats a value more than {MAX_ELEMENTS:,} times", self.span(token),
                f"an array has at most {MAX_ELEMENTS:,} elements"))
            return 0
        return n

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
        settings = [c for c in node.children if c.data == "setting"]
        relations = tuple(
            ast.Termt(self.expr(relation(c)), self.span(c))
            for c in node.children if c.data == "finish_relation")
        return ast.Finish(self.settings(settings), self.span(node), relations)

    def items(self, nodes) -> tuple[ast.Item, ...]:
        out = []
        for item in nodes:
            name, value = item.children
            text = string_value(str(value.children[0])) if value.data == "string" \
                else self.value(value)
            out.append(ast.Item(str(name).upper(), text, self.span(item)))
        return tuple(out)

    def st_translation(self, node) -> ast.Translation:
        kind, *items = node.children
        return ast.Translation(str(kind).upper(), self.items(i for i in items if i is not None),
                               self.span(node))

    def st_weather(self, node) -> ast.Weather:
        return ast.Weather(self.items(node.children), self.span(node))

    @staticmethod
    def _named_lists(node):
        """`O1, O2 = NAME(I1, I2)` after MACRO or PROCEDURE: (outputs, NAME, inputs)."""
        import re

        text = str(node.children[0]) if node.children and node.children[0] else ""
        head = re.fullmatch(r"\s*([A-Za-z]\w*(?:\s*,\s*[A-Za-z]\w*)*)\s*=\s*([A-Za-z]\w*)"
                            r"\s*\(\s*([A-Za-z]\w*(?:\s*,\s*[A-Za-z]\w*)*)?\s*\)\s*", text)
        if head is None:
            return None
        outputs = tuple(n.strip().upper() for n in head.group(1).split(","))
        inputs = tuple(n.strip().upper() for n in (head.group(3) or "").split(",") if n.strip())
        return outputs, head.group(2).upper(), inputs

    def st_procedure(self, node) -> Head | None:
        """PROCEDURE O1, O2 = NAME(I1, I2) (CSMP III): a PROCEDURAL block."""
        lists = self._named_lists(node)
        if lists is None:
            self.errors.append(Diagnostic(
                "PROCEDURE needs its lists: PROCEDURE O1, O2 = NAME(I1, I2)", self.span(node),
                "name the outputs before '=' and the inputs in the parentheses"))
            return None
        outputs, name, inputs = lists
        return Head("PROCEDURE", self.span(node), name, (outputs, inputs))

    def st_endpro(self, node) -> Close:
        return Close("ENDPRO", self.span(node))

    def st_macro(self, node) -> Head | Close | ast.MacroDirective | None:
        """MACRO O1, O2 = NAME(P1, ...) (CSMP III's); ACSL's MACRO NAME(A1, ...), MACRO
        END, MACRO STANDVAL A = v, ... and MACRO REDEFINE X, ...; ACSL's other MACRO
        directives (RELABEL, IF, GO TO, EXIT, ...) are refused by name."""
        span = self.span(node)
        lists = self._named_lists(node)
        if lists is not None:
            outputs, name, params = lists
            return Head("MACRO", span, name, (outputs, params, False))
        text = _code(str(node.children[0]) if node.children and node.children[0] else "")
        head = re.fullmatch(r"([A-Za-z]\w*)\s*\(\s*([A-Za-z]\w*(?:\s*,\s*[A-Za-z]\w*)*)?"
                            r"\s*\)", text)
        if head is not None and head.group(1).upper() not in ACSL_MACRO_WORDS:
            params = tuple(n.strip().upper() for n in (head.group(2) or "").split(",")
                           if n.strip())
            return Head("MACRO", span, head.group(1).upper(), ((), params, True))
        word = re.match(r"[A-Za-z]+", text)
        word = word.group().upper() if word else ""
        rest = text[len(word):].strip()
        if word in ("END", "ENDMACRO") and not rest:
            return Close("ENDMAC", span)
        if word == "REDEFINE":
            names = [n.strip().upper() for n in rest.split(",")]
            if names and all(re.fullmatch(r"[A-Z]\w*", n) for n in names):
                return ast.MacroDirective("REDEFINE", tuple(names), (), span)
            self.errors.append(Diagnostic(
                "MACRO REDEFINE takes names: MACRO REDEFINE X, Y", span,
                "list the names each call of the MACRO keeps to itself"))
            return None
        if word == "STANDVAL":
            items = [re.fullmatch(r"([A-Za-z]\w*)\s*=\s*([-+]?(?:\d+\.?\d*|\.\d+)"
                                  r"(?:[EDed][-+]?\d+)?)", part.strip())
                     for part in rest.split(",")]
            if rest and all(items):
                return ast.MacroDirective(
                    "STANDVAL", tuple(m.group(1).upper() for m in items),
                    tuple(fortran_float(m.group(2)) for m in items), span)
            self.errors.append(Diagnostic(
                "MACRO STANDVAL takes NAME = number items: MACRO STANDVAL IC = 0.0", span,
                "give each argument that may be left out its number"))
            return None
        if word in ACSL_MACRO_WORDS:
            self.refuse(f"ACSL's MACRO {'GO TO' if word == 'GO' else word}", span,
                        "amilpy expands ACSL MACROs with their arguments, MACRO STANDVAL and "
                        "MACRO REDEFINE: write the MACRO's statements without it")
            return None
        self.errors.append(Diagnostic(
            "a MACRO head reads MACRO NAME(A1, A2, ...) (ACSL) or MACRO O1, O2 = NAME(P1, "
            "P2) (CSMP III)", span,
            "name the MACRO and its arguments; end an ACSL MACRO with MACRO END"))
        return None

    def st_macro_call(self, node) -> ast.MacroCall:
        name, *args = node.children
        args = [a for a in args if a is not None]
        return ast.MacroCall(str(name).upper(), tuple(self.expr(a) for a in args),
                             self.span(node))

    def st_nosort(self, node) -> ast.Nosort:
        return ast.Nosort(False, self.span(node))

    def st_sort(self, node) -> ast.Nosort:
        return ast.Nosort(True, self.span(node))

    def st_endmac(self, node) -> Close:
        return Close("ENDMAC", self.span(node))

    def st_call_sub(self, node) -> ast.SubroutineCall | None:
        name, *args = node.children
        text = next((a for a in args if getattr(a, "data", None) == "string"), None)
        if text is not None:
            # (LINTUL-banana's CALL INTERPOL('PCOTB', ..., PCOTB, ...): FST's STRING
            # argument, a table's name a routine hands on to LINT2)
            self.errors.append(Diagnostic(
                f"CALL {str(name).upper()} gives the string {text.children[0]}: a string "
                "argument (FST's STRING) is not supported", self.span(text),
                "a routine after STOP takes numbers and arrays; read a table in the "
                "listing with LINT2('F', F, N, X) or AFGEN(F, X)"))
            return None
        self.calls = True
        return ast.SubroutineCall(str(name).upper(),
                                  tuple(self.expr(a) for a in args if a is not None),
                                  self.span(node))

    def st_event(self, node) -> Head:
        return Head("EVENT", self.span(node))

    def st_endevent(self, node) -> Close:
        return Close("ENDEVENT", self.span(node))

    def st_zerocondition(self, node) -> ast.ZeroCondition:
        return ast.ZeroCondition(self.expr(node.children[0]), self.span(node))

    def st_event_time(self, node) -> ast.ZeroCondition:
        kind, expr = node.children
        return ast.ZeroCondition(self.expr(expr), self.span(node), str(kind).upper())

    def st_newvalue(self, node) -> ast.NewValue:
        name, expr = node.children
        return ast.NewValue(str(name).upper(), self.span(name), self.expr(expr), self.span(node))

    def st_set_value(self, node) -> ast.SetValue:
        name, expr = node.children
        return ast.SetValue(str(name).upper(), self.span(name), self.expr(expr), self.span(node))

    def st_define_call(self, node) -> ast.DefineCall:
        return ast.DefineCall(self.span(node))

    def st_termt(self, node) -> ast.Termt:
        expr, message = node.children
        return ast.Termt(self.expr(expr), self.span(node),
                         string_value(str(message)) if message is not None else None)

    def st_report(self, node) -> ast.Report:
        kind = REPORT_KEYWORDS[str(node.children[0]).upper()]
        *names, x = node.children[1:]  # x: the name after VS, or None
        return ast.Report(
            kind,
            tuple(str(n).upper() for n in names),
            tuple(self.span(n) for n in names),
            self.span(node),
            str(x).upper() if x is not None else None,
            self.span(x) if x is not None else None,
        )

    # expressions -----------------------------------------------------------
    def expr(self, root) -> ast.Expr:
        """The syntax of an expression tree: the one made as it reduced (`tree`), else
        built bottom-up without recursion."""
        if root.__class__ is Node and root.expr is not None:
            return root.expr

        def parts(node) -> list:
            if node.data == "call":
                args = [a for a in node.children[1:] if a is not None]
                if named_table(node, args):
                    return args[1:]  # LINT2('F', F, N, X): the name is read here
                return args
            if node.data == "subscript":
                return list(node.children[1:])
            if node.data in _BINOPS or node.data in _LOGIC:
                return [node.children[0], node.children[-1]]
            if node.data in ("neg", "pos", "lnot"):
                return [node.children[-1]]
            return []

        def named_table(node, args) -> bool:
            """FST's LINT2('F', F, N, X) names its table in a string first: the string
            must be the table's name; the call goes on as LINT2(F, N, X)."""
            if str(node.children[0]).upper() != "LINT2" or len(args) != 4 or \
                    getattr(args[0], "data", None) != "string":
                return False
            written = string_value(str(args[0].children[0])).strip().upper()
            table = args[1]
            if id(node) not in named and (getattr(table, "data", None) != "name" or
                                          str(table.children[0]).upper() != written):
                self.errors.append(Diagnostic(
                    f"LINT2 names the table '{written}' but reads another", self.span(args[0]),
                    "write LINT2('F', F, N, X) with the same name twice"))
            named.add(id(node))
            return True

        named: set[int] = set()

        done: list[tuple[ast.Expr, int]] = []  # built nodes with their depth
        stack: list[tuple[object, bool]] = [(root, False)]
        while stack:
            node, ready = stack.pop()
            if node.__class__ is not Node:  # (a token: a bare NUMBER/NAME never reaches here)
                done.append((ast.Name(str(node).upper(), self.span(node)), 1))
                continue
            if node.expr is not None:  # (a part made as it reduced)
                done.append((node.expr, node.depth))
                continue
            children = parts(node)
            if not ready and children:
                stack.append((node, True))
                stack.extend((c, False) for c in reversed(children))
                continue
            built = [done.pop() for _ in children][::-1]
            depth = 1 + max((d for _, d in built), default=0)
            if depth > MAX_DEPTH:
                raise AmilError([Diagnostic(
                    f"expression nested too deeply (more than {MAX_DEPTH} levels)",
                    self.span(node), "split it into several assignments")],
                    self.path, self.source)
            done.append((self.node(node, [b for b, _ in built]), depth))
        assert len(done) == 1
        return done[0][0]

    def node(self, node, args: list[ast.Expr]) -> ast.Expr:
        kind = node.data
        if kind == "number":
            tok = node.children[0]
            return ast.Num(fortran_float(str(tok)), self.span(node), str(tok))
        if kind == "name":
            return ast.Name(str(node.children[0]).upper(), self.span(node))
        if kind == "call":
            real = [a for a in node.children[1:] if a is not None]
            if len(real) == len(args) + 1:  # LINT2's table name, read by `expr`
                real = real[1:]
            return ast.Call(str(node.children[0]).upper(), tuple(args), self.span(node),
                            tuple(self.span(a) for a in real))
        if kind in _BINOPS:
            return ast.BinOp(_BINOPS[kind], args[0], args[1], self.span(node))
        if kind == "neg":
            return ast.Neg(args[0], self.span(node))
        if kind == "pos":
            return args[0]
        if kind in _LOGIC:
            op = _OPERATORS[str(node.children[1]).upper()]
            return ast.BinOp(op, args[0], args[1], self.span(node))
        if kind == "lnot":
            return ast.Not(args[0], self.span(node))
        if kind == "truth":
            tok = str(node.children[0]).upper()
            return ast.Num(1.0 if tok == ".TRUE." else 0.0, self.span(node), tok)
        if kind == "string":
            text = str(node.children[0])
            self.errors.append(Diagnostic(
                f"the string {text} cannot be a value", self.span(node),
                "strings are TERMT messages, WEATHER/TRANSLATION values and comments; put "
                "the text in a TERMT message or a comment"))
            return ast.Num(0.0, self.span(node), "0")
        if kind == "subscript":
            return ast.Index(str(node.children[0]).upper(), tuple(args), self.span(node))
        raise AssertionError(f"unknown expression node {kind}")
