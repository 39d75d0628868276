"""lark parse tree -> `syntax` nodes (lark trees never leave the `parse` package).

Expressions are built bottom-up with an explicit stack, so any nesting is read
without recursion; one nested deeper than `syntax.MAX_DEPTH` is a located error
(every later stage walks expressions recursively, with room for that depth).
"""

from __future__ import annotations

from .. import syntax as ast
from ..diagnostics import AmilError, Diagnostic, Span
from ..language import DATA_KEYWORDS, REPORT_KEYWORDS, SECTIONS
from ..syntax import MAX_DEPTH

# -------------------------------------------------------------- tree -> syntax

MAX_RUNS = 10_000  # value-list runs in one group: beyond this, a typo or a sweep

_BINOPS = {"add": "+", "sub": "-", "mul": "*", "div": "/", "pow": "**"}


def _number(text: str) -> float:
    return float(text.replace("D", "E").replace("d", "e"))


class Builder:
    """Turns lark trees into `syntax` nodes; iterative over statements and expressions."""

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
        """The syntax of an expression tree, built bottom-up without recursion."""
        from lark import Token, Tree

        def parts(node) -> list:
            if node.data == "call":
                return [a for a in node.children[1:] if a is not None]
            if node.data in _BINOPS:
                return [node.children[0], node.children[-1]]
            if node.data in ("neg", "pos"):
                return [node.children[0]]
            return []

        done: list[tuple[ast.Expr, int]] = []  # built nodes with their depth
        stack: list[tuple[object, bool]] = [(root, False)]
        while stack:
            node, ready = stack.pop()
            if isinstance(node, Token):  # a bare NUMBER/NAME never reaches here
                done.append((ast.Name(str(node).upper(), self.span(node)), 1))
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
        assert isinstance(root, (Tree, Token)) and len(done) == 1
        return done[0][0]

    def node(self, node, args: list[ast.Expr]) -> ast.Expr:
        kind = node.data
        if kind == "number":
            tok = node.children[0]
            return ast.Num(_number(str(tok)), self.span(node), str(tok))
        if kind == "name":
            return ast.Name(str(node.children[0]).upper(), self.span(node))
        if kind == "call":
            real = [a for a in node.children[1:] if a is not None]
            return ast.Call(str(node.children[0]).upper(), tuple(args), self.span(node),
                            tuple(self.span(a) for a in real))
        if kind in _BINOPS:
            return ast.BinOp(_BINOPS[kind], args[0], args[1], self.span(node))
        if kind == "neg":
            return ast.Neg(args[0], self.span(node))
        if kind == "pos":
            return args[0]
        raise AssertionError(f"unknown expression node {kind}")
